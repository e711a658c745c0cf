// The box detector: a RetinaNet-style network trained by `orchard train
// retinanet` finds each apple as a box. For the stages that read masks and
// blobs, every box becomes one blob, the ellipse inscribed in it; a counter
// then counts one apple per blob. LibTorch stays in the .cc file.
#pragma once

#include <filesystem>
#include <memory>

#include "orchard/detect/detector.h"

namespace orchard {

struct RetinaNetDetectorOptions {
  // Boxes scoring below this are dropped. 0.5 suits counting; give 0.05 to
  // write every candidate for precision-recall curves and AP.
  double score_threshold = 0.5;
  double nms_iou = 0.5;        // non-maximum suppression between boxes (the paper's)
  int max_detections = 1000;   // per frame, highest scores first
  // Frames are resized by this factor before the network and the boxes mapped
  // back: apples in video frames can be smaller than the network learnt them.
  double input_scale = 1;
  BlobOptions blobs;           // boxes whose ellipse covers fewer pixels are dropped
  int threads = 0;             // LibTorch threads; 0 = all cores

  void Check() const;
};

class RetinaNetDetector : public Detector {
 public:
  // Loads a RetinaNet model; throws orchard::Error when the file is missing, is
  // not a RetinaNet model, or does not match its architecture.
  RetinaNetDetector(const std::filesystem::path& model_path, const RetinaNetDetectorOptions& options);
  ~RetinaNetDetector() override;

  // One blob per box, highest score first (id 1); where ellipses overlap, the
  // higher-scoring box keeps the pixels. Each blob's box is the detected box.
  FrameDetection Detect(const cv::Mat& bgr) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace orchard
