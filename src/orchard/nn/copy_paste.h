// Copy-paste augmentation for the cluster counter: multi-apple clusters are
// rare in the annotated photos (a few dozen of 4..6 apples), so the counter
// also learns from clusters composed of real single apples pasted, touching
// and partly overlapping, onto real background of the same photo, labelled
// with the number pasted. OpenCV only (no LibTorch).
#pragma once

#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace orchard::nn {

struct CopyPasteOptions {
  // Probability that a drawn training sample of 1..6 apples is replaced by a
  // fresh composite of the same count; 0 = off. Single apples are composed
  // too, so pasting seams do not tell the network "more than one".
  double probability = 0;
  // Centre distance of a pasted apple to the one it touches, as a fraction of
  // the sum of their radii, uniform in [min, max]: below 1 they overlap as in
  // real clusters. No two apples come closer than `min_separation`, so none
  // hides most of another.
  double min_separation = 0.6;
  double max_separation = 1.0;
  // Apples of one composite are resized to the first one's radius times
  // U(1 - jitter, 1 + jitter): neighbours on a branch are of similar size,
  // while one photo's single apples range from small to large.
  double size_jitter = 0.15;
  // How the patches were cut (CountPatchOptions): the apple of a single-apple
  // patch is its inner box, and composites get the same margin.
  double margin = 0.1;
  int min_margin = 3;

  void Check() const;
};

struct AppleSprite {
  cv::Mat bgr;         // 8-bit BGR
  cv::Mat1f alpha;     // same size, 1 on the apple, soft edge
  double radius = 0;   // half the mean of the sides, pixels
};

// The apple of a single-apple patch: the box inside the cut margin, with an
// inscribed elliptical alpha.
AppleSprite SpriteFromSingleApplePatch(const cv::Mat& bgr, const CopyPasteOptions& options);

// A cluster of sprites.size() apples: the first in the middle, every further
// one touching a random earlier one; pasted in a random order onto
// `background` stretched to the cluster box plus the margin, and cut there.
// `centres` (optional) receives the apples' centres in the composite's pixels.
cv::Mat ComposeCluster(const std::vector<const AppleSprite*>& sprites, const cv::Mat& background,
                       const CopyPasteOptions& options, std::mt19937_64& rng,
                       std::vector<cv::Point2f>* centres = nullptr);

// Sprites and backgrounds grouped by photo, so a composite keeps one photo's
// scale and light.
class CopyPasteSource {
 public:
  // Patch images with their counts and photos (the training side only):
  // count 1 gives sprites, count 0 backgrounds.
  CopyPasteSource(const std::vector<cv::Mat>& bgr, const std::vector<int>& counts,
                  const std::vector<std::string>& photos, const CopyPasteOptions& options);
  bool empty() const { return photos_.empty(); }
  size_t num_photos() const { return photos_.size(); }
  // A composite of `count` apples (sprites and background from one random photo).
  cv::Mat Compose(int count, std::mt19937_64& rng, std::vector<cv::Point2f>* centres = nullptr) const;

 private:
  struct Photo {
    std::vector<AppleSprite> sprites;
    std::vector<cv::Mat> backgrounds;
  };
  std::vector<Photo> photos_;
  CopyPasteOptions options_;
};

}  // namespace orchard::nn
