#include <random>

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/sfm/ground_plane.h"

namespace orchard {
namespace {

CameraView CameraAt(const Eigen::Vector3d& c) {
  CameraView v;
  v.width = 640, v.height = 480, v.fx = v.fy = 500, v.cx = 320, v.cy = 240;
  v.R << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // looking along +y, image y down = world -z
  v.t = -v.R * c;
  return v;
}

TEST(GroundPlane, RobustToFruitWallAndOutliers) {
  // A ground tilted 3 degrees about x, 60 points on it (+-1 cm noise), a vertical
  // "fruit wall" of 120 points (more than the ground!) and 40 random outliers.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const double tilt = 3 * M_PI / 180;
  const Eigen::Vector3d n(0, -std::sin(tilt), std::cos(tilt));
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 60; ++i) {
    Eigen::Vector3d p(4 * u(rng), 3 * u(rng), 0);
    p.z() = -(n.x() * p.x() + n.y() * p.y()) / n.z() + 0.01 * u(rng);
    pts.push_back(p);
  }
  for (int i = 0; i < 120; ++i) pts.push_back({4 * u(rng), 0.01 * u(rng), 1.5 + u(rng)});
  for (int i = 0; i < 40; ++i) pts.push_back({4 * u(rng), 3 * u(rng), 1.5 + 1.5 * u(rng)});
  std::vector<CameraView> views;
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 5; ++i) {
    views.push_back(CameraAt({i * 0.5, -2.5, 1.5}));
    centres.push_back(views.back().Center());
  }
  const Eigen::Vector3d up = MeanCameraUp(views);
  EXPECT_NEAR(up.z(), 1, 1e-12);
  int inliers = 0;
  const Plane g = FitGroundPlane(pts, centres, up, GroundPlaneOptions{}, &inliers);
  EXPECT_GT(g.normal.dot(n), std::cos(0.5 * M_PI / 180));
  EXPECT_NEAR(g.SignedDistance(Eigen::Vector3d::Zero()), 0, 0.01);
  EXPECT_GE(inliers, 58);
  EXPECT_LE(inliers, 75);
  // Scale: cameras at 1.5 m in a model scaled by 1/3 -> factor 3 restores 1.5 m.
  Plane scaled = g;
  scaled.d /= 3;
  std::vector<CameraView> small = views;
  ScaleViews(1.0 / 3, &small);
  const double s = ScaleFromCameraHeight(scaled, small, 1.5);
  const double expected = 1.5 / g.SignedDistance(views[2].Center()) * 3;
  EXPECT_NEAR(s, expected, 0.02 * expected);
  EXPECT_NEAR(g.SignedDistance(views[2].Center()), 1.5 + 0.0 * s, 0.15);
}

TEST(GroundPlane, PrefersTheLowestSurfaceToADenserLayerAboveIt) {
  // 100 ground points and a horizontal layer of 120 (the canopy's lower edge,
  // seen densely) 0.75 m up, both below the cameras: the layer has more
  // inliers, but the whole ground lies below it.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 100; ++i) pts.push_back({4 * u(rng), 1 + 2 * u(rng), 0.01 * u(rng)});
  for (int i = 0; i < 120; ++i) pts.push_back({4 * u(rng), 0.4 * u(rng), 0.75 + 0.01 * u(rng)});
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 5; ++i) centres.push_back({i * 0.5, -2.5, 1.5});
  const Eigen::Vector3d up(0, 0, 1);
  GroundPlaneOptions o;
  EXPECT_NEAR(FitGroundPlane(pts, centres, up, o).SignedDistance(Eigen::Vector3d::Zero()), 0, 0.02);
  o.below_penalty = 0;  // inliers alone take the layer
  EXPECT_NEAR(FitGroundPlane(pts, centres, up, o).SignedDistance(Eigen::Vector3d::Zero()), -0.75, 0.02);
  o.below_penalty = -1;
  EXPECT_THROW(o.Check(), Error);
}

TEST(GroundPlane, TakesNoSurfaceTiltedMoreThanTheCamerasArePitched) {
  // 100 level ground points (y -1..1) and 200 on a surface tilted 25 degrees
  // about the row's axis beyond them (y 1.5..3.5, rising away from the
  // cameras), nothing below either: the surface has more points, as on
  // two-tree rows' backs whose COLMAP points gave a surface rising 19-20
  // degrees away from the cameras more support than the ground.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double slope = std::tan(25 * M_PI / 180);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 100; ++i) pts.push_back({4 * u(rng), u(rng), 0.01 * u(rng)});
  for (int i = 0; i < 200; ++i) {
    const double y = 2.5 + u(rng);
    pts.push_back({4 * u(rng), y, slope * (y - 1.5) + 0.01 * u(rng)});
  }
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 5; ++i) centres.push_back({i * 0.5, -2.5, 1.5});
  const Eigen::Vector3d up(0, 0, 1);
  GroundPlaneOptions o;
  const Plane ground = FitGroundPlane(pts, centres, up, o);
  // (The inlier distance, 2% of ~5 m, lets planes a few degrees off take
  // the ground and a strip of the surface.)
  EXPECT_GT(ground.normal.z(), std::cos(6 * M_PI / 180));
  EXPECT_NEAR(ground.SignedDistance(Eigen::Vector3d::Zero()), 0, 0.05);
  o.max_tilt_deg = 30;  // the slope is taken
  EXPECT_NEAR(std::acos(FitGroundPlane(pts, centres, up, o).normal.z()) * 180 / M_PI, 25, 1);
}

TEST(GroundPlane, FruitKnownToBeAboveCorrectsAPlaneThroughIt) {
  // The same ground and layer as above, with inliers alone (the layer wins),
  // and a fruit wall 0.3-2.3 m high that the layer cuts: each fruit point
  // below a candidate costs an inlier, and the ground wins.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> pts, fruit;
  for (int i = 0; i < 100; ++i) pts.push_back({4 * u(rng), 1 + 2 * u(rng), 0.01 * u(rng)});
  for (int i = 0; i < 120; ++i) pts.push_back({4 * u(rng), 0.4 * u(rng), 0.75 + 0.01 * u(rng)});
  for (int i = 0; i < 300; ++i) fruit.push_back({4 * u(rng), 0.3 * u(rng), 1.3 + u(rng)});
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 5; ++i) centres.push_back({i * 0.5, -2.5, 1.5});
  const Eigen::Vector3d up(0, 0, 1);
  GroundPlaneOptions o;
  o.below_penalty = 0;
  EXPECT_NEAR(FitGroundPlane(pts, centres, up, o).SignedDistance(Eigen::Vector3d::Zero()), -0.75, 0.02);
  int inliers = 0;
  const Plane g = FitGroundPlane(pts, centres, up, o, &inliers, &fruit, 1.0);
  EXPECT_NEAR(g.SignedDistance(Eigen::Vector3d::Zero()), 0, 0.02);
  EXPECT_GE(inliers, 95);
  EXPECT_LE(inliers, 105);
  // Fruit above both planes changes nothing.
  std::vector<Eigen::Vector3d> high;
  for (const auto& x : fruit) high.push_back(x + Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR(FitGroundPlane(pts, centres, up, o, nullptr, &high, 1.0).SignedDistance(Eigen::Vector3d::Zero()), -0.75,
              0.02);
}

TEST(GroundPlane, FindsTheThinGroundLayerUnderLowClutter) {
  // As the frames of a camera 2.5 m off the row see it: level ground points
  // (5 mm noise) densely under the row (y 0..0.75) and sparsely beyond it,
  // and clutter 2-12 cm above the ground along the row's foot (trunk bases,
  // weeds, fallen fruit), inside the wide first band. The least-squares
  // plane of the wide band rises towards the clutter; the thin layer does not.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.005);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 400; ++i) pts.push_back({8 * u(rng), 0.75 * u(rng), noise(rng)});
  for (int i = 0; i < 100; ++i) pts.push_back({8 * u(rng), 1 + 3 * u(rng), noise(rng)});
  for (int i = 0; i < 250; ++i) pts.push_back({8 * u(rng), -0.2 + 0.5 * u(rng), 0.02 + 0.1 * u(rng)});
  for (int i = 0; i < 300; ++i) pts.push_back({8 * u(rng), 0.6 * (u(rng) - 0.5), 0.6 + 2.4 * u(rng)});  // canopy
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 17; ++i) centres.push_back({i * 0.5, -2.5, 1.5});
  const Eigen::Vector3d up(0, 0, 1);
  const Eigen::Vector3d under_camera(4, -2.5, 0), under_row(4, 0.3, 0);
  GroundPlaneOptions o;
  const Plane thin = FitGroundPlane(pts, centres, up, o);
  EXPECT_GT(thin.normal.z(), std::cos(0.3 * M_PI / 180));
  EXPECT_NEAR(thin.SignedDistance(under_row), 0, 0.005);
  EXPECT_NEAR(thin.SignedDistance(under_camera), 0, 0.015);
  o.fine_inlier_fraction = 0;  // the wide band's plane alone
  const Plane wide = FitGroundPlane(pts, centres, up, o);
  EXPECT_GT(std::abs(wide.SignedDistance(under_camera)), 0.03);
  o.fine_inlier_fraction = 2 * o.inlier_fraction;
  EXPECT_THROW(o.Check(), Error);
}

TEST(GroundPlane, FailsClearlyWithoutGroundPoints) {
  std::vector<CameraView> views = {CameraAt({0, -2.5, 1.5}), CameraAt({1, -2.5, 1.5})};
  std::vector<Eigen::Vector3d> centres = {views[0].Center(), views[1].Center()};
  // Only a vertical wall: no horizontal plane.
  std::vector<Eigen::Vector3d> wall;
  for (int i = 0; i < 50; ++i) wall.push_back({0.1 * i, 0, 0.5 + 0.03 * (i % 7)});
  EXPECT_THROW(FitGroundPlane(wall, centres, MeanCameraUp(views), GroundPlaneOptions{}), Error);
  EXPECT_THROW(FitGroundPlane({}, centres, MeanCameraUp(views), GroundPlaneOptions{}), Error);
  Plane above;
  above.d = -3;  // z = 3: the cameras are below it
  EXPECT_THROW(ScaleFromCameraHeight(above, views, 1.5), Error);
  EXPECT_THROW(ScaleFromCameraHeight(Plane{}, views, 0), Error);
}

}  // namespace
}  // namespace orchard
