#include "orchard/nn/segmentation_training.h"

#include <algorithm>
#include <set>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/split.h"
#include "orchard/nn/adadelta.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/losses.h"
#include "orchard/nn/patch_input.h"

namespace orchard::nn {
namespace {

struct Tile {
  int sample;
  cv::Rect rect;
};

// Tile origins along one axis: every `stride` pixels, plus one flush with the far edge.
std::vector<int> TileOrigins(int length, int tile, int stride) {
  std::vector<int> origins;
  if (length <= tile) return {0};
  for (int x = 0; x + tile <= length; x += stride) origins.push_back(x);
  if (origins.back() + tile < length) origins.push_back(length - tile);
  return origins;
}

// An image smaller than a tile is zero-padded (mask: background).
void PadToTile(SegmentationSample* sample, int tile) {
  const int pad_x = std::max(0, tile - sample->bgr.cols), pad_y = std::max(0, tile - sample->bgr.rows);
  if (pad_x == 0 && pad_y == 0) return;
  cv::copyMakeBorder(sample->bgr, sample->bgr, 0, pad_y, 0, pad_x, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  cv::copyMakeBorder(sample->mask, sample->mask, 0, pad_y, 0, pad_x, cv::BORDER_CONSTANT, cv::Scalar::all(0));
}

class SegmentationTask : public TrainingTask {
 public:
  SegmentationTask(UNet net, std::vector<SegmentationSample> samples, std::vector<Tile> train, std::vector<Tile> val,
                   std::vector<double> weights, std::function<void()> save_best)
      : net_(net),
        samples_(std::move(samples)),
        train_(std::move(train)),
        val_(std::move(val)),
        weights_(std::move(weights)),
        save_best_(std::move(save_best)) {}

  size_t NumTrain() const override { return train_.size(); }

  torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64& rng) override {
    std::vector<cv::Mat> images, masks;
    for (size_t i : indices) {
      cv::Mat image = samples_[train_[i].sample].bgr(train_[i].rect).clone();
      cv::Mat mask = samples_[train_[i].sample].mask(train_[i].rect).clone();
      if (rng() & 1) {
        cv::flip(image, image, 1);
        cv::flip(mask, mask, 1);
      }
      images.push_back(image);
      masks.push_back(mask);
    }
    return WeightedCrossEntropy(net_->forward(ImagesToTensor(images)), MasksToTensor(masks), weights_);
  }

  // Apple IoU over all validation tiles (pooled intersection over pooled union).
  double Validate() override {
    int64_t intersection = 0, union_ = 0;
    for (size_t begin = 0; begin < val_.size(); begin += 8) {
      const size_t end = std::min(val_.size(), begin + 8);
      std::vector<cv::Mat> images, masks;
      for (size_t i = begin; i < end; ++i) {
        images.push_back(samples_[val_[i].sample].bgr(val_[i].rect).clone());
        masks.push_back(samples_[val_[i].sample].mask(val_[i].rect).clone());
      }
      const torch::Tensor predicted = net_->forward(ImagesToTensor(images)).argmax(1).eq(1);
      const torch::Tensor truth = MasksToTensor(masks).eq(1);
      intersection += (predicted & truth).sum().item<int64_t>();
      union_ += (predicted | truth).sum().item<int64_t>();
    }
    return union_ > 0 ? static_cast<double>(intersection) / union_ : 1.0;
  }

  std::string MetricName() const override { return "val_apple_iou"; }
  void SaveBest() override { save_best_(); }

 private:
  static torch::Tensor MasksToTensor(const std::vector<cv::Mat>& masks) {
    const int h = masks[0].rows, w = masks[0].cols;
    torch::Tensor t = torch::empty({static_cast<int64_t>(masks.size()), h, w}, torch::kUInt8);
    for (size_t i = 0; i < masks.size(); ++i) {
      cv::Mat m = masks[i].isContinuous() ? masks[i] : masks[i].clone();
      std::memcpy(t[i].data_ptr(), m.data, static_cast<size_t>(h) * w);
    }
    return t.to(torch::kLong);
  }

  UNet net_;
  std::vector<SegmentationSample> samples_;
  std::vector<Tile> train_, val_;
  std::vector<double> weights_;
  std::function<void()> save_best_;
};

}  // namespace

std::vector<SegmentationSample> LoadSegmentationSamples(const Dataset& dataset) {
  std::vector<SegmentationSample> samples;
  for (const AnnotatedImage& image : dataset.images) {
    if (image.path.empty()) Fail("no image file for ", image.name, ": give the images folder");
    SegmentationSample sample;
    sample.bgr = ReadImage(image.path);
    sample.photo = PhotoId(image.name);
    sample.mask = cv::Mat1b::zeros(sample.bgr.size());
    if (dataset.has_masks) {
      // MinneApple layout: <root>/images/<name> beside <root>/masks/<stem>.png.
      const fs::path mask_path = image.path.parent_path().parent_path() / "masks" / (image.path.stem().string() + ".png");
      const cv::Mat ids = ReadInstanceMask(mask_path);
      if (ids.size() != sample.bgr.size()) Fail("mask ", mask_path.string(), " and its image differ in size");
      sample.mask.setTo(1, ids != 0);
    } else {
      for (const Annotation& object : image.objects) {
        const Box& b = object.box;
        if (b.Width() < 1 || b.Height() < 1) continue;
        cv::ellipse(sample.mask, cv::RotatedRect(cv::Point2f(b.CenterX(), b.CenterY()),
                                                 cv::Size2f(b.Width(), b.Height()), 0),
                    cv::Scalar(1), cv::FILLED);
      }
    }
    samples.push_back(std::move(sample));
  }
  return samples;
}

void UNetTrainingOptions::Check() const {
  architecture.Check();
  trainer.Check();
  ORCHARD_CHECK_OPTION(architecture.num_classes == 2, "the U-Net segments 2 classes, got ", architecture.num_classes);
  ORCHARD_CHECK_OPTION(tile >= 32 && tile % architecture.InputMultiple() == 0, "tile must be >= 32 and a multiple of ",
                       architecture.InputMultiple(), ", got ", tile);
  ORCHARD_CHECK_OPTION(stride >= 1, "stride must be positive, got ", stride);
  ORCHARD_CHECK_OPTION(learning_rate > 0, "learning rate must be positive, got ", learning_rate);
  ORCHARD_CHECK_OPTION(validation_fraction > 0 && validation_fraction < 1, "validation fraction must be in (0, 1), got ",
                       validation_fraction);
  ORCHARD_CHECK_OPTION(max_validation_tiles >= 1, "max validation tiles must be positive, got ", max_validation_tiles);
}

UNetTrainingResult TrainUNet(const std::vector<SegmentationSample>& input, const UNetTrainingOptions& options,
                             const nlohmann::json& data_description, const fs::path& model_path) {
  options.Check();
  if (input.empty()) Fail("no training images");
  std::vector<SegmentationSample> samples = input;
  std::vector<std::string> photo_ids;
  for (SegmentationSample& s : samples) {
    PadToTile(&s, options.tile);
    photo_ids.push_back(s.photo);
  }
  const std::vector<std::string> chosen = ChooseTestPhotos(photo_ids, options.validation_fraction, options.split_seed);
  const std::set<std::string> val_photos(chosen.begin(), chosen.end());

  std::vector<Tile> train, val;
  std::vector<int64_t> class_counts(2, 0);
  for (int i = 0; i < static_cast<int>(samples.size()); ++i) {
    const SegmentationSample& s = samples[i];
    if (val_photos.count(s.photo)) {
      for (int y : TileOrigins(s.bgr.rows, options.tile, options.tile)) {
        for (int x : TileOrigins(s.bgr.cols, options.tile, options.tile)) {
          val.push_back({i, cv::Rect(x, y, options.tile, options.tile)});
        }
      }
    } else {
      const int apple = cv::countNonZero(s.mask);
      class_counts[1] += apple;
      class_counts[0] += static_cast<int64_t>(s.mask.total()) - apple;
      for (int y : TileOrigins(s.bgr.rows, options.tile, options.stride)) {
        for (int x : TileOrigins(s.bgr.cols, options.tile, options.stride)) {
          train.push_back({i, cv::Rect(x, y, options.tile, options.tile)});
        }
      }
    }
  }
  if (train.empty() || val.empty()) {
    Fail("training and validation each need at least one photo: give images from more photos");
  }
  // A fixed, evenly spread subset of validation tiles keeps validation cheap.
  if (static_cast<int>(val.size()) > options.max_validation_tiles) {
    std::vector<Tile> subset;
    for (int k = 0; k < options.max_validation_tiles; ++k) subset.push_back(val[k * val.size() / options.max_validation_tiles]);
    val = subset;
  }

  UNetTrainingResult result;
  result.train_tiles = static_cast<int>(train.size());
  result.validation_tiles = static_cast<int>(val.size());
  result.class_weights = InverseFrequencyWeights(class_counts);

  SetUpTorch(options.trainer);
  UNet net(options.architecture);
  nlohmann::json header = {{"kind", "unet"},
                           {"architecture", options.architecture.ToJson()},
                           {"tile", options.tile},
                           {"stride", options.stride},
                           {"data", data_description},
                           {"train_tiles", result.train_tiles},
                           {"validation_tiles", result.validation_tiles},
                           {"class_weights", result.class_weights}};
  BestCheckpoint best(model_path);
  SegmentationTask task(net, std::move(samples), std::move(train), std::move(val), result.class_weights,
                        [&] { best.Save(*net, header); });
  Adadelta optimizer(net->parameters(), AdadeltaOptions(options.learning_rate));
  result.record = Train(task, *net, optimizer, options.trainer);
  header["training"] = result.record.ToJson();
  best.Finish(*net, header);
  return result;
}

}  // namespace orchard::nn
