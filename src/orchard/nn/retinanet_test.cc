#include "orchard/nn/retinanet.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"

namespace orchard::nn {
namespace {

RetinaNetOptions Tiny() {
  RetinaNetOptions o;
  o.base_width = 4;
  o.fpn_channels = 8;
  o.head_convs = 1;
  return o;
}

TEST(RetinaNet, OutputsOneLogitAndFourDeltasPerAnchor) {
  torch::manual_seed(0);
  RetinaNet net(Tiny());
  const torch::Tensor anchors = net->Anchors(64, 96);
  // 9 anchors per cell on 8x12 + 4x6 + 2x3 cells.
  ASSERT_EQ(anchors.size(0), 9 * (8 * 12 + 4 * 6 + 2 * 3));
  // The first anchor: P3's first cell centre (4, 4), side 16 at aspect 0.5
  // (height / width), i.e. 16 / sqrt(0.5) wide.
  const double w = 16 / std::sqrt(0.5), h = 16 * std::sqrt(0.5);
  EXPECT_NEAR(anchors[0][0].item<double>(), 4 - w / 2, 1e-4);
  EXPECT_NEAR(anchors[0][3].item<double>(), 4 + h / 2, 1e-4);
  auto [logits, deltas] = net->forward(torch::zeros({2, 3, 64, 96}));
  EXPECT_EQ(logits.sizes(), (std::vector<int64_t>{2, anchors.size(0)}));
  EXPECT_EQ(deltas.sizes(), (std::vector<int64_t>{2, anchors.size(0), 4}));
  // The classification bias starts every anchor near the prior 0.01.
  EXPECT_NEAR(torch::sigmoid(logits).mean().item<double>(), 0.01, 0.005);
  EXPECT_THROW(net->forward(torch::zeros({1, 3, 60, 96})), Error);
}

TEST(RetinaNet, EncodesAndDecodesBoxes) {
  const torch::Tensor anchors = torch::tensor({0.f, 0.f, 16.f, 16.f, 10.f, 20.f, 42.f, 36.f}).reshape({2, 4});
  const torch::Tensor boxes = torch::tensor({2.f, 1.f, 20.f, 15.f, 5.f, 25.f, 50.f, 33.f}).reshape({2, 4});
  const torch::Tensor deltas = EncodeBoxes(boxes, anchors);
  EXPECT_NEAR(deltas[0][0].item<double>(), 10 * (11 - 8) / 16.0, 1e-5);  // centre x offset in anchor widths x 10
  EXPECT_NEAR(deltas[0][2].item<double>(), 5 * std::log(18 / 16.0), 1e-5);
  EXPECT_LT((DecodeBoxes(deltas, anchors) - boxes).abs().max().item<double>(), 1e-4);
  EXPECT_NEAR(BoxIoU(anchors, boxes)[0][0].item<double>(), (14.0 * 14) / (256 + 18 * 14 - 14 * 14), 1e-5);
}

TEST(RetinaNet, MatchesAnchorsToBoxes) {
  RetinaNet net(Tiny());
  const torch::Tensor anchors = net->Anchors(64, 64);
  // A box equal to an anchor, a small box that overlaps no anchor by 0.5, and
  // an ignored box.
  const auto a = anchors[40];
  const Box exact{a[0].item<double>(), a[1].item<double>(), a[2].item<double>(), a[3].item<double>()};
  const Box small{50, 50, 56, 56};
  const Box ignored{0, 40, 14, 54};
  const AnchorTargets t = MatchAnchors(anchors, {exact, small}, {ignored});
  EXPECT_EQ(t.labels[40].item<float>(), 1);
  EXPECT_LT((t.boxes[40] - a).abs().max().item<double>(), 1e-5);
  // The small box gets exactly its best anchor, matched to it.
  const torch::Tensor iou_small = BoxIoU(anchors, torch::tensor({50.f, 50.f, 56.f, 56.f}).reshape({1, 4})).squeeze(1);
  const int64_t best = iou_small.argmax().item<int64_t>();
  EXPECT_LT(iou_small[best].item<double>(), 0.5);
  EXPECT_EQ(t.labels[best].item<float>(), 1);
  EXPECT_NEAR(t.boxes[best][0].item<double>(), 50, 1e-5);
  // Anchors overlapping the ignored box are ignored; far ones are background.
  const torch::Tensor iou_ignored = BoxIoU(anchors, torch::tensor({0.f, 40.f, 14.f, 54.f}).reshape({1, 4})).squeeze(1);
  EXPECT_EQ(t.labels[iou_ignored.argmax().item<int64_t>()].item<float>(), -1);
  EXPECT_EQ(t.labels.eq(1).sum().item<int64_t>(), BoxIoU(anchors, torch::tensor({exact.x1, exact.y1, exact.x2, exact.y2})
                                                                                .to(torch::kFloat32)
                                                                                .reshape({1, 4}))
                                                          .ge(0.5)
                                                          .sum()
                                                          .item<int64_t>() +
                                                      1);
  const AnchorTargets none = MatchAnchors(anchors, {}, {});
  EXPECT_EQ(none.labels.abs().sum().item<float>(), 0);
}

TEST(RetinaNet, LossFallsWhenTheRightAnchorsScore) {
  RetinaNet net(Tiny());
  const torch::Tensor anchors = net->Anchors(64, 64);
  const AnchorTargets t = MatchAnchors(anchors, {Box{20, 20, 36, 36}}, {});
  const int64_t n = anchors.size(0);
  const torch::Tensor zero_deltas = torch::zeros({1, n, 4});
  const torch::Tensor prior = torch::full({1, n}, -4.6);
  const torch::Tensor good = prior + 9.2 * t.labels.clamp_min(0).unsqueeze(0);
  EXPECT_LT(RetinaNetLoss(good, zero_deltas, anchors, {t}).item<double>(),
            RetinaNetLoss(prior, zero_deltas, anchors, {t}).item<double>());
  const torch::Tensor exact = EncodeBoxes(t.boxes, anchors).unsqueeze(0);
  EXPECT_LT(RetinaNetLoss(good, exact, anchors, {t}).item<double>(),
            RetinaNetLoss(good, zero_deltas, anchors, {t}).item<double>());
}

TEST(RetinaNet, DecodesAndSuppressesOverlappingBoxes) {
  RetinaNetOptions o = Tiny();
  RetinaNet net(o);
  const torch::Tensor anchors = net->Anchors(64, 64);
  const int64_t n = anchors.size(0);
  torch::Tensor logits = torch::full({n}, -10.0);
  // Two neighbouring scales of one cell (IoU about 0.63) and one far anchor.
  logits[4] = 3.0;
  logits[7] = 2.0;
  logits[9 * 30 + 4] = 1.0;
  const std::vector<ScoredApple> found =
      DecodeDetections(logits, torch::zeros({n, 4}), anchors, o, cv::Size(64, 64), cv::Size(64, 64), DecodeOptions{});
  ASSERT_EQ(found.size(), 2u);
  EXPECT_NEAR(found[0].score, 1 / (1 + std::exp(-3.0)), 1e-5);
  EXPECT_NEAR(found[1].score, 1 / (1 + std::exp(-1.0)), 1e-5);
  // Boxes are clipped to the image.
  EXPECT_GE(found[0].box.x1, 0);
  EXPECT_GE(found[0].box.y1, 0);
  // An image padded to the network's input: levels follow the input, boxes
  // are clipped to the image; the coarsest level's last anchor is found too.
  torch::Tensor last = torch::full({n}, -10.0);
  last[n - 1] = 3.0;
  const std::vector<ScoredApple> padded =
      DecodeDetections(last, torch::zeros({n, 4}), anchors, o, cv::Size(64, 64), cv::Size(60, 50), DecodeOptions{});
  ASSERT_EQ(padded.size(), 1u);
  EXPECT_LE(padded[0].box.x2, 60);
  EXPECT_LE(padded[0].box.y2, 50);
  EXPECT_THROW(DecodeDetections(last, torch::zeros({n, 4}), anchors, o, cv::Size(96, 64), cv::Size(60, 50),
                                DecodeOptions{}),
               Error);
}

}  // namespace
}  // namespace orchard::nn
