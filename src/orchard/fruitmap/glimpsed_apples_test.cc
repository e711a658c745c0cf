#include "orchard/fruitmap/glimpsed_apples.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/fruitmap/test_views.h"

namespace orchard {
namespace {

using test::ViewAt;

constexpr double kAppleRadius = 0.04;

// What a frame shows of an apple through the leaves.
enum class Piece {
  kHalf,   // the half of its disc on one side of a leaf's edge through its centre
  kSmall,  // a small disc inside it (a gap in the leaves smaller than the apple)
};

struct Glimpse {
  int frame;
  Piece piece;
  double angle;  // which half shows / where the small disc lies (radians)
};

// Frames showing one apple at `centre` only as the given pieces.
std::vector<FruitFrame> Render(const std::vector<CameraView>& views, const Eigen::Vector3d& centre,
                               const std::vector<Glimpse>& glimpses) {
  std::vector<FruitFrame> frames(views.size());
  for (size_t f = 0; f < views.size(); ++f) frames[f].labels = cv::Mat1i::zeros(views[f].height, views[f].width);
  for (const Glimpse& g : glimpses) {
    const CameraView& v = views[g.frame];
    Eigen::Vector2d p;
    v.Project(centre, &p);
    const double r = v.fx * kAppleRadius / v.Depth(centre);
    cv::Mat1b piece = cv::Mat1b::zeros(v.height, v.width);
    const Eigen::Vector2d dir(std::cos(g.angle), std::sin(g.angle));
    for (int y = 0; y < v.height; ++y)
      for (int x = 0; x < v.width; ++x) {
        const Eigen::Vector2d d = Eigen::Vector2d(x + 0.5, y + 0.5) - p;
        if (g.piece == Piece::kHalf) piece(y, x) = d.norm() <= r && d.dot(dir) >= 0 ? 255 : 0;
        else piece(y, x) = (d - 0.5 * r * dir).norm() <= 0.3 * r ? 255 : 0;
      }
    FruitFrame& frame = frames[g.frame];
    Blob blob;
    blob.id = static_cast<int>(frame.blobs.size()) + 1;
    blob.pixels = cv::countNonZero(piece);
    frame.labels.setTo(blob.id, piece);
    const cv::Rect box = cv::boundingRect(piece);
    blob.box = Box{static_cast<double>(box.x), static_cast<double>(box.y), static_cast<double>(box.x + box.width - 1),
                   static_cast<double>(box.y + box.height - 1)};
    const cv::Moments m = cv::moments(piece, true);
    blob.centroid = {m.m10 / m.m00, m.m01 / m.m00};
    frame.blobs.push_back(blob);
    frame.counts.push_back(1);
  }
  return frames;
}

RowFrame Row() {
  RowFrame row;
  row.origin = {0, -2.5, 0};  // under the camera path; across = +y
  row.row_distance = 2.5;
  return row;
}

std::vector<CameraView> Views() {
  std::vector<CameraView> views;
  for (int i = 0; i < 12; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  return views;
}

const Eigen::Vector3d kApple(0.1, 0.2, 1.6);  // 2.7 m from the camera path, behind the row distance

TEST(GlimpsedApples, HalvesInScatteredFramesAreOneAppleNearItsCentre) {
  const std::vector<CameraView> views = Views();
  const std::vector<FruitFrame> frames =
      Render(views, kApple, {{2, Piece::kHalf, 0.3}, {5, Piece::kHalf, 2.5}, {8, Piece::kHalf, -1.7}});
  const std::vector<GlimpsedApple> apples = FindGlimpsedApples(views, frames, {}, Row(), 3.7, GlimpsedAppleOptions());
  ASSERT_EQ(apples.size(), 1u);
  EXPECT_EQ(apples[0].pieces.size(), 3u);
  EXPECT_EQ(apples[0].piece_points.size(), 3u);
  // Across the row the disc fixes it to about an apple's radius; along and up
  // to a few centimetres.
  EXPECT_NEAR(apples[0].distance, 2.7, 0.08);
  EXPECT_NEAR(apples[0].centre.x(), kApple.x(), 0.03);
  EXPECT_NEAR(apples[0].centre.z(), kApple.z(), 0.03);
}

TEST(GlimpsedApples, TwoFramesAreNotEnough) {
  const std::vector<CameraView> views = Views();
  const std::vector<FruitFrame> frames = Render(views, kApple, {{2, Piece::kHalf, 0.3}, {5, Piece::kHalf, 2.5}});
  EXPECT_TRUE(FindGlimpsedApples(views, frames, {}, Row(), 3.7, GlimpsedAppleOptions()).empty());
}

TEST(GlimpsedApples, PiecesAClusterExplainsAreItsApple) {
  const std::vector<CameraView> views = Views();
  const std::vector<FruitFrame> frames =
      Render(views, kApple, {{2, Piece::kHalf, 0.3}, {5, Piece::kHalf, 2.5}, {8, Piece::kHalf, -1.7}});
  EXPECT_TRUE(FindGlimpsedApples(views, frames, {kApple}, Row(), 3.7, GlimpsedAppleOptions()).empty());
  // A point elsewhere explains nothing here.
  EXPECT_EQ(FindGlimpsedApples(views, frames, {kApple + Eigen::Vector3d(0.3, 0, 0)}, Row(), 3.7,
                               GlimpsedAppleOptions())
                .size(),
            1u);
}

TEST(GlimpsedApples, PiecesNoWiderThanTheNextRowsApplesAreNotUsed) {
  // Small pieces could be the next row's apples seen through a gap in the
  // leaves, which moves like an object at the row's depth.
  const std::vector<CameraView> views = Views();
  const std::vector<FruitFrame> frames =
      Render(views, kApple, {{2, Piece::kSmall, 0.3}, {5, Piece::kSmall, 2.5}, {8, Piece::kSmall, -1.7}});
  GlimpsedAppleOptions o;
  o.min_pixels = 5;
  EXPECT_TRUE(FindGlimpsedApples(views, frames, {}, Row(), 3.7, o).empty());
  o.min_extent = 0.4;
  EXPECT_EQ(FindGlimpsedApples(views, frames, {}, Row(), 3.7, o).size(), 1u);
}

TEST(GlimpsedApples, BeyondTheSearchNothingIsFound) {
  const std::vector<CameraView> views = Views();
  const std::vector<FruitFrame> frames =
      Render(views, kApple, {{2, Piece::kHalf, 0.3}, {5, Piece::kHalf, 2.5}, {8, Piece::kHalf, -1.7}});
  GlimpsedAppleOptions o;
  o.far_search = 0;
  // The cut-off at 2.4 m, the search to 2.4 m: the apple at 2.7 m is out of reach.
  EXPECT_TRUE(FindGlimpsedApples(views, frames, {}, Row(), 2.4, o).empty());
}

TEST(GlimpsedApples, OptionsAreChecked) {
  GlimpsedAppleOptions o;
  EXPECT_NO_THROW(o.Check());
  o.min_support = 1;
  EXPECT_THROW(o.Check(), Error);
  o = GlimpsedAppleOptions();
  o.min_extent = -1;
  EXPECT_THROW(o.Check(), Error);
  o = GlimpsedAppleOptions();
  o.depth_step = 0;
  EXPECT_THROW(o.Check(), Error);
  const std::vector<CameraView> views = Views();
  EXPECT_THROW(FindGlimpsedApples(views, {}, {}, Row(), 3.7, GlimpsedAppleOptions()), Error);
}

}  // namespace
}  // namespace orchard
