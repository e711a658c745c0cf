#include "orchard/detect/detector.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"

namespace orchard {
namespace {

TEST(ExtractBlobs, BoxesPixelsCentroidsAndSpecksDropped) {
  cv::Mat1b mask(50, 60, uchar(0));
  mask(cv::Rect(5, 10, 20, 10)).setTo(255);   // 200 px
  mask(cv::Rect(40, 30, 12, 15)).setTo(255);  // 180 px
  mask(cv::Rect(55, 2, 3, 3)).setTo(255);     // 9 px speck
  BlobOptions options;
  options.min_pixels = 20;
  const FrameDetection d = ExtractBlobs(mask, options);
  ASSERT_EQ(d.blobs.size(), 2u);
  EXPECT_EQ(d.blobs[0].id, 1);
  EXPECT_DOUBLE_EQ(d.blobs[0].box.x1, 5);
  EXPECT_DOUBLE_EQ(d.blobs[0].box.x2, 25);
  EXPECT_DOUBLE_EQ(d.blobs[0].box.y2, 20);
  EXPECT_EQ(d.blobs[0].pixels, 200);
  EXPECT_NEAR(d.blobs[1].centroid.x, 45.5, 1e-9);
  EXPECT_NEAR(d.blobs[1].centroid.y, 37, 1e-9);
  EXPECT_EQ(d.labels(35, 45), 2);
  EXPECT_EQ(d.labels(3, 56), 0);  // the speck is gone from labels and mask
  EXPECT_EQ(d.mask(3, 56), 0);
  EXPECT_EQ(cv::countNonZero(d.mask), 380);

  cv::Mat1f scores(mask.size(), 0.25f);
  scores(cv::Rect(5, 10, 10, 10)).setTo(0.75f);
  FrameDetection scored = d;
  ScoreBlobs(scores, &scored);
  EXPECT_NEAR(scored.blobs[0].score, 0.5, 1e-6);
  EXPECT_NEAR(scored.blobs[1].score, 0.25, 1e-6);
  EXPECT_THROW(ExtractBlobs(cv::Mat1b(), options), Error);
}

TEST(BlobFiles, WriteAndReadBack) {
  const fs::path dir = fs::temp_directory_path() / ("orchard_blobs_" + std::to_string(::getpid()));
  cv::Mat1b mask(40, 40, uchar(0));
  mask(cv::Rect(2, 3, 10, 11)).setTo(255);
  NamedDetection f{"frame_000001.png", ExtractBlobs(mask, {})};
  f.detection.blobs[0].score = 0.8125;
  WriteBlobsCsv({f}, dir / "blobs.csv");
  WriteDetectionsCsv({f}, dir / "detections.csv");
  const std::vector<BlobRecord> back = ReadBlobsCsv(dir / "blobs.csv");
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].name, "frame_000001.png");
  EXPECT_EQ(back[0].blob.pixels, 110);
  EXPECT_DOUBLE_EQ(back[0].blob.box.y2, 14);
  EXPECT_DOUBLE_EQ(back[0].blob.score, 0.8125);
  const Predictions p = ReadCodaLabDetections(dir / "detections.csv");
  ASSERT_EQ(p.at("frame_000001.png").size(), 1u);
  EXPECT_DOUBLE_EQ(p.at("frame_000001.png")[0].box.x2, 12);
  WriteTextFileAtomic(dir / "bad.csv", "name,blob_id,x1,y1,x2,y2,pixels,cx,cy,score\na,1,2,3\n");
  EXPECT_THROW(ReadBlobsCsv(dir / "bad.csv"), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
