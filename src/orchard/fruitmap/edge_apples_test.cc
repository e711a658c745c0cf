#include "orchard/fruitmap/edge_apples.h"

#include <map>
#include <set>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/fruitmap/side.h"
#include "orchard/fruitmap/test_views.h"

namespace orchard {
namespace {

using test::ViewAt;

struct Ball {
  Eigen::Vector3d centre;
  std::set<int> frames;  // the frames that show it (leaves hide it in the others); empty: all
};

// Balls of radius r drawn as discs, clipped to the frame: a ball hanging just
// above the top edge shows as a sliver.
std::vector<FruitFrame> Render(const std::vector<CameraView>& views, const std::vector<Ball>& balls, double r) {
  std::vector<FruitFrame> frames;
  for (size_t f = 0; f < views.size(); ++f) {
    const CameraView& v = views[f];
    FruitFrame frame;
    frame.labels = cv::Mat1i::zeros(v.height, v.width);
    for (const Ball& b : balls) {
      if (!b.frames.empty() && !b.frames.count(static_cast<int>(f))) continue;
      Eigen::Vector2d p;
      v.Project(b.centre, &p);  // inside the image or not
      const double rad = v.fx * r / v.Depth(b.centre);
      cv::Mat1b disc = cv::Mat1b::zeros(frame.labels.size());
      cv::circle(disc, cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))),
                 static_cast<int>(rad), 255, -1);
      const int pixels = cv::countNonZero(disc);
      if (pixels == 0) continue;
      Blob blob;
      blob.id = static_cast<int>(frame.blobs.size()) + 1;
      frame.labels.setTo(blob.id, disc);
      blob.pixels = pixels;
      const cv::Rect box = cv::boundingRect(disc);
      blob.box = Box{static_cast<double>(box.x), static_cast<double>(box.y), static_cast<double>(box.x + box.width),
                     static_cast<double>(box.y + box.height)};
      blob.centroid = {box.x + 0.5 * box.width, box.y + 0.5 * box.height};
      frame.blobs.push_back(blob);
      frame.counts.push_back(1);
    }
    frames.push_back(frame);
  }
  return frames;
}

RowFrame Row() {
  RowFrame row;
  row.origin = {0, -2.5, 0};
  row.row_distance = 2.5;
  return row;
}

std::vector<CameraView> Views() {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  return views;
}

TEST(EdgeApples, SliversNoClusterExplainsAreFoundAndGroupedWhereTheirRaysCross) {
  const std::vector<CameraView> views = Views();
  const double top_at_row = 1.5 + 0.48 * 2.5;  // 2.7 m
  const std::vector<Ball> balls = {
      {{0.1, 0.0, top_at_row + 0.015}, {3, 9}},    // A: a sliver in two frames far apart
      {{0.8, 0.3, 1.5 + 0.48 * 2.8 + 0.015}, {12}},  // B: a sliver in one frame, 0.3 m behind the row
      {{-0.2, 0.1, top_at_row + 0.015}, {}},       // C: at the edge, but a kept cluster holds it
      {{0.3, -0.1, 1.8}, {}},                      // D: a whole apple, held too
  };
  const std::vector<FruitFrame> frames = Render(views, balls, 0.04);
  EdgeAppleOptions o;
  o.min_pixels = 20;
  const std::vector<Eigen::Vector3d> explained = {balls[2].centre, balls[3].centre};
  const std::vector<EdgeSighting> sightings = FindEdgeSightings(views, frames, explained, Row(), o);
  std::map<int, int> per_frame;
  for (const auto& s : sightings) ++per_frame[s.frame];
  EXPECT_EQ(per_frame, (std::map<int, int>{{3, 1}, {9, 1}, {12, 1}}));
  // The sliver's middle is the apple's column.
  for (const auto& s : sightings) {
    Eigen::Vector2d p;
    views[s.frame].Project(s.frame == 12 ? balls[1].centre : balls[0].centre, &p);
    EXPECT_NEAR(s.column, p.x(), 1.0) << s.frame;
    EXPECT_GE(s.pixels, 20);
  }
  const std::vector<EdgeApple> apples = GroupEdgeSightings(sightings, Row(), o);
  ASSERT_EQ(apples.size(), 2u);
  const EdgeApple& a = apples[0];
  ASSERT_EQ(a.sightings.size(), 2u);
  EXPECT_TRUE(a.crossed);
  EXPECT_NEAR(a.distance, 2.5, 0.05);
  EXPECT_NEAR(a.centre.x(), 0.1, 0.02);
  EXPECT_NEAR(a.centre.z(), top_at_row, 0.03);  // the top edge where it meets the apple
  // A lone sighting hangs at the row distance.
  EXPECT_FALSE(apples[1].crossed);
  EXPECT_DOUBLE_EQ(apples[1].distance, 2.5);
  // More than the window apart, the two sightings of A are two apples.
  o.window = 5;
  EXPECT_EQ(GroupEdgeSightings(sightings, Row(), o).size(), 3u);
  // Below the pixel threshold nothing is a sighting.
  o.min_pixels = 1000;
  EXPECT_TRUE(FindEdgeSightings(views, frames, explained, Row(), o).empty());
  o.window = 0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(EdgeApples, TwoSliversOfOneFrameAreTwoApplesAndACornerIsNoSighting) {
  const std::vector<CameraView> views = Views();
  const double top = 1.5 + 0.48 * 2.5 + 0.015;
  // Two apples 20 cm apart at the edge, both in frames 4 and 8; a third in
  // the top-left corner of frame 0 (column 320 + 200 (x + 0.5) = 3).
  const std::vector<Ball> balls = {{{0.0, 0.0, top}, {4, 8}}, {{0.2, 0.0, top}, {4, 8}}, {{-2.085, 0.0, top}, {0}}};
  const std::vector<FruitFrame> frames = Render(views, balls, 0.04);
  ASSERT_FALSE(frames[0].blobs.empty());
  EXPECT_LT(frames[0].blobs[0].box.x1, 2);  // the corner blob touches the left edge too
  EdgeAppleOptions o;
  o.min_pixels = 20;
  const std::vector<EdgeSighting> sightings = FindEdgeSightings(views, frames, {}, Row(), o);
  EXPECT_EQ(sightings.size(), 4u);  // none in frame 0
  const std::vector<EdgeApple> apples = GroupEdgeSightings(sightings, Row(), o);
  ASSERT_EQ(apples.size(), 2u);
  for (const auto& a : apples) {
    EXPECT_TRUE(a.crossed);
    EXPECT_NEAR(a.distance, 2.5, 0.05);
  }
  EXPECT_NEAR(std::abs(apples[0].centre.x() - apples[1].centre.x()), 0.2, 0.02);
}

TEST(EdgeApples, TheThreeDStageCountsAnAppleSeenOnlyAtTheTopEdge) {
  const std::vector<CameraView> views = Views();
  const double top = 1.5 + 0.48 * 2.5;
  // Three whole apples in every frame, and one at the top edge that leaves
  // show in two frames only: too few for a fruit point.
  const std::vector<Ball> balls = {
      {{-0.2, 0, 1.2}, {}}, {{0.3, -0.1, 1.6}, {}}, {{0.7, 0.1, 2.0}, {}}, {{0.4, 0, top + 0.015}, {5, 10}}};
  const std::vector<FruitFrame> frames = Render(views, balls, 0.04);
  Plane ground;  // z = 0
  ClusterOptions o;
  o.edge.min_pixels = 20;
  const ClusterResult r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(r.count, 4);
  EXPECT_EQ(r.edge_apples, 1);
  int edge = 0;
  for (const auto& c : r.clusters) {
    if (!c.edge) continue;
    ++edge;
    EXPECT_EQ(c.status, "kept");
    EXPECT_EQ(c.count, 1);
    EXPECT_EQ(c.views.size(), 2u);
    EXPECT_EQ(c.edge_rays.size(), 2u);
    EXPECT_NEAR(c.centre.x(), 0.4, 0.03);
    EXPECT_EQ(c.points.size(), 2u);
  }
  EXPECT_EQ(edge, 1);
  // Its points follow the triangulated ones.
  EXPECT_EQ(static_cast<size_t>(r.triangulated_points) + 2, r.points.size());
  // Off, the apple is not counted.
  o.edge.enabled = false;
  EXPECT_EQ(CountFruitClusters(views, frames, ground, o).count, 3);
}

}  // namespace
}  // namespace orchard
