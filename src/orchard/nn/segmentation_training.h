// Training the U-Net fruit segmenter: 224x224 tiles cut with stride 50 (the
// study's), weighted cross-entropy with class weights inversely proportional to
// class frequency, AdaDelta, early stopping on the validation apple IoU.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "orchard/data/dataset.h"
#include "orchard/nn/models.h"
#include "orchard/nn/trainer.h"

namespace orchard::nn {

namespace fs = std::filesystem;

struct SegmentationSample {
  cv::Mat bgr;        // 8-bit BGR image
  cv::Mat1b mask;     // 1 = apple, 0 = background; image size
  std::string photo;  // source photo id: validation keeps a photo on one side
};

// Images and apple masks of an annotated dataset: instance masks when the
// dataset has them (MinneApple layout, the synthetic generator's output), else
// ellipses inscribed in the boxes (box-only real data).
std::vector<SegmentationSample> LoadSegmentationSamples(const Dataset& dataset);

struct UNetTrainingOptions {
  // Narrow VGG-16 U-Net (base width 8 instead of 64) so it trains on 2 CPU cores.
  UNetOptions architecture{8, 3, 2, 5, true};
  int tile = 224;    // training tile side (the study's)
  int stride = 50;   // tiles are cut every `stride` pixels (the study's)
  double learning_rate = 1.0;  // AdaDelta's (PyTorch default)
  double validation_fraction = 0.2;
  uint64_t split_seed = 1;
  // Validation tiles at most (non-overlapping tiles of the validation photos).
  int max_validation_tiles = 200;
  TrainerOptions trainer;  // set samples_per_epoch: all stride-50 tiles are ~80 per 640x640 image

  void Check() const;
};

struct UNetTrainingResult {
  TrainingRecord record;
  int train_tiles = 0;
  int validation_tiles = 0;
  std::vector<double> class_weights;
};

UNetTrainingResult TrainUNet(const std::vector<SegmentationSample>& samples, const UNetTrainingOptions& options,
                             const nlohmann::json& data_description, const fs::path& model_path);

}  // namespace orchard::nn
