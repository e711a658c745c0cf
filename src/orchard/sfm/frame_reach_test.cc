#include <cmath>

#include <gtest/gtest.h>

#include "orchard/sfm/frame_reach.h"

namespace orchard {
namespace {

constexpr double kDeg = M_PI / 180;

// A 960x540 camera at `centre` (world: x along the row, y across towards it,
// z up) turned `yaw` from facing across and pitched `pitch` (down < 0).
CameraView Camera(const Eigen::Vector3d& centre, double pitch, double yaw = 0) {
  CameraView v;
  v.width = 960, v.height = 540, v.fx = v.fy = 572, v.cx = 480, v.cy = 270;
  const Eigen::Vector3d forward(std::sin(yaw) * std::cos(pitch), std::cos(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  v.R.row(0) = right.transpose();
  v.R.row(1) = down.transpose();
  v.R.row(2) = forward.transpose();
  v.t = -v.R * centre;
  return v;
}

TEST(FrameReach, EdgesMeetTheRowWhereTheGeometrySays) {
  // The generator's default: 1.5 m up, 5 degrees down, the row's middle 2.5 m
  // across; the top edge rises atan(270 / 572) - 5 degrees above level.
  const Plane ground;  // z = 0, normal up
  std::vector<CameraView> views;
  for (int i = 0; i < 5; ++i) views.push_back(Camera({0.125 * i, 0, 1.5}, -5 * kDeg));
  const FrameReach r = FramesReachAt(views, ground, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 2.5);
  EXPECT_EQ(r.views, 5);
  const double up = std::atan(270.0 / 572) - 5 * kDeg, down = std::atan(270.0 / 572) + 5 * kDeg;
  EXPECT_NEAR(r.top, 1.5 + 2.5 * std::tan(up), 1e-9);
  EXPECT_NEAR(r.top, 2.42, 0.01);
  EXPECT_NEAR(r.bottom, 1.5 - 2.5 * std::tan(down), 1e-9);
  EXPECT_NEAR(r.bottom, 0.04, 0.01);
  // 3 m across the lower edge meets the ground first (1.5 - 3 tan(30.3 deg) < 0).
  const FrameReach far = FramesReachAt(views, ground, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 3.0);
  EXPECT_LT(1.5 - 3.0 * std::tan(down), 0);
  EXPECT_EQ(far.bottom, 0);
  EXPECT_NEAR(far.top, 1.5 + 3.0 * std::tan(up), 1e-9);
}

TEST(FrameReach, ObliqueViewsReachFartherAndViewsFacingAwayAreLeftOut) {
  const Plane ground;
  // Turned 20 degrees along the row, the middle column meets the row
  // 2.5 / cos(20 deg) away, so its top edge is higher there.
  const CameraView oblique = Camera({0, 0, 1.5}, -5 * kDeg, 20 * kDeg);
  const FrameReach r = FramesReachAt({oblique}, ground, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 2.5);
  ASSERT_EQ(r.views, 1);
  const Eigen::Vector2d top = oblique.Normalize({480, 0});
  const Eigen::Vector3d ray = oblique.R.transpose() * Eigen::Vector3d(top.x(), top.y(), 1);
  EXPECT_NEAR(r.top, 1.5 + 2.5 * ray.z() / ray.y(), 1e-9);
  EXPECT_GT(r.top, 2.45);
  // Facing away from the row, or already beyond it: nothing to report.
  const CameraView away = Camera({0, 0, 1.5}, -5 * kDeg, 180 * kDeg);
  const CameraView beyond = Camera({0, 3, 1.5}, -5 * kDeg);
  EXPECT_EQ(FramesReachAt({away, beyond}, ground, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 2.5).views, 0);
  EXPECT_EQ(FramesReachAt({}, ground, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(), 2.5).views, 0);
}

}  // namespace
}  // namespace orchard
