#include "orchard/count/cnn_counter.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_ensemble.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"
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

// A counter that trains in a second: width 4, 32-pixel inputs, one thread.
nn::CounterTrainingOptions TinyCounterOptions(int epochs) {
  nn::CounterTrainingOptions options;
  options.architecture.base_width = 4;
  options.input_size = 32;
  options.trainer.max_epochs = epochs;
  options.trainer.patience = epochs;
  options.trainer.progress = false;
  options.trainer.threads = 1;
  return options;
}

TEST(CnnCounter, TrainsReloadsAndCounts) {
  const fs::path dir = TempDir("train");
  std::mt19937_64 rng(5);
  std::vector<nn::LabelledPatch> patches;
  for (int i = 0; i < 120; ++i) {
    const int count = i % 3;
    patches.push_back({DiscPatch(count, rng), count, "photo" + std::to_string(i % 10), {}, false});
  }
  const nn::CounterTrainingOptions options = TinyCounterOptions(6);
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
  // The side stage's per-frame call, through the Counter interface.
  Counter& as_counter = again;
  const std::vector<BlobCount> many = as_counter.CountMany(test, {});
  ASSERT_EQ(many.size(), counts.size());
  for (size_t i = 0; i < many.size(); ++i) EXPECT_EQ(many[i].count, counts[i]);
  EXPECT_TRUE(as_counter.CountMany({}, {}).empty());
  EXPECT_THROW(as_counter.CountMany(test, {cv::Mat1b(3, 3)}), Error);  // one mask for 30 patches
}

// A counter with the density head learns from the discs' positions where they
// are known and from the count alone where not; it loads and counts like any.
TEST(CnnCounter, DensityHeadTrainsOnPointsAndReloads) {
  const fs::path dir = TempDir("density");
  std::mt19937_64 rng(7);
  std::vector<nn::LabelledPatch> patches;
  for (int i = 0; i < 60; ++i) {
    const int count = i % 3;
    cv::Mat patch(48, 48, CV_8UC3, cv::Scalar(40, 140, 40));
    std::vector<cv::Point2f> centres;
    for (int k = 0; k < count; ++k) {
      centres.emplace_back(12 + 24 * k, 14 + rng() % 20);
      cv::circle(patch, centres.back(), 7, cv::Scalar(30, 30, 200), -1);
    }
    patches.push_back({patch, count, "photo" + std::to_string(i % 6), centres, i % 4 != 0});
  }
  nn::CounterTrainingOptions options = TinyCounterOptions(5);
  options.density_weight = 1;
  const nn::CounterTrainingResult result = TrainCounter(patches, options, {{"source", "test"}}, dir / "counter.pt");
  EXPECT_LT(result.record.train_loss.back(), result.record.train_loss.front());
  EXPECT_TRUE(nn::ReadCheckpointHeader(dir / "counter.pt", "counter")["architecture"]["density_head"].get<bool>());
  CnnCounter counter(dir / "counter.pt", 1);
  std::vector<cv::Mat> test;
  for (int i = 0; i < 6; ++i) test.push_back(patches[i].bgr);
  EXPECT_EQ(CnnCounter(dir / "counter.pt", 1).CountBatch(test), counter.CountBatch(test));
  options.density_sigma = 0;
  EXPECT_THROW(options.Check(), Error);
}

// With no validation photos every patch trains, nothing stops early, and the
// file holds the last epoch's network.
TEST(CnnCounter, WithoutValidationEveryPatchTrainsAndTheLastEpochIsKept) {
  const fs::path dir = TempDir("no_validation");
  std::mt19937_64 rng(9);
  std::vector<nn::LabelledPatch> patches;
  for (int i = 0; i < 60; ++i) patches.push_back({DiscPatch(i % 3, rng), i % 3, "photo" + std::to_string(i % 6), {}, false});
  nn::CounterTrainingOptions options = TinyCounterOptions(3);
  options.validation_fraction = 0;
  options.trainer.patience = 1;
  const nn::CounterTrainingResult result = TrainCounter(patches, options, {{"source", "test"}}, dir / "counter.pt");
  EXPECT_EQ(result.train_patches, 60);
  EXPECT_EQ(result.validation_patches, 0);
  EXPECT_EQ(result.record.epochs_run, 3);
  EXPECT_EQ(result.record.best_epoch, 3);
  EXPECT_TRUE(result.record.validation.empty());
  EXPECT_EQ(nn::ReadCheckpointHeader(dir / "counter.pt", "counter")["training"]["best_epoch"].get<int>(), 3);
  EXPECT_EQ(CnnCounter(dir / "counter.pt", 1).CountBatch({patches[0].bgr}).size(), 1u);
  options.validation_fraction = -0.1;
  EXPECT_THROW(options.Check(), Error);
  options.validation_fraction = 1;
  EXPECT_THROW(options.Check(), Error);
}

TEST(CnnCounter, FlipAverageIsMirrorInvariant) {
  const fs::path dir = TempDir("flip");
  torch::manual_seed(2);
  nn::ResNet net(nn::ResNetOptions{18, 4, 3, 7});
  nn::SaveCheckpoint(*net, {{"kind", "counter"}, {"architecture", net->options().ToJson()}, {"input_size", 32}},
                     dir / "counter.pt");
  std::mt19937_64 rng(9);
  std::vector<cv::Mat> patches, mirrored;
  for (int i = 0; i < 6; ++i) {
    // Even padding (width 40 -> 32 x 26, 3 px each side) so mirroring commutes with the letterbox.
    cv::Mat patch(33, 40, CV_8UC3);
    cv::randu(patch, 0, 255);
    patches.push_back(patch);
    cv::Mat flipped;
    cv::flip(patch, flipped, 1);
    mirrored.push_back(flipped);
  }
  CnnCounter averaged(dir / "counter.pt", 1);
  const auto p = averaged.CountProbabilities(patches);
  const auto q = averaged.CountProbabilities(mirrored);
  for (size_t i = 0; i < p.size(); ++i) {
    ASSERT_EQ(p[i].size(), 7u);
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(p[i][k], q[i][k], 1e-6) << "patch " << i << " count " << k;
  }
  // Without averaging, a random network tells a patch from its mirror; for a
  // mirror-symmetric patch both settings agree.
  CnnCounter single(dir / "counter.pt", 1, CnnCounterOptions{false});
  const auto r = single.CountProbabilities(patches);
  const auto t = single.CountProbabilities(mirrored);
  double differ = 0;
  for (size_t i = 0; i < r.size(); ++i)
    for (int k = 0; k < 7; ++k) differ = std::max<double>(differ, std::abs(r[i][k] - t[i][k]));
  EXPECT_GT(differ, 1e-4);
  cv::Mat symmetric = patches[0].clone();
  cv::Mat left = symmetric(cv::Rect(0, 0, 20, 33)), right;
  cv::flip(left, right, 1);
  right.copyTo(symmetric(cv::Rect(20, 0, 20, 33)));
  const auto a = averaged.CountProbabilities({symmetric});
  const auto b = single.CountProbabilities({symmetric});
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(a[0][k], b[0][k], 1e-6);
}

TEST(CnnCounter, PriorWeightMultipliesByClassFrequencies) {
  const fs::path dir = TempDir("prior");
  torch::manual_seed(3);
  nn::ResNet net(nn::ResNetOptions{18, 4, 3, 7});
  const std::vector<int> class_counts{10, 40, 20, 10, 0, 10, 10};
  nn::SaveCheckpoint(*net,
                     {{"kind", "counter"}, {"architecture", net->options().ToJson()}, {"input_size", 32},
                      {"train_class_counts", class_counts}},
                     dir / "counter.pt");
  cv::Mat patch(30, 30, CV_8UC3);
  cv::randu(patch, 0, 255);
  const auto plain = CnnCounter(dir / "counter.pt", 1, CnnCounterOptions{false, 0.0}).CountProbabilities({patch})[0];
  const auto weighted = CnnCounter(dir / "counter.pt", 1, CnnCounterOptions{false, 0.5}).CountProbabilities({patch})[0];
  // p'(k) is p(k) sqrt(n_k) renormalised; an unseen count is weighted as seen once.
  std::vector<double> expected;
  double sum = 0;
  for (int k = 0; k < 7; ++k) sum += expected.emplace_back(plain[k] * std::sqrt(std::max(1, class_counts[k])));
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(weighted[k], expected[k] / sum, 1e-5) << "count " << k;
  EXPECT_THROW(CnnCounter(dir / "counter.pt", 1, CnnCounterOptions{false, 2.0}), Error);
}

TEST(CnnCounter, PriorWeightUndoesTheBalancePowerTrainedWith) {
  // A network trained on the data's own frequencies (balance power 0) has
  // learnt their prior: weight 1 leaves it as it is, weight 0 divides it out.
  const fs::path dir = TempDir("prior_balance");
  torch::manual_seed(4);
  nn::ResNet net(nn::ResNetOptions{18, 4, 3, 7});
  const std::vector<int> class_counts{10, 40, 20, 10, 5, 10, 10};
  for (const double balance : {0.0, 0.5}) {
    nn::SaveCheckpoint(*net,
                       {{"kind", "counter"}, {"architecture", net->options().ToJson()}, {"input_size", 32},
                        {"train_class_counts", class_counts}, {"balance_power", balance}},
                       dir / ("b" + std::to_string(balance) + ".pt"));
  }
  nn::SaveCheckpoint(*net,
                     {{"kind", "counter"}, {"architecture", net->options().ToJson()}, {"input_size", 32},
                      {"train_class_counts", class_counts}},
                     dir / "full.pt");  // no balance_power: trained before the option, fully balanced
  cv::Mat patch(30, 30, CV_8UC3);
  cv::randu(patch, 0, 255);
  const auto probabilities = [&](const std::string& file, double weight) {
    return CnnCounter(dir / file, 1, CnnCounterOptions{false, weight}).CountProbabilities({patch})[0];
  };
  const auto raw = probabilities("full.pt", 0.0);
  const auto check = [&](const std::vector<float>& p, double exponent) {
    std::vector<double> expected;
    double sum = 0;
    for (int k = 0; k < 7; ++k) sum += expected.emplace_back(raw[k] * std::pow(class_counts[k], exponent));
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(p[k], expected[k] / sum, 1e-5) << "count " << k;
  };
  check(probabilities("b0.000000.pt", 1.0), 0);
  check(probabilities("b0.000000.pt", 0.0), -1);
  check(probabilities("b0.500000.pt", 0.0), -0.5);
  check(probabilities("b0.500000.pt", 0.5), 0);
  // An ensemble of members trained with different powers assumes no one prior.
  EXPECT_THROW(nn::WriteCounterEnsemble({dir / "b0.000000.pt", dir / "full.pt"}, dir / "mixed.pt"), Error);
  nn::WriteCounterEnsemble({dir / "b0.000000.pt", dir / "b0.000000.pt"}, dir / "same.pt");
  EXPECT_EQ(nn::CounterBalancePower(nn::ReadCheckpointHeader(dir / "same.pt", "counter")), 0.0);
  check(probabilities("same.pt", 0.0), -1);
}

TEST(CnnCounter, EnsembleAveragesItsMembers) {
  const fs::path dir = TempDir("ensemble");
  std::vector<fs::path> files;
  for (int i = 0; i < 2; ++i) {
    torch::manual_seed(10 + i);
    nn::ResNet net(nn::ResNetOptions{18, 4, 3, 7});
    files.push_back(dir / ("m" + std::to_string(i) + ".pt"));
    nn::SaveCheckpoint(*net,
                       {{"kind", "counter"}, {"architecture", net->options().ToJson()}, {"input_size", 32 + 16 * i},
                        {"train_class_counts", std::vector<int>{1, 2, 3, 4, 5, 6, 7}}},
                       files.back());
  }
  nn::WriteCounterEnsemble(files, dir / "ensemble.pt");
  std::mt19937_64 rng(3);
  const std::vector<cv::Mat> patches{DiscPatch(1, rng), DiscPatch(2, rng)};
  CnnCounter ensemble(dir / "ensemble.pt", 1);
  EXPECT_EQ(ensemble.num_networks(), 2);
  const auto p = ensemble.CountProbabilities(patches);
  const auto a = CnnCounter(files[0], 1).CountProbabilities(patches);
  const auto b = CnnCounter(files[1], 1).CountProbabilities(patches);
  for (size_t i = 0; i < patches.size(); ++i)
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(p[i][k], 0.5 * (a[i][k] + b[i][k]), 1e-6);
  // A reader of single counters loads the ensemble file as its first network.
  nn::ResNet first(nn::ResNetOptions{18, 4, 3, 7});
  nn::LoadCheckpointWeights(*first, dir / "ensemble.pt");
  first->eval();
  const auto as_single = CnnCounter(files[0], 1, CnnCounterOptions{false}).CountProbabilities({patches[0]})[0];
  torch::NoGradGuard no_grad;
  const torch::Tensor direct =
      torch::softmax(first->forward(nn::ImagesToTensor({nn::LetterboxPatch(patches[0], 32)})), 1);
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(direct[0][k].item<float>(), as_single[k], 1e-6);
  // Class counts add up for the prior; an ensemble is not a member, nor is one file an ensemble.
  EXPECT_EQ(nn::ReadCheckpointHeader(dir / "ensemble.pt", "counter").at("train_class_counts"),
            (std::vector<int>{2, 4, 6, 8, 10, 12, 14}));
  EXPECT_THROW(nn::WriteCounterEnsemble({dir / "ensemble.pt", files[0]}, dir / "twice.pt"), Error);
  EXPECT_THROW(nn::WriteCounterEnsemble({files[0]}, dir / "one.pt"), Error);
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
