#include "orchard/detect/gmm/gmm_detector.h"

#include <filesystem>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"

namespace orchard {
namespace {

struct Scene {
  cv::Mat bgr;
  std::vector<Box> apples;
};

// Red discs (apples) on green foliage with brown stripes and noise.
Scene RedDiscsOnGreen(unsigned seed, int w = 320, int h = 240) {
  std::mt19937 rng(seed);
  Scene s;
  s.bgr = cv::Mat(h, w, CV_8UC3, cv::Scalar(40, 130, 60));
  cv::line(s.bgr, {0, h / 4}, {w, h / 2}, cv::Scalar(40, 60, 90), 6);
  const std::vector<cv::Point> centres = {{60, 60}, {200, 70}, {120, 170}, {260, 180}};
  for (const cv::Point& c : centres) {
    const int r = 18 + static_cast<int>(rng() % 6);
    cv::circle(s.bgr, c, r, cv::Scalar(35, 35, 190), cv::FILLED);
    s.apples.push_back({double(c.x - r), double(c.y - r), double(c.x + r + 1), double(c.y + r + 1)});
  }
  cv::Mat noise(h, w, CV_8UC3);
  cv::RNG cvrng(seed);
  cvrng.fill(noise, cv::RNG::NORMAL, 0, 8);
  cv::Mat noisy;
  s.bgr.convertTo(noisy, CV_16SC3);
  cv::Mat n16;
  noise.convertTo(n16, CV_16SC3);
  noisy += n16;
  noisy.convertTo(s.bgr, CV_8UC3);
  return s;
}

class GmmDetectorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("orchard_gmm_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    for (int i = 0; i < 2; ++i) {
      scenes_.push_back(RedDiscsOnGreen(i + 1));
      images_.push_back(dir_ / ("train_" + std::to_string(i) + ".png"));
      WriteImageAtomic(images_.back(), scenes_.back().bgr);
    }
    options_.num_classes = 5;
    options_.min_clicks_per_class = 1;
  }
  void TearDown() override { fs::remove_all(dir_); }

  void ExpectFindsTheDiscs(const ColourModel& model, bool reference) {
    GmmDetectorOptions options;
    options.reference_slic = reference;
    GmmDetector detector(model, options);
    const Scene test = RedDiscsOnGreen(42);
    const FrameDetection d = detector.Detect(test.bgr);
    ASSERT_EQ(d.blobs.size(), test.apples.size());
    for (const Box& apple : test.apples) {
      double best = 0;
      for (const Blob& b : d.blobs) best = std::max(best, IoU(apple, b.box));
      EXPECT_GT(best, 0.75);
    }
    for (const Blob& b : d.blobs) {
      EXPECT_GT(b.score, 0.5);
      EXPECT_LE(b.score, 1.0);
      EXPECT_EQ(d.labels(static_cast<int>(b.centroid.y), static_cast<int>(b.centroid.x)), b.id);
    }
    EXPECT_EQ(d.mask.size(), test.bgr.size());
  }

  fs::path dir_;
  std::vector<Scene> scenes_;
  std::vector<fs::path> images_;
  ColourTrainingOptions options_;
};

TEST_F(GmmDetectorTest, UserSupervisedFromClicksFindsRedDiscs) {
  const std::vector<Click> clicks = {{"train_0.png", 60, 60}, {"train_1", 200, 70}};
  const ColourModel model = TrainColourModelFromClicks(images_, clicks, options_);
  EXPECT_GE(model.NumApple(), 1);
  ExpectFindsTheDiscs(model, false);
  ExpectFindsTheDiscs(model, true);
}

// The fast path works at 0.375 scale: redrawing the blob edges at frame
// resolution brings the boxes and pixel counts closer to the discs.
TEST_F(GmmDetectorTest, EdgesRedrawnAtFrameResolutionFitTheDiscsBetter) {
  const std::vector<Click> clicks = {{"train_0.png", 60, 60}, {"train_1", 200, 70}};
  const ColourModel model = TrainColourModelFromClicks(images_, clicks, options_);
  const Scene test = RedDiscsOnGreen(42);
  double iou[2] = {0, 0}, area_error[2] = {0, 0};
  for (int refine = 0; refine < 2; ++refine) {
    GmmDetectorOptions options;
    options.refine_edges = refine == 1;
    GmmDetector detector(model, options);
    const FrameDetection d = detector.Detect(test.bgr);
    ASSERT_EQ(d.blobs.size(), test.apples.size());
    for (const Box& apple : test.apples) {
      const Blob* best = nullptr;
      for (const Blob& b : d.blobs)
        if (!best || IoU(apple, b.box) > IoU(apple, best->box)) best = &b;
      iou[refine] += IoU(apple, best->box) / test.apples.size();
      const double disc = M_PI * 0.25 * apple.Width() * apple.Width();
      area_error[refine] += std::abs(best->pixels - disc) / disc / test.apples.size();
      // Measured at frame resolution: labels and pixel count agree (without
      // the refinement the count is scaled from working resolution).
      if (refine) EXPECT_EQ(cv::countNonZero(d.labels == best->id), best->pixels);
    }
    EXPECT_EQ(cv::countNonZero(d.mask), cv::countNonZero(d.labels > 0));
  }
  // Measured: mean box IoU 0.878 -> 0.983, area error 0.110 -> 0.075.
  EXPECT_GT(iou[1], iou[0]);
  EXPECT_GT(iou[1], 0.9);
  EXPECT_LT(area_error[1], area_error[0]);
}

// Blob 1 fell apart at frame resolution into two pieces and shed a sliver;
// blob 2 is whole. Working resolution is half the frame's.
TEST(RegroupBlobsAtFrameResolution, PiecesBecomeBlobsSliversAreDropped) {
  FrameDetection d;
  d.labels = cv::Mat1i(40, 60, 0);
  d.labels(cv::Rect(4, 4, 6, 5)).setTo(1);    // 30 px
  d.labels(cv::Rect(12, 4, 4, 5)).setTo(1);   // 20 px, 2 px away: a piece of its own
  d.labels(cv::Rect(4, 11, 2, 1)).setTo(1);   // 2 px sliver
  d.labels(cv::Rect(40, 20, 10, 10)).setTo(2);  // 100 px
  cv::compare(d.labels, 0, d.mask, cv::CMP_GT);
  Blob b1, b2;
  b1.id = 1, b1.box = {4, 4, 16, 12}, b1.pixels = 52;
  b2.id = 2, b2.box = {40, 20, 50, 30}, b2.pixels = 100;
  d.blobs = {b1, b2};
  cv::Mat1f scores(20, 30, 0.8f);
  scores.colRange(7, 30).setTo(0.4f);  // frame columns 14.. score 0.4
  RegroupBlobsAtFrameResolution(scores, /*min_pixels=*/5, &d);
  ASSERT_EQ(d.blobs.size(), 3u);
  const Box expected[3] = {{4, 4, 10, 9}, {12, 4, 16, 9}, {40, 20, 50, 30}};
  const int pixels[3] = {30, 20, 100};
  const double score[3] = {0.8, (2 * 5 * 0.8 + 2 * 5 * 0.4) / 20, 0.4};
  for (int i = 0; i < 3; ++i) {
    const Blob& b = d.blobs[i];
    EXPECT_EQ(b.id, i + 1);
    EXPECT_EQ(b.box.x1, expected[i].x1);
    EXPECT_EQ(b.box.y1, expected[i].y1);
    EXPECT_EQ(b.box.x2, expected[i].x2);
    EXPECT_EQ(b.box.y2, expected[i].y2);
    EXPECT_EQ(b.pixels, pixels[i]);
    EXPECT_EQ(cv::countNonZero(d.labels == b.id), pixels[i]);
    EXPECT_NEAR(b.centroid.x, (expected[i].x1 + expected[i].x2 - 1) / 2, 1e-9);
    EXPECT_NEAR(b.centroid.y, (expected[i].y1 + expected[i].y2 - 1) / 2, 1e-9);
    EXPECT_NEAR(b.score, score[i], 1e-6);
  }
  EXPECT_EQ(d.labels(11, 4), 0);  // the sliver is gone from labels and mask
  EXPECT_EQ(d.mask(11, 4), 0);
  EXPECT_EQ(cv::countNonZero(d.mask), 150);
  EXPECT_EQ(cv::countNonZero(d.labels < 0), 0);
}

TEST_F(GmmDetectorTest, ClickAgreementMarksOnlyClassesSeveralClicksShare) {
  options_.min_clicks_per_class = 2;
  // One click: no class has two votes, a clear error.
  EXPECT_THROW(TrainColourModelFromClicks(images_, {{"train_0.png", 60, 60}}, options_), Error);
  // Two clicks on red discs agree on the red class.
  const ColourModel model =
      TrainColourModelFromClicks(images_, {{"train_0.png", 60, 60}, {"train_1.png", 120, 170}}, options_);
  EXPECT_EQ(model.NumApple(), 1);
  ExpectFindsTheDiscs(model, false);
}

TEST_F(GmmDetectorTest, SemiSupervisedFromAnnotationsFindsRedDiscs) {
  Dataset train;
  for (size_t i = 0; i < images_.size(); ++i) {
    AnnotatedImage image;
    image.name = images_[i].filename().string();
    image.path = images_[i];
    image.width = 320;
    image.height = 240;
    for (const Box& b : scenes_[i].apples) image.objects.push_back({b});
    train.images.push_back(image);
  }
  // Apple classes chosen for the best training F1 (default) and by a fixed fraction.
  const ColourModel model = TrainColourModelFromAnnotations(train, options_);
  EXPECT_NE(model.apple_rule.find("best training apple-pixel F1"), std::string::npos) << model.apple_rule;
  ExpectFindsTheDiscs(model, false);
  options_.apple_pixel_fraction = 0.5;
  ExpectFindsTheDiscs(TrainColourModelFromAnnotations(train, options_), false);
}

TEST_F(GmmDetectorTest, ModelFileRoundTripAndBadFiles) {
  const ColourModel model = TrainColourModelFromClicks(images_, {{"train_0.png", 60, 60}}, options_);
  const fs::path path = dir_ / "model.json";
  WriteColourModel(model, path);
  const ColourModel back = ReadColourModel(path);
  EXPECT_EQ(back.apple, model.apple);
  EXPECT_NEAR(back.mixture.components[2].mean[1], model.mixture.components[2].mean[1], 1e-9);

  std::string text = ReadTextFile(path);
  const size_t at = text.find("\"version\": 1");
  ASSERT_NE(at, std::string::npos);
  WriteTextFileAtomic(dir_ / "v2.json", text.substr(0, at) + "\"version\": 2" + text.substr(at + 12));
  try {
    ReadColourModel(dir_ / "v2.json");
    FAIL() << "a version-2 model was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
  }
  WriteTextFileAtomic(dir_ / "corrupt.json", text.substr(0, text.size() / 2));
  EXPECT_THROW(ReadColourModel(dir_ / "corrupt.json"), Error);
  EXPECT_THROW(ReadColourModel(dir_ / "missing.json"), Error);
}

// A rare, broad apple class and a common, narrow leaf class: between them the
// KL rule (sub-mixtures renormalised, so each group has prior 1) says apple,
// while the true prior (2% apple) puts the apple posterior near 0.02.
TEST(ColourClassifierTest, ApplePosteriorGateRemovesWhatOnlyTheRenormalisedKlCallsApple) {
  ColourModel model;
  Gaussian apple, leaf;
  apple.mean = Eigen::Vector3d(50, 40, 20);
  apple.covariance = Eigen::Vector3d(100, 400, 100).asDiagonal();
  leaf.mean = Eigen::Vector3d(50, -10, 20);
  leaf.covariance = Eigen::Matrix3d::Identity() * 25;
  model.mixture.components = {apple, leaf};
  model.mixture.weights = {0.02, 0.98};
  model.apple = {true, false};
  const Eigen::Matrix3d small = Eigen::Matrix3d::Identity();
  bool is_apple = false;
  float posterior = -1;
  // Between the classes: KL costs 9.14 (apple) < 9.39 (leaf); posterior 0.024.
  ColourClassifier(model, 0.0).Classify(Eigen::Vector3d(50, 5, 20), small, &is_apple, &posterior);
  EXPECT_TRUE(is_apple);
  EXPECT_NEAR(posterior, 0.024, 0.002);
  ColourClassifier(model, kDefaultMinApplePosterior).Classify(Eigen::Vector3d(50, 5, 20), small, &is_apple, &posterior);
  EXPECT_FALSE(is_apple);
  // On the apple class both rules agree.
  ColourClassifier(model, kDefaultMinApplePosterior).Classify(Eigen::Vector3d(50, 40, 20), small, &is_apple, &posterior);
  EXPECT_TRUE(is_apple);
  EXPECT_GT(posterior, 0.9);
  // On the leaf class neither does.
  ColourClassifier(model, 0.0).Classify(Eigen::Vector3d(50, -10, 20), small, &is_apple, &posterior);
  EXPECT_FALSE(is_apple);
  GmmDetectorOptions options;
  options.min_apple_posterior = 1;
  EXPECT_THROW(options.Check(), Error);
}

TEST_F(GmmDetectorTest, BadInputGivesClearErrors) {
  // A click on an image that is not among the training images, or outside it.
  EXPECT_THROW(TrainColourModelFromClicks(images_, {{"nope.png", 5, 5}}, options_), Error);
  EXPECT_THROW(TrainColourModelFromClicks(images_, {{"train_0.png", 500, 5}}, options_), Error);
  EXPECT_THROW(TrainColourModelFromClicks(images_, {}, options_), Error);
  WriteTextFileAtomic(dir_ / "clicks.json", "[]");
  EXPECT_THROW(ReadClicks(dir_ / "clicks.json"), Error);
  WriteTextFileAtomic(dir_ / "clicks.json", "{\"image\": 3}");
  EXPECT_THROW(ReadClicks(dir_ / "clicks.json"), Error);
  // An empty image.
  const ColourModel model = TrainColourModelFromClicks(images_, {{"train_0.png", 60, 60}}, options_);
  GmmDetector detector(model, {});
  EXPECT_THROW(detector.Detect(cv::Mat()), Error);
  // Annotations without apples: no apple class.
  Dataset empty;
  AnnotatedImage image;
  image.name = "train_0.png";
  image.path = images_[0];
  empty.images.push_back(image);
  EXPECT_THROW(TrainColourModelFromAnnotations(empty, options_), Error);
}

}  // namespace
}  // namespace orchard
