// The opposite-faces check on textured scenes: a camera panning over the same
// texture twice (another pass along the same side) matches, the texture's
// mirror image (the row seen from its other side) does not.
#include "orchard/merge/face_check.h"

#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

// A wide strip of random shapes (leaves, fruit, posts for a feature detector).
cv::Mat Texture(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, 1199), y(0, 359), r(3, 25), g(0, 255);
  cv::Mat3b t(360, 1200, cv::Vec3b(90, 120, 80));
  for (int i = 0; i < 1100; ++i) {
    const cv::Scalar colour(g(rng), g(rng), g(rng));
    if (i % 2)
      cv::circle(t, {x(rng), y(rng)}, r(rng), colour, cv::FILLED);
    else
      cv::rectangle(t, cv::Rect(x(rng), y(rng), r(rng), r(rng)), colour, cv::FILLED);
  }
  return t;
}

// Frames of a camera panning along the strip, `step` pixels apart.
std::vector<fs::path> Pan(const cv::Mat& strip, int first, int step, const fs::path& dir) {
  fs::create_directories(dir);
  std::vector<fs::path> paths;
  for (int x = first, i = 0; x + 640 <= strip.cols; x += step, ++i) {
    paths.push_back(dir / ("frame_" + std::to_string(i) + ".png"));
    WriteImageAtomic(paths.back(), strip(cv::Rect(x, 0, 640, 360)).clone());
  }
  return paths;
}

TEST(CheckOppositeFaces, SameSideMatchesAndTheMirroredSideDoesNot) {
  const fs::path dir = test::FreshTempDir("face_check");
  const cv::Mat strip = Texture(3);
  const std::vector<fs::path> front = Pan(strip, 0, 60, dir / "front");
  // A second pass along the same side, its frames between the first's.
  const FaceCheck same = CheckOppositeFaces(front, Pan(strip, 30, 60, dir / "again"));
  EXPECT_TRUE(same.same_face);
  EXPECT_GT(same.best_inliers, 200);
  // The other side of the row sees the canopy mirrored.
  cv::Mat mirrored;
  cv::flip(strip, mirrored, 1);
  const FaceCheck opposite = CheckOppositeFaces(front, Pan(mirrored, 0, 60, dir / "back"));
  EXPECT_FALSE(opposite.same_face);
  EXPECT_LE(opposite.best_inliers, FaceCheckOptions().max_inliers);
  // Another scene altogether.
  EXPECT_FALSE(CheckOppositeFaces(front, Pan(Texture(4), 0, 60, dir / "other")).same_face);
  EXPECT_THROW(CheckOppositeFaces(front, {}), Error);
  EXPECT_THROW(CheckOppositeFaces(front, {dir / "missing.png"}), Error);
  FaceCheckOptions bad;
  bad.frames = 0;
  EXPECT_THROW(CheckOppositeFaces(front, front, bad), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
