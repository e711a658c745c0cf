#include "orchard/count/gmm_counter.h"

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/LU>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/detect/gmm/gmm_detector.h"

namespace orchard {

ModelSelection ParseModelSelection(const std::string& name) {
  if (name == "bic") return ModelSelection::kBic;
  if (name == "aic") return ModelSelection::kAic;
  if (name == "coverage") return ModelSelection::kCoverage;
  Fail("unknown model-selection criterion '", name, "' (use coverage, bic or aic)");
}

void GmmCounterOptions::Check() const {
  ORCHARD_CHECK_OPTION(max_fruits >= 1, "max_fruits must be >= 1, got ", max_fruits);
  ORCHARD_CHECK_OPTION(restarts >= 1, "restarts must be >= 1, got ", restarts);
  ORCHARD_CHECK_OPTION(max_points >= 10, "max_points must be >= 10, got ", max_points);
  ORCHARD_CHECK_OPTION(min_points_per_fruit >= 3, "min_points_per_fruit must be >= 3, got ", min_points_per_fruit);
  ORCHARD_CHECK_OPTION(min_separation >= 0, "min_separation must be >= 0, got ", min_separation);
}

GmmCounter::GmmCounter(const GmmCounterOptions& options, std::shared_ptr<const ColourModel> colour_model)
    : options_(options), colour_model_(std::move(colour_model)) {
  options_.Check();
}

cv::Mat1b ColourFruitMask(const cv::Mat& bgr_patch, const ColourModel& model) {
  GmmDetectorOptions options;
  options.blobs.min_pixels = 1;
  GmmDetector detector(model, options);
  return detector.Detect(bgr_patch).mask;
}

namespace {

// A uniform disc of radius r has variance r^2 / 4 along each axis.
double FruitRadius(const Gaussian& g) { return 2.0 * std::sqrt(std::sqrt(std::max(0.0, g.covariance.determinant()))); }

// IoU of the blob's pixels and the union of the fruits drawn as discs.
double DiscCoverage(const GaussianMixture& m, const cv::Mat1b& blob, double blob_pixels) {
  cv::Mat1b discs(blob.size(), uchar(0));
  for (const Gaussian& g : m.components)
    cv::circle(discs, cv::Point(cvRound(g.mean[0]), cvRound(g.mean[1])), std::max(1, cvRound(FruitRadius(g))), 255,
               cv::FILLED);
  const double both = cv::countNonZero(discs & blob);
  const double either = blob_pixels + cv::countNonZero(discs) - both;
  return either > 0 ? both / either : 0.0;
}

bool Separated(const GaussianMixture& m, double min_separation) {
  for (int i = 0; i < m.NumComponents(); ++i)
    for (int j = i + 1; j < m.NumComponents(); ++j) {
      const double d = (m.components[i].mean - m.components[j].mean).norm();
      if (d < min_separation * (FruitRadius(m.components[i]) + FruitRadius(m.components[j]))) return false;
    }
  return true;
}

}  // namespace

BlobCount GmmCounter::Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) {
  if (bgr_patch.empty()) Fail("cannot count apples in an empty patch");
  cv::Mat1b mask = fruit_mask;
  if (mask.empty()) {
    if (!colour_model_) Fail("the GMM counter needs a fruit mask or a colour model to find the fruit pixels");
    mask = ColourFruitMask(bgr_patch, *colour_model_);
  }
  if (mask.size() != bgr_patch.size()) Fail("fruit mask and patch differ in size");
  std::vector<cv::Point> pixels;
  cv::findNonZero(mask, pixels);
  BlobCount result;
  if (static_cast<int>(pixels.size()) < 2 * options_.min_points_per_fruit) {
    // No (usable) fruit pixels: still one apple, as the detector reported a blob.
    result.count = 1;
    result.fruits.push_back({{0.5 * (bgr_patch.cols - 1), 0.5 * (bgr_patch.rows - 1)},
                             0.25 * (bgr_patch.cols + bgr_patch.rows)});
    return result;
  }
  const int n = std::min<int>(options_.max_points, static_cast<int>(pixels.size()));
  Eigen::MatrixXd x(n, 2);
  // A seeded random subsample: a strided one aliases with the pixel grid.
  std::mt19937_64 rng(options_.seed);
  if (n < static_cast<int>(pixels.size())) {
    for (int i = 0; i < n; ++i)
      std::swap(pixels[i], pixels[i + std::uniform_int_distribution<size_t>(0, pixels.size() - 1 - i)(rng)]);
  }
  for (int i = 0; i < n; ++i) {
    const cv::Point& p = pixels[i];
    x(i, 0) = p.x;
    x(i, 1) = p.y;
  }
  const int k_max = std::max(1, std::min(options_.max_fruits, n / options_.min_points_per_fruit));
  double best_score = std::numeric_limits<double>::infinity();
  GaussianMixture best;
  const cv::Mat1b blob = mask != 0;
  const double blob_pixels = static_cast<double>(pixels.size());
  for (int k = 1; k <= k_max; ++k) {
    GaussianMixtureOptions em;
    em.num_components = k;
    em.regularization = 0.25;  // pixels^2: a pixel-quantised blob never has zero spread
    em.max_iterations = 100;
    em.tolerance = 1e-5;
    // EM finds local optima: keep the best of a few seeded starts.
    GaussianMixtureFit fit;
    fit.log_likelihood = -std::numeric_limits<double>::infinity();
    for (int start = 0; start < options_.restarts; ++start) {
      em.seed = options_.seed + start;
      GaussianMixtureFit f = FitGaussianMixture(x, em);
      if (f.log_likelihood > fit.log_likelihood) fit = f;
    }
    double score = 0;
    switch (options_.criterion) {
      case ModelSelection::kBic: score = fit.Bic(); break;
      case ModelSelection::kAic: score = fit.Aic(); break;
      // Lower is better; each extra fruit must buy coverage_tolerance of IoU.
      case ModelSelection::kCoverage:
        score = -DiscCoverage(fit.mixture, blob, blob_pixels) + options_.coverage_tolerance * k;
        break;
    }
    if (score < best_score && Separated(fit.mixture, options_.min_separation)) best_score = score, best = fit.mixture;
  }
  result.count = best.NumComponents();
  for (const Gaussian& g : best.components) result.fruits.push_back({{g.mean[0], g.mean[1]}, FruitRadius(g)});
  return result;
}

std::vector<ScoredBox> FruitBoxes(const cv::Mat& bgr, const FrameDetection& detection, Counter& counter) {
  std::vector<ScoredBox> boxes;
  const cv::Rect frame(0, 0, bgr.cols, bgr.rows);
  for (const Blob& b : detection.blobs) {
    const cv::Rect roi = cv::Rect(static_cast<int>(std::floor(b.box.x1)), static_cast<int>(std::floor(b.box.y1)),
                                  static_cast<int>(std::ceil(b.box.Width())), static_cast<int>(std::ceil(b.box.Height()))) &
                         frame;
    if (roi.empty()) continue;
    const cv::Mat1b mask = detection.labels(roi) == b.id;
    const BlobCount c = counter.Count(bgr(roi), mask);
    for (const Fruit& f : c.fruits) {
      const double x = f.centre.x + roi.x, y = f.centre.y + roi.y;
      boxes.push_back({{std::max(0.0, x - f.radius), std::max(0.0, y - f.radius),
                        std::min<double>(bgr.cols, x + f.radius), std::min<double>(bgr.rows, y + f.radius)},
                       b.score});
    }
  }
  return boxes;
}

}  // namespace orchard
