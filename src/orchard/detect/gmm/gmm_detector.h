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
  // Blob boxes, centroids and pixel counts are in frame pixels. On the fast
  // path they are measured at frame resolution after the edges are redrawn
  // (refine_edges), else at working resolution and scaled up (pixel counts to
  // within the downscaling's rounding).
  FrameDetection Detect(const cv::Mat& bgr) override;

 private:
  ColourModel model_;
  GmmDetectorOptions options_;
  SegmentationOptions segmentation_;
  ColourClassifier classifier_;
};

// The fast path's last step, after the blob edges were redrawn at frame
// resolution: a blob may then fall apart (two apples joined at working
// resolution by a gap narrower than a working pixel) or shed slivers (edge
// pixels matching an apple superpixel but not touching the blob; they used to
// stretch its box). Each blob's pixels are regrouped into 8-connected pieces
// within its box grown by one working pixel (the furthest an edge moves):
// pieces under `min_pixels` are dropped from labels and mask, the others
// become blobs measured at frame resolution (box, pixels, centroid; score =
// mean of `working_scores`, the working-resolution posterior map, under their
// pixels). Ids are renumbered 1..N keeping the old order.
void RegroupBlobsAtFrameResolution(const cv::Mat1f& working_scores, int min_pixels, FrameDetection* detection);

}  // namespace orchard
