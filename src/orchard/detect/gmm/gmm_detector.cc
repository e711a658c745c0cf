#include "orchard/detect/gmm/gmm_detector.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {

void GmmDetectorOptions::Check() const {
  blobs.Check();
  ORCHARD_CHECK_OPTION(min_apple_posterior >= 0 && min_apple_posterior < 1,
                       "min_apple_posterior must be in [0, 1), got ", min_apple_posterior);
  ORCHARD_CHECK_OPTION(num_threads >= 1, "num_threads must be >= 1, got ", num_threads);
}

GmmDetector::GmmDetector(const ColourModel& model, const GmmDetectorOptions& options)
    : model_(model), options_(options), classifier_(model, options.min_apple_posterior) {
  options_.Check();
  segmentation_ = model.segmentation;
  segmentation_.superpixels.use_opencv = options.reference_slic;
  segmentation_.superpixels.num_threads = options.num_threads;
  segmentation_.Check();
}

FrameDetection GmmDetector::Detect(const cv::Mat& bgr) {
  const SegmentedFrame f = SegmentFrame(bgr, segmentation_);
  const int n = f.superpixels.num_labels;
  std::vector<uchar> apple(n);
  std::vector<float> posterior(n);
  for (int i = 0; i < n; ++i) {
    bool is_apple = false;
    classifier_.Classify(f.colours.mean[i], f.colours.covariance[i], &is_apple, &posterior[i]);
    apple[i] = is_apple ? 255 : 0;
  }
  cv::Mat1b mask(f.lab8.size());
  cv::Mat1f scores(f.lab8.size());
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = f.superpixels.labels.ptr<int>(y);
    uchar* m = mask.ptr<uchar>(y);
    float* s = scores.ptr<float>(y);
    for (int x = 0; x < mask.cols; ++x) {
      m[x] = apple[l[x]];
      s[x] = posterior[l[x]];
    }
  }
  BlobOptions blob_options = options_.blobs;
  const double area_scale = f.scale * f.scale;
  blob_options.min_pixels = std::max(1, static_cast<int>(std::lround(options_.blobs.min_pixels * area_scale)));
  FrameDetection d = ExtractBlobs(mask, blob_options);
  ScoreBlobs(scores, &d);
  if (f.scale == 1.0) return d;
  // Back to frame resolution.
  const double inv = 1.0 / f.scale;
  for (Blob& b : d.blobs) {
    b.box = {b.box.x1 * inv, b.box.y1 * inv, std::min<double>(bgr.cols, b.box.x2 * inv),
             std::min<double>(bgr.rows, b.box.y2 * inv)};
    b.centroid = {(b.centroid.x + 0.5) * inv - 0.5, (b.centroid.y + 0.5) * inv - 0.5};
    b.pixels = static_cast<int>(std::lround(b.pixels / area_scale));
  }
  cv::Mat1i labels;
  cv::resize(d.labels, labels, bgr.size(), 0, 0, cv::INTER_NEAREST);
  d.labels = labels;
  cv::compare(labels, 0, d.mask, cv::CMP_GT);
  return d;
}

}  // namespace orchard
