#include "orchard/nn/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <cstdio>
#include <numeric>

#include <unistd.h>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard::nn {
namespace {

void PrintProgress(int epoch, int max_epochs, size_t done, size_t total, double loss, bool tty) {
  if (!tty) return;
  const int width = 30;
  const int filled = total ? static_cast<int>(width * done / total) : width;
  std::fprintf(stderr, "\repoch %d/%d [%s%s] %3d%% loss %.4f", epoch, max_epochs, std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), total ? static_cast<int>(100 * done / total) : 100, loss);
  std::fflush(stderr);
}

void SaveState(const fs::path& dir, torch::nn::Module& model, torch::optim::Optimizer& optimizer,
               const TrainingRecord& record, const std::mt19937_64& rng, const WeightAverage* average) {
  fs::create_directories(dir);
  if (average) {
    torch::serialize::OutputArchive average_archive;
    average->Save(average_archive);
    WriteFileAtomic(dir / "ema.pt", [&](const fs::path& tmp) { average_archive.save_to(tmp.string()); });
  }
  torch::serialize::OutputArchive model_archive;
  model.save(model_archive);
  WriteFileAtomic(dir / "model.pt", [&](const fs::path& tmp) { model_archive.save_to(tmp.string()); });
  torch::serialize::OutputArchive optimizer_archive;
  optimizer.save(optimizer_archive);
  WriteFileAtomic(dir / "optimizer.pt", [&](const fs::path& tmp) { optimizer_archive.save_to(tmp.string()); });
  std::ostringstream rng_state;
  rng_state << rng;
  nlohmann::json json = record.ToJson();
  json["rng"] = rng_state.str();
  // The record is written last: its presence means the state is complete.
  WriteTextFileAtomic(dir / "record.json", json.dump(1));
}

bool LoadState(const fs::path& dir, torch::nn::Module& model, torch::optim::Optimizer& optimizer,
               TrainingRecord* record, std::mt19937_64* rng) {
  if (!fs::exists(dir / "record.json")) return false;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(dir / "record.json"));
    *record = TrainingRecord::FromJson(json);
    std::istringstream rng_state(json.at("rng").get<std::string>());
    rng_state >> *rng;
    torch::serialize::InputArchive model_archive;
    model_archive.load_from((dir / "model.pt").string());
    model.load(model_archive);
    torch::serialize::InputArchive optimizer_archive;
    optimizer_archive.load_from((dir / "optimizer.pt").string());
    optimizer.load(optimizer_archive);
  } catch (const std::exception& e) {
    Fail("cannot resume from ", dir.string(), " (delete it to start afresh): ", std::string(e.what()).substr(0, 200));
  }
  return true;
}

// The average of a resumed run; a state written without one restarts it from the loaded weights.
void LoadAverage(const fs::path& dir, WeightAverage* average) {
  if (!fs::exists(dir / "ema.pt")) return;
  try {
    torch::serialize::InputArchive archive;
    archive.load_from((dir / "ema.pt").string());
    average->Load(archive);
  } catch (const std::exception& e) {
    Fail("cannot resume the weight average from ", dir.string(), ": ", std::string(e.what()).substr(0, 200));
  }
}

}  // namespace

WeightAverage::WeightAverage(torch::nn::Module& model, double decay) : decay_(decay) {
  torch::NoGradGuard no_grad;
  for (const torch::Tensor& p : model.parameters()) live_.push_back(p);
  for (const torch::Tensor& b : model.buffers()) live_.push_back(b);
  for (const torch::Tensor& t : live_) average_.push_back(t.detach().clone());
}

void WeightAverage::Update() {
  torch::NoGradGuard no_grad;
  const double decay = std::min(decay_, (1.0 + updates_) / (10.0 + updates_));
  for (size_t i = 0; i < live_.size(); ++i) {
    if (average_[i].is_floating_point()) {
      average_[i].mul_(decay).add_(live_[i].detach(), 1.0 - decay);
    } else {
      average_[i].copy_(live_[i]);
    }
  }
  ++updates_;
}

void WeightAverage::Swap() {
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < live_.size(); ++i) {
    torch::Tensor held = live_[i].detach().clone();
    live_[i].detach().copy_(average_[i]);
    average_[i].copy_(held);
  }
}

void WeightAverage::Save(torch::serialize::OutputArchive& archive) const {
  for (size_t i = 0; i < average_.size(); ++i) archive.write("t" + std::to_string(i), average_[i]);
  archive.write("updates", torch::tensor(updates_, torch::kLong));
}

void WeightAverage::Load(torch::serialize::InputArchive& archive) {
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < average_.size(); ++i) {
    torch::Tensor t;
    archive.read("t" + std::to_string(i), t);
    if (!t.sizes().equals(average_[i].sizes())) Fail("weight average does not match the model");
    average_[i].copy_(t);
  }
  torch::Tensor updates;
  archive.read("updates", updates);
  updates_ = updates.item<int64_t>();
}

void TrainerOptions::Check() const {
  ORCHARD_CHECK_OPTION(max_epochs >= 1, "max epochs must be at least 1, got ", max_epochs);
  ORCHARD_CHECK_OPTION(patience >= 1, "patience must be at least 1, got ", patience);
  ORCHARD_CHECK_OPTION(batch_size >= 1, "batch size must be at least 1, got ", batch_size);
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0 (0 = all cores), got ", threads);
  ORCHARD_CHECK_OPTION(ema_decay >= 0 && ema_decay < 1, "weight-average decay must be in [0, 1), got ", ema_decay);
}

nlohmann::json TrainingRecord::ToJson() const {
  return {{"epochs_run", epochs_run}, {"best_epoch", best_epoch}, {"best_metric", best_metric},
          {"stopped_early", stopped_early}, {"seconds", seconds}, {"train_loss", train_loss},
          {"validation", validation}};
}

TrainingRecord TrainingRecord::FromJson(const nlohmann::json& json) {
  TrainingRecord r;
  r.epochs_run = json.at("epochs_run");
  r.best_epoch = json.at("best_epoch");
  r.best_metric = json.at("best_metric");
  r.stopped_early = json.at("stopped_early");
  r.seconds = json.at("seconds");
  r.train_loss = json.at("train_loss").get<std::vector<double>>();
  r.validation = json.at("validation").get<std::vector<double>>();
  return r;
}

void SetUpTorch(const TrainerOptions& options) {
  at::set_num_threads(ThreadsOrAvailableCores(options.threads));
  torch::manual_seed(options.seed);
}

TrainingRecord Train(TrainingTask& task, torch::nn::Module& model, torch::optim::Optimizer& optimizer,
                     const TrainerOptions& options) {
  options.Check();
  if (task.NumTrain() == 0) Fail("no training samples");
  const bool tty = options.progress && ::isatty(2);
  std::mt19937_64 rng(options.seed);
  TrainingRecord record;
  // The optimiser's learning rates as built: a resumed state holds the decayed ones.
  std::vector<double> initial_lr;
  for (const auto& group : optimizer.param_groups()) initial_lr.push_back(group.options().get_lr());
  const bool resumed = !options.state_dir.empty() && LoadState(options.state_dir, model, optimizer, &record, &rng);
  if (resumed) {
    std::fprintf(stderr, "resuming after epoch %d (best %s %.4f at epoch %d)\n", record.epochs_run,
                 task.MetricName().c_str(), record.best_metric, record.best_epoch);
  }
  std::unique_ptr<WeightAverage> average;
  if (options.ema_decay > 0) {
    average = std::make_unique<WeightAverage>(model, options.ema_decay);
    if (resumed) LoadAverage(options.state_dir, average.get());
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<size_t> order(task.NumTrain());
  std::iota(order.begin(), order.end(), 0);

  while (record.epochs_run < options.max_epochs && !record.stopped_early) {
    const int epoch = record.epochs_run + 1;
    std::shuffle(order.begin(), order.end(), rng);
    const size_t epoch_size =
        options.samples_per_epoch > 0 ? std::min(order.size(), options.samples_per_epoch) : order.size();
    if (options.cosine_lr) {
      const double factor = 0.5 * (1 + std::cos(M_PI * (epoch - 1) / options.max_epochs));
      for (size_t g = 0; g < initial_lr.size(); ++g) optimizer.param_groups()[g].options().set_lr(initial_lr[g] * factor);
    }
    model.train();
    double loss_sum = 0;
    size_t batches = 0;
    for (size_t begin = 0; begin < epoch_size; begin += options.batch_size) {
      const size_t end = std::min(epoch_size, begin + options.batch_size);
      std::vector<size_t> indices(order.begin() + begin, order.begin() + end);
      optimizer.zero_grad();
      torch::Tensor loss = task.TrainLoss(indices, rng);
      if (!std::isfinite(loss.item<double>())) Fail("training diverged: the loss is not finite at epoch ", epoch);
      loss.backward();
      optimizer.step();
      if (average) average->Update();
      loss_sum += loss.item<double>();
      ++batches;
      PrintProgress(epoch, options.max_epochs, end, epoch_size, loss_sum / batches, tty);
    }
    model.eval();
    // The average is validated and, when best, saved; training continues from the live weights.
    if (average) average->Swap();
    const bool validates = task.HasValidation();
    double metric = 0;
    if (validates) {
      torch::NoGradGuard no_grad;
      metric = task.Validate();
    }
    record.epochs_run = epoch;
    record.train_loss.push_back(loss_sum / std::max<size_t>(1, batches));
    if (validates) record.validation.push_back(metric);
    const bool improved = !validates || record.best_epoch == 0 || metric > record.best_metric;
    if (improved) {
      record.best_metric = metric;
      record.best_epoch = epoch;
      task.SaveBest();
    }
    if (average) average->Swap();
    if (epoch - record.best_epoch >= options.patience) record.stopped_early = true;
    if (options.progress) {
      if (tty) std::fputc('\r', stderr);
      if (validates) {
        std::fprintf(stderr, "epoch %d/%d loss %.4f %s %.4f%s\n", epoch, options.max_epochs, record.train_loss.back(),
                     task.MetricName().c_str(), metric, improved ? " (best)" : "");
      } else {
        std::fprintf(stderr, "epoch %d/%d loss %.4f (no validation: this epoch kept)\n", epoch, options.max_epochs,
                     record.train_loss.back());
      }
    }
    record.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!options.state_dir.empty()) SaveState(options.state_dir, model, optimizer, record, rng, average.get());
  }
  record.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return record;
}

}  // namespace orchard::nn
