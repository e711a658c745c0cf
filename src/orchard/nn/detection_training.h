// Training the RetinaNet-style apple detector: random tiles of the training
// images at a random scale, flipped half the time, with the apples' boxes;
// focal loss; Adam; validation by COCO AP50 on whole images of held-out photos.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "orchard/data/dataset.h"
#include "orchard/nn/retinanet.h"
#include "orchard/nn/trainer.h"

namespace orchard::nn {

namespace fs = std::filesystem;

struct BoxSample {
  std::string name;         // image file name
  cv::Mat bgr;              // 8-bit BGR image
  std::vector<Box> boxes;   // one per apple, pixels
  std::string photo;        // source photo id: validation keeps a photo on one side
};

// Images and apple boxes of an annotated dataset (box datasets as they are;
// MinneApple-layout datasets, such as the synthetic generator's sides, give
// each instance's tight box).
std::vector<BoxSample> LoadBoxSamples(const Dataset& dataset);

struct RetinaNetTrainingOptions {
  RetinaNetOptions architecture;
  int tile = 320;  // training tile side, a multiple of 32
  // Each drawn image is scaled by a factor uniform in [min_scale, max_scale]
  // before the tile is cut, so apples of every size train every level.
  double min_scale = 0.75;
  double max_scale = 1.25;
  // Boxes smaller than this (pixels, shorter side after scaling) are not
  // learnt as apples; their anchors are ignored rather than called background.
  double min_box_side = 6;
  // A box the tile cuts is an apple when at least this fraction of it lies
  // inside, else ignored.
  double min_visible = 0.5;
  AnchorMatching matching;
  double learning_rate = 1e-3;  // Adam
  double validation_fraction = 0.2;
  uint64_t split_seed = 1;
  int max_validation_images = 40;  // whole held-out images scored each epoch, evenly spread
  TrainerOptions trainer;

  void Check() const;
};

struct RetinaNetTrainingResult {
  TrainingRecord record;
  int train_images = 0;
  int validation_images = 0;
  int train_boxes = 0;
};

RetinaNetTrainingResult TrainRetinaNet(const std::vector<BoxSample>& samples, const RetinaNetTrainingOptions& options,
                                       const nlohmann::json& data_description, const fs::path& model_path);

// One image through the network: padded to a multiple of 32, decoded, boxes
// in the image's pixels.
std::vector<ScoredApple> DetectApples(RetinaNet& net, const cv::Mat& bgr, const DecodeOptions& options);

}  // namespace orchard::nn
