#include "orchard/nn/models.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/losses.h"
#include "orchard/nn/patch_input.h"
#include "orchard/nn/trainer.h"
#include "orchard/core/test_util.h"

namespace orchard::nn {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("nn_test_" + name); }

TEST(Models, ResNetShapes) {
  for (int depth : {18, 34, 50}) {
    ResNet net(ResNetOptions{depth, 4, 3, 7});
    net->eval();
    EXPECT_EQ(net->forward(torch::rand({2, 3, 64, 64})).sizes(), (std::vector<int64_t>{2, 7})) << depth;
  }
  EXPECT_THROW(ResNet(ResNetOptions{19, 4, 3, 7}), Error);
}

TEST(Models, ResNetDensityHeadIsASecondOutput) {
  ResNetOptions options{18, 4, 3, 7};
  options.density_head = true;
  ResNet net(options);
  net->eval();
  const torch::Tensor x = torch::rand({2, 3, 64, 64});
  auto [logits, density] = net->ForwardWithDensity(x);
  EXPECT_EQ(density.sizes(), (std::vector<int64_t>{2, 1, 8, 8}));  // 1/8 of the input
  EXPECT_GE(density.min().item<float>(), 0.0f);
  EXPECT_TRUE(torch::equal(logits, net->forward(x)));  // the classifier does not depend on the head
  EXPECT_TRUE(ResNetOptions::FromJson(options.ToJson()).density_head);
  // Files written before the head existed have no key and no head.
  nlohmann::json old = ResNetOptions{18, 4, 3, 7}.ToJson();
  EXPECT_FALSE(old.contains("density_head"));
  EXPECT_FALSE(ResNetOptions::FromJson(old).density_head);
  ResNet plain(ResNetOptions{18, 4, 3, 7});
  EXPECT_THROW(plain->ForwardWithDensity(x), Error);
  EXPECT_LT(CountParameters(*plain), CountParameters(*net));
}

TEST(PatchInput, LetterboxPointAndAugmentationMovePointsWithThePixels) {
  // A 40x20 patch letterboxed to 64: scale 1.6, placed at rows 16..48.
  EXPECT_NEAR(LetterboxPoint({40, 20}, 64, {0, 0}).y, 16 + 0.5 * 1.6 - 0.5, 1e-5);
  EXPECT_NEAR(LetterboxPoint({40, 20}, 64, {39, 19}).x, 39.5 * 1.6 - 0.5, 1e-5);  // the last pixel's centre
  // A bright pixel and its point stay together through flips and rotations.
  cv::Mat image(64, 64, CV_8UC3, cv::Scalar::all(0));
  cv::circle(image, {15, 40}, 3, cv::Scalar::all(255), -1);
  PatchAugmentation augmentation;
  augmentation.max_rotation_deg = 20;
  augmentation.max_blur_sigma = 0;
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 8; ++trial) {
    std::vector<cv::Point2f> points{{15, 40}};
    const cv::Mat out = AugmentPatch(image, augmentation, rng, &points);
    const cv::Point p(cvRound(points[0].x), cvRound(points[0].y));
    EXPECT_GT(out.at<cv::Vec3b>(p)[0], 200) << "trial " << trial << " point " << points[0];
  }
}

TEST(Models, UNetKeepsResolution) {
  UNetOptions options;
  options.base_width = 4;
  UNet net(options);
  net->eval();
  EXPECT_EQ(net->forward(torch::rand({1, 3, 32, 48})).sizes(), (std::vector<int64_t>{1, 2, 32, 48}));
  options.blocks = 3;
  UNet small(options);
  small->eval();
  EXPECT_EQ(small->forward(torch::rand({1, 3, 8, 12})).sizes(), (std::vector<int64_t>{1, 2, 8, 12}));
}

TEST(Losses, InverseFrequencyWeights) {
  auto w = InverseFrequencyWeights({900, 100});
  // 1/900 : 1/100 normalised = 0.1 : 0.9.
  EXPECT_NEAR(w[0], 0.1, 1e-12);
  EXPECT_NEAR(w[1], 0.9, 1e-12);
  EXPECT_THROW(InverseFrequencyWeights({0, 0}), Error);
}

TEST(Losses, FocalLossKnownValue) {
  // One positive with logit 0: p = 0.5, ce = ln 2, (1-p)^2 = 0.25, alpha 0.25.
  torch::Tensor loss = SigmoidFocalLoss(torch::zeros({1}), torch::ones({1}));
  EXPECT_NEAR(loss.item<double>(), 0.25 * 0.25 * std::log(2.0), 1e-6);
  // gamma 0 and alpha 0.5 is half the binary cross-entropy.
  loss = SigmoidFocalLoss(torch::tensor({2.0f}), torch::zeros({1}), 0.5, 0.0);
  EXPECT_NEAR(loss.item<double>(), 0.5 * std::log(1 + std::exp(2.0)), 1e-5);
}

// A tiny task: classify whether a 16x16 image is bright on its left or right half.
class HalvesTask : public TrainingTask {
 public:
  explicit HalvesTask(ResNet net) : net_(net) {
    torch::manual_seed(3);
    images_ = torch::rand({64, 1, 16, 16}) * 0.3;
    labels_ = torch::randint(0, 2, {64}, torch::kLong);
    for (int i = 0; i < 64; ++i) {
      const int64_t half = labels_[i].item<int64_t>();
      images_[i].narrow(2, half * 8, 8) += 0.7;
    }
  }
  size_t NumTrain() const override { return 48; }
  torch::Tensor TrainLoss(const std::vector<size_t>& indices, std::mt19937_64&) override {
    auto idx = torch::tensor(std::vector<int64_t>(indices.begin(), indices.end()), torch::kLong);
    return torch::cross_entropy_loss(net_->forward(images_.index_select(0, idx)), labels_.index_select(0, idx));
  }
  double Validate() override {
    auto pred = net_->forward(images_.narrow(0, 48, 16)).argmax(1);
    return pred.eq(labels_.narrow(0, 48, 16)).to(torch::kFloat64).mean().item<double>();
  }
  std::string MetricName() const override { return "accuracy"; }
  void SaveBest() override { ++saved; }
  int saved = 0;

 private:
  ResNet net_;
  torch::Tensor images_, labels_;
};

// Training that runs every epoch (no early stop) without a progress bar.
TrainerOptions QuietOptions(int epochs, int batch_size) {
  TrainerOptions options;
  options.max_epochs = epochs;
  options.patience = 100;
  options.batch_size = batch_size;
  options.progress = false;
  return options;
}

TEST(Trainer, LossFallsAndResumes) {
  TrainerOptions options = QuietOptions(6, 8);
  options.state_dir = TempDir("resume");
  SetUpTorch(options);
  ResNet net(ResNetOptions{18, 4, 1, 2});
  HalvesTask task(net);
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(1e-2));
  TrainingRecord record = Train(task, *net, adam, options);
  ASSERT_EQ(record.epochs_run, 6);
  EXPECT_LT(record.train_loss.back(), record.train_loss.front());
  EXPECT_GE(task.saved, 1);
  // A second run with the same state folder and more epochs continues from epoch 6.
  options.max_epochs = 7;
  TrainingRecord resumed = Train(task, *net, adam, options);
  EXPECT_EQ(resumed.epochs_run, 7);
  EXPECT_EQ(resumed.train_loss.size(), 7u);
  EXPECT_DOUBLE_EQ(resumed.train_loss[0], record.train_loss[0]);
}

TEST(Trainer, WeightAverageArithmetic) {
  torch::nn::BatchNorm1d bn(1);
  torch::NoGradGuard no_grad;
  bn->weight.fill_(1.0);
  bn->running_mean.fill_(0.0);
  WeightAverage average(*bn, 0.5);
  // First update: the decay warms up to min(0.5, 1 / 10) = 0.1.
  bn->weight.fill_(3.0);
  bn->running_mean.fill_(2.0);
  bn->num_batches_tracked.fill_(7);
  average.Update();
  // Second update: min(0.5, 2 / 11) = 2 / 11.
  bn->weight.fill_(5.0);
  average.Update();
  EXPECT_EQ(average.updates(), 2);
  const double w1 = 0.1 * 1.0 + 0.9 * 3.0;
  const double d2 = 2.0 / 11.0;
  average.Swap();
  EXPECT_NEAR(bn->weight.item<double>(), d2 * w1 + (1 - d2) * 5.0, 1e-6);
  EXPECT_NEAR(bn->running_mean.item<double>(), d2 * (0.9 * 2.0) + (1 - d2) * 2.0, 1e-6);  // buffers averaged too
  EXPECT_EQ(bn->num_batches_tracked.item<int64_t>(), 7);                                  // integer buffers copied
  average.Swap();  // back to the live weights
  EXPECT_DOUBLE_EQ(bn->weight.item<double>(), 5.0);
  // Saved and loaded, the average is the same.
  torch::serialize::OutputArchive out;
  average.Save(out);
  std::ostringstream bytes;
  out.save_to(bytes);
  WeightAverage reloaded(*bn, 0.5);
  torch::serialize::InputArchive in;
  std::istringstream read(bytes.str());
  in.load_from(read);
  reloaded.Load(in);
  EXPECT_EQ(reloaded.updates(), 2);
  reloaded.Swap();
  EXPECT_NEAR(bn->weight.item<double>(), d2 * w1 + (1 - d2) * 5.0, 1e-6);
}

TEST(Trainer, WeightAverageTrainsAndResumes) {
  TrainerOptions options = QuietOptions(3, 8);
  options.ema_decay = 0.9;
  options.state_dir = TempDir("resume_ema");
  SetUpTorch(options);
  ResNet net(ResNetOptions{18, 4, 1, 2});
  HalvesTask task(net);
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(1e-2));
  TrainingRecord record = Train(task, *net, adam, options);
  ASSERT_EQ(record.epochs_run, 3);
  EXPECT_TRUE(fs::exists(options.state_dir / "ema.pt"));
  options.max_epochs = 4;
  EXPECT_EQ(Train(task, *net, adam, options).epochs_run, 4);
}

TEST(Trainer, CosineLearningRate) {
  TrainerOptions options = QuietOptions(4, 16);
  options.cosine_lr = true;
  SetUpTorch(options);
  ResNet net(ResNetOptions{18, 4, 1, 2});
  HalvesTask task(net);
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(1e-2));
  Train(task, *net, adam, options);
  // The last epoch (4 of 4) ran at 1e-2 * 0.5 (1 + cos(3 pi / 4)).
  EXPECT_NEAR(adam.param_groups()[0].options().get_lr(), 1e-2 * 0.5 * (1 + std::cos(3 * M_PI / 4)), 1e-12);
}

TEST(Checkpoint, ReloadGivesIdenticalOutputsAndRejectsMismatch) {
  const fs::path dir = TempDir("ckpt");
  ResNetOptions arch{18, 4, 3, 7};
  ResNet net(arch);
  net->eval();
  SaveCheckpoint(*net, {{"kind", "counter"}, {"architecture", arch.ToJson()}}, dir / "m.pt");

  nlohmann::json header = ReadCheckpointHeader(dir / "m.pt", "counter");
  ResNet loaded(ResNetOptions::FromJson(header["architecture"]));
  LoadCheckpointWeights(*loaded, dir / "m.pt");
  loaded->eval();
  torch::Tensor x = torch::rand({2, 3, 40, 40});
  EXPECT_TRUE(torch::equal(net->forward(x), loaded->forward(x)));

  EXPECT_THROW(ReadCheckpointHeader(dir / "m.pt", "unet"), Error);
  EXPECT_THROW(ReadCheckpointHeader(dir / "missing.pt", "counter"), Error);
  std::ofstream(dir / "junk.pt") << "not a model";
  EXPECT_THROW(ReadCheckpointHeader(dir / "junk.pt", "counter"), Error);
  ResNet wider(ResNetOptions{18, 8, 3, 7});
  EXPECT_THROW(LoadCheckpointWeights(*wider, dir / "m.pt"), Error);
  UNet unet(UNetOptions{4});
  EXPECT_THROW(LoadCheckpointWeights(*unet, dir / "m.pt"), Error);
}

TEST(CounterTraining, BalancedIndicesUpSampleByThePower) {
  std::vector<int> labels(100, 1);
  labels.insert(labels.end(), 4, 3);  // indices 100..103
  auto count = [](const std::vector<size_t>& indices, size_t from, size_t to) {
    return std::count_if(indices.begin(), indices.end(), [&](size_t i) { return i >= from && i < to; });
  };
  const std::vector<size_t> full = BalancedIndices(labels, 1.0);  // the study's: as large as the largest
  EXPECT_EQ(count(full, 0, 100), 100);
  EXPECT_EQ(count(full, 100, 104), 100);
  for (size_t i = 100; i < 104; ++i) EXPECT_EQ(std::count(full.begin(), full.end(), i), 25);
  const std::vector<size_t> half = BalancedIndices(labels, 0.5);  // sqrt(100 * 4) = 20
  EXPECT_EQ(count(half, 0, 100), 100);
  EXPECT_EQ(count(half, 100, 104), 20);
  const std::vector<size_t> none = BalancedIndices(labels, 0.0);  // the data as it is
  EXPECT_EQ(none.size(), 104u);
  CounterTrainingOptions o;
  o.balance_power = 1.5;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace orchard::nn
