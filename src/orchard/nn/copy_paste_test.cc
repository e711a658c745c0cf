#include "orchard/nn/copy_paste.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard::nn {
namespace {

// A single-apple patch as `orchard patches` cuts it: a disc of `colour` in a
// box of side `side`, with the 10% margin of grey background around it.
cv::Mat SingleApplePatch(int side, const cv::Scalar& colour) {
  const int m = std::max(3, static_cast<int>(std::lround(0.1 * side)));
  cv::Mat patch(side + 2 * m, side + 2 * m, CV_8UC3, cv::Scalar(90, 90, 90));
  cv::circle(patch, cv::Point(m + side / 2, m + side / 2), side / 2, colour, -1);
  return patch;
}

TEST(CopyPaste, SpriteIsTheInnerBox) {
  CopyPasteOptions options;
  const AppleSprite sprite = SpriteFromSingleApplePatch(SingleApplePatch(40, cv::Scalar(0, 0, 255)), options);
  EXPECT_EQ(sprite.bgr.cols, 40);
  EXPECT_EQ(sprite.bgr.rows, 40);
  EXPECT_DOUBLE_EQ(sprite.radius, 20);
  EXPECT_GT(sprite.alpha(20, 20), 0.99f);  // opaque in the middle
  EXPECT_LT(sprite.alpha(0, 0), 0.01f);    // transparent in the corners
}

// Every pasted apple stays visible: paste apples of distinct colours on grey
// and count each colour's pixels, so the label (the number pasted) is right.
TEST(CopyPaste, ComposedClusterShowsEveryApple) {
  CopyPasteOptions options;
  const cv::Scalar colours[] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 0}, {255, 0, 255}, {0, 255, 255}};
  std::vector<AppleSprite> sprites;
  for (const cv::Scalar& c : colours) sprites.push_back(SpriteFromSingleApplePatch(SingleApplePatch(30, c), options));
  const cv::Mat background(20, 20, CV_8UC3, cv::Scalar(90, 90, 90));
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 2 + trial % 5;
    std::vector<const AppleSprite*> chosen;
    for (int k = 0; k < n; ++k) chosen.push_back(&sprites[k]);
    std::vector<cv::Point2f> centres;
    const cv::Mat cluster = ComposeCluster(chosen, background, options, rng, &centres);
    ASSERT_EQ(cluster.type(), CV_8UC3);
    // The centres handed back are those of the pasted apples: each lies on
    // the apple of its own colour, unless a later apple covers it.
    ASSERT_EQ(centres.size(), static_cast<size_t>(n));
    int on_own_apple = 0;
    for (int k = 0; k < n; ++k) {
      const cv::Point c(cvRound(centres[k].x), cvRound(centres[k].y));
      ASSERT_TRUE(cv::Rect(0, 0, cluster.cols, cluster.rows).contains(c));
      const cv::Vec3b pixel = cluster.at<cv::Vec3b>(c);
      on_own_apple += cv::norm(cv::Scalar(pixel[0], pixel[1], pixel[2]) - colours[k]) < 35;
    }
    EXPECT_GE(on_own_apple, n - 1) << "trial " << trial;
    // At least the apples' box and the margin; no more than n apples side by side.
    EXPECT_GE(std::max(cluster.cols, cluster.rows), 30 + 6);
    EXPECT_LE(std::max(cluster.cols, cluster.rows), (30 * n) * 1.2 + 8);
    for (int k = 0; k < 6; ++k) {
      cv::Mat same;
      cv::inRange(cluster, colours[k] - cv::Scalar::all(20), colours[k] + cv::Scalar::all(20), same);
      const double visible = cv::countNonZero(same) / (M_PI * 15 * 15);
      if (k < n) {
        EXPECT_GT(visible, 0.2) << "apple " << k << " of " << n << " hidden, trial " << trial;
      } else {
        EXPECT_EQ(visible, 0) << "apple " << k << " was not pasted";
      }
    }
    // Background shows in the corners (the margin).
    EXPECT_EQ(cluster.at<cv::Vec3b>(0, 0), cv::Vec3b(90, 90, 90));
  }
}

TEST(CopyPaste, SourceGroupsByPhotoAndChecksInput) {
  CopyPasteOptions options;
  std::vector<cv::Mat> patches{SingleApplePatch(30, {0, 0, 255}), SingleApplePatch(34, {0, 0, 200}),
                               cv::Mat(40, 40, CV_8UC3, cv::Scalar(0, 120, 0)), SingleApplePatch(30, {0, 0, 255}),
                               cv::Mat(40, 40, CV_8UC3, cv::Scalar(0, 120, 0))};
  // Photo b has one apple only, c no apple: only a can compose.
  const CopyPasteSource source(patches, {1, 1, 0, 1, 0}, {"a", "a", "a", "b", "c"}, options);
  EXPECT_EQ(source.num_photos(), 1u);
  std::mt19937_64 rng(1);
  const cv::Mat three = source.Compose(3, rng);
  EXPECT_FALSE(three.empty());
  EXPECT_EQ(three.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 120, 0));
  EXPECT_THROW(CopyPasteSource(patches, {1, 1}, {"a", "a"}, options), Error);
  EXPECT_TRUE(CopyPasteSource(patches, {1, 0, 0, 0, 0}, {"a", "a", "a", "a", "a"}, options).empty());
  options.min_separation = 1.5;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace orchard::nn
