#include "orchard/count/cnn_counter.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_training.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("cnn_counter_test_" + name); }

// A leafy patch with `count` red discs (0..2 here, to keep the test quick).
cv::Mat DiscPatch(int count, std::mt19937_64& rng) {
  cv::Mat patch(40 + rng() % 20, 40 + rng() % 20, CV_8UC3, cv::Scalar(40, 120 + rng() % 40, 40));
  for (int i = 0; i < count; ++i) {
    const cv::Point centre(8 + i * (patch.cols - 16) / std::max(1, count - 1 + (count == 1)), 10 + rng() % (patch.rows - 20));
    cv::circle(patch, count == 1 ? cv::Point(patch.cols / 2, patch.rows / 2) : centre, 7, cv::Scalar(30, 30, 200), -1);
  }
  return patch;
}

TEST(CnnCounter, TrainsReloadsAndCounts) {
  const fs::path dir = TempDir("train");
  std::mt19937_64 rng(5);
  std::vector<nn::LabelledPatch> patches;
  for (int i = 0; i < 120; ++i) {
    const int count = i % 3;
    patches.push_back({DiscPatch(count, rng), count, "photo" + std::to_string(i % 10)});
  }
  nn::CounterTrainingOptions options;
  options.architecture.base_width = 4;
  options.input_size = 32;
  options.trainer.max_epochs = 6;
  options.trainer.patience = 6;
  options.trainer.progress = false;
  options.trainer.threads = 1;
  nn::CounterTrainingResult result = TrainCounter(patches, options, {{"source", "test"}}, dir / "counter.pt");
  ASSERT_GE(result.record.epochs_run, 1);
  EXPECT_LT(result.record.train_loss.back(), result.record.train_loss.front());
  EXPECT_EQ(result.train_patches + result.validation_patches, 120);
  EXPECT_FALSE(fs::exists(dir / ".counter.pt.best"));

  CnnCounter counter(dir / "counter.pt", 1);
  EXPECT_EQ(counter.input_size(), 32);
  std::vector<cv::Mat> test;
  std::vector<int> truth;
  for (int i = 0; i < 30; ++i) {
    truth.push_back(i % 3);
    test.push_back(DiscPatch(i % 3, rng));
  }
  const std::vector<int> counts = counter.CountBatch(test);
  int correct = 0;
  for (size_t i = 0; i < counts.size(); ++i) correct += counts[i] == truth[i];
  EXPECT_GE(correct, 20) << "a tiny counter should separate 0, 1 and 2 discs";
  // Reloading gives the same answers, one by one or batched.
  CnnCounter again(dir / "counter.pt", 1);
  EXPECT_EQ(again.CountBatch(test), counts);
  EXPECT_EQ(again.Count(test[4], cv::Mat1b()).count, counts[4]);
}

TEST(CnnCounter, RejectsWrongFiles) {
  const fs::path dir = TempDir("bad");
  EXPECT_THROW(CnnCounter(dir / "missing.pt"), Error);
  std::ofstream(dir / "junk.pt") << "junk";
  EXPECT_THROW(CnnCounter(dir / "junk.pt"), Error);
  nn::UNet unet(nn::UNetOptions{4});
  nn::SaveCheckpoint(*unet, {{"kind", "unet"}, {"architecture", unet->options().ToJson()}}, dir / "unet.pt");
  EXPECT_THROW(CnnCounter(dir / "unet.pt"), Error);
  // A counter header whose architecture differs from the stored weights.
  nn::ResNet small(nn::ResNetOptions{18, 4, 3, 7});
  nlohmann::json wrong = nn::ResNetOptions{18, 8, 3, 7}.ToJson();
  nn::SaveCheckpoint(*small, {{"kind", "counter"}, {"architecture", wrong}, {"input_size", 32}}, dir / "lying.pt");
  EXPECT_THROW(CnnCounter(dir / "lying.pt"), Error);
}

}  // namespace
}  // namespace orchard
