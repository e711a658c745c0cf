// The training loop shared by every network: shuffled mini-batches, validation
// after each epoch, early stopping on the validation metric, the best model
// kept, resumable state, a progress bar, a fixed seed and all cores in use.
#pragma once

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <torch/torch.h>

namespace orchard::nn {

namespace fs = std::filesystem;

struct TrainerOptions {
  int max_epochs = 50;   // upper bound on passes over the training set
  int patience = 5;      // stop after this many epochs without a better validation metric
  int batch_size = 16;
  // Training samples drawn (without replacement, reshuffled) per epoch; 0 =
  // all. Dense tilings hold far more samples than a CPU epoch can afford.
  size_t samples_per_epoch = 0;
  uint64_t seed = 0;     // shuffling, augmentation and weight initialisation
  int threads = 0;       // LibTorch intra-op threads; 0 = all cores of the machine
  // Folder for the resumable state (model, optimiser, record after each epoch);
  // empty = no resume. A run with the same folder continues where it stopped.
  fs::path state_dir;
  bool progress = true;  // progress bar on stderr
  // Exponential moving average of the weights and BatchNorm statistics,
  // updated after every step; the average is what is validated and saved.
  // 0 = off. Smooths the epoch-to-epoch swings of the validation metric that
  // make the early-stopping pick noisy (a decay of 0.998 averages ~500 steps).
  double ema_decay = 0;
  // Learning rate of epoch e (1-based) = initial * 0.5 (1 + cos(pi (e - 1) / max_epochs)):
  // large steps first, small ones at the end, where the best epochs are.
  bool cosine_lr = false;

  void Check() const;
};

// What a training run needs from its data and its model.
class TrainingTask {
 public:
  virtual ~TrainingTask() = default;
  virtual size_t NumTrain() const = 0;
  // Loss of one training batch (the model in training mode); the trainer
  // back-propagates and steps the optimiser.
  virtual torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64& rng) = 0;
  // Metric over the whole validation set, higher is better (model in eval
  // mode, gradients off).
  virtual double Validate() = 0;
  virtual std::string MetricName() const = 0;
  // Called when the validation metric improves: keep this model.
  virtual void SaveBest() = 0;
  // False when every sample trains (no held-out set): the trainer then keeps
  // each epoch's model in turn (the last is saved), without early stopping.
  virtual bool HasValidation() const { return true; }
};

struct TrainingRecord {
  int epochs_run = 0;
  int best_epoch = 0;  // 1-based; 0 when no epoch ran
  double best_metric = -1e300;
  bool stopped_early = false;
  double seconds = 0;  // wall time of this run (not counting earlier resumed runs)
  std::vector<double> train_loss;  // mean per epoch
  std::vector<double> validation;  // metric per epoch (empty without validation)

  nlohmann::json ToJson() const;
  static TrainingRecord FromJson(const nlohmann::json& json);
};

// The moving average of a model's parameters and buffers (trainer.h's
// ema_decay). Floating-point tensors are averaged, integer buffers (BatchNorm's
// batch counter) copied. The decay warms up as min(decay, (1 + t) / (10 + t))
// after t updates, so the first steps' random weights fade quickly.
class WeightAverage {
 public:
  WeightAverage(torch::nn::Module& model, double decay);
  void Update();
  // Exchanges the model's tensors with the averages (call again to undo).
  void Swap();
  int64_t updates() const { return updates_; }
  void Save(torch::serialize::OutputArchive& archive) const;
  void Load(torch::serialize::InputArchive& archive);

 private:
  std::vector<torch::Tensor> live_;     // the model's parameters and buffers
  std::vector<torch::Tensor> average_;  // their averages, same order
  double decay_;
  int64_t updates_ = 0;
};

// Uses options.threads cores and seeds LibTorch; call before building a model
// so its initial weights follow the seed.
void SetUpTorch(const TrainerOptions& options);

TrainingRecord Train(TrainingTask& task, torch::nn::Module& model, torch::optim::Optimizer& optimizer,
                     const TrainerOptions& options);

}  // namespace orchard::nn
