// Counting by mixture model selection: Gaussian mixtures with k = 1..max
// components are fitted to the positions of a blob's fruit pixels and the k
// with the lowest information criterion is the count; each component is one
// fruit (centre = mean, radius from its covariance). A blob without fruit
// pixels still counts as one: this counter cannot reject false positives.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "orchard/count/counter.h"
#include "orchard/data/dataset.h"
#include "orchard/detect/detector.h"
#include "orchard/detect/gmm/colour_model.h"

namespace orchard {

// kCoverage: the smallest k whose fruits, drawn as discs (centre, radius from
// the covariance), cover the blob (IoU of their union with the blob's pixels)
// within coverage_tolerance of the best k. BIC/AIC on pixel positions prefer
// splitting a filled disc, which is not a Gaussian.
enum class ModelSelection { kBic, kAic, kCoverage };
// "bic" / "aic" / "coverage" -> criterion; throws otherwise.
ModelSelection ParseModelSelection(const std::string& name);

struct GmmCounterOptions {
  // Largest count considered (the study's clusters hold 0..6 apples).
  int max_fruits = 6;
  // Coverage (default; BIC and AIC split filled discs and count more, see
  // docs/detection.md), BIC, or AIC, which penalises components least.
  ModelSelection criterion = ModelSelection::kCoverage;
  // kCoverage: IoU a larger k must gain over a smaller one to be chosen.
  double coverage_tolerance = 0.03;
  // EM runs on at most this many fruit pixels (a seeded random subsample):
  // the criteria's penalties grow as ln N while the likelihood gain of extra
  // components on non-Gaussian (disc-shaped) fruit grows as N, so a fixed
  // sample size keeps counts independent of the blob's size in pixels.
  int max_points = 150;
  // EM starts per k (best log-likelihood kept).
  int restarts = 3;
  // Fewer fruit pixels than this per component makes a k impossible.
  int min_points_per_fruit = 8;
  // A k is admissible only when every two fruits are at least this far apart,
  // in units of the sum of their radii (fruit radius = 2 sqrt(sqrt(det C)), exact
  // for a uniform disc). Touching equal discs give 1; a single disc split in two
  // by EM gives about 0.58, so the information criterion alone, which prefers
  // splitting filled discs (not Gaussians), cannot over-count. 0 disables it.
  double min_separation = 0.7;
  std::uint64_t seed = 0;
  void Check() const;
};

class GmmCounter : public Counter {
 public:
  // `colour_model` (optional) finds the fruit pixels of patches given without a mask.
  explicit GmmCounter(const GmmCounterOptions& options, std::shared_ptr<const ColourModel> colour_model = nullptr);
  BlobCount Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) override;

 private:
  GmmCounterOptions options_;
  std::shared_ptr<const ColourModel> colour_model_;
};

// Fruit pixels of a patch by the colour model (superpixels classified apple).
cv::Mat1b ColourFruitMask(const cv::Mat& bgr_patch, const ColourModel& model);

// One box per fruit: each blob of `detection` (found in `bgr`) is split by
// `counter` into fruits, each boxed as centre +- radius (clipped to the frame)
// with the blob's score. The fair comparison with per-apple ground-truth boxes.
std::vector<ScoredBox> FruitBoxes(const cv::Mat& bgr, const FrameDetection& detection, Counter& counter);

}  // namespace orchard
