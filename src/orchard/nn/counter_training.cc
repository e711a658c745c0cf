#include "orchard/nn/counter_training.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
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
// The density map's squared error against its target, relative to the count term.
constexpr double kDensityMapWeight = 10;

// Target density at the map's cells: a Gaussian of `sigma` cells around each
// centre (input pixels), each normalised to sum 1 so the map sums to the count.
torch::Tensor DensityTarget(const std::vector<cv::Point2f>& centres, int input_size, int64_t rows, int64_t cols,
                            double sigma) {
  torch::Tensor target = torch::zeros({1, rows, cols});
  const double stride_x = static_cast<double>(input_size) / cols, stride_y = static_cast<double>(input_size) / rows;
  auto t = target.accessor<float, 3>();
  for (const cv::Point2f& c : centres) {
    std::vector<double> w(rows * cols);
    double total = 0;
    for (int64_t i = 0; i < rows; ++i) {
      for (int64_t j = 0; j < cols; ++j) {
        const double dx = (c.x + 0.5) / stride_x - (j + 0.5), dy = (c.y + 0.5) / stride_y - (i + 0.5);
        total += w[i * cols + j] = std::exp(-(dx * dx + dy * dy) / (2 * sigma * sigma));
      }
    }
    if (total <= 0) continue;
    for (int64_t i = 0; i < rows; ++i) {
      for (int64_t j = 0; j < cols; ++j) t[0][i][j] += static_cast<float>(w[i * cols + j] / total);
    }
  }
  return target;
}

class CounterTask : public TrainingTask {
 public:
  CounterTask(ResNet net, const CounterTrainingOptions& options, std::vector<cv::Mat> train_images,
              std::vector<int> train_labels, std::vector<std::optional<std::vector<cv::Point2f>>> train_centres,
              std::vector<cv::Mat> val_images, std::vector<int> val_labels, const CopyPasteSource* copy_paste,
              std::function<void()> save_best)
      : net_(net),
        copy_paste_(copy_paste),
        options_(options),
        train_images_(std::move(train_images)),
        train_labels_(std::move(train_labels)),
        train_centres_(std::move(train_centres)),
        val_images_(std::move(val_images)),
        val_labels_(std::move(val_labels)),
        save_best_(std::move(save_best)) {
    balanced_ = BalancedIndices(train_labels_, options_.balance_power);
  }
  size_t NumTrain() const override { return balanced_.size(); }
  torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64& rng) override {
    const bool density = net_->options().density_head;
    std::vector<cv::Mat> images;
    std::vector<int64_t> labels;
    std::vector<std::optional<std::vector<cv::Point2f>>> centres;  // input pixels, where known
    for (size_t i : indices) {
      const size_t sample = balanced_[i];
      const int label = train_labels_[sample];
      std::optional<std::vector<cv::Point2f>> points;
      if (copy_paste_ && label >= 1 && Uniform01(rng) < options_.copy_paste.probability) {
        std::vector<cv::Point2f> pasted;
        const cv::Mat composite = copy_paste_->Compose(label, rng, density ? &pasted : nullptr);
        for (cv::Point2f& p : pasted) p = LetterboxPoint(composite.size(), options_.input_size, p);
        if (density) points = std::move(pasted);
        images.push_back(AugmentPatch(LetterboxPatch(composite, options_.input_size), options_.augmentation, rng,
                                      points ? &*points : nullptr));
      } else {
        if (density) points = train_centres_[sample];
        images.push_back(AugmentPatch(train_images_[sample], options_.augmentation, rng, points ? &*points : nullptr));
      }
      labels.push_back(label);
      centres.push_back(std::move(points));
    }
    const torch::Tensor input = ImagesToTensor(images), target = torch::tensor(labels, torch::kLong);
    if (!density) return torch::cross_entropy_loss(net_->forward(input), target);
    auto [logits, map] = net_->ForwardWithDensity(input);
    torch::Tensor loss = torch::cross_entropy_loss(logits, target);
    const torch::Tensor count_loss = torch::smooth_l1_loss(map.sum({1, 2, 3}), target.to(torch::kFloat32));
    std::vector<torch::Tensor> map_errors;
    for (size_t k = 0; k < centres.size(); ++k) {
      if (!centres[k]) continue;
      const torch::Tensor want =
          DensityTarget(*centres[k], options_.input_size, map.size(2), map.size(3), options_.density_sigma);
      map_errors.push_back((map[k] - want).pow(2).sum());
    }
    torch::Tensor density_loss = count_loss;
    if (!map_errors.empty()) density_loss = density_loss + kDensityMapWeight * torch::stack(map_errors).mean();
    return loss + options_.density_weight * density_loss;
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
  bool HasValidation() const override { return !val_images_.empty(); }

 private:
  ResNet net_;
  const CopyPasteSource* copy_paste_;  // null when copy-paste is off
  const CounterTrainingOptions& options_;
  std::vector<cv::Mat> train_images_;
  std::vector<int> train_labels_;
  std::vector<std::optional<std::vector<cv::Point2f>>> train_centres_;  // letterboxed, where known
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
    patches.push_back({ReadImage(path), entry.count, PatchPhotoId(entry.name), {}, false});
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
                       PhotoId(patch.image), patch.centres, true});
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
  ORCHARD_CHECK_OPTION(density_weight >= 0, "density weight must be >= 0, got ", density_weight);
  ORCHARD_CHECK_OPTION(density_sigma > 0, "density sigma must be positive, got ", density_sigma);
  ORCHARD_CHECK_OPTION(validation_fraction >= 0 && validation_fraction < 1,
                       "validation fraction must be in [0, 1), got ", validation_fraction);
}

CounterTrainingResult TrainCounter(const std::vector<LabelledPatch>& patches, const CounterTrainingOptions& options,
                                   const nlohmann::json& data_description, const fs::path& model_path) {
  options.Check();
  if (patches.empty()) Fail("no training patches");
  std::vector<std::string> photo_ids;
  for (const LabelledPatch& p : patches) photo_ids.push_back(p.photo);
  // A fraction of 0 chooses no photo: every patch trains.
  const std::vector<std::string> chosen = ChooseTestPhotos(photo_ids, options.validation_fraction, options.split_seed);
  const std::set<std::string> val_photos(chosen.begin(), chosen.end());

  CounterTrainingResult result;
  result.train_class_counts.assign(kClasses, 0);
  std::vector<cv::Mat> train_images, val_images, train_originals;
  std::vector<int> train_labels, val_labels;
  std::vector<std::optional<std::vector<cv::Point2f>>> train_centres;
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
      std::optional<std::vector<cv::Point2f>> centres;
      if (p.has_centres) {
        centres.emplace();
        for (const cv::Point2f& c : p.centres) centres->push_back(LetterboxPoint(p.bgr.size(), options.input_size, c));
      }
      train_centres.push_back(std::move(centres));
      ++result.train_class_counts[p.count];
    }
  }
  std::unique_ptr<CopyPasteSource> copy_paste;
  if (options.copy_paste.probability > 0) {
    copy_paste = std::make_unique<CopyPasteSource>(train_originals, train_labels, train_photos, options.copy_paste);
    if (copy_paste->empty()) Fail("copy-paste needs training photos with background and single-apple patches");
  }
  if (train_images.empty() || (options.validation_fraction > 0 && val_images.empty())) {
    Fail("training and validation each need patches from at least one photo: give patches from more photos");
  }
  result.train_patches = static_cast<int>(train_images.size());
  result.validation_patches = static_cast<int>(val_images.size());

  SetUpTorch(options.trainer);
  ResNetOptions architecture = options.architecture;
  architecture.density_head = options.density_weight > 0;
  ResNet net(architecture);
  nlohmann::json header = {{"kind", "counter"},
                           {"architecture", architecture.ToJson()},
                           {"input_size", options.input_size},
                           {"data", data_description},
                           {"train_patches", result.train_patches},
                           {"validation_patches", result.validation_patches},
                           {"train_class_counts", result.train_class_counts},
                           {"copy_paste_probability", options.copy_paste.probability},
                           {"balance_power", options.balance_power},
                           {"ema_decay", options.trainer.ema_decay}};
  if (architecture.density_head) {
    header["density_weight"] = options.density_weight;
    header["density_sigma"] = options.density_sigma;
  }
  BestCheckpoint best(model_path);
  auto save_best = [&] { best.Save(*net, header); };
  CounterTask task(net, options, std::move(train_images), std::move(train_labels), std::move(train_centres),
                   std::move(val_images), std::move(val_labels), copy_paste.get(), save_best);
  torch::optim::Adam adam(net->parameters(),
                          torch::optim::AdamOptions(options.learning_rate).betas(std::make_tuple(0.9, 0.999)));
  result.record = Train(task, *net, adam, options.trainer);
  header["training"] = result.record.ToJson();
  best.Finish(*net, header);
  return result;
}

}  // namespace orchard::nn
