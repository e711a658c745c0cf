#include "orchard/nn/counter_training.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <regex>
#include <set>

#include "orchard/core/error.h"
#include "orchard/core/random.h"
#include "orchard/core/file_io.h"
#include "orchard/data/split.h"
#include "orchard/nn/checkpoint.h"

namespace orchard::nn {
namespace {

constexpr int kClasses = 7;

class CounterTask : public TrainingTask {
 public:
  CounterTask(ResNet net, const CounterTrainingOptions& options, std::vector<cv::Mat> train_images,
              std::vector<int> train_labels, std::vector<cv::Mat> val_images, std::vector<int> val_labels,
              const CopyPasteSource* copy_paste, std::function<void()> save_best)
      : net_(net),
        copy_paste_(copy_paste),
        options_(options),
        train_images_(std::move(train_images)),
        train_labels_(std::move(train_labels)),
        val_images_(std::move(val_images)),
        val_labels_(std::move(val_labels)),
        save_best_(std::move(save_best)) {
    balanced_ = BalancedIndices(train_labels_, options_.balance_power);
  }
  size_t NumTrain() const override { return balanced_.size(); }
  torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64& rng) override {
    std::vector<cv::Mat> images;
    std::vector<int64_t> labels;
    for (size_t i : indices) {
      const size_t sample = balanced_[i];
      const int label = train_labels_[sample];
      if (copy_paste_ && label >= 1 && Uniform01(rng) < options_.copy_paste.probability) {
        images.push_back(
            AugmentPatch(LetterboxPatch(copy_paste_->Compose(label, rng), options_.input_size), options_.augmentation, rng));
      } else {
        images.push_back(AugmentPatch(train_images_[sample], options_.augmentation, rng));
      }
      labels.push_back(label);
    }
    return torch::cross_entropy_loss(net_->forward(ImagesToTensor(images)), torch::tensor(labels, torch::kLong));
  }
  double Validate() override {
    if (val_images_.empty()) return 0;
    int correct = 0;
    for (size_t begin = 0; begin < val_images_.size(); begin += 64) {
      const size_t end = std::min(val_images_.size(), begin + 64);
      std::vector<cv::Mat> batch(val_images_.begin() + begin, val_images_.begin() + end);
      torch::Tensor predicted = net_->forward(ImagesToTensor(batch)).argmax(1);
      for (size_t i = begin; i < end; ++i) correct += predicted[i - begin].item<int64_t>() == val_labels_[i];
    }
    return static_cast<double>(correct) / val_images_.size();
  }
  std::string MetricName() const override { return "val_accuracy"; }
  void SaveBest() override { save_best_(); }

 private:
  ResNet net_;
  const CopyPasteSource* copy_paste_;  // null when copy-paste is off
  const CounterTrainingOptions& options_;
  std::vector<cv::Mat> train_images_;
  std::vector<int> train_labels_;
  std::vector<cv::Mat> val_images_;
  std::vector<int> val_labels_;
  std::vector<size_t> balanced_;
  std::function<void()> save_best_;
};

}  // namespace

std::vector<size_t> BalancedIndices(const std::vector<int>& labels, double power) {
  std::map<int, std::vector<size_t>> by_class;
  for (size_t i = 0; i < labels.size(); ++i) by_class[labels[i]].push_back(i);
  size_t largest = 0;
  for (const auto& [label, members] : by_class) largest = std::max(largest, members.size());
  std::vector<size_t> balanced;
  for (const auto& [label, members] : by_class) {
    const double target = std::pow(static_cast<double>(largest), power) *
                          std::pow(static_cast<double>(members.size()), 1 - power);
    const size_t size = std::max(members.size(), static_cast<size_t>(std::lround(target)));
    for (size_t k = 0; k < size; ++k) balanced.push_back(members[k % members.size()]);
  }
  return balanced;
}

std::string PatchPhotoId(const std::string& patch_name) {
  static const std::regex kPatchSuffix("_p[0-9]+$");
  return PhotoId(std::regex_replace(fs::path(patch_name).stem().string(), kPatchSuffix, ""));
}

std::vector<LabelledPatch> ReadPatchFolder(const fs::path& dir) {
  const fs::path counts_file = dir / "counts.csv";
  std::error_code ec;
  if (!fs::is_regular_file(counts_file, ec)) Fail("no counts.csv in patch folder ", dir.string());
  std::vector<LabelledPatch> patches;
  for (const ImageCount& entry : ReadCodaLabCounts(counts_file)) {
    if (entry.count < 0 || entry.count >= kClasses) {
      Fail(counts_file.string(), ": count of ", entry.name, " is ", entry.count, ", the counter knows 0..6");
    }
    // Patches sit beside counts.csv or in images/ below it (the synthetic generator's layout).
    std::error_code exists_ec;
    const fs::path path = fs::exists(dir / entry.name, exists_ec) ? dir / entry.name : dir / "images" / entry.name;
    patches.push_back({ReadImage(path), entry.count, PatchPhotoId(entry.name)});
  }
  if (patches.empty()) Fail("patch folder ", dir.string(), " has no patches");
  return patches;
}

std::vector<LabelledPatch> CutDatasetPatches(const Dataset& dataset, const CountPatchOptions& options) {
  std::vector<LabelledPatch> patches;
  std::string current;
  cv::Mat image;
  for (const CountPatch& patch : MakeCountPatches(dataset, options)) {
    if (patch.image != current) {
      const AnnotatedImage* source = dataset.Find(patch.image);
      if (!source || source->path.empty()) Fail("no image file for ", patch.image);
      image = ReadImage(source->path);
      current = patch.image;
    }
    patches.push_back({image(patch.crop & cv::Rect(0, 0, image.cols, image.rows)).clone(), patch.count,
                       PhotoId(patch.image)});
  }
  return patches;
}

void CounterTrainingOptions::Check() const {
  architecture.Check();
  trainer.Check();
  copy_paste.Check();
  ORCHARD_CHECK_OPTION(architecture.num_classes == kClasses, "the counter has 7 classes (0..6), got ",
                       architecture.num_classes);
  ORCHARD_CHECK_OPTION(input_size >= 32 && input_size <= 512, "input size must be in [32, 512], got ", input_size);
  ORCHARD_CHECK_OPTION(learning_rate > 0, "learning rate must be positive, got ", learning_rate);
  ORCHARD_CHECK_OPTION(balance_power >= 0 && balance_power <= 1, "balance power must be in [0, 1], got ", balance_power);
  ORCHARD_CHECK_OPTION(validation_fraction > 0 && validation_fraction < 1, "validation fraction must be in (0, 1), got ",
                       validation_fraction);
}

CounterTrainingResult TrainCounter(const std::vector<LabelledPatch>& patches, const CounterTrainingOptions& options,
                                   const nlohmann::json& data_description, const fs::path& model_path) {
  options.Check();
  if (patches.empty()) Fail("no training patches");
  std::vector<std::string> photo_ids;
  for (const LabelledPatch& p : patches) photo_ids.push_back(p.photo);
  const std::vector<std::string> chosen = ChooseTestPhotos(photo_ids, options.validation_fraction, options.split_seed);
  const std::set<std::string> val_photos(chosen.begin(), chosen.end());

  CounterTrainingResult result;
  result.train_class_counts.assign(kClasses, 0);
  std::vector<cv::Mat> train_images, val_images, train_originals;
  std::vector<int> train_labels, val_labels;
  std::vector<std::string> train_photos;
  for (const LabelledPatch& p : patches) {
    cv::Mat input = LetterboxPatch(p.bgr, options.input_size);
    if (val_photos.count(p.photo)) {
      val_images.push_back(input);
      val_labels.push_back(p.count);
    } else {
      train_images.push_back(input);
      train_labels.push_back(p.count);
      train_originals.push_back(p.bgr);
      train_photos.push_back(p.photo);
      ++result.train_class_counts[p.count];
    }
  }
  std::unique_ptr<CopyPasteSource> copy_paste;
  if (options.copy_paste.probability > 0) {
    copy_paste = std::make_unique<CopyPasteSource>(train_originals, train_labels, train_photos, options.copy_paste);
    if (copy_paste->empty()) Fail("copy-paste needs training photos with background and single-apple patches");
  }
  if (train_images.empty() || val_images.empty()) {
    Fail("training and validation each need patches from at least one photo: give patches from more photos");
  }
  result.train_patches = static_cast<int>(train_images.size());
  result.validation_patches = static_cast<int>(val_images.size());

  SetUpTorch(options.trainer);
  ResNet net(options.architecture);
  nlohmann::json header = {{"kind", "counter"},
                           {"architecture", options.architecture.ToJson()},
                           {"input_size", options.input_size},
                           {"data", data_description},
                           {"train_patches", result.train_patches},
                           {"validation_patches", result.validation_patches},
                           {"train_class_counts", result.train_class_counts},
                           {"copy_paste_probability", options.copy_paste.probability},
                           {"balance_power", options.balance_power},
                           {"ema_decay", options.trainer.ema_decay}};
  BestCheckpoint best(model_path);
  auto save_best = [&] { best.Save(*net, header); };
  CounterTask task(net, options, std::move(train_images), std::move(train_labels), std::move(val_images),
                   std::move(val_labels), copy_paste.get(), save_best);
  torch::optim::Adam adam(net->parameters(),
                          torch::optim::AdamOptions(options.learning_rate).betas(std::make_tuple(0.9, 0.999)));
  result.record = Train(task, *net, adam, options.trainer);
  header["training"] = result.record.ToJson();
  best.Finish(*net, header);
  return result;
}

}  // namespace orchard::nn
