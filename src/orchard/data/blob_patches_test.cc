#include "orchard/data/blob_patches.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace {

TEST(BlobPatches, CountsTheApplesMostlyInEachBlob) {
  cv::Mat1w apples = cv::Mat1w::zeros(60, 100), blobs = cv::Mat1w::zeros(60, 100);
  // Apples 0 and 1 touch and make blob 1; apple 2 is split 70/30 between blobs 2 and 3;
  // apple 3 (10 px) is too small to count; blob 4 is a leaf.
  apples(cv::Rect(5, 5, 10, 10)).setTo(1);
  apples(cv::Rect(15, 5, 10, 10)).setTo(2);
  blobs(cv::Rect(4, 4, 22, 12)).setTo(1);
  apples(cv::Rect(40, 5, 10, 10)).setTo(3);
  blobs(cv::Rect(40, 5, 7, 10)).setTo(2);
  blobs(cv::Rect(47, 5, 3, 10)).setTo(3);
  apples(cv::Rect(70, 5, 5, 2)).setTo(4);
  blobs(cv::Rect(70, 5, 5, 2)).setTo(4);
  blobs(cv::Rect(80, 40, 6, 6)).setTo(5);
  const std::vector<BlobPatch> p = LabelBlobPatches(blobs, apples, {});
  ASSERT_EQ(p.size(), 5u);
  EXPECT_EQ(p[0].blob, 1);
  EXPECT_EQ(p[0].crop, cv::Rect(4, 4, 22, 12));
  EXPECT_EQ(p[0].count, 2);
  EXPECT_EQ(p[1].count, 1);
  EXPECT_EQ(p[2].count, 0);
  EXPECT_EQ(p[2].crop, cv::Rect(47, 5, 3, 10));
  EXPECT_EQ(p[3].count, 0);  // 10 px: not a visible apple
  EXPECT_EQ(p[4].count, 0);
  BlobPatchOptions small;
  small.min_apple_pixels = 5;
  EXPECT_EQ(LabelBlobPatches(blobs, apples, small)[3].count, 1);
  // An apple split 50/50 would belong to both blobs with min_share below one half: refused.
  BlobPatchOptions bad;
  bad.min_share = 0.4;
  EXPECT_THROW(LabelBlobPatches(blobs, apples, bad), Error);
  EXPECT_THROW(LabelBlobPatches(blobs, cv::Mat1w::zeros(10, 10), {}), Error);
}

TEST(BlobPatches, ClipsLargeBlobsToTheTopClass) {
  cv::Mat1w apples = cv::Mat1w::zeros(20, 100), blobs = cv::Mat1w::zeros(20, 100);
  for (int i = 0; i < 8; ++i) apples(cv::Rect(10 * i, 0, 10, 10)).setTo(i + 1);
  blobs(cv::Rect(0, 0, 80, 10)).setTo(1);
  BlobPatchOptions o;
  EXPECT_EQ(LabelBlobPatches(blobs, apples, o).at(0).count, 6);
  o.max_count = 3;
  EXPECT_EQ(LabelBlobPatches(blobs, apples, o).at(0).count, 3);
}

TEST(BlobPatches, CutsEveryNthFrameAndNamesMissingInputs) {
  const fs::path dir = fs::temp_directory_path() / "orchard_blob_patches_test";
  fs::remove_all(dir);
  for (const char* d : {"det", "img", "masks"}) fs::create_directories(dir / d);
  for (int f = 0; f < 3; ++f) {
    const std::string stem = "frame_000" + std::to_string(f);
    cv::Mat1w apples = cv::Mat1w::zeros(30, 40), blobs = cv::Mat1w::zeros(30, 40);
    apples(cv::Rect(5, 5, 8, 8)).setTo(1);
    blobs(cv::Rect(5, 5, 8, 8)).setTo(1);
    blobs(cv::Rect(25, 20, 5, 5)).setTo(2);
    WriteImageAtomic(dir / "det" / (stem + ".png"), blobs);
    WriteImageAtomic(dir / "masks" / (stem + ".png"), apples);
    WriteImageAtomic(dir / "img" / (stem + ".jpg"), cv::Mat3b(30, 40, cv::Vec3b(0, 0, 200)));
  }
  std::vector<ImageCount> counts;
  const std::vector<int> histogram =
      CutBlobPatches(dir / "det", dir / "img", dir / "masks", dir / "out", "r1_front_", 2, {}, &counts);
  ASSERT_EQ(counts.size(), 4u);  // frames 0 and 2, two blobs each
  EXPECT_EQ(counts[0].name, "r1_front_frame_0000_b1.png");
  EXPECT_EQ(counts[0].count, 1);
  EXPECT_EQ(counts[3].name, "r1_front_frame_0002_b2.png");
  EXPECT_EQ(counts[3].count, 0);
  EXPECT_EQ(histogram[0], 2);
  EXPECT_EQ(histogram[1], 2);
  EXPECT_EQ(ReadImage(dir / "out" / "images" / "r1_front_frame_0000_b1.png").size(), cv::Size(8, 8));
  fs::remove(dir / "masks" / "frame_0002.png");
  counts.clear();
  EXPECT_THROW(CutBlobPatches(dir / "det", dir / "img", dir / "masks", dir / "out", "", 1, {}, &counts), Error);
  EXPECT_THROW(CutBlobPatches(dir / "det", dir / "img", dir / "masks", dir / "out", "", 0, {}, &counts), Error);
  EXPECT_THROW(CutBlobPatches(dir / "img", dir / "img", dir / "masks", dir / "out", "", 1, {}, &counts), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
