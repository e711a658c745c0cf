#include "orchard/nn/detection_training.h"

#include <algorithm>
#include <set>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/split.h"
#include "orchard/eval/detection_metrics.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/patch_input.h"

namespace orchard::nn {
namespace {

int RoundUp(int value, int multiple) { return (value + multiple - 1) / multiple * multiple; }

// A random tile of one image at a random scale, flipped half the time, with
// the boxes it holds: apples, and those to ignore (too small, or cut).
struct Tile {
  cv::Mat bgr;
  std::vector<Box> boxes, ignore;
};

Tile CutTile(const BoxSample& sample, const RetinaNetTrainingOptions& options, std::mt19937_64& rng) {
  const double scale = std::uniform_real_distribution<double>(options.min_scale, options.max_scale)(rng);
  cv::Mat scaled;
  cv::resize(sample.bgr, scaled, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  const int t = options.tile;
  // Tiles may reach past a small image; the rest is zero-padded.
  const int x0 = scaled.cols > t ? static_cast<int>(rng() % static_cast<uint64_t>(scaled.cols - t + 1)) : 0;
  const int y0 = scaled.rows > t ? static_cast<int>(rng() % static_cast<uint64_t>(scaled.rows - t + 1)) : 0;
  const cv::Rect inside = cv::Rect(x0, y0, t, t) & cv::Rect(0, 0, scaled.cols, scaled.rows);
  Tile tile;
  tile.bgr = cv::Mat(t, t, CV_8UC3, cv::Scalar::all(0));
  scaled(inside).copyTo(tile.bgr(cv::Rect(0, 0, inside.width, inside.height)));
  const Box frame{0, 0, static_cast<double>(inside.width), static_cast<double>(inside.height)};
  const bool flip = rng() & 1;
  if (flip) cv::flip(tile.bgr, tile.bgr, 1);
  for (const Box& b : sample.boxes) {
    const Box moved{b.x1 * scale - x0, b.y1 * scale - y0, b.x2 * scale - x0, b.y2 * scale - y0};
    const double inter = IntersectionArea(moved, frame);
    if (inter <= 0) continue;
    Box clipped{std::max(moved.x1, 0.0), std::max(moved.y1, 0.0), std::min(moved.x2, frame.x2),
                std::min(moved.y2, frame.y2)};
    if (flip) clipped = {t - clipped.x2, clipped.y1, t - clipped.x1, clipped.y2};
    const bool small = std::min(moved.Width(), moved.Height()) < options.min_box_side;
    const bool cut = inter < options.min_visible * moved.Area();
    (small || cut ? tile.ignore : tile.boxes).push_back(clipped);
  }
  return tile;
}

class DetectionTask : public TrainingTask {
 public:
  DetectionTask(RetinaNet net, const std::vector<BoxSample>& samples, std::vector<int> train, std::vector<int> val,
                const RetinaNetTrainingOptions& options, std::function<void()> save_best)
      : net_(net),
        samples_(samples),
        train_(std::move(train)),
        val_(std::move(val)),
        options_(options),
        save_best_(std::move(save_best)),
        anchors_(net->Anchors(options.tile, options.tile)) {}

  size_t NumTrain() const override { return train_.size(); }

  torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64& rng) override {
    std::vector<cv::Mat> images;
    std::vector<AnchorTargets> targets;
    for (size_t i : indices) {
      Tile tile = CutTile(samples_[train_[i]], options_, rng);
      targets.push_back(MatchAnchors(anchors_, tile.boxes, tile.ignore, options_.matching));
      images.push_back(tile.bgr);
    }
    auto [logits, deltas] = net_->forward(ImagesToTensor(images));
    return RetinaNetLoss(logits, deltas, anchors_, targets);
  }

  // COCO AP50 over the whole validation images.
  double Validate() override {
    Dataset truth;
    Predictions predictions;
    for (int i : val_) {
      const BoxSample& s = samples_[i];
      AnnotatedImage image;
      // Datasets may repeat a file name (two sides' frame_0000.png): number them.
      image.name = std::to_string(i) + "/" + s.name;
      image.id = static_cast<int64_t>(truth.images.size()) + 1;
      image.width = s.bgr.cols;
      image.height = s.bgr.rows;
      for (const Box& b : s.boxes) {
        Annotation object;
        object.box = b;
        image.objects.push_back(object);
      }
      truth.images.push_back(image);
      std::vector<ScoredBox>& found = predictions[image.name];
      for (const ScoredApple& a : DetectApples(net_, s.bgr, DecodeOptions{})) found.push_back({a.box, a.score});
    }
    return EvaluateDetections(truth, predictions).coco.ap50;
  }

  std::string MetricName() const override { return "val_ap50"; }
  void SaveBest() override { save_best_(); }
  bool HasValidation() const override { return !val_.empty(); }

 private:
  RetinaNet net_;
  const std::vector<BoxSample>& samples_;
  std::vector<int> train_, val_;
  RetinaNetTrainingOptions options_;
  std::function<void()> save_best_;
  torch::Tensor anchors_;
};

}  // namespace

std::vector<BoxSample> LoadBoxSamples(const Dataset& dataset) {
  std::vector<BoxSample> samples;
  for (const AnnotatedImage& image : dataset.images) {
    if (image.path.empty()) Fail("no image file for ", image.name, ": give the images folder");
    BoxSample sample;
    sample.name = image.name;
    sample.bgr = ReadImage(image.path);
    sample.photo = PhotoId(image.name);
    for (const Annotation& object : image.objects) {
      if (object.box.Width() >= 1 && object.box.Height() >= 1) sample.boxes.push_back(object.box);
    }
    samples.push_back(std::move(sample));
  }
  return samples;
}

void RetinaNetTrainingOptions::Check() const {
  architecture.Check();
  trainer.Check();
  ORCHARD_CHECK_OPTION(tile >= 64 && tile % RetinaNetOptions::kInputMultiple == 0,
                       "tile must be >= 64 and a multiple of 32, got ", tile);
  ORCHARD_CHECK_OPTION(min_scale > 0 && min_scale <= max_scale, "need 0 < min scale <= max scale, got ", min_scale,
                       " and ", max_scale);
  ORCHARD_CHECK_OPTION(min_box_side >= 0, "min box side must be >= 0, got ", min_box_side);
  ORCHARD_CHECK_OPTION(min_visible > 0 && min_visible <= 1, "min visible must be in (0, 1], got ", min_visible);
  ORCHARD_CHECK_OPTION(matching.negative_iou > 0 && matching.negative_iou <= matching.positive_iou &&
                           matching.positive_iou <= 1,
                       "need 0 < negative IoU <= positive IoU <= 1");
  ORCHARD_CHECK_OPTION(learning_rate > 0, "learning rate must be positive, got ", learning_rate);
  ORCHARD_CHECK_OPTION(validation_fraction >= 0 && validation_fraction < 1,
                       "validation fraction must be in [0, 1), got ", validation_fraction);
  ORCHARD_CHECK_OPTION(max_validation_images >= 1, "max validation images must be positive, got ",
                       max_validation_images);
}

std::vector<ScoredApple> DetectApples(RetinaNet& net, const cv::Mat& bgr, const DecodeOptions& options) {
  if (bgr.empty()) Fail("empty frame");
  if (bgr.type() != CV_8UC3) Fail("frame must be 8-bit BGR");
  torch::NoGradGuard no_grad;
  const int m = RetinaNetOptions::kInputMultiple;
  const int height = RoundUp(bgr.rows, m), width = RoundUp(bgr.cols, m);
  cv::Mat padded;
  cv::copyMakeBorder(bgr, padded, 0, height - bgr.rows, 0, width - bgr.cols, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  auto [logits, deltas] = net->forward(ImagesToTensor({padded}));
  return DecodeDetections(logits[0], deltas[0], net->Anchors(height, width), net->options(), cv::Size(width, height),
                          bgr.size(), options);
}

RetinaNetTrainingResult TrainRetinaNet(const std::vector<BoxSample>& samples, const RetinaNetTrainingOptions& options,
                                       const nlohmann::json& data_description, const fs::path& model_path) {
  options.Check();
  if (samples.empty()) Fail("no training images");
  std::vector<std::string> photo_ids;
  for (const BoxSample& s : samples) photo_ids.push_back(s.photo);
  std::set<std::string> val_photos;
  if (options.validation_fraction > 0) {
    const std::vector<std::string> chosen = ChooseTestPhotos(photo_ids, options.validation_fraction, options.split_seed);
    val_photos.insert(chosen.begin(), chosen.end());
  }
  std::vector<int> train, val;
  RetinaNetTrainingResult result;
  for (int i = 0; i < static_cast<int>(samples.size()); ++i) {
    if (val_photos.count(samples[i].photo)) {
      val.push_back(i);
    } else {
      train.push_back(i);
      result.train_boxes += static_cast<int>(samples[i].boxes.size());
    }
  }
  if (train.empty()) Fail("no training images left after holding out validation photos: give more photos");
  if (options.validation_fraction > 0 && val.empty()) {
    Fail("validation needs at least one photo: give images from more photos, or --val-fraction 0");
  }
  // A fixed, evenly spread subset of validation images keeps validation cheap.
  if (static_cast<int>(val.size()) > options.max_validation_images) {
    std::vector<int> subset;
    for (int k = 0; k < options.max_validation_images; ++k) subset.push_back(val[k * val.size() / options.max_validation_images]);
    val = subset;
  }
  result.train_images = static_cast<int>(train.size());
  result.validation_images = static_cast<int>(val.size());

  SetUpTorch(options.trainer);
  RetinaNet net(options.architecture);
  nlohmann::json header = {{"kind", "retinanet"},
                           {"architecture", options.architecture.ToJson()},
                           {"tile", options.tile},
                           {"scale_range", {options.min_scale, options.max_scale}},
                           {"data", data_description},
                           {"train_images", result.train_images},
                           {"validation_images", result.validation_images},
                           {"train_boxes", result.train_boxes}};
  BestCheckpoint best(model_path);
  DetectionTask task(net, samples, std::move(train), std::move(val), options, [&] { best.Save(*net, header); });
  torch::optim::Adam optimizer(net->parameters(), torch::optim::AdamOptions(options.learning_rate));
  result.record = Train(task, *net, optimizer, options.trainer);
  header["training"] = result.record.ToJson();
  best.Finish(*net, header);
  return result;
}

}  // namespace orchard::nn
