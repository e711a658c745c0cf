// The colour model of the GMM detector: ~25 colour classes (a Gaussian mixture
// over the mean CIELAB colours of superpixels) of which some are marked
// "apple", either from a user's clicks or from annotated boxes; its json file
// format; and the per-superpixel classifier.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "orchard/detect/gmm/gaussian_mixture.h"
#include "orchard/detect/gmm/superpixels.h"

namespace orchard {

namespace fs = std::filesystem;
struct Dataset;

// How frames are over-segmented: superpixels of `superpixels.region_size`
// frame pixels, computed (fast path) on the frame downscaled so that a
// superpixel is `working_region_size` pixels wide; the reference path
// (superpixels.use_opencv) runs OpenCV's SLIC at full resolution.
struct SegmentationOptions {
  SuperpixelOptions superpixels;
  // Superpixel width in pixels of the downscaled frame (fast path). 6 keeps
  // ~14 superpixels across a 60 px apple after downscaling a 16 px grid by 0.375.
  int working_region_size = 6;

  void Check() const;
  // Downscale factor of the fast path (1 for the reference path).
  double WorkingScale() const;
};

// A frame over-segmented at working resolution.
struct SegmentedFrame {
  double scale = 1;  // working size / frame size
  cv::Mat lab8;      // working-resolution 8-bit LAB image
  Superpixels superpixels;
  SuperpixelColours colours;
};
SegmentedFrame SegmentFrame(const cv::Mat& bgr, const SegmentationOptions& options);

struct ColourModel {
  static constexpr int kFormatVersion = 1;
  GaussianMixture mixture;      // 3-D CIELAB (L 0..100, a, b)
  std::vector<bool> apple;      // one per component
  SegmentationOptions segmentation;  // as used in training; detection reuses it
  std::string supervision;      // "clicks" or "annotations"
  std::string trained_on;       // free text: images/annotations the model came from
  std::string apple_rule;       // free text: how the apple classes were chosen

  // Throws orchard::Error when components/flags are inconsistent or there is
  // no apple class or no background class.
  void Validate() const;
  int NumApple() const;
};

void WriteColourModel(const ColourModel& model, const fs::path& path);
// Throws orchard::Error (naming the file) when it is missing, not json, not a
// colour model, of another format version, or inconsistent.
ColourModel ReadColourModel(const fs::path& path);

// A superpixel the KL rule calls apple must also have at least this apple
// posterior at its mean colour. The KL rule compares renormalised
// sub-mixtures, which lifts the apple classes' prior (a few percent of the
// colours) to that of all the foliage; the posterior keeps the true prior and
// removes the shadowed leaves and bark the KL rule lets in. 0.2 was the best
// detection F1 on the AppleBBCH training photos (docs/detection.md); 0 is
// the KL rule alone.
inline constexpr double kDefaultMinApplePosterior = 0.2;

struct ColourTrainingOptions {
  // Number of colour classes (mixture components).
  int num_classes = 25;
  // EM runs on at most this many superpixels (a deterministic even subsample);
  // all superpixels vote when classes are marked apple from annotations.
  int max_samples = 60000;
  // Annotations: a class is apple when more than this fraction of the pixels of
  // the training superpixels it explains best lie inside apples (ellipses
  // inscribed in the annotated boxes). 0 (default): the fraction is chosen so
  // that the detector's superpixel decision has the best apple-pixel F1 on the
  // training images.
  double apple_pixel_fraction = 0;
  // Clicks: a class is apple when at least this many clicks fall in it. 2
  // (chosen with simulated clicks on training photos, docs/detection.md) keeps
  // a class that one click on a shaded fruit shares with foliage shadow out.
  int min_clicks_per_class = 2;
  // Annotations: the superpixel decision the apple classes are chosen for
  // (as the detector's GmmDetectorOptions::min_apple_posterior).
  double min_apple_posterior = kDefaultMinApplePosterior;
  std::uint64_t seed = 0;
  SegmentationOptions segmentation;

  void Check() const;
};

// A click on an apple: image file name (or name without extension) and pixel.
struct Click {
  std::string image;
  double x = 0, y = 0;
};
// Reads a json list [{"image": "...", "x": .., "y": ..}, ...].
std::vector<Click> ReadClicks(const fs::path& path);
void WriteClicks(const std::vector<Click>& clicks, const fs::path& path);

// User-supervised: classes fitted on the superpixels of the images of `images`
// that the clicks are on; the class of the superpixel under each click is
// apple (when min_clicks_per_class clicks agree). Throws when there are no clicks, a
// click names an image not in `images` or falls outside it.
ColourModel TrainColourModelFromClicks(const std::vector<fs::path>& images, const std::vector<Click>& clicks,
                                       const ColourTrainingOptions& options);

// Semi-supervised: classes fitted on the superpixels of the dataset's images;
// apple classes by the apple_pixel_fraction rule above.
ColourModel TrainColourModelFromAnnotations(const Dataset& dataset, const ColourTrainingOptions& options);

// Per-superpixel decision with per-class constants precomputed, so a
// superpixel costs a few 3x3 products per class.
class ColourClassifier {
 public:
  ColourClassifier(const ColourModel& model, double min_apple_posterior);
  // Apple when Goldberger's KL from the superpixel's Gaussian (mean, cov) to
  // the apple sub-mixture is smaller than to the non-apple sub-mixture (each
  // sub-mixture's weights renormalised) and `apple_posterior`, the posterior
  // of the apple classes at the superpixel's mean colour, is at least
  // min_apple_posterior.
  void Classify(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, bool* is_apple,
                float* apple_posterior) const;
  // Most likely class of a colour.
  int MostLikelyClass(const Eigen::Vector3d& mean) const;

 private:
  struct ClassConstants {
    Eigen::Matrix3d inverse;
    Eigen::Vector3d mean;
    double half_log_det;
    double log_weight;        // in the whole mixture
    double log_group_weight;  // renormalised within apple / non-apple
    bool apple;
  };
  std::vector<ClassConstants> classes_;
  double min_apple_posterior_;
};

}  // namespace orchard
