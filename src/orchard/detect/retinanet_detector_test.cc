#include "orchard/detect/retinanet_detector.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/models_dir.h"
#include "orchard/core/test_util.h"
#include "orchard/data/split.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/detection_training.h"

namespace orchard {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("retinanet_test_" + name); }

// Red discs on a mottled green background, with their boxes.
nn::BoxSample DiscImage(std::mt19937_64& rng, const std::string& name) {
  nn::BoxSample s;
  s.name = name + ".png";
  s.photo = name;
  s.bgr = cv::Mat(64, 96, CV_8UC3);
  cv::randu(s.bgr, cv::Scalar(20, 90, 20), cv::Scalar(60, 150, 60));
  for (int i = 0; i < 3; ++i) {
    const cv::Point c(10 + i * 30 + static_cast<int>(rng() % 12), 10 + static_cast<int>(rng() % 44));
    cv::circle(s.bgr, c, 8, cv::Scalar(40, 40, 190), cv::FILLED);
    s.boxes.push_back(Box{c.x - 8.5, c.y - 8.5, c.x + 8.5, c.y + 8.5});
  }
  return s;
}

TEST(RetinaNetDetector, TrainsTinyNetworkAndFindsDiscs) {
  const fs::path dir = TempDir("train");
  std::mt19937_64 rng(5);
  std::vector<nn::BoxSample> samples;
  for (int i = 0; i < 12; ++i) samples.push_back(DiscImage(rng, "photo" + std::to_string(i)));
  nn::RetinaNetTrainingOptions options;
  options.architecture.base_width = 4;
  options.architecture.fpn_channels = 16;
  options.architecture.head_convs = 1;
  options.tile = 64;
  options.min_scale = 0.9;
  options.max_scale = 1.1;
  options.learning_rate = 3e-3;
  options.trainer.max_epochs = 8;
  options.trainer.patience = 8;
  options.trainer.batch_size = 8;
  options.trainer.samples_per_epoch = 32;
  options.trainer.threads = 1;
  options.trainer.progress = false;
  // With validation photos: the best epoch by AP50 is kept.
  const nn::RetinaNetTrainingResult validated =
      nn::TrainRetinaNet(samples, options, {{"source", "test"}}, dir / "v.pt");
  EXPECT_GT(validated.record.best_metric, 0.3) << "validation AP50 of a tiny RetinaNet on red discs";
  EXPECT_EQ(validated.train_images + validated.validation_images, 12);
  EXPECT_GT(validated.validation_images, 0);
  // On every photo, longer: the last epoch is kept.
  options.validation_fraction = 0;
  options.trainer.max_epochs = 40;
  options.trainer.samples_per_epoch = 64;
  const nn::RetinaNetTrainingResult result = nn::TrainRetinaNet(samples, options, {{"source", "test"}}, dir / "r.pt");
  EXPECT_EQ(result.train_images, 12);
  EXPECT_EQ(result.record.epochs_run, 40);
  EXPECT_LT(result.record.train_loss.back(), 0.5 * result.record.train_loss.front());

  RetinaNetDetectorOptions detector_options;
  detector_options.score_threshold = 0.3;
  detector_options.blobs.min_pixels = 20;
  detector_options.threads = 1;
  RetinaNetDetector detector(dir / "r.pt", detector_options);
  const nn::BoxSample test = DiscImage(rng, "test");
  const FrameDetection detection = detector.Detect(test.bgr);
  ASSERT_EQ(detection.mask.size(), test.bgr.size());
  ASSERT_EQ(detection.labels.size(), test.bgr.size());
  // Each disc is found as one blob whose box overlaps it.
  int found = 0;
  for (const Box& truth : test.boxes) {
    for (const Blob& blob : detection.blobs) found += IoU(truth, blob.box) >= 0.5 ? 1 : 0;
  }
  EXPECT_GE(found, 2);

  EXPECT_LE(detection.blobs.size(), 5u);
  for (size_t i = 0; i < detection.blobs.size(); ++i) {
    const Blob& blob = detection.blobs[i];
    EXPECT_EQ(blob.id, static_cast<int>(i) + 1);
    EXPECT_EQ(cv::countNonZero(detection.labels == blob.id), blob.pixels);
    if (i > 0) {
      EXPECT_LE(blob.score, detection.blobs[i - 1].score);
    }
  }
  EXPECT_EQ(cv::countNonZero(detection.mask), cv::countNonZero(detection.labels > 0));
  // A frame at half size, enlarged twice by the detector: about the same
  // boxes, in the small frame's pixels.
  RetinaNetDetectorOptions scaled_options = detector_options;
  scaled_options.input_scale = 2;
  scaled_options.blobs.min_pixels = 5;
  RetinaNetDetector scaled(dir / "r.pt", scaled_options);
  cv::Mat half;
  cv::resize(test.bgr, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  const FrameDetection small = scaled.Detect(half);
  ASSERT_EQ(small.mask.size(), half.size());
  ASSERT_GE(small.blobs.size(), 1u);
  ASSERT_GE(detection.blobs.size(), 1u);
  const Box& b = small.blobs[0].box;
  double best = 0;
  for (const Blob& blob : detection.blobs) best = std::max(best, IoU(Box{2 * b.x1, 2 * b.y1, 2 * b.x2, 2 * b.y2}, blob.box));
  EXPECT_GT(best, 0.6);
  // Reloading gives identical boxes.
  RetinaNetDetector again(dir / "r.pt", detector_options);
  const FrameDetection repeat = again.Detect(test.bgr);
  ASSERT_EQ(repeat.blobs.size(), detection.blobs.size());
  for (size_t i = 0; i < repeat.blobs.size(); ++i) {
    EXPECT_EQ(repeat.blobs[i].box.x1, detection.blobs[i].box.x1);
    EXPECT_EQ(repeat.blobs[i].score, detection.blobs[i].score);
  }
}

// The shipped model on crops of a photo it never saw (the held-out split of
// its card): most boxes found, few false ones (card: F1@0.5 0.84 on all 70).
TEST(RetinaNetDetector, ShippedModelFindsApplesOnHeldOutPhotos) {
  const Dataset test =
      SplitByPhoto(ReadDataset(fs::path(ORCHARD_SHARED_DATA_DIR) / "applebbch81"), 0.25, 1).test;
  ASSERT_GE(test.images.size(), 4u);
  RetinaNetDetectorOptions options;
  options.threads = 1;
  RetinaNetDetector detector(DefaultModelsDir() / "retinanet.pt", options);
  int truth = 0, found = 0, matched = 0;
  for (size_t i = 0; i < test.images.size(); i += test.images.size() / 4) {
    const AnnotatedImage& image = test.images[i];
    const FrameDetection detection = detector.Detect(ReadImage(image.path));
    std::vector<bool> used(detection.blobs.size(), false);
    for (const Annotation& object : image.objects) {
      for (size_t b = 0; b < detection.blobs.size(); ++b) {
        if (!used[b] && IoU(object.box, detection.blobs[b].box) >= 0.5) {
          used[b] = true;
          ++matched;
          break;
        }
      }
    }
    truth += static_cast<int>(image.objects.size());
    found += static_cast<int>(detection.blobs.size());
  }
  ASSERT_GT(truth, 10);
  EXPECT_GT(matched, 0.6 * truth) << matched << " of " << truth << " apples found";
  EXPECT_GT(matched, 0.6 * found) << matched << " of " << found << " boxes right";
}

TEST(RetinaNetDetector, RejectsWrongFilesAndOptions) {
  const fs::path dir = TempDir("bad");
  EXPECT_THROW(RetinaNetDetector(dir / "missing.pt", {}), Error);
  std::ofstream(dir / "junk.pt") << "junk";
  EXPECT_THROW(RetinaNetDetector(dir / "junk.pt", {}), Error);
  nn::UNet unet(nn::UNetOptions{4, 3, 2, 3, true});
  nn::SaveCheckpoint(*unet, {{"kind", "unet"}, {"architecture", unet->options().ToJson()}}, dir / "u.pt");
  EXPECT_THROW(RetinaNetDetector(dir / "u.pt", {}), Error);
  // A RetinaNet header whose architecture differs from the weights.
  nn::RetinaNetOptions small;
  small.base_width = 4;
  small.fpn_channels = 8;
  nn::RetinaNet net(small);
  nn::RetinaNetOptions other = small;
  other.fpn_channels = 16;
  nn::SaveCheckpoint(*net, {{"kind", "retinanet"}, {"architecture", other.ToJson()}}, dir / "m.pt");
  EXPECT_THROW(RetinaNetDetector(dir / "m.pt", {}), Error);
  RetinaNetDetectorOptions bad;
  bad.score_threshold = 0;
  EXPECT_THROW(bad.Check(), Error);
  RetinaNetDetectorOptions huge;
  huge.input_scale = 10;
  EXPECT_THROW(huge.Check(), Error);
  nn::RetinaNetTrainingOptions training;
  training.tile = 100;
  EXPECT_THROW(training.Check(), Error);
}

}  // namespace
}  // namespace orchard
