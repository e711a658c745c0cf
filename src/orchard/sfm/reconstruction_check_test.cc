#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/sfm/reconstruction_check.h"

namespace orchard {
namespace {

// A camera at c looking along `forward` (horizontal), image y down = world -z.
CameraView CameraAt(const Eigen::Vector3d& c, const std::string& name,
                    const Eigen::Vector3d& forward = Eigen::Vector3d::UnitY()) {
  CameraView v;
  v.name = name;
  v.width = 960, v.height = 540, v.fx = v.fy = 570, v.cx = 480, v.cy = 270;
  const Eigen::Vector3d z = forward.normalized(), y = -Eigen::Vector3d::UnitZ(), x = y.cross(z);
  v.R.row(0) = x.transpose(), v.R.row(1) = y.transpose(), v.R.row(2) = z.transpose();
  v.t = -v.R * c;
  return v;
}

std::string Name(int i) {
  char s[32];
  std::snprintf(s, sizeof s, "frame_%04d.png", i);
  return s;
}

// A row video's path: 41 frames 12.5 cm apart along x, 1.5 m above z = 0,
// with 1 cm of shake, the camera looking across the row (+y).
std::vector<CameraView> RowPath(int frames = 41) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  std::vector<CameraView> views;
  for (int i = 0; i < frames; ++i) views.push_back(CameraAt({0.125 * i + u(rng), -2.5 + u(rng), 1.5 + u(rng)}, Name(i)));
  return views;
}

const Plane kGround;  // z = 0

bool Warns(const ReconstructionCheck& r, const std::string& words) {
  return std::any_of(r.warnings.begin(), r.warnings.end(),
                     [&](const std::string& w) { return w.find(words) != std::string::npos; });
}

TEST(ReconstructionCheck, ARowVideoPasses) {
  const ReconstructionCheck r = CheckReconstruction(RowPath(), kGround, nullptr, {});
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  EXPECT_EQ(r.frames, 41);
  EXPECT_NEAR(r.path_extent, 5.0, 0.03);
  EXPECT_NEAR(r.median_step, 0.125, 0.01);
  EXPECT_LT(r.max_step_ratio, 1.4);
  EXPECT_EQ(r.backward_steps, 0);
  EXPECT_LT(r.bend, 0.01);
  EXPECT_NEAR(r.height_median, 1.5, 0.01);
  EXPECT_LT(r.height_spread, 0.02);
  EXPECT_LT(r.view_angle_deg, 1);
  EXPECT_EQ(r.reprojection_error_px, -1);  // no model
}

TEST(ReconstructionCheck, AJumpNamesTheFrameBeforeIt) {
  std::vector<CameraView> views = RowPath();
  // Frames 20.. placed 1 m further on: 9 steps' worth missing.
  for (size_t i = 20; i < views.size(); ++i) views[i] = CameraAt(views[i].Center() + Eigen::Vector3d(1, 0, 0), views[i].name);
  const ReconstructionCheck r = CheckReconstruction(views, kGround, nullptr, {});
  EXPECT_NEAR(r.max_step_ratio, 9, 0.5);
  EXPECT_EQ(r.longest_step_after, Name(19));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(Warns(r, "a jump of 1.1")) << r.warnings.front();
  EXPECT_NEAR(r.longest_step, 1.125, 0.03);
  EXPECT_TRUE(Warns(r, "after frame frame_0019.png"));
}

TEST(ReconstructionCheck, AWalkThatStopsIsNoJump) {
  // 12 frames walking 12.5 cm apart, 30 standing (1 mm of shake), 12 walking:
  // the median step is the shake, the walking steps are not jumps.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.001, 0.001);
  std::vector<CameraView> views;
  double x = 0;
  for (int i = 0; i < 54; ++i) {
    if (i < 12 || i >= 42) x += 0.125;
    views.push_back(CameraAt({x + u(rng), -2.5 + u(rng), 1.5 + u(rng)}, Name(i)));
  }
  const ReconstructionCheck r = CheckReconstruction(views, kGround, nullptr, {});
  EXPECT_LT(r.median_step, 0.01);
  EXPECT_LT(r.max_step_ratio, 2);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
}

TEST(ReconstructionCheck, FramesOutOfOrderGoBackwards) {
  // Frames named without leading zeros and taken in the order of their names:
  // 0, 1, 10, 11, ..., 19, 2, 20, ...
  std::vector<CameraView> views = RowPath(30);
  std::vector<std::pair<std::string, CameraView>> named;
  for (size_t i = 0; i < views.size(); ++i) named.push_back({"frame_" + std::to_string(i) + ".png", views[i]});
  std::sort(named.begin(), named.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<CameraView> sorted;
  for (const auto& [name, v] : named) sorted.push_back(v);
  const ReconstructionCheck r = CheckReconstruction(sorted, kGround, nullptr, {});
  EXPECT_GE(r.backward_steps, 2);
  EXPECT_TRUE(Warns(r, "go back along the row")) << (r.warnings.empty() ? "" : r.warnings.front());
  EXPECT_TRUE(Warns(r, "order of their names"));
}

TEST(ReconstructionCheck, AFoldedSequenceGoesBackwards) {
  // The second half mirrored back over the first (a reconstruction folded on
  // itself): same steps, same height, the path doubles back.
  std::vector<CameraView> views = RowPath();
  for (size_t i = 21; i < views.size(); ++i) {
    Eigen::Vector3d c = views[i].Center();
    c.x() = 2 * views[20].Center().x() - c.x();
    views[i] = CameraAt(c, views[i].name);
  }
  const ReconstructionCheck r = CheckReconstruction(views, kGround, nullptr, {});
  EXPECT_GE(r.backward_steps, 15);
  EXPECT_TRUE(Warns(r, "folded"));
}

TEST(ReconstructionCheck, ABentPath) {
  // A quarter circle of 3 m radius: not a walk along one row.
  std::vector<CameraView> views;
  for (int i = 0; i <= 40; ++i) {
    const double a = M_PI / 2 * i / 40;
    views.push_back(CameraAt({3 * std::sin(a), 3 - 3 * std::cos(a), 1.5}, Name(i)));
  }
  const ReconstructionCheck r = CheckReconstruction(views, kGround, nullptr, {});
  EXPECT_GT(r.bend, 0.1);
  EXPECT_TRUE(Warns(r, "off a straight line")) << (r.warnings.empty() ? "" : r.warnings.front());
}

TEST(ReconstructionCheck, AGroundPlaneTiltedAgainstThePath) {
  // The ground plane 10 degrees off about the across axis: the heights above
  // it run from about 1.9 to 1.0 m along the 5 m path.
  Plane tilted;
  const double a = 10 * M_PI / 180;
  tilted.normal = Eigen::Vector3d(-std::sin(a), 0, std::cos(a));
  tilted.d = 2.5 * std::sin(a);  // through the middle of the path's foot
  const ReconstructionCheck r = CheckReconstruction(RowPath(), tilted, nullptr, {});
  EXPECT_GT(r.height_spread, 0.4);
  EXPECT_TRUE(Warns(r, "camera heights above the ground plane range from")) << (r.warnings.empty() ? "" : r.warnings.front());
}

TEST(ReconstructionCheck, ACameraLookingAlongTheRow) {
  std::vector<CameraView> views = RowPath();
  for (auto& v : views) v = CameraAt(v.Center(), v.name, Eigen::Vector3d(1, 0.2, 0));
  const ReconstructionCheck r = CheckReconstruction(views, kGround, nullptr, {});
  EXPECT_NEAR(r.view_angle_deg, 90 - std::atan(0.2) * 180 / M_PI, 1);
  EXPECT_TRUE(Warns(r, "degrees away from across the row"));
}

TEST(ReconstructionCheck, ReprojectionErrorOfTheSparsePoints) {
  ColmapModel model;
  for (int i = 0; i < 10; ++i) {
    ColmapPoint3D p;
    p.point3D_id = i;
    p.error = i < 5 ? 0.5 : 1.0;
    model.points3D[i] = p;
  }
  ReconstructionCheck r = CheckReconstruction(RowPath(), kGround, &model, {});
  EXPECT_NEAR(r.reprojection_error_px, 0.75, 1e-12);
  EXPECT_TRUE(r.warnings.empty());
  for (auto& [id, p] : model.points3D) p.error = 3;
  r = CheckReconstruction(RowPath(), kGround, &model, {});
  EXPECT_TRUE(Warns(r, "mean reprojection error is 3.00 px"));
}

TEST(ReconstructionCheck, ShortAndStillPaths) {
  ReconstructionCheck r = CheckReconstruction(RowPath(6), kGround, nullptr, {});  // 0.625 m
  EXPECT_TRUE(Warns(r, "only 0.6")) << (r.warnings.empty() ? "" : r.warnings.front());
  std::vector<CameraView> still;
  for (int i = 0; i < 5; ++i) still.push_back(CameraAt({0, -2.5, 1.5}, Name(i)));
  r = CheckReconstruction(still, kGround, nullptr, {});
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(Warns(r, "hardly move"));
}

TEST(ReconstructionCheck, FruitBelowTheGroundPlane) {
  // 200 fruit points in a wall 0.5-3 m high; three fallen apples on the ground.
  std::vector<Eigen::Vector3d> fruit;
  for (int i = 0; i < 200; ++i) fruit.push_back({0.025 * i, 0.1 * (i % 5), 0.5 + 2.5 * (i % 7) / 6.0});
  for (int i = 0; i < 3; ++i) fruit.push_back({i, 0, 0.04});
  ReconstructionCheck r = CheckReconstruction(RowPath(), kGround, nullptr, {});
  CheckFruitAboveGround(fruit, kGround, {}, &r);
  EXPECT_EQ(r.fruit_below_ground, 0);
  EXPECT_TRUE(r.warnings.empty());
  // A plane tilted 30 degrees about the path (x): the cameras keep their
  // height, the wall's lower half sinks below the plane.
  Plane tilted;
  tilted.normal = Eigen::Vector3d(0, -0.5, std::sqrt(0.75));
  tilted.d = -1.25;  // the cameras (y = -2.5, z = 1.5) 1.3 m above it
  r = CheckReconstruction(RowPath(), tilted, nullptr, {});
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  CheckFruitAboveGround(fruit, tilted, {}, &r);
  EXPECT_GT(r.fruit_below_ground, 0.3);
  EXPECT_TRUE(Warns(r, "of the fruit points lie below the ground plane"));
}

TEST(ReconstructionCheck, ApplesOfTheWrongSizeMeanAWrongScale) {
  // Single apples of 3-5 cm, as the exact masks show them at the right scale.
  std::vector<double> radii;
  for (int i = 0; i < 40; ++i) radii.push_back(0.03 + 0.02 * i / 39.0);
  ReconstructionCheck r;
  CheckAppleSize(radii, 0.03, {}, &r);
  EXPECT_NEAR(r.apple_radius, 0.045, 0.001);  // the 75th percentile
  EXPECT_EQ(r.single_apples, 40);
  EXPECT_TRUE(r.warnings.empty());
  // A scale 3x too small (a camera height given that much too low) shrinks
  // them to 1-1.7 cm (1.5 cm, half of 3 cm, at the 75th percentile) ...
  std::vector<double> small = radii, large = radii;
  for (auto& x : small) x /= 3;
  CheckAppleSize(small, 0.03, {}, &r);
  EXPECT_TRUE(Warns(r, "the scale is likely too small"));
  EXPECT_TRUE(Warns(r, "--apple-radius"));  // or the fruit is small: the user is told how to say so
  // ... and 2.5x too large grows them to 7.5-12.5 cm (11.25 cm, 3.75 times
  // 3 cm).
  r = {};
  for (auto& x : large) x *= 2.5;
  CheckAppleSize(large, 0.03, {}, &r);
  EXPECT_TRUE(Warns(r, "the scale is likely too large"));
  // Fruitlets of 1-1.7 cm with --apple-radius 0.015 pass.
  r = {};
  CheckAppleSize(small, 0.015, {}, &r);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  // Too few single apples to tell: no measure, no warning.
  r = {};
  CheckAppleSize(std::vector<double>(small.begin(), small.begin() + 9), 0.03, {}, &r);
  EXPECT_EQ(r.apple_radius, -1);
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_THROW(CheckAppleSize(radii, 0, {}, &r), Error);
}

TEST(ReconstructionCheck, FramesTooDenseOrTooSparseForThe3DStage) {
  ReconstructionCheck r;
  r.median_step = 0.125;  // the synthetic rows' 8 frames per second at 1 m/s
  CheckFrameSpacing(2.2, {}, &r);
  EXPECT_NEAR(r.frame_spacing, 0.0568, 1e-4);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  r.median_step = 0.0625;  // 16 frames per second
  CheckFrameSpacing(2.2, {}, &r);
  EXPECT_TRUE(Warns(r, "the count is likely high; keep fewer frames"));
  r = {};
  r.median_step = 0.2;  // 5 frames per second
  CheckFrameSpacing(2.2, {}, &r);
  EXPECT_TRUE(Warns(r, "the count is likely low; keep more frames"));
  r = {};
  r.median_step = 0.125;
  CheckFrameSpacing(0, {}, &r);  // no row distance: no measure
  EXPECT_EQ(r.frame_spacing, -1);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(ReconstructionCheck, BadOptions) {
  ReconstructionCheckOptions o;
  o.max_step_ratio = 1;
  EXPECT_THROW(CheckReconstruction(RowPath(), kGround, nullptr, o), Error);
  o = {};
  o.max_view_angle_deg = 0;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.min_apple_size = 4;  // above the maximum
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace orchard
