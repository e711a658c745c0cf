// The U-Net detector: a segmentation network trained by `orchard train unet`
// labels every pixel apple or background; its apple mask becomes blobs like the
// colour detector's. LibTorch stays in the .cc file.
#pragma once

#include <filesystem>
#include <memory>

#include "orchard/detect/detector.h"

namespace orchard {

struct UNetDetectorOptions {
  // Inference tile side in pixels (frames are cut into tiles without overlap,
  // as the study did); 0 = the tile size the model was trained with.
  int tile = 0;
  // Run the (fully convolutional) network once on the whole frame, zero-padded
  // to the network's input multiple, instead of tile by tile: the same
  // weights, no seams at tile borders, and fewer padded pixels (1920x1080
  // becomes 1920x1088 instead of 2016x1120). Memory grows with the frame.
  bool whole_frame = false;
  // Tiles per forward pass: larger is faster up to memory.
  int batch = 4;
  // A pixel is apple when the network's apple probability exceeds this.
  double threshold = 0.5;
  BlobOptions blobs;
  int threads = 0;  // LibTorch threads; 0 = all cores

  void Check() const;
};

class UNetDetector : public Detector {
 public:
  // Loads a U-Net model; throws orchard::Error when the file is missing, is not
  // a U-Net model, or does not match its architecture.
  UNetDetector(const std::filesystem::path& model_path, const UNetDetectorOptions& options);
  ~UNetDetector() override;

  FrameDetection Detect(const cv::Mat& bgr) override;

  // Per-pixel apple probability (CV_32F, frame size).
  cv::Mat1f AppleProbability(const cv::Mat& bgr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace orchard
