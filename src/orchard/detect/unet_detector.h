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
