#include "orchard/nn/retinanet.h"

#include <algorithm>
#include <cmath>

#include <opencv2/dnn.hpp>

#include "orchard/core/error.h"
#include "orchard/nn/losses.h"

namespace orchard::nn {
namespace {

namespace tnn = torch::nn;

constexpr int kLevels = 3;          // P3, P4, P5
constexpr int kFirstStride = 8;     // P3's
constexpr double kPriorProbability = 0.01;  // initial apple probability of every anchor (the paper's)
// Delta weights of the box encoding (x, y, w, h), as torchvision's RetinaNet.
constexpr double kCentreWeight = 10, kSizeWeight = 5;
// Decoded log size ratios are clamped here so a wild delta cannot overflow exp().
const double kMaxLogRatio = std::log(1000.0 / 16);

tnn::Sequential Subnet(int channels, int convs, int outputs, double bias) {
  tnn::Sequential seq;
  for (int i = 0; i < convs; ++i) {
    seq->push_back(tnn::Conv2d(tnn::Conv2dOptions(channels, channels, 3).padding(1)));
    seq->push_back(tnn::ReLU(tnn::ReLUOptions(true)));
  }
  tnn::Conv2d out(tnn::Conv2dOptions(channels, outputs, 3).padding(1));
  tnn::init::normal_(out->weight, 0, 0.01);
  tnn::init::constant_(out->bias, bias);
  seq->push_back(out);
  return seq;
}

// [N, A*K, H, W] -> [N, H*W*A, K]: the order of Anchors() (row, column, anchor).
torch::Tensor Flatten(const torch::Tensor& x, int k) {
  return x.permute({0, 2, 3, 1}).reshape({x.size(0), -1, k});
}

int LevelSize(int side, int level) { return side / (kFirstStride << level); }

}  // namespace

void RetinaNetOptions::Check() const {
  ResNetOptions{depth, base_width, 3, 0}.Check();
  ORCHARD_CHECK_OPTION(fpn_channels >= 4 && fpn_channels <= 512, "FPN channels must be in [4, 512], got ", fpn_channels);
  ORCHARD_CHECK_OPTION(head_convs >= 0 && head_convs <= 8, "head convolutions must be in [0, 8], got ", head_convs);
  ORCHARD_CHECK_OPTION(anchor_sizes.size() == kLevels, "give one anchor size per level (P3, P4, P5), got ",
                       anchor_sizes.size());
  for (double s : anchor_sizes) ORCHARD_CHECK_OPTION(s > 0, "anchor sizes must be positive, got ", s);
  ORCHARD_CHECK_OPTION(scales_per_octave >= 1 && scales_per_octave <= 4, "scales per octave must be in [1, 4], got ",
                       scales_per_octave);
  ORCHARD_CHECK_OPTION(!aspect_ratios.empty(), "give at least one aspect ratio");
  for (double r : aspect_ratios) ORCHARD_CHECK_OPTION(r > 0, "aspect ratios must be positive, got ", r);
}

nlohmann::json RetinaNetOptions::ToJson() const {
  return {{"depth", depth},
          {"base_width", base_width},
          {"fpn_channels", fpn_channels},
          {"head_convs", head_convs},
          {"anchor_sizes", anchor_sizes},
          {"scales_per_octave", scales_per_octave},
          {"aspect_ratios", aspect_ratios}};
}

RetinaNetOptions RetinaNetOptions::FromJson(const nlohmann::json& json) {
  RetinaNetOptions o;
  o.depth = json.at("depth").get<int>();
  o.base_width = json.at("base_width").get<int>();
  o.fpn_channels = json.at("fpn_channels").get<int>();
  o.head_convs = json.at("head_convs").get<int>();
  o.anchor_sizes = json.at("anchor_sizes").get<std::vector<double>>();
  o.scales_per_octave = json.at("scales_per_octave").get<int>();
  o.aspect_ratios = json.at("aspect_ratios").get<std::vector<double>>();
  o.Check();
  return o;
}

RetinaNetImpl::RetinaNetImpl(const RetinaNetOptions& options) : options_(options) {
  options_.Check();
  backbone_ = register_module("backbone", ResNet(ResNetOptions{options_.depth, options_.base_width, 3, 0}));
  const std::vector<int> channels = backbone_->StageChannels();
  const int c = options_.fpn_channels;
  for (int l = 0; l < kLevels; ++l) {
    // Stages 2..4 (C3..C5): 1x1 lateral connections, 3x3 output convolutions.
    lateral_.push_back(register_module("lateral" + std::to_string(l), tnn::Conv2d(tnn::Conv2dOptions(channels[l + 1], c, 1))));
    output_.push_back(
        register_module("output" + std::to_string(l), tnn::Conv2d(tnn::Conv2dOptions(c, c, 3).padding(1))));
  }
  const int a = options_.AnchorsPerCell();
  class_subnet_ = register_module(
      "class_subnet", Subnet(c, options_.head_convs, a, -std::log((1 - kPriorProbability) / kPriorProbability)));
  box_subnet_ = register_module("box_subnet", Subnet(c, options_.head_convs, 4 * a, 0));
}

std::pair<torch::Tensor, torch::Tensor> RetinaNetImpl::forward(torch::Tensor x) {
  if (x.size(2) % RetinaNetOptions::kInputMultiple != 0 || x.size(3) % RetinaNetOptions::kInputMultiple != 0) {
    Fail("RetinaNet input sides must be multiples of ", RetinaNetOptions::kInputMultiple, ", got ", x.size(2), "x",
         x.size(3));
  }
  const std::vector<torch::Tensor> stages = backbone_->ForwardStages(x);
  // Top-down pathway: each level adds the upsampled coarser one.
  std::vector<torch::Tensor> pyramid(kLevels);
  torch::Tensor top;
  for (int l = kLevels - 1; l >= 0; --l) {
    torch::Tensor lateral = lateral_[l]->forward(stages[l + 1]);
    if (top.defined()) {
      lateral = lateral + torch::nn::functional::interpolate(
                              top, torch::nn::functional::InterpolateFuncOptions()
                                       .size(std::vector<int64_t>{lateral.size(2), lateral.size(3)})
                                       .mode(torch::kNearest));
    }
    top = lateral;
    pyramid[l] = output_[l]->forward(lateral);
  }
  std::vector<torch::Tensor> logits, deltas;
  for (const torch::Tensor& p : pyramid) {
    logits.push_back(Flatten(class_subnet_->forward(p), 1));
    deltas.push_back(Flatten(box_subnet_->forward(p), 4));
  }
  return {torch::cat(logits, 1).squeeze(2), torch::cat(deltas, 1)};
}

torch::Tensor RetinaNetImpl::Anchors(int height, int width) const {
  std::vector<float> values;
  for (int l = 0; l < kLevels; ++l) {
    const int stride = kFirstStride << l;
    // Shapes of this level's anchors: scales x aspect ratios, centred on the cell.
    std::vector<std::pair<double, double>> shapes;
    for (int s = 0; s < options_.scales_per_octave; ++s) {
      const double size = options_.anchor_sizes[l] * std::pow(2.0, static_cast<double>(s) / options_.scales_per_octave);
      for (double ratio : options_.aspect_ratios) shapes.emplace_back(size / std::sqrt(ratio), size * std::sqrt(ratio));
    }
    for (int y = 0; y < LevelSize(height, l); ++y) {
      for (int x = 0; x < LevelSize(width, l); ++x) {
        const double cx = (x + 0.5) * stride, cy = (y + 0.5) * stride;
        for (const auto& [w, h] : shapes) {
          values.insert(values.end(), {static_cast<float>(cx - w / 2), static_cast<float>(cy - h / 2),
                                       static_cast<float>(cx + w / 2), static_cast<float>(cy + h / 2)});
        }
      }
    }
  }
  return torch::tensor(values).reshape({-1, 4});
}

torch::Tensor EncodeBoxes(const torch::Tensor& boxes, const torch::Tensor& anchors) {
  const torch::Tensor aw = anchors.select(1, 2) - anchors.select(1, 0), ah = anchors.select(1, 3) - anchors.select(1, 1);
  const torch::Tensor ax = anchors.select(1, 0) + 0.5 * aw, ay = anchors.select(1, 1) + 0.5 * ah;
  const torch::Tensor bw = (boxes.select(1, 2) - boxes.select(1, 0)).clamp_min(1e-3);
  const torch::Tensor bh = (boxes.select(1, 3) - boxes.select(1, 1)).clamp_min(1e-3);
  const torch::Tensor bx = boxes.select(1, 0) + 0.5 * bw, by = boxes.select(1, 1) + 0.5 * bh;
  return torch::stack({kCentreWeight * (bx - ax) / aw, kCentreWeight * (by - ay) / ah,
                       kSizeWeight * torch::log(bw / aw), kSizeWeight * torch::log(bh / ah)},
                      1);
}

torch::Tensor DecodeBoxes(const torch::Tensor& deltas, const torch::Tensor& anchors) {
  const torch::Tensor aw = anchors.select(1, 2) - anchors.select(1, 0), ah = anchors.select(1, 3) - anchors.select(1, 1);
  const torch::Tensor ax = anchors.select(1, 0) + 0.5 * aw, ay = anchors.select(1, 1) + 0.5 * ah;
  const torch::Tensor cx = ax + deltas.select(1, 0) / kCentreWeight * aw;
  const torch::Tensor cy = ay + deltas.select(1, 1) / kCentreWeight * ah;
  const torch::Tensor w = aw * torch::exp((deltas.select(1, 2) / kSizeWeight).clamp_max(kMaxLogRatio));
  const torch::Tensor h = ah * torch::exp((deltas.select(1, 3) / kSizeWeight).clamp_max(kMaxLogRatio));
  return torch::stack({cx - 0.5 * w, cy - 0.5 * h, cx + 0.5 * w, cy + 0.5 * h}, 1);
}

torch::Tensor BoxIoU(const torch::Tensor& a, const torch::Tensor& b) {
  const torch::Tensor area_a = (a.select(1, 2) - a.select(1, 0)) * (a.select(1, 3) - a.select(1, 1));
  const torch::Tensor area_b = (b.select(1, 2) - b.select(1, 0)) * (b.select(1, 3) - b.select(1, 1));
  const torch::Tensor x1 = torch::max(a.select(1, 0).unsqueeze(1), b.select(1, 0).unsqueeze(0));
  const torch::Tensor y1 = torch::max(a.select(1, 1).unsqueeze(1), b.select(1, 1).unsqueeze(0));
  const torch::Tensor x2 = torch::min(a.select(1, 2).unsqueeze(1), b.select(1, 2).unsqueeze(0));
  const torch::Tensor y2 = torch::min(a.select(1, 3).unsqueeze(1), b.select(1, 3).unsqueeze(0));
  const torch::Tensor inter = (x2 - x1).clamp_min(0) * (y2 - y1).clamp_min(0);
  return inter / (area_a.unsqueeze(1) + area_b.unsqueeze(0) - inter).clamp_min(1e-9);
}

namespace {

torch::Tensor BoxesToTensor(const std::vector<Box>& boxes) {
  std::vector<float> values;
  for (const Box& b : boxes) {
    values.insert(values.end(), {static_cast<float>(b.x1), static_cast<float>(b.y1), static_cast<float>(b.x2),
                                 static_cast<float>(b.y2)});
  }
  return torch::tensor(values).reshape({-1, 4});
}

}  // namespace

AnchorTargets MatchAnchors(const torch::Tensor& anchors, const std::vector<Box>& boxes, const std::vector<Box>& ignore,
                           const AnchorMatching& matching) {
  const int64_t n = anchors.size(0);
  AnchorTargets targets{torch::zeros({n}), torch::zeros({n, 4})};
  if (!ignore.empty()) {
    const torch::Tensor overlap = std::get<0>(BoxIoU(anchors, BoxesToTensor(ignore)).max(1));
    targets.labels.masked_fill_(overlap >= matching.negative_iou, -1);
  }
  if (boxes.empty()) return targets;
  const torch::Tensor gt = BoxesToTensor(boxes);
  const torch::Tensor iou = BoxIoU(anchors, gt);  // [A, B]
  auto [best_iou, best_box] = iou.max(1);
  targets.labels.masked_fill_((best_iou >= matching.negative_iou) & (best_iou < matching.positive_iou), -1);
  torch::Tensor positive = best_iou >= matching.positive_iou;
  // Each box's best anchor is an apple too, matched to that box.
  const torch::Tensor best_anchor = std::get<1>(iou.max(0));  // [B]
  best_box.index_put_({best_anchor}, torch::arange(static_cast<int64_t>(boxes.size())));
  positive.index_put_({best_anchor}, true);
  targets.labels.masked_fill_(positive, 1);
  targets.boxes = gt.index_select(0, best_box);
  return targets;
}

torch::Tensor RetinaNetLoss(const torch::Tensor& logits, const torch::Tensor& deltas, const torch::Tensor& anchors,
                            const std::vector<AnchorTargets>& targets) {
  std::vector<torch::Tensor> labels_per_image, boxes_per_image;
  for (const AnchorTargets& t : targets) {
    labels_per_image.push_back(t.labels);
    boxes_per_image.push_back(t.boxes);
  }
  const torch::Tensor labels = torch::stack(labels_per_image);  // [N, A]
  const torch::Tensor valid = labels >= 0, positive = labels > 0;
  const double positives = std::max<double>(1, positive.sum().item<double>());
  const torch::Tensor loss = SigmoidFocalLoss(logits.masked_select(valid), labels.masked_select(valid));
  // The positives of every image at once: [P, 4] deltas, boxes and anchors.
  const torch::Tensor target = EncodeBoxes(torch::stack(boxes_per_image).index({positive}),
                                           anchors.expand({labels.size(0), -1, -1}).index({positive}));
  const torch::Tensor box_loss = (deltas.index({positive}) - target).abs().sum();
  return (loss + box_loss) / positives;
}

std::vector<ScoredApple> DecodeDetections(const torch::Tensor& logits, const torch::Tensor& deltas,
                                          const torch::Tensor& anchors, const RetinaNetOptions& architecture,
                                          cv::Size input, cv::Size image, const DecodeOptions& options) {
  if (input.width % RetinaNetOptions::kInputMultiple != 0 || input.height % RetinaNetOptions::kInputMultiple != 0) {
    Fail("internal: RetinaNet input sides must be multiples of ", RetinaNetOptions::kInputMultiple);
  }
  const int width = image.width, height = image.height;
  const torch::Tensor scores = torch::sigmoid(logits.detach().to(torch::kFloat32));
  const torch::Tensor box_deltas = deltas.detach().to(torch::kFloat32);
  std::vector<cv::Rect2d> rects;
  std::vector<float> kept_scores;
  // Each level's anchors are a contiguous run (RetinaNetImpl::Anchors).
  std::vector<int64_t> counts;
  for (int l = 0; l < kLevels; ++l) {
    counts.push_back(static_cast<int64_t>(LevelSize(input.height, l)) * LevelSize(input.width, l) *
                     architecture.AnchorsPerCell());
  }
  const int64_t total = counts[0] + counts[1] + counts[2];
  if (total != anchors.size(0) || total != logits.size(0) || total != deltas.size(0)) {
    Fail("internal: ", logits.size(0), " outputs and ", anchors.size(0), " anchors for a ", input.width, "x",
         input.height, " input, which has ", total);
  }
  int64_t begin = 0;
  for (int l = 0; l < kLevels; ++l) {
    const int64_t count = counts[l];
    if (count == 0) continue;
    const torch::Tensor level = scores.slice(0, begin, begin + count);
    auto [top, index] = level.topk(std::min<int64_t>(count, options.candidates_per_level));
    const torch::Tensor keep = top >= options.score_threshold;
    top = top.masked_select(keep);
    index = index.masked_select(keep) + begin;
    begin += count;
    if (index.numel() == 0) continue;
    const torch::Tensor boxes =
        DecodeBoxes(box_deltas.index_select(0, index), anchors.index_select(0, index));
    const auto b = boxes.accessor<float, 2>();
    const auto s = top.accessor<float, 1>();
    for (int64_t i = 0; i < boxes.size(0); ++i) {
      const double x1 = std::clamp<double>(b[i][0], 0, width), y1 = std::clamp<double>(b[i][1], 0, height);
      const double x2 = std::clamp<double>(b[i][2], 0, width), y2 = std::clamp<double>(b[i][3], 0, height);
      if (x2 - x1 < 1 || y2 - y1 < 1) continue;
      rects.emplace_back(x1, y1, x2 - x1, y2 - y1);
      kept_scores.push_back(s[i]);
    }
  }
  std::vector<int> indices;
  cv::dnn::NMSBoxes(rects, kept_scores, static_cast<float>(options.score_threshold),
                    static_cast<float>(options.nms_iou), indices, 1.f, options.max_detections);
  std::vector<ScoredApple> detections;
  for (int i : indices) {
    const cv::Rect2d& r = rects[i];
    detections.push_back({Box{r.x, r.y, r.x + r.width, r.y + r.height}, kept_scores[i]});
  }
  std::stable_sort(detections.begin(), detections.end(),
                   [](const ScoredApple& a, const ScoredApple& b) { return a.score > b.score; });
  return detections;
}

}  // namespace orchard::nn
