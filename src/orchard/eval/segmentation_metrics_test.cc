#include "orchard/eval/segmentation_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

constexpr double kTol = 1e-12;

// 4x4 masks; gt apple = 3x3 ring at the top left (8 px, a hole in the middle).
cv::Mat RingMask(int value, int type = CV_8U) {
  cv::Mat m = cv::Mat::zeros(4, 4, type);
  m(cv::Rect(0, 0, 3, 3)).setTo(value);
  m.at<unsigned char>(1, 1) = 0;
  return m;
}

TEST(SegmentationScores, MaskWithHoleByHand) {
  // gt: ring of 8 apple px; pred: the full 3x3 block (9 px). N = 16.
  // apple: tp 8, gt 8, pred 9 -> IoU 8/9, acc 1.
  // background: gt 8, pred 7, tp 16-8-9+8 = 7 -> IoU 7/8, acc 7/8.
  // mIoU = (8/9+7/8)/2; fwIoU = 8/16*7/8 + 8/16*8/9; pixel acc 15/16; mAcc 15/16.
  cv::Mat gt = RingMask(1);
  cv::Mat pred = cv::Mat::zeros(4, 4, CV_8U);
  pred(cv::Rect(0, 0, 3, 3)).setTo(255);
  const SegmentationScores s = ScoreSegmentation(gt, pred);
  EXPECT_NEAR(s.apple_iou, 8.0 / 9, kTol);
  EXPECT_NEAR(s.apple_accuracy, 1.0, kTol);
  EXPECT_NEAR(s.mean_iou, (8.0 / 9 + 7.0 / 8) / 2, kTol);
  EXPECT_NEAR(s.fw_iou, 0.5 * 7 / 8 + 0.5 * 8 / 9, kTol);
  EXPECT_NEAR(s.pixel_accuracy, 15.0 / 16, kTol);
  EXPECT_NEAR(s.mean_accuracy, 15.0 / 16, kTol);
}

TEST(SegmentationScores, NoAppleInGroundTruthOrPrediction) {
  const cv::Mat empty = cv::Mat::zeros(4, 4, CV_8U);
  // gt without apple, 2 false apple px: background only: gt 16, pred 14,
  // tp 14 -> IoU 14/16 = mIoU = fwIoU; pixel acc = mAcc = 14/16; apple NaN.
  cv::Mat pred = empty.clone();
  pred.at<unsigned char>(0, 0) = pred.at<unsigned char>(3, 3) = 1;
  const SegmentationScores s = ScoreSegmentation(empty, pred);
  EXPECT_NEAR(s.mean_iou, 0.875, kTol);
  EXPECT_NEAR(s.fw_iou, 0.875, kTol);
  EXPECT_NEAR(s.pixel_accuracy, 0.875, kTol);
  EXPECT_NEAR(s.mean_accuracy, 0.875, kTol);
  EXPECT_TRUE(std::isnan(s.apple_iou));
  EXPECT_TRUE(std::isnan(s.apple_accuracy));
  // Neither has apple: everything 1.
  const SegmentationScores none = ScoreSegmentation(empty, empty);
  EXPECT_EQ(none.mean_iou, 1.0);
  EXPECT_EQ(none.pixel_accuracy, 1.0);
  // Apples missed entirely: apple IoU and accuracy 0; background gt 8,
  // pred 16, tp 8 -> IoU 1/2; mIoU 1/4; mAcc (1 + 0)/2.
  const SegmentationScores missed = ScoreSegmentation(RingMask(1), empty);
  EXPECT_EQ(missed.apple_iou, 0.0);
  EXPECT_EQ(missed.apple_accuracy, 0.0);
  EXPECT_NEAR(missed.mean_iou, 0.25, kTol);
  EXPECT_NEAR(missed.mean_accuracy, 0.5, kTol);
  EXPECT_THROW(ScoreSegmentation(empty, cv::Mat::zeros(4, 5, CV_8U)), Error);
}

fs::path TempDir(const std::string& name) {
  const fs::path dir = test::FreshTempDir("eval_seg_" + name);
  fs::create_directories(dir / "gt" / "masks");
  fs::create_directories(dir / "pred");
  return dir;
}

TEST(EvaluateSegmentation, FoldersAveragedPerImage) {
  const fs::path dir = TempDir("folders");
  // a: 16-bit instance ids (two apples) vs a 0/255 jpg-free png prediction.
  cv::Mat ids = cv::Mat::zeros(4, 4, CV_16U);
  ids(cv::Rect(0, 0, 2, 4)).setTo(1);
  ids(cv::Rect(2, 0, 1, 4)).setTo(300);
  cv::Mat pred_a = cv::Mat::zeros(4, 4, CV_8U);
  pred_a(cv::Rect(0, 0, 3, 4)).setTo(255);  // perfect
  cv::imwrite((dir / "gt" / "masks" / "a.png").string(), ids);
  cv::imwrite((dir / "pred" / "a.png").string(), pred_a);
  // b: no apple in gt, prediction empty too: all 1, apple undefined.
  cv::imwrite((dir / "gt" / "masks" / "b.png").string(), cv::Mat::zeros(4, 4, CV_8U));
  cv::imwrite((dir / "pred" / "b.bmp").string(), cv::Mat::zeros(4, 4, CV_8U));
  cv::imwrite((dir / "pred" / "extra.png").string(), cv::Mat::zeros(4, 4, CV_8U));

  std::vector<std::string> unmatched;
  const SegmentationMetrics m = EvaluateSegmentation(dir / "gt", dir / "pred", &unmatched);
  EXPECT_EQ(m.images, 2);
  EXPECT_EQ(m.images_with_apple, 1);
  EXPECT_EQ(m.mean.mean_iou, 1.0);
  EXPECT_EQ(m.mean.apple_iou, 1.0);
  ASSERT_EQ(unmatched.size(), 1u);
  EXPECT_EQ(unmatched[0], "extra.png");

  // A prediction that misses a's apples: a mIoU = (0 + 4/16)/2 = 1/8 (bg gt 4,
  // pred 16, tp 4), b 1 -> mean 9/16; apple IoU averaged over a only: 0.
  cv::imwrite((dir / "pred" / "a.png").string(), cv::Mat::zeros(4, 4, CV_8U));
  const SegmentationMetrics missed = EvaluateSegmentation(dir / "gt" / "masks", dir / "pred");
  EXPECT_NEAR(missed.mean.mean_iou, (0.125 + 1) / 2, kTol);
  EXPECT_EQ(missed.mean.apple_iou, 0.0);
}

TEST(EvaluateSegmentation, BadInputsAreErrors) {
  const fs::path dir = TempDir("bad");
  cv::imwrite((dir / "gt" / "masks" / "a.png").string(), RingMask(1));
  EXPECT_THROW(EvaluateSegmentation(dir / "gt", dir / "pred"), Error);  // missing prediction
  cv::imwrite((dir / "pred" / "a.png").string(), cv::Mat::zeros(5, 4, CV_8U));
  EXPECT_THROW(EvaluateSegmentation(dir / "gt", dir / "pred"), Error);  // size mismatch
  std::ofstream(dir / "pred" / "a.png") << "not a png";
  EXPECT_THROW(EvaluateSegmentation(dir / "gt", dir / "pred"), Error);  // unreadable
  EXPECT_THROW(EvaluateSegmentation(dir / "pred" / "nothing", dir / "pred"), Error);
  fs::remove(dir / "gt" / "masks" / "a.png");
  EXPECT_THROW(EvaluateSegmentation(dir / "gt", dir / "pred"), Error);  // no masks
}

}  // namespace
}  // namespace orchard
