#include "orchard/detect/unet_detector.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/nn/adadelta.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/segmentation_training.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("unet_test_" + name); }

// Red discs on a mottled green background, with their mask.
nn::SegmentationSample DiscImage(std::mt19937_64& rng, const std::string& photo) {
  nn::SegmentationSample s;
  s.bgr = cv::Mat(64, 96, CV_8UC3);
  cv::randu(s.bgr, cv::Scalar(20, 90, 20), cv::Scalar(60, 150, 60));
  s.mask = cv::Mat1b::zeros(s.bgr.size());
  for (int i = 0; i < 3; ++i) {
    const cv::Point c(10 + rng() % 76, 10 + rng() % 44);
    cv::circle(s.bgr, c, 7, cv::Scalar(40, 40, 190), cv::FILLED);
    cv::circle(s.mask, c, 7, cv::Scalar(1), cv::FILLED);
  }
  s.photo = photo;
  return s;
}

TEST(Adadelta, FollowsTheUpdateRule) {
  // One step from zero state: E[g^2] = (1-rho) g^2; delta = sqrt(eps) / sqrt(E[g^2] + eps) * g.
  torch::Tensor w = torch::tensor({1.0}, torch::requires_grad());
  nn::Adadelta optimizer({w}, nn::AdadeltaOptions(1.0));
  (w * 3.0).sum().backward();  // gradient 3
  optimizer.step();
  const double rho = 0.9, eps = 1e-6, g = 3.0;
  const double delta = std::sqrt(eps) / std::sqrt((1 - rho) * g * g + eps) * g;
  EXPECT_NEAR(w.item<double>(), 1.0 - delta, 1e-7);
}

TEST(UNetDetector, TrainsTinyNetworkAndDetectsDiscs) {
  const fs::path dir = TempDir("train");
  std::mt19937_64 rng(11);
  std::vector<nn::SegmentationSample> samples;
  for (int i = 0; i < 10; ++i) samples.push_back(DiscImage(rng, "photo" + std::to_string(i)));
  nn::UNetTrainingOptions options;
  options.architecture = nn::UNetOptions{4, 3, 2, 3, true};
  options.tile = 32;
  options.stride = 16;
  options.trainer.max_epochs = 8;
  options.trainer.patience = 8;
  options.trainer.batch_size = 8;
  options.trainer.threads = 1;
  options.trainer.progress = false;
  nn::UNetTrainingResult result = nn::TrainUNet(samples, options, {{"source", "test"}}, dir / "unet.pt");
  EXPECT_LT(result.record.train_loss.back(), result.record.train_loss.front());
  EXPECT_GT(result.record.best_metric, 0.3) << "validation apple IoU of a tiny U-Net on red discs";

  UNetDetectorOptions detector_options;
  detector_options.blobs.min_pixels = 20;
  detector_options.threads = 1;
  UNetDetector detector(dir / "unet.pt", detector_options);
  nn::SegmentationSample test = DiscImage(rng, "test");
  FrameDetection detection = detector.Detect(test.bgr);
  ASSERT_EQ(detection.mask.size(), test.bgr.size());
  cv::Mat1b truth = test.mask > 0;
  const double iou = static_cast<double>(cv::countNonZero(truth & detection.mask)) /
                     std::max(1, cv::countNonZero(truth | detection.mask));
  EXPECT_GT(iou, 0.3);
  EXPECT_GE(detection.blobs.size(), 1u);
  // Reloading gives identical probabilities.
  UNetDetector again(dir / "unet.pt", detector_options);
  cv::Mat1f a = detector.AppleProbability(test.bgr), b = again.AppleProbability(test.bgr);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  // One pass over the whole frame: same size; identical to the tiles on a
  // frame of exactly one tile; close to them elsewhere (only the tile seams
  // differ).
  UNetDetectorOptions whole_options = detector_options;
  whole_options.whole_frame = true;
  UNetDetector whole(dir / "unet.pt", whole_options);
  const cv::Mat one_tile = test.bgr(cv::Rect(0, 0, 32, 32)).clone();
  EXPECT_LT(cv::norm(whole.AppleProbability(one_tile), detector.AppleProbability(one_tile), cv::NORM_INF), 1e-5);
  const cv::Mat odd = test.bgr(cv::Rect(0, 0, test.bgr.cols - 5, test.bgr.rows - 3)).clone();
  const cv::Mat1f w = whole.AppleProbability(odd), t = detector.AppleProbability(odd);
  ASSERT_EQ(w.size(), odd.size());
  const cv::Mat1b agree = (w > 0.5) == (t > 0.5);
  EXPECT_GT(cv::countNonZero(agree), 0.9 * static_cast<double>(agree.total()));
}

TEST(UNetDetector, RejectsWrongFiles) {
  const fs::path dir = TempDir("bad");
  EXPECT_THROW(UNetDetector(dir / "missing.pt", {}), Error);
  std::ofstream(dir / "junk.pt") << "junk";
  EXPECT_THROW(UNetDetector(dir / "junk.pt", {}), Error);
  nn::ResNet counter(nn::ResNetOptions{18, 4, 3, 7});
  nn::SaveCheckpoint(*counter, {{"kind", "counter"}, {"architecture", counter->options().ToJson()}}, dir / "c.pt");
  EXPECT_THROW(UNetDetector(dir / "c.pt", {}), Error);
  UNetDetectorOptions bad;
  bad.threshold = 1.5;
  EXPECT_THROW(bad.Check(), Error);
}

}  // namespace
}  // namespace orchard
