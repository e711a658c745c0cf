// Known-answer tests for the detection metrics; every expected value is
// computed by hand in the comment above it.
#include "orchard/eval/detection_metrics.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"

namespace orchard {
namespace {

constexpr double kTol = 1e-12;

Box B(double x1, double y1, double x2, double y2) { return {x1, y1, x2, y2}; }

DetectionFrame Frame(std::vector<Box> gt, std::vector<ScoredBox> pred,
                     std::vector<double> areas = {}) {
  DetectionFrame f;
  f.gt_boxes = gt;
  for (size_t i = 0; i < gt.size(); ++i) {
    f.gt_areas.push_back(i < areas.size() && areas[i] >= 0 ? areas[i] : gt[i].Area());
  }
  f.predictions = pred;
  return f;
}

// Index of threshold t = i / 100 in the curve.
int T(int percent) { return percent - 1; }

TEST(StudyProtocol, ThresholdsAre001To099) {
  const std::vector<double> t = StudyIouThresholds();
  ASSERT_EQ(t.size(), 99u);
  EXPECT_EQ(t[0], 0.01);
  EXPECT_EQ(t[49], 0.5);
  EXPECT_EQ(t[98], 0.99);
}

TEST(StudyProtocol, OneFrameByHand) {
  // gt A=[0,0,10,10], B=[20,0,30,10]. p1 = A (IoU 1), p2 = [20,0,30,5] (IoU with
  // B = 50/100 = 0.5), p3 far away. t <= 0.50: TP 2 of 3 preds, 2 gt:
  // P = 2/3, R = 1, F1 = 2*(2/3)/(5/3) = 0.8. t >= 0.51: TP 1: P = 1/3,
  // R = 1/2, F1 = 2*(1/6)/(5/6) = 0.4.
  const auto curve = EvaluateStudyProtocol({Frame(
      {B(0, 0, 10, 10), B(20, 0, 30, 10)},
      {{B(0, 0, 10, 10), 0.9}, {B(20, 0, 30, 5), 0.8}, {B(100, 100, 110, 110), 0.7}})});
  for (int p : {1, 25, 50}) {
    EXPECT_NEAR(curve.precision[T(p)], 2.0 / 3, kTol) << p;
    EXPECT_NEAR(curve.recall[T(p)], 1.0, kTol) << p;
    EXPECT_NEAR(curve.f1[T(p)], 0.8, kTol) << p;
  }
  for (int p : {51, 99}) {
    EXPECT_NEAR(curve.precision[T(p)], 1.0 / 3, kTol) << p;
    EXPECT_NEAR(curve.recall[T(p)], 0.5, kTol) << p;
    EXPECT_NEAR(curve.f1[T(p)], 0.4, kTol) << p;
  }
}

TEST(StudyProtocol, TiesInScoreKeepFileOrder) {
  // gt A=[0,0,10,10], B=[10,0,20,10]. px=[2,0,12,10]: IoU A = 80/120 = 2/3,
  // IoU B = 20/180 = 1/9. py = A: IoU A = 1, B = 0. Equal scores.
  // File order (py, px): py takes A, px takes B while t <= 1/9 (t = 0.11):
  // TP 2, P = R = F1 = 1. At t = 0.12: TP 1, P = R = F1 = 1/2.
  // File order (px, py): px takes A (2/3 > 1/9), py finds nothing: TP 1 for
  // t <= 0.66; for t >= 0.67 px matches nothing and py takes A: TP 1 again.
  const std::vector<Box> gt = {B(0, 0, 10, 10), B(10, 0, 20, 10)};
  const ScoredBox px{B(2, 0, 12, 10), 0.5}, py{B(0, 0, 10, 10), 0.5};
  const auto yx = EvaluateStudyProtocol({Frame(gt, {py, px})});
  EXPECT_NEAR(yx.f1[T(11)], 1.0, kTol);
  EXPECT_NEAR(yx.f1[T(12)], 0.5, kTol);
  const auto xy = EvaluateStudyProtocol({Frame(gt, {px, py})});
  for (int p : {1, 11, 12, 66, 67, 99}) EXPECT_NEAR(xy.f1[T(p)], 0.5, kTol) << p;
  // A higher score puts py first whatever the file order.
  ScoredBox py_high = py;
  py_high.score = 0.6;
  EXPECT_NEAR(EvaluateStudyProtocol({Frame(gt, {px, py_high})}).f1[T(11)], 1.0, kTol);
}

TEST(StudyProtocol, TiesInIoUTakeTheFirstGroundTruth) {
  // gt A=[0,0,10,10], B=[10,0,20,10]. p1=[5,0,15,10] (.9): IoU 50/150 = 1/3
  // with both. p2 = B (.8). p1 takes A (the first of the tie), p2 takes B:
  // at t = 0.33 TP 2, F1 = 1 (had p1 taken B, p2 would find nothing: F1 0.5).
  // At t = 0.34 p1 matches nothing, p2 takes B: P = R = F1 = 1/2.
  const auto curve = EvaluateStudyProtocol({Frame({B(0, 0, 10, 10), B(10, 0, 20, 10)},
                                                  {{B(5, 0, 15, 10), 0.9}, {B(10, 0, 20, 10), 0.8}})});
  EXPECT_NEAR(curve.f1[T(33)], 1.0, kTol);
  EXPECT_NEAR(curve.f1[T(34)], 0.5, kTol);
}

TEST(StudyProtocol, EmptyFramesConventions) {
  // F1: 1 gt, exact pred: P=R=F1=1. F2: neither: P=R=1, F1=1.
  // F3: no gt, 1 pred: P=0, R=1, F1=0. F4: 1 gt, no pred: P=1, R=0, F1=0.
  // Means over 4 frames: P = 3/4, R = 3/4, F1 = 2/4.
  const auto curve = EvaluateStudyProtocol({Frame({B(0, 0, 10, 10)}, {{B(0, 0, 10, 10), 0.9}}),
                                            Frame({}, {}), Frame({}, {{B(0, 0, 5, 5), 0.5}}),
                                            Frame({B(0, 0, 10, 10)}, {})});
  for (int p = 1; p <= 99; ++p) {
    EXPECT_NEAR(curve.precision[T(p)], 0.75, kTol);
    EXPECT_NEAR(curve.recall[T(p)], 0.75, kTol);
    EXPECT_NEAR(curve.f1[T(p)], 0.5, kTol);
  }
}

TEST(StudyProtocol, DuplicatePredictionsAreFalsePositives) {
  // Two identical predictions on one gt: TP 1, P = 1/2, R = 1, F1 = 2/3 at every t.
  const auto curve =
      EvaluateStudyProtocol({Frame({B(0, 0, 10, 10)}, {{B(0, 0, 10, 10), 0.9}, {B(0, 0, 10, 10), 0.9}})});
  EXPECT_NEAR(curve.precision[T(99)], 0.5, kTol);
  EXPECT_NEAR(curve.recall[T(99)], 1.0, kTol);
  EXPECT_NEAR(curve.f1[T(50)], 2.0 / 3, kTol);
}

TEST(StudyProtocol, BoxesOnTheImageBorderAreNotClipped) {
  // gt [0,0,10,10] on the border, pred [-5,0,5,10] half outside the image:
  // inter 50, union 150, IoU 1/3. Matched at t = 0.33, not at t = 0.34.
  const auto curve = EvaluateStudyProtocol({Frame({B(0, 0, 10, 10)}, {{B(-5, 0, 5, 10), 1.0}})});
  EXPECT_NEAR(curve.f1[T(33)], 1.0, kTol);
  EXPECT_NEAR(curve.f1[T(34)], 0.0, kTol);
  EXPECT_NEAR(curve.precision[T(34)], 0.0, kTol);
  EXPECT_NEAR(curve.recall[T(34)], 0.0, kTol);
}

TEST(StudyProtocol, NoFramesIsAnError) { EXPECT_THROW(EvaluateStudyProtocol({}), Error); }

TEST(Coco, BoxIoUMatchesMaskApi) {
  EXPECT_NEAR(CocoBoxIoU(B(-5, 0, 5, 10), B(0, 0, 10, 10)), 1.0 / 3, kTol);
  EXPECT_EQ(CocoBoxIoU(B(0, 0, 10, 10), B(10, 0, 20, 10)), 0.0);  // touching edges
  EXPECT_EQ(CocoBoxIoU(B(0, 0, 0, 0), B(0, 0, 0, 0)), 0.0);      // empty boxes
}

TEST(Coco, PartialMatchByHand) {
  // gt A=[0,0,10,10], B=[20,0,30,10] (areas 100: small). d1 = A (.9, IoU 1),
  // d2 = [20,0,30,6.8] (.8, IoU 0.68), d3 far away (.7).
  // t = .50,.55,.60,.65: TP TP FP -> rc [.5,1,1], pr [1,1,2/3]: every recall
  //   threshold finds precision 1: AP_t = 1.
  // t = .70 ... .95 (6 thresholds): TP FP FP -> rc [.5,.5,.5], pr [1,.5,1/3]:
  //   r = 0.00..0.50 (51 points) -> 1, r > .5 -> 0: AP_t = 51/101.
  // AP = (4 + 6*51/101)/10 = 710/1010; AP50 = 1; AP75 = 51/101; APs = AP;
  // no medium or large gt: -1.
  const auto coco = EvaluateCoco({Frame(
      {B(0, 0, 10, 10), B(20, 0, 30, 10)},
      {{B(0, 0, 10, 10), 0.9}, {B(20, 0, 30, 6.8), 0.8}, {B(50, 50, 60, 60), 0.7}})});
  EXPECT_NEAR(coco.ap, 710.0 / 1010, kTol);
  EXPECT_NEAR(coco.ap50, 1.0, kTol);
  EXPECT_NEAR(coco.ap75, 51.0 / 101, kTol);
  EXPECT_NEAR(coco.aps, 710.0 / 1010, kTol);
  EXPECT_EQ(coco.apm, -1);
  EXPECT_EQ(coco.apl, -1);
}

TEST(Coco, FalsePositiveFirstHalvesPrecision) {
  // FP (.9) before TP (.8): rc [0,1], pr [0,.5] -> envelope [.5,.5]: AP 0.5.
  const auto coco =
      EvaluateCoco({Frame({B(0, 0, 10, 10)}, {{B(50, 50, 60, 60), 0.9}, {B(0, 0, 10, 10), 0.8}})});
  EXPECT_NEAR(coco.ap, 0.5, kTol);
  EXPECT_NEAR(coco.ap50, 0.5, kTol);
  EXPECT_NEAR(coco.ap75, 0.5, kTol);
}

TEST(Coco, UnmatchedDetectionsOutsideTheAreaRangeAreIgnored) {
  // gt 10x10 (small) found by d (.8); a 100x100 FP (.9, area 10^4: large).
  // all: FP, TP -> AP 0.5. small: the large FP is ignored -> AP 1.
  // medium, large: no gt in range -> -1.
  const auto coco = EvaluateCoco(
      {Frame({B(0, 0, 10, 10)}, {{B(200, 200, 300, 300), 0.9}, {B(0, 0, 10, 10), 0.8}})});
  EXPECT_NEAR(coco.ap, 0.5, kTol);
  EXPECT_NEAR(coco.aps, 1.0, kTol);
  EXPECT_EQ(coco.apm, -1);
  EXPECT_EQ(coco.apl, -1);
}

TEST(Coco, MaskAreaWithHolesDecidesTheSizeClass) {
  // A 40x40 box (box area 1600: medium) whose mask has holes (900 px: small).
  // Found exactly: with the mask area APs = 1, APm = -1 (the gt is ignored in
  // medium and the matching detection with it); with the box area the reverse.
  const Box box = B(0, 0, 40, 40);
  const auto with_mask = EvaluateCoco({Frame({box}, {{box, 1.0}}, {900})});
  EXPECT_NEAR(with_mask.aps, 1.0, kTol);
  EXPECT_EQ(with_mask.apm, -1);
  const auto with_box = EvaluateCoco({Frame({box}, {{box, 1.0}})});
  EXPECT_EQ(with_box.aps, -1);
  EXPECT_NEAR(with_box.apm, 1.0, kTol);
  EXPECT_NEAR(with_box.ap, 1.0, kTol);
}

TEST(Coco, AreaRangeBoundsAreInclusive) {
  // Area exactly 32^2 = 1024 belongs to small and to medium (pycocotools
  // ignores a gt only when area < lo or area > hi).
  const Box box = B(0, 0, 32, 32);
  const auto coco = EvaluateCoco({Frame({box}, {{box, 1.0}})});
  EXPECT_NEAR(coco.aps, 1.0, kTol);
  EXPECT_NEAR(coco.apm, 1.0, kTol);
  EXPECT_EQ(coco.apl, -1);
}

TEST(Coco, EmptyFrames) {
  // F1: gt + exact d (.9). F2: neither (skipped). F3: no gt, d (.5) = FP.
  // F4: gt, no d. npig 2; TP, FP -> rc [.5,.5], pr [1,.5]: AP_t = 51/101.
  const auto coco = EvaluateCoco({Frame({B(0, 0, 10, 10)}, {{B(0, 0, 10, 10), 0.9}}),
                                  Frame({}, {}), Frame({}, {{B(0, 0, 5, 5), 0.5}}),
                                  Frame({B(0, 0, 10, 10)}, {})});
  EXPECT_NEAR(coco.ap, 51.0 / 101, kTol);
  // Without any gt pycocotools reports -1 everywhere.
  EXPECT_EQ(EvaluateCoco({Frame({}, {{B(0, 0, 5, 5), 0.5}})}).ap, -1);
}

TEST(Coco, EqualScoresAcrossImagesRankInImageOrder) {
  // Each image has one gt. I1: an FP at .5; I2: a TP at .5.
  // I1 first: FP, TP -> rc [0,.5], pr [0,.5] -> envelope .5 up to recall .5:
  //   51 points x .5 -> AP = 25.5/101.
  // I2 first: TP, FP -> rc [.5,.5], pr [1,.5] -> 51 points x 1 -> AP = 51/101.
  const DetectionFrame i1 = Frame({B(0, 0, 10, 10)}, {{B(50, 50, 60, 60), 0.5}});
  const DetectionFrame i2 = Frame({B(0, 0, 10, 10)}, {{B(0, 0, 10, 10), 0.5}});
  EXPECT_NEAR(EvaluateCoco({i1, i2}).ap, 25.5 / 101, kTol);
  EXPECT_NEAR(EvaluateCoco({i2, i1}).ap, 51.0 / 101, kTol);
}

TEST(Coco, AtMost100DetectionsPerImage) {
  // 99 FPs at score 1 then the TP at .5: rc 0 ... 0, 1; pr 0 ... 0, 1/100 ->
  // envelope 1/100 everywhere: AP50 = 0.01. With 100 FPs the TP is cut: AP50 = 0.
  for (int fps : {99, 100}) {
    std::vector<ScoredBox> d(fps, ScoredBox{B(50, 50, 60, 60), 1.0});
    d.push_back({B(0, 0, 10, 10), 0.5});
    EXPECT_NEAR(EvaluateCoco({Frame({B(0, 0, 10, 10)}, d)}).ap50, fps == 99 ? 0.01 : 0.0, kTol);
  }
}

TEST(Coco, DuplicateDetections) {
  // Two copies of the exact box: TP then FP -> rc [1,1], pr [1,.5]: AP 1.
  const auto coco =
      EvaluateCoco({Frame({B(0, 0, 10, 10)}, {{B(0, 0, 10, 10), 0.9}, {B(0, 0, 10, 10), 0.9}})});
  EXPECT_NEAR(coco.ap, 1.0, kTol);
}

Dataset TwoImageDataset() {
  Dataset gt;
  for (int i = 0; i < 2; ++i) {
    AnnotatedImage image;
    image.name = "img" + std::to_string(i) + ".png";
    image.id = i + 1;
    image.width = image.height = 100;
    Annotation a;
    a.box = B(0, 0, 10, 10);
    image.objects.push_back(a);
    gt.images.push_back(image);
  }
  return gt;
}

TEST(EvaluateDetections, ResolvesNamesAndCounts) {
  // img0 found exactly (named without extension), img1 missed:
  // study: F1 = (1 + 0)/2 at every t; COCO: TP only, npig 2 -> AP_t = 51/101.
  const Dataset gt = TwoImageDataset();
  Predictions pred;
  pred["img0"] = {{B(0, 0, 10, 10), 0.9}};
  const DetectionMetrics m = EvaluateDetections(gt, pred);
  EXPECT_EQ(m.images, 2);
  EXPECT_EQ(m.gt_boxes, 2);
  EXPECT_EQ(m.pred_boxes, 1);
  EXPECT_NEAR(m.f1_at_05, 0.5, kTol);
  EXPECT_NEAR(m.coco.ap, 51.0 / 101, kTol);
}

TEST(EvaluateDetections, BadPredictionsAreErrors) {
  const Dataset gt = TwoImageDataset();
  Predictions unknown;
  unknown["nope.png"] = {{B(0, 0, 10, 10), 0.9}};
  EXPECT_THROW(EvaluateDetections(gt, unknown), Error);
  Predictions twice;
  twice["img0"] = {{B(0, 0, 10, 10), 0.9}};
  twice["img0.png"] = {{B(0, 0, 10, 10), 0.9}};
  EXPECT_THROW(EvaluateDetections(gt, twice), Error);
  Predictions nan;
  nan["img0.png"] = {{B(0, 0, 10, 10), std::nan("")}};
  EXPECT_THROW(EvaluateDetections(gt, nan), Error);
  EXPECT_THROW(EvaluateDetections(Dataset{}, Predictions{}), Error);
}

}  // namespace
}  // namespace orchard
