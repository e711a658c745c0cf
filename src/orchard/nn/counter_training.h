// Training the cluster counter: a ResNet classifying a cluster patch into
// 0..6 apples, with the study's recipe (flips, +-5 degree rotations, Gaussian
// smoothing, classes balanced by up-sampling, Adam 1e-3, early stopping).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "orchard/data/count_patches.h"
#include "orchard/data/dataset.h"
#include "orchard/nn/copy_paste.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"
#include "orchard/nn/trainer.h"

namespace orchard::nn {

namespace fs = std::filesystem;

struct LabelledPatch {
  cv::Mat bgr;        // the patch as cut (any size)
  int count = 0;      // 0..6
  std::string photo;  // source photo id: validation splits keep a photo on one side
  // The apples' centres in patch pixels, where known (patches cut from box
  // annotations, empty for background); patch folders carry only counts.
  std::vector<cv::Point2f> centres;
  bool has_centres = false;
};

// A folder with a CodaLab counting file `counts.csv` (`name,count`) and the
// patch images beside it or in `images/` (as `orchard patches` and
// `orchard synth` write them).
std::vector<LabelledPatch> ReadPatchFolder(const fs::path& dir);

// Patches cut from an annotated dataset (touching boxes -> clusters).
std::vector<LabelledPatch> CutDatasetPatches(const Dataset& dataset, const CountPatchOptions& options);

// Source photo of a patch named "<image stem>_p<k>.png".
std::string PatchPhotoId(const std::string& patch_name);

struct CounterTrainingOptions {
  // ResNet-18 at width 16 (a quarter of the paper's) trains on 2 CPU cores in minutes.
  ResNetOptions architecture{18, 16, 3, 7};
  // Patch side fed to the network. The study used 224; clusters of up to six
  // apples stay readable at 64 and training is ~12x cheaper.
  int input_size = 64;
  double learning_rate = 1e-3;  // Adam, betas 0.9 / 0.999 (the study's)
  // Class balancing by up-sampling: class c (n_c patches) is drawn as if it
  // had n_max^p * n_c^(1-p). 1 = every class as large as the largest (the
  // study's); 0.5 or 0 raise per-patch accuracy on real photos, where most
  // clusters hold one apple, but count multi-apple clusters too low
  // (models/counter.md, "GPU recipe sweep").
  double balance_power = 1.0;
  // Fraction of the training photos held out for early stopping. 0 = none:
  // every training photo trains and the last epoch is kept (for a recipe
  // whose epoch count was chosen on a run with validation).
  double validation_fraction = 0.2;
  uint64_t split_seed = 1;
  PatchAugmentation augmentation;
  // Composites of real single apples on real background (training photos only).
  CopyPasteOptions copy_paste;
  // Weight of the density head's loss (0 = no head; the architecture's
  // density_head follows it). The head's map should sum to the count (smooth
  // L1, every patch) and, where the apples' centres are known, match a
  // Gaussian of `density_sigma` cells around each (squared error, x10 so
  // both terms start at similar size).
  double density_weight = 0;
  double density_sigma = 1.0;
  TrainerOptions trainer;  // defaults: 50 epochs, patience 5

  void Check() const;
};

struct CounterTrainingResult {
  TrainingRecord record;
  int train_patches = 0;
  int validation_patches = 0;
  std::vector<int> train_class_counts;  // before balancing
};

// Indices into `labels` with each class repeated to its balanced size
// (CounterTrainingOptions::balance_power), classes in ascending order.
std::vector<size_t> BalancedIndices(const std::vector<int>& labels, double power);

// Trains on `patches` (split by photo into train / validation) and writes the
// best model to `model_path` with a header describing architecture, input
// size, the data (`data_description`) and the training record.
CounterTrainingResult TrainCounter(const std::vector<LabelledPatch>& patches, const CounterTrainingOptions& options,
                                   const nlohmann::json& data_description, const fs::path& model_path);

}  // namespace orchard::nn
