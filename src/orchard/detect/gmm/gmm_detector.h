// The colour-GMM detector: superpixels -> colour classes -> apple superpixels
// (KL rule of the colour model) -> fruit mask -> blobs scored by their mean
// apple posterior.
#pragma once

#include "orchard/detect/detector.h"
#include "orchard/detect/gmm/colour_model.h"

namespace orchard {

struct GmmDetectorOptions {
  // Use OpenCV's SLIC at full resolution (the slow reference path) instead of
  // the fast superpixels on the downscaled frame.
  bool reference_slic = false;
  // Superpixels need this apple posterior besides the KL rule (0 = KL alone);
  // see kDefaultMinApplePosterior.
  double min_apple_posterior = kDefaultMinApplePosterior;
  // Fast path: redraw the edges of the apple mask at frame resolution (see
  // gmm_detector.cc) instead of scaling the working mask up.
  bool refine_edges = true;
  BlobOptions blobs;
  int num_threads = 2;
  void Check() const;
};

class GmmDetector : public Detector {
 public:
  GmmDetector(const ColourModel& model, const GmmDetectorOptions& options);
  // Blob boxes, centroids and pixel counts are in frame pixels; on the fast
  // path they are measured at working resolution and scaled up (pixel counts
  // to within the downscaling's rounding).
  FrameDetection Detect(const cv::Mat& bgr) override;

 private:
  ColourModel model_;
  GmmDetectorOptions options_;
  SegmentationOptions segmentation_;
  ColourClassifier classifier_;
};

}  // namespace orchard
