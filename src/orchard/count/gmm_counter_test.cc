#include "orchard/count/gmm_counter.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace {

// A blob of `centres.size()` touching/separate discs of radius r.
cv::Mat1b Discs(const std::vector<cv::Point>& centres, int r, cv::Size size = {160, 120}) {
  cv::Mat1b mask(size, uchar(0));
  for (const cv::Point& c : centres) cv::circle(mask, c, r, 255, cv::FILLED);
  return mask;
}

TEST(GmmCounter, CountsDiscsInABlob) {
  GmmCounter counter({});
  const cv::Mat patch(120, 160, CV_8UC3, cv::Scalar(0, 0, 200));
  for (int r : {10, 20, 30}) {
    EXPECT_EQ(counter.Count(patch, Discs({{80, 60}}, r)).count, 1) << r;
    EXPECT_EQ(counter.Count(patch, Discs({{80 - r, 60}, {80 + r, 60}}, r)).count, 2) << r;  // touching pair
  }
  EXPECT_EQ(counter.Count(patch, Discs({{30, 30}, {130, 30}, {80, 95}}, 12)).count, 3);  // separate discs
  const BlobCount one = counter.Count(patch, Discs({{70, 50}}, 25));
  ASSERT_EQ(one.fruits.size(), 1u);
  EXPECT_NEAR(one.fruits[0].centre.x, 70, 3.0);
  EXPECT_NEAR(one.fruits[0].centre.y, 50, 3.0);
  EXPECT_NEAR(one.fruits[0].radius, 25, 3.0);
  // Many blobs at once (the interface's default: one by one).
  const std::vector<BlobCount> many =
      counter.CountMany({patch, patch}, {Discs({{80, 60}}, 20), Discs({{30, 30}, {130, 30}, {80, 95}}, 12)});
  ASSERT_EQ(many.size(), 2u);
  EXPECT_EQ(many[0].count, 1);
  EXPECT_EQ(many[1].count, 3);
}

TEST(GmmCounter, SeparationKeepsLargeDiscsWhole) {
  // With many pixels the information criterion alone splits a filled disc;
  // the separation rule keeps it one fruit and still splits a touching pair.
  GmmCounterOptions options;
  options.max_points = 2000;
  GmmCounter counter(options);
  const cv::Mat patch(200, 260, CV_8UC3, cv::Scalar::all(0));
  EXPECT_EQ(counter.Count(patch, Discs({{130, 100}}, 60, {260, 200})).count, 1);
  EXPECT_EQ(counter.Count(patch, Discs({{80, 100}, {180, 100}}, 50, {260, 200})).count, 2);
  // Fruit boxes: one per fruit, in frame coordinates.
  FrameDetection d = ExtractBlobs(Discs({{80, 100}, {180, 100}}, 50, {260, 200}), BlobOptions());
  ASSERT_EQ(d.blobs.size(), 1u);
  const std::vector<ScoredBox> boxes = FruitBoxes(patch, d, counter);
  ASSERT_EQ(boxes.size(), 2u);
  const double left = std::min(boxes[0].box.CenterX(), boxes[1].box.CenterX());
  EXPECT_NEAR(left, 80, 4.0);
  EXPECT_NEAR(boxes[0].box.Width(), 100, 12.0);
}

TEST(GmmCounter, EmptyBlobCountsAsOneAndBadInputThrows) {
  GmmCounter counter({});
  const cv::Mat patch(40, 40, CV_8UC3, cv::Scalar(0, 200, 0));
  EXPECT_EQ(counter.Count(patch, cv::Mat1b(40, 40, uchar(0))).count, 1);
  EXPECT_THROW(counter.Count(cv::Mat(), cv::Mat1b()), Error);
  EXPECT_THROW(counter.Count(patch, cv::Mat1b(10, 10, uchar(0))), Error);
  EXPECT_THROW(counter.Count(patch, cv::Mat1b()), Error);  // no mask and no colour model
  EXPECT_THROW(ParseModelSelection("bogus"), Error);
  GmmCounterOptions bad;
  bad.max_fruits = 0;
  EXPECT_THROW(bad.Check(), Error);
}

}  // namespace
}  // namespace orchard
