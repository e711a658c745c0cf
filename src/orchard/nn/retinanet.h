// A one-stage box detector in the style of RetinaNet (Lin et al. 2017): a
// ResNet backbone, a feature pyramid (P3-P5), a classification and a box
// subnet shared across levels, anchors of three scales and three aspect
// ratios per cell, and the focal loss, so the many easy background anchors do
// not swamp the few apples. One class (apple): each box is one apple.
//
// This header includes LibTorch: include it only from nn/ and from the .cc
// files that run the network.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <torch/torch.h>

#include "orchard/core/box.h"
#include "orchard/nn/models.h"

namespace orchard::nn {

struct RetinaNetOptions {
  int depth = 18;          // ResNet backbone depth (18, 34, 50)
  int base_width = 16;     // backbone's first-stage channels (paper: 64); 16 trains on CPU
  int fpn_channels = 64;   // pyramid and subnet channels (paper: 256)
  int head_convs = 2;      // 3x3 convolutions per subnet before its output (paper: 4)
  // Anchor side (pixels) at P3, P4, P5 (strides 8, 16, 32); the paper's 32,
  // 64, 128 halved, because apples in 640x640 crops are 24-90 px and smaller
  // in video frames.
  std::vector<double> anchor_sizes = {16, 32, 64};
  int scales_per_octave = 3;                        // sizes x 2^(i/3), i = 0..2
  std::vector<double> aspect_ratios = {0.5, 1, 2};  // height / width

  void Check() const;
  nlohmann::json ToJson() const;
  static RetinaNetOptions FromJson(const nlohmann::json& json);
  int AnchorsPerCell() const { return scales_per_octave * static_cast<int>(aspect_ratios.size()); }
  // Inputs are padded to a multiple of the coarsest stride.
  static constexpr int kInputMultiple = 32;
};

class RetinaNetImpl : public torch::nn::Module {
 public:
  explicit RetinaNetImpl(const RetinaNetOptions& options);
  // [N, 3, H, W] (H, W multiples of 32) -> apple logits [N, A] and box deltas
  // [N, A, 4] for the A anchors of Anchors(H, W), in the same order.
  std::pair<torch::Tensor, torch::Tensor> forward(torch::Tensor x);
  // Anchor boxes [A, 4] (x1, y1, x2, y2 in input pixels): level by level, then
  // row, column and anchor of each cell.
  torch::Tensor Anchors(int height, int width) const;
  const RetinaNetOptions& options() const { return options_; }

 private:
  RetinaNetOptions options_;
  ResNet backbone_{nullptr};
  std::vector<torch::nn::Conv2d> lateral_, output_;
  torch::nn::Sequential class_subnet_{nullptr}, box_subnet_{nullptr};
};
TORCH_MODULE(RetinaNet);

// Box regression targets relative to anchors [A, 4] -> deltas [A, 4]
// (centre offsets in anchor sizes x 10, log size ratios x 5: the
// Faster R-CNN encoding with RetinaNet's weights), and back.
torch::Tensor EncodeBoxes(const torch::Tensor& boxes, const torch::Tensor& anchors);
torch::Tensor DecodeBoxes(const torch::Tensor& deltas, const torch::Tensor& anchors);

// Pairwise IoU of boxes [N, 4] and [M, 4] -> [N, M].
torch::Tensor BoxIoU(const torch::Tensor& a, const torch::Tensor& b);

struct AnchorTargets {
  torch::Tensor labels;  // [A] float: 1 apple, 0 background, -1 ignored
  torch::Tensor boxes;   // [A, 4] the matched box of each anchor (positives only meaningful)
};

struct AnchorMatching {
  double positive_iou = 0.5;  // an anchor is an apple at this IoU with a box (paper: 0.5)
  double negative_iou = 0.4;  // background below it; in between: ignored (paper: 0.4)
};

// Labels every anchor against the boxes: apple at IoU >= positive_iou with a
// box, and each box's best anchor too (small apples overlap no anchor by 0.5);
// background below negative_iou with every box; ignored otherwise, and where
// an anchor overlaps an ignored box (an apple cut by the tile's edge) by
// negative_iou or more.
AnchorTargets MatchAnchors(const torch::Tensor& anchors, const std::vector<Box>& boxes,
                           const std::vector<Box>& ignore, const AnchorMatching& matching = {});

// The detector's loss over a batch: sigmoid focal loss over the anchors that
// are not ignored plus L1 on the positives' deltas, both divided by the
// number of positive anchors (at least 1), as in the paper.
torch::Tensor RetinaNetLoss(const torch::Tensor& logits, const torch::Tensor& deltas, const torch::Tensor& anchors,
                            const std::vector<AnchorTargets>& targets);

struct DecodeOptions {
  double score_threshold = 0.05;  // candidates below this are dropped before NMS
  int candidates_per_level = 1000;  // most-likely anchors per level kept for NMS (paper: 1000)
  double nms_iou = 0.5;            // non-maximum suppression threshold (paper: 0.5)
  int max_detections = 300;        // per image, highest scores first
};

struct ScoredApple {
  Box box;
  double score = 0;
};

// The detections of one image from its logits [A] and deltas [A, 4] for the
// anchors of a network input of `input` size (multiples of 32): boxes clipped
// to `image` (the input before padding), highest score first.
std::vector<ScoredApple> DecodeDetections(const torch::Tensor& logits, const torch::Tensor& deltas,
                                          const torch::Tensor& anchors, const RetinaNetOptions& architecture,
                                          cv::Size input, cv::Size image, const DecodeOptions& options);

}  // namespace orchard::nn
