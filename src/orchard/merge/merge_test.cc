// Registration of two sides on synthetic geometry with known transforms, its
// failures (unrelated rows, different stretches of a row), the registration
// on the row's ground and canopy for sides that share few fruit clusters, and
// the inclusion-exclusion arithmetic of the shared count.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/core/test_util.h"
#include "orchard/core/file_io.h"
#include "orchard/merge/registration.h"
#include "orchard/merge/row_registration.h"
#include "orchard/merge/merge_truth.h"
#include "orchard/merge/shared_count.h"
#include "orchard/merge/side_cloud.h"
#include "orchard/merge/yield.h"

namespace orchard {
namespace {

SideCluster Cluster(int id, int count, std::vector<Eigen::Vector3d> points) {
  SideCluster c;
  c.id = id, c.count = count, c.points = std::move(points);
  UpdateClusterExtent(&c);
  return c;
}

// Apples of a thin canopy in the front row frame: x along [x0, x1], y across
// 2.2..2.8 m from the front camera path, z 0.8..2.8 m, at least 9 cm apart.
std::vector<Eigen::Vector3d> Canopy(int n, double x0, double x1, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(x0, x1), uy(2.2, 2.8), uz(0.8, 2.8);
  std::vector<Eigen::Vector3d> apples;
  while (static_cast<int>(apples.size()) < n) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    bool free = true;
    for (const auto& a : apples) free &= (a - p).norm() > 0.09;
    if (free) apples.push_back(p);
  }
  return apples;
}

// The front side sees the apples nearer than 2.6 m, the back those beyond
// 2.4 m (so the 2.4-2.6 m slab is seen from both), each with 1 cm noise; the
// back cloud is expressed in its own row frame through `back_to_front`.
void Sides(const std::vector<Eigen::Vector3d>& apples, const Eigen::Isometry3d& back_to_front, unsigned seed,
           SideCloud* front, SideCloud* back) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.01);
  auto jitter = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))); };
  front->name = "front", back->name = "back";
  for (size_t i = 0; i < apples.size(); ++i) {
    if (apples[i].y() < 2.6) front->clusters.push_back(Cluster(static_cast<int>(i), 1, {jitter(apples[i])}));
    if (apples[i].y() > 2.4)
      back->clusters.push_back(Cluster(static_cast<int>(i), 1, {back_to_front.inverse() * jitter(apples[i])}));
  }
}

TEST(RegistrationTest, RecoversKnownTransforms) {
  const std::vector<Eigen::Vector3d> apples = Canopy(150, 0, 5, 1);
  for (const auto& [heading, along, across] : {std::tuple{0.0, 0.0, 5.0}, {2.5, 0.7, 5.3}, {-4.0, -1.2, 4.6}}) {
    SideCloud front, back;
    const Eigen::Isometry3d truth = BackToFrontTransform(heading, along, across);
    Sides(apples, truth, 2, &front, &back);
    const Registration r = RegisterSides(front, back, RegistrationOptions());
    EXPECT_NEAR(r.heading_deg, heading, 0.3);
    EXPECT_NEAR(r.along, along, 0.03);
    EXPECT_NEAR(r.across, across, 0.03);
    int shared = 0;
    for (const auto& a : apples) shared += a.y() > 2.4 && a.y() < 2.6;
    EXPECT_GE(r.matched, 0.9 * shared);
    EXPECT_LE(r.matched, shared + 2);
    EXPECT_LT(r.residual, 0.03);
    EXPECT_GT(r.overlap, 4.5);
    EXPECT_LT(r.chance_matched * 1.5, r.matched);
  }
}

TEST(RegistrationTest, FallenApplesRegisterSidesThatShareNoHangingOne) {
  // A canopy no apple of which is seen from both sides, and fallen apples on
  // the ground under it that both sides see (the side stage removes them as
  // fallen; they are landmarks, not counted).
  const std::vector<Eigen::Vector3d> apples = Canopy(150, 0, 5, 4);
  const Eigen::Isometry3d truth = BackToFrontTransform(1.5, 0.4, 5.1);
  SideCloud front, back;
  Sides(apples, truth, 5, &front, &back);
  auto seen_by_both = [](const Eigen::Vector3d& p) { return p.y() > 2.4 && p.y() < 2.6; };
  front.clusters.erase(std::remove_if(front.clusters.begin(), front.clusters.end(),
                                      [&](const SideCluster& c) { return seen_by_both(c.centre); }),
                       front.clusters.end());
  back.clusters.erase(std::remove_if(back.clusters.begin(), back.clusters.end(),
                                     [&](const SideCluster& c) { return seen_by_both(truth * c.centre); }),
                      back.clusters.end());
  EXPECT_THROW(RegisterSides(front, back, RegistrationOptions()), Error);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> ux(0, 5), uy(2.0, 3.0), uz(0.03, 0.05);
  std::normal_distribution<double> noise(0, 0.01);
  for (int i = 0; i < 24; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng)), n(noise(rng), noise(rng), 0);
    front.fallen.push_back(Cluster(1000 + i, 1, {p + n}));
    back.fallen.push_back(Cluster(1000 + i, 1, {truth.inverse() * (p - n)}));
  }
  const SideCloud front_marks = WithFallenLandmarks(front), back_marks = WithFallenLandmarks(back);
  EXPECT_EQ(front_marks.clusters.size(), front.clusters.size() + 24);
  EXPECT_TRUE(front_marks.fallen.empty());
  const Registration r = RegisterSides(front_marks, back_marks, RegistrationOptions());
  EXPECT_NEAR(r.heading_deg, 1.5, 0.3);
  EXPECT_NEAR(r.along, 0.4, 0.03);
  EXPECT_NEAR(r.across, 5.1, 0.03);
  EXPECT_GE(r.matched, 22);
  EXPECT_LE(r.matched, 24 + 2);
}

TEST(RegistrationTest, RecoversTheBackSidesScale) {
  // The back side's reconstruction 6% too large (its ground fit off, as
  // COLMAP's sparse ground can make it): its clusters lie up to 30 cm from
  // the front's at the right alignment, beyond the 8 cm match distance.
  const std::vector<Eigen::Vector3d> apples = Canopy(150, 0, 5, 1);
  const Eigen::Isometry3d truth = BackToFrontTransform(1.5, 0.4, 5.0);
  SideCloud front, back;
  Sides(apples, truth, 2, &front, &back);
  ScaleSideCloud(&back, 1.06);
  int shared = 0;
  for (const auto& a : apples) shared += a.y() > 2.4 && a.y() < 2.6;
  const Registration r = RegisterSides(front, back, RegistrationOptions());
  EXPECT_NEAR(r.back_scale, 1 / 1.06, 0.005);
  EXPECT_NEAR(r.heading_deg, 1.5, 0.3);
  EXPECT_NEAR(r.along, 0.4, 0.03);
  EXPECT_NEAR(r.across, 5.0, 0.03);
  EXPECT_GE(r.matched, 0.9 * shared);
  EXPECT_LT(r.residual, 0.03);
  // The same alignment checked on the back side rescaled by the result.
  SideCloud rescaled = back;
  ScaleSideCloud(&rescaled, r.back_scale);
  EXPECT_EQ(EvaluateAlignment(front, rescaled, r.back_to_front, RegistrationOptions()).matched, r.matched);
  // Taken at its own scale, the side matches too few clusters.
  RegistrationOptions fixed;
  fixed.max_scale_change = 0;
  EXPECT_THROW(RegisterSides(front, back, fixed), Error);
  // Right scales are left alone.
  SideCloud right_front, right_back;
  Sides(apples, truth, 2, &right_front, &right_back);
  EXPECT_NEAR(RegisterSides(right_front, right_back, RegistrationOptions()).back_scale, 1.0, 0.003);
}

TEST(RegistrationTest, EvaluatesAGivenTransform) {
  const std::vector<Eigen::Vector3d> apples = Canopy(100, 0, 4, 3);
  SideCloud front, back;
  const Eigen::Isometry3d truth = BackToFrontTransform(1.0, 0.3, 5.0);
  Sides(apples, truth, 4, &front, &back);
  const Registration r = EvaluateAlignment(front, back, truth, RegistrationOptions());
  EXPECT_NEAR(r.heading_deg, 1.0, 1e-9);
  EXPECT_NEAR(r.along, 0.3, 1e-9);
  EXPECT_NEAR(r.across, 5.0, 1e-9);
  EXPECT_GT(r.matched, 5);
}

TEST(RegistrationTest, FailsOnSidesOfDifferentRows) {
  SideCloud front, back, other_front, other_back;
  const Eigen::Isometry3d t = BackToFrontTransform(0, 0, 5);
  Sides(Canopy(150, 0, 5, 11), t, 5, &front, &back);
  Sides(Canopy(150, 0, 5, 12), t, 6, &other_front, &other_back);  // another row
  try {
    RegisterSides(front, other_back, RegistrationOptions());
    FAIL() << "registered two different rows";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("same row"), std::string::npos) << e.what();
  }
}

TEST(RegistrationTest, GivenPosesSettleAnAlignmentThatIsNotDistinct) {
  // A canopy that repeats every 1.5 m: shifted by one period, three of the
  // four tiles still match, so the fruit alone cannot tell the alignments
  // apart (a dense, regular canopy of U-Net blobs does the same).
  std::vector<Eigen::Vector3d> apples;
  for (const auto& a : Canopy(40, 0, 1.5, 21))
    for (int tile = 0; tile < 4; ++tile) apples.push_back(a + Eigen::Vector3d(1.5 * tile, 0, 0));
  const Eigen::Isometry3d truth = BackToFrontTransform(1.0, 0.2, 5.0);
  SideCloud front, back;
  Sides(apples, truth, 22, &front, &back);
  try {
    RegisterSides(front, back, RegistrationOptions());
    FAIL() << "took an alignment that another matches nearly as well";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ambiguous"), std::string::npos) << e.what();
  }
  // Poses given for both sides that imply the same alignment settle it...
  const Eigen::Isometry3d given = BackToFrontTransform(1.3, 0.25, 5.05);
  const Registration r = RegisterSides(front, back, RegistrationOptions(), &given);
  EXPECT_TRUE(r.settled_by_given_poses);
  EXPECT_NEAR(r.along, 0.2, 0.03);
  EXPECT_NEAR(r.across, 5.0, 0.03);
  EXPECT_GE(2 * r.chance_matched, r.matched);
  // ...poses that imply another (one period off) do not.
  const Eigen::Isometry3d off = BackToFrontTransform(1.0, 1.7, 5.0);
  EXPECT_THROW(RegisterSides(front, back, RegistrationOptions(), &off), Error);
  // A distinct alignment is not marked as settled by the poses.
  SideCloud plain_front, plain_back;
  Sides(Canopy(150, 0, 5, 1), truth, 2, &plain_front, &plain_back);
  EXPECT_FALSE(RegisterSides(plain_front, plain_back, RegistrationOptions(), &given).settled_by_given_poses);
}

TEST(RegistrationTest, FailsWhenTheSidesCoverDifferentStretches) {
  // The back side films 3..10 m of a row whose front side covers 0..5 m.
  const std::vector<Eigen::Vector3d> apples = Canopy(220, 0, 10, 7);
  SideCloud front, back;
  Sides(apples, BackToFrontTransform(0, 0, 5), 8, &front, &back);
  front.clusters.erase(std::remove_if(front.clusters.begin(), front.clusters.end(),
                                      [](const SideCluster& c) { return c.centre.x() > 5; }),
                       front.clusters.end());
  const Eigen::Isometry3d to_front = BackToFrontTransform(0, 0, 5);
  back.clusters.erase(std::remove_if(back.clusters.begin(), back.clusters.end(),
                                     [&](const SideCluster& c) { return (to_front * c.centre).x() < 3; }),
                      back.clusters.end());
  try {
    RegisterSides(front, back, RegistrationOptions());
    FAIL() << "registered sides that overlap by 2 of 5 m";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("different stretches"), std::string::npos) << e.what();
  }
}

TEST(RegistrationTest, FailsWithTooFewClusters) {
  SideCloud front, back;
  Sides(Canopy(6, 0, 2, 9), BackToFrontTransform(0, 0, 5), 10, &front, &back);
  back.clusters.resize(2);
  EXPECT_THROW(RegisterSides(front, back, RegistrationOptions()), Error);
}

// Four trees 1.25 m apart. (A function, not a braced default member: GCC 12
// wrongly warns of a dangling pointer where that default is inlined.)
std::vector<double> FourTrees() { return {0, 1.25, 2.5, 3.75}; }

// A row seen by COLMAP from both sides, in the front row frame: trees 1 m
// wide at `trees` (x centres), canopy 1.2 m thick centred 2.5 m from the
// front path, 0.6..3 m high; each side's sparse points are leaves between its
// face and the centre plane, and ground over the stretch it films
// (`seen_*`, x range); apples near each face, `shared` of them seen from both.
struct RowScene {
  std::vector<double> trees = FourTrees();
  double seen_front_lo = -2, seen_front_hi = 5.75, seen_back_lo = -2, seen_back_hi = 5.75;
  int shared = 0;
  unsigned seed = 1;
  // Trunks 4.5 cm in radius at `trees`, under the canopy (points on the
  // face each side sees, 0.12-0.5 m up); grass over the whole stretch at
  // trunk height; a clod (a low lump) at x = 1.8 m.
  bool trunks = false, grass = false, clod = false;
};

void RowSides(const RowScene& scene, const Eigen::Isometry3d& back_to_front, SideCloud* front, SideCloud* back) {
  std::mt19937 rng(scene.seed);
  std::uniform_real_distribution<double> u(0, 1);
  front->name = "front", back->name = "back";
  const Eigen::Isometry3d to_back = back_to_front.inverse();
  auto seen = [&](double x, bool f) {
    return f ? x > scene.seen_front_lo && x < scene.seen_front_hi : x > scene.seen_back_lo && x < scene.seen_back_hi;
  };
  for (const bool f : {true, false}) {
    SideCloud* side = f ? front : back;
    auto add = [&](const Eigen::Vector3d& p) { side->sparse.push_back(f ? p : Eigen::Vector3d(to_back * p)); };
    for (double t : scene.trees)
      for (int i = 0; i < 600; ++i) {
        const Eigen::Vector3d p(t - 0.5 + u(rng), f ? 1.9 + 0.6 * u(rng) : 3.1 - 0.6 * u(rng), 0.6 + 2.4 * u(rng));
        if (seen(p.x(), f)) add(p);
      }
    std::normal_distribution<double> noise(0, 0.015);
    if (scene.trunks)
      for (double t : scene.trees)
        for (int i = 0; i < 25; ++i) {
          const Eigen::Vector3d p(t + noise(rng), (f ? 2.5 - 0.045 : 2.5 + 0.045) + noise(rng), 0.12 + 0.38 * u(rng));
          if (seen(p.x(), f)) add(p);
        }
    const double lo = f ? scene.seen_front_lo : scene.seen_back_lo, hi = f ? scene.seen_front_hi : scene.seen_back_hi;
    if (scene.grass)
      for (int i = 0; i < 200; ++i) add(Eigen::Vector3d(lo + (hi - lo) * u(rng), 1.9 + 1.2 * u(rng), 0.12 + 0.2 * u(rng)));
    if (scene.clod && seen(1.8, f))
      for (int i = 0; i < 30; ++i) add(Eigen::Vector3d(1.8 + noise(rng), 2.3 + noise(rng), 0.12 + 0.04 * u(rng)));
    // The cameras film 2 m either side of where they pass, 1.5 m high.
    for (double x = lo + 2; x <= hi - 2 + 1e-9; x += 0.125) {
      const Eigen::Vector3d c(x, f ? 0 : 5, 1.5);
      side->cameras.push_back(f ? c : Eigen::Vector3d(to_back * c));
    }
    for (int i = 0; i < 800; ++i) add(Eigen::Vector3d(lo + (hi - lo) * u(rng), f ? 0.5 + 5 * u(rng) : 5 - 4.5 * u(rng), 0.01 * u(rng)));
    // Apples near the face, the two sides' apart along the row so that none
    // is shared by chance.
    int id = 0;
    for (double x = scene.trees.front() - 0.4 + (f ? 0 : 0.18); x < scene.trees.back() + 0.4; x += 0.37) {
      if (!seen(x, f)) continue;
      const Eigen::Vector3d p(x, f ? 2.0 : 3.0, 1.0 + std::fmod(x * 7.3 + 10, 1.5));
      side->clusters.push_back(Cluster(id++, 1, {f ? p : Eigen::Vector3d(to_back * p)}));
    }
    for (int k = 0; k < scene.shared; ++k) {
      const Eigen::Vector3d p(0.2 + 0.9 * k, 2.5, 2.7 - 0.3 * k);
      side->clusters.push_back(Cluster(id++, 1, {f ? p : Eigen::Vector3d(to_back * p)}));
    }
  }
}

TEST(RowRegistrationTest, RecoversKnownTransformsWithoutSharedFruit) {
  // The apples seen by both sides are too few for the fruit registration.
  // Without shared fruit the row's shape alone cannot tell it from another
  // row of the same planting: it takes the user's word (--same-row).
  RowRegistrationOptions same_row;
  same_row.assume_same_row = true;
  for (const auto& [along, across] : {std::pair{0.0, 5.0}, {0.4, 5.3}, {-0.8, 4.7}}) {
    SideCloud front, back;
    RowSides(RowScene(), BackToFrontTransform(0, along, across), &front, &back);
    EXPECT_THROW(RegisterSides(front, back, RegistrationOptions()), Error);
    try {
      RegisterSidesOnRow(front, back, RowRegistrationOptions());
      FAIL() << "registered on the canopy alone without --same-row";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--same-row"), std::string::npos) << e.what();
    }
    const Registration r = RegisterSidesOnRow(front, back, same_row);
    EXPECT_TRUE(r.on_row);
    EXPECT_NEAR(r.heading_deg, 0, 1e-9);  // kept at the half turn
    EXPECT_NEAR(r.along, along, 0.05);
    // Assumed: each side's leaves reach the centre plane; the 95% quantile
    // of a 0.6 m band falls 3 cm short of it on each side.
    EXPECT_EQ(r.across_from, Registration::Across::kAssumed);
    EXPECT_NEAR(r.across, across - 0.06, 0.03);
    EXPECT_GT(r.correlation, 0.9);
    EXPECT_GT(r.overlap, 3.5);  // the camera paths: 0..3.75 m
  }
  // Row distances that leave no room for the canopy between the sides: the
  // canopy found is not the row's.
  {
    SideCloud front, back;
    RowSides(RowScene(), BackToFrontTransform(0, 0, 5.0), &front, &back);
    front.row_distance = back.row_distance = 0.9;
    try {
      RegisterSidesOnRow(front, back, same_row);
      FAIL() << "placed the sides farther apart than the row allows";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("not its own row's"), std::string::npos) << e.what();
    }
    front.row_distance = back.row_distance = 2.0;  // 4.94 m within 2.0 + 2.0 + 3 m
    EXPECT_NO_THROW(RegisterSidesOnRow(front, back, same_row));
  }
  // A path not quite parallel (0.5 deg): the half turn is kept, so the
  // heading is off by that much and the offsets stay close.
  SideCloud front, back;
  RowSides(RowScene(), BackToFrontTransform(0.5, 0.3, 5.0), &front, &back);
  const Registration r = RegisterSidesOnRow(front, back, same_row);
  EXPECT_NEAR(r.along, 0.3, 0.06);
  EXPECT_NEAR(r.across, 5.0 - 0.06, 0.06);
}

TEST(RowRegistrationTest, FindsTrunksUnderTheCanopy) {
  RowScene scene;
  scene.trunks = scene.grass = scene.clod = true;
  SideCloud front, back;
  const double across = 5.2;
  RowSides(scene, BackToFrontTransform(0, 0.3, across), &front, &back);
  const RowRegistrationOptions o;
  for (const SideCloud* side : {&front, &back}) {
    const std::vector<Trunk> trunks = FindTrunks(*side, o);
    ASSERT_EQ(trunks.size(), 4u) << side->name;  // not the clod, not the grass
    for (size_t i = 0; i < trunks.size(); ++i) {
      // The back's trunks, brought into the front frame.
      const Eigen::Vector3d at =
          side == &front ? Eigen::Vector3d(trunks[i].along, trunks[i].across, 0)
                         : Eigen::Vector3d(BackToFrontTransform(0, 0.3, across) *
                                           Eigen::Vector3d(trunks[i].along, trunks[i].across, 0));
      const size_t tree = side == &front ? i : trunks.size() - 1 - i;  // the back runs the other way
      EXPECT_NEAR(at.x(), scene.trees[tree], 0.02) << side->name << " trunk " << i;
      EXPECT_NEAR(at.y(), side == &front ? 2.455 : 2.545, 0.02) << side->name << " trunk " << i;
      EXPECT_GE(trunks[i].points, 20);
    }
  }
  // Grass and a clod alone are no trunks.
  scene.trunks = false;
  SideCloud bare_front, bare_back;
  RowSides(scene, BackToFrontTransform(0, 0.3, across), &bare_front, &bare_back);
  EXPECT_TRUE(FindTrunks(bare_front, o).empty());
  EXPECT_TRUE(FindTrunks(bare_back, o).empty());
  // Given poses: no sparse points, no trunks.
  bare_front.sparse.clear();
  EXPECT_TRUE(FindTrunks(bare_front, o).empty());
  EXPECT_TRUE(std::isnan(AcrossFromTrunks(FindTrunks(bare_front, o), FindTrunks(back, o), o).across));
}

TEST(RowRegistrationTest, TreesFromBothSidesTrunks) {
  auto trunks = [](std::vector<double> xs) {
    std::vector<Trunk> t;
    for (double x : xs) t.push_back({x, 2.5, 20});
    return t;
  };
  // The back misses the last tree and sees one the front misses; the two
  // sides' trunks of a tree are 4 cm apart.
  const std::vector<RowTree> trees = TreesFromTrunks(trunks({0, 1.25, 3.75}), trunks({2.48, 1.21, -0.04}), 0.25);
  ASSERT_EQ(trees.size(), 4u);
  EXPECT_NEAR(trees[0].along, -0.02, 1e-12);
  EXPECT_TRUE(trees[0].front && trees[0].back);
  EXPECT_NEAR(trees[1].along, 1.23, 1e-12);
  EXPECT_NEAR(trees[2].along, 2.48, 1e-12);
  EXPECT_TRUE(!trees[2].front && trees[2].back);
  EXPECT_NEAR(trees[3].along, 3.75, 1e-12);
  EXPECT_TRUE(trees[3].front && !trees[3].back);
  // Farther apart than the merge distance: two trees.
  EXPECT_EQ(TreesFromTrunks(trunks({0}), trunks({0.3}), 0.25).size(), 2u);

  // Each tree holds the row up to the midpoints; the ends reach half the
  // inner spacing beyond the end trees.
  const std::vector<RowTree> row = {{0, true, true}, {1.2, true, true}, {2.6, true, true}};
  EXPECT_EQ(TreeAt(row, 0.59, 0.5), 0);
  EXPECT_EQ(TreeAt(row, 0.61, 0.5), 1);
  EXPECT_EQ(TreeAt(row, 1.89, 0.5), 1);
  EXPECT_EQ(TreeAt(row, 1.91, 0.5), 2);
  EXPECT_EQ(TreeAt(row, -0.59, 0.5), 0);
  EXPECT_EQ(TreeAt(row, -0.61, 0.5), -1);
  EXPECT_EQ(TreeAt(row, 3.29, 0.5), 2);
  EXPECT_EQ(TreeAt(row, 3.31, 0.5), -1);
  EXPECT_EQ(TreeAt({{1.0, true, false}}, 1.4, 0.5), 0);
  EXPECT_EQ(TreeAt({{1.0, true, false}}, 1.6, 0.5), -1);
  EXPECT_EQ(TreeAt({}, 0, 0.5), -1);
}

TEST(RowRegistrationTest, TakesTheAcrossDistanceFromTrunks) {
  // No shared fruit: the trunks measure the distance across where the
  // centre-plane assumption would guess it; still only on the user's word.
  RowScene scene;
  scene.trunks = scene.grass = true;
  RowRegistrationOptions same_row;
  same_row.assume_same_row = true;
  for (const auto& [along, across] : {std::pair{0.0, 5.0}, {0.4, 5.6}, {-0.8, 4.7}}) {
    SideCloud front, back;
    RowSides(scene, BackToFrontTransform(0, along, across), &front, &back);
    try {
      RegisterSidesOnRow(front, back, RowRegistrationOptions());
      FAIL() << "registered on the canopy and trunks without --same-row";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--same-row to register the sides on the canopy and the trunks"),
                std::string::npos)
          << e.what();
    }
    const Registration r = RegisterSidesOnRow(front, back, same_row);
    EXPECT_EQ(r.across_from, Registration::Across::kTrunks);
    EXPECT_EQ(r.trunks_front, 4);
    EXPECT_EQ(r.trunks_back, 4);
    // The trunks' near faces: the paths' distance less a trunk's diameter.
    EXPECT_NEAR(r.across, across - 0.09, 0.02);
    EXPECT_NEAR(r.across_trunks, r.across, 1e-12);
    EXPECT_NEAR(r.along, along, 0.05);
    // Too few trunks for the rule: the assumption (1.2 m band: 6 cm short
    // whatever the distance, where the trunks follow it).
    RowRegistrationOptions more = same_row;
    more.min_trunks = 5;
    const Registration a = RegisterSidesOnRow(front, back, more);
    EXPECT_EQ(a.across_from, Registration::Across::kAssumed);
    EXPECT_TRUE(std::isnan(a.across_trunks));
  }
}

TEST(RowRegistrationTest, TakesTheAcrossDistanceFromSharedFruit) {
  RowScene scene;
  scene.shared = 4;  // too few for the fruit registration (needs 5)
  SideCloud front, back;
  RowSides(scene, BackToFrontTransform(0, 0.25, 5.1), &front, &back);
  EXPECT_THROW(RegisterSides(front, back, RegistrationOptions()), Error);
  const Registration r = RegisterSidesOnRow(front, back, RowRegistrationOptions());
  EXPECT_EQ(r.across_from, Registration::Across::kFruit);
  EXPECT_EQ(r.matched, 4);
  EXPECT_NEAR(r.along, 0.25, 0.01);
  EXPECT_NEAR(r.across, 5.1, 0.01);
  EXPECT_LT(r.residual, 0.01);
}

TEST(RowRegistrationTest, ChecksAnAlignmentAgainstTheCanopy) {
  RowScene scene;
  scene.trees = {0, 1.1, 2.5, 3.6};  // uneven, as real trees
  SideCloud front, back;
  const Eigen::Isometry3d truth = BackToFrontTransform(0, 0.3, 5.0);
  RowSides(scene, truth, &front, &back);
  const RowRegistrationOptions o;
  EXPECT_GT(CanopyProfileCorrelation(front, back, truth, o), o.min_correlation);
  EXPECT_LT(CanopyProfileCorrelation(front, back, BackToFrontTransform(0, 1.5, 5.0), o), o.min_correlation);
  SideCloud bare = back;
  bare.sparse.clear();
  EXPECT_TRUE(std::isnan(CanopyProfileCorrelation(front, bare, truth, o)));
}

TEST(RowRegistrationTest, FailsOnTheSameSideGivenTwice) {
  SideCloud front, back;
  RowSides(RowScene(), BackToFrontTransform(0, 0, 5), &front, &back);
  SideCloud again = front;
  again.name = "back";
  RowRegistrationOptions o;
  o.assume_same_row = true;  // reach the faces check (no fruit is shared)
  try {
    RegisterSidesOnRow(front, again, o);
    FAIL() << "registered a side with itself";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("same row"), std::string::npos) << e.what();
  }
}

TEST(RowRegistrationTest, FailsWhenTheProfilesDoNotMatch) {
  // The back side of another row: three trees of other widths and gaps.
  SideCloud front, back, other_front, other_back;
  const Eigen::Isometry3d t = BackToFrontTransform(0, 0, 5);
  RowSides(RowScene(), t, &front, &back);
  RowScene other;
  other.trees = {-1.0, 0.1, 3.9};
  other.seed = 2;
  RowSides(other, t, &other_front, &other_back);
  RowRegistrationOptions o;
  o.assume_same_row = true;  // the profiles alone must tell these rows apart
  try {
    RegisterSidesOnRow(front, other_back, o);
    FAIL() << "registered two different rows";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("same row"), std::string::npos) << e.what();
  }
}

TEST(RowRegistrationTest, FailsWhenTheSidesCoverDifferentStretches) {
  // A row of eight trees (unevenly spaced, as real ones are); the front
  // passes 0..4 m, the back 5..9 m.
  RowScene scene;
  scene.trees = {0, 1.1, 2.5, 3.6, 5.1, 6.2, 7.6, 8.9};
  scene.seen_front_lo = -2, scene.seen_front_hi = 6, scene.seen_back_lo = 3, scene.seen_back_hi = 11;
  SideCloud front, back;
  RowSides(scene, BackToFrontTransform(0, 0, 5), &front, &back);
  RowRegistrationOptions o;
  o.assume_same_row = true;  // the path overlap alone must stop it
  try {
    RegisterSidesOnRow(front, back, o);
    FAIL() << "registered sides that cover different stretches";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_TRUE(m.find("different stretches") != std::string::npos || m.find("same row") != std::string::npos) << m;
  }
}

TEST(RowRegistrationTest, StopsOnSidesOfTwoRowsOfOnePlanting) {
  // Two rows of one planting grid: the same trees, other leaves. Their
  // canopy profiles agree, and no apple is seen from both sides.
  SideCloud front, back, other_front, other_back;
  const Eigen::Isometry3d t = BackToFrontTransform(0, 0, 5);
  RowSides(RowScene(), t, &front, &back);
  RowScene other;
  other.seed = 3;
  RowSides(other, t, &other_front, &other_back);
  try {
    RegisterSidesOnRow(front, other_back, RowRegistrationOptions());
    FAIL() << "registered the sides of two rows on their canopies";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("another row of the same planting"), std::string::npos) << m;
    EXPECT_NE(m.find("--same-row"), std::string::npos) << m;
  }
  // Why it stops: on the user's word the canopies register as well as a
  // row's own sides do.
  RowRegistrationOptions o;
  o.assume_same_row = true;
  EXPECT_GT(RegisterSidesOnRow(front, other_back, o).correlation, o.min_correlation);
  // One shared apple too few for the across distance is still no evidence;
  // enough of them are (TakesTheAcrossDistanceFromSharedFruit).
  RowScene few;
  few.shared = 2;
  SideCloud few_front, few_back;
  RowSides(few, t, &few_front, &few_back);
  EXPECT_THROW(RegisterSidesOnRow(few_front, few_back, RowRegistrationOptions()), Error);
}

TEST(RowRegistrationTest, LevelsASideOnTheGroundOfItsSparsePoints) {
  SideCloud front, back;
  RowSides(RowScene(), BackToFrontTransform(0, 0, 5), &front, &back);
  RowRegistrationOptions o;
  EXPECT_FALSE(LevelOnSparseGround(&front, o).changed);  // already on its ground
  // The side took a plane 0.75 m above the ground for its ground and
  // scaled itself so that the cameras stand 1.5 m above that plane: lengths
  // are 2x too long, the true ground at z = -1.5.
  SideCloud wrong = front;
  for (auto& p : wrong.sparse) p = 2 * (p - Eigen::Vector3d(0, 0, 0.75));
  for (auto& c : wrong.clusters) {
    for (auto& p : c.points) p = 2 * (p - Eigen::Vector3d(0, 0, 0.75));
    UpdateClusterExtent(&c);
  }
  const Levelling l = LevelOnSparseGround(&wrong, o);
  EXPECT_TRUE(l.changed);
  EXPECT_NEAR(l.ground_height, -1.5, 0.02);
  EXPECT_NEAR(l.scale, 0.5, 0.01);
  for (size_t i = 0; i < front.clusters.size(); ++i)
    EXPECT_LT((wrong.clusters[i].centre - front.clusters[i].centre).norm(), 0.02) << i;
  // Metric given poses whose own ground fit took a plane 10 cm up and tilted
  // 2 degrees across the row: levelled onto the true ground, lengths kept.
  SideCloud tilted = front;
  const Eigen::AngleAxisd tilt(2 * M_PI / 180, Eigen::Vector3d::UnitX());
  const auto onto_tilted = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(tilt * (p - Eigen::Vector3d(0, 0, 0.1)));
  };
  for (auto& p : tilted.sparse) p = onto_tilted(p);
  for (auto& c : tilted.clusters) {
    for (auto& p : c.points) p = onto_tilted(p);
    UpdateClusterExtent(&c);
  }
  const Levelling kept = LevelOnSparseGround(&tilted, o, /*keep_scale=*/true);
  EXPECT_TRUE(kept.changed);
  EXPECT_EQ(kept.scale, 1.0);
  EXPECT_NEAR(kept.tilt_deg, 2.0, 0.1);
  for (size_t i = 0; i < front.clusters.size(); ++i)
    EXPECT_LT((tilted.clusters[i].centre - front.clusters[i].centre).norm(), 0.02) << i;
  // Too few sparse points: no levelling, and no registration on the row.
  SideCloud bare = front;
  bare.sparse.resize(20);
  EXPECT_FALSE(LevelOnSparseGround(&bare, o).changed);
  EXPECT_THROW(RegisterSidesOnRow(bare, back, o), Error);
  o.min_correlation = 1.5;
  EXPECT_THROW(o.Check(), Error);
}

TEST(SharedCountTest, InclusionExclusionOverIntersectingClusters) {
  const Eigen::Vector3d a(0, 2.5, 1.5), b(1, 2.5, 1.5), far(3, 2.5, 1.5), dx(0.09, 0, 0), e(0.01, 0, 0);
  const std::vector<SideCluster> front = {
      Cluster(1, 1, {a}),                          // one apple, also seen from the back (C)
      Cluster(2, 3, {b, b + dx, b + 2 * dx}),     // three apples, two of them also in the back's D
      Cluster(3, 2, {far, far + dx}),              // front only
  };
  const std::vector<SideCluster> back = {
      Cluster(1, 1, {a + e}),                             // C: the same apple as front 1
      Cluster(2, 2, {b + 2 * dx + e, b + 3 * dx}),        // D: meets front 2 at one point
      Cluster(3, 1, {far + Eigen::Vector3d(0, 0, 0.5)}),  // back only
  };
  const SharedCount s = CountSharedApples(front, back, SharedCountOptions());
  EXPECT_EQ(s.front, 6);
  EXPECT_EQ(s.back, 4);
  ASSERT_EQ(s.links.size(), 2u);
  EXPECT_DOUBLE_EQ(s.links[0].back_fraction, 1.0);  // C wholly near front 1
  EXPECT_DOUBLE_EQ(s.links[1].front_fraction, 1.0 / 3);
  EXPECT_DOUBLE_EQ(s.links[1].back_fraction, 0.5);
  ASSERT_EQ(s.groups.size(), 2u);
  EXPECT_DOUBLE_EQ(s.shared, 3.0);  // min(1, 1) + min(3, 2)
  EXPECT_EQ(s.total, 7);            // 6 + 4 - 3
  EXPECT_DOUBLE_EQ(s.front_shared[0], 1.0);
  EXPECT_DOUBLE_EQ(s.front_shared[1], 2.0);
  EXPECT_DOUBLE_EQ(s.front_shared[2], 0.0);
  EXPECT_DOUBLE_EQ(s.back_shared[1], 2.0);
  EXPECT_DOUBLE_EQ(s.back_shared[2], 0.0);
}

TEST(SharedCountTest, LinkedClustersShareTheSmallerSidesApples) {
  // One front apple near two back clusters of one apple each (one of them
  // a duplicate): the group holds max(1, 2) = 2 apples.
  const Eigen::Vector3d a(0, 2.5, 1.5), e(0.02, 0, 0);
  const std::vector<SideCluster> front = {Cluster(1, 1, {a})};
  const std::vector<SideCluster> back = {Cluster(1, 1, {a + e}), Cluster(2, 1, {a - e})};
  const SharedCount s = CountSharedApples(front, back, SharedCountOptions());
  EXPECT_DOUBLE_EQ(s.shared, 1.0);
  EXPECT_EQ(s.total, 2);
  EXPECT_DOUBLE_EQ(s.back_shared[0], 0.5);
  // A chain links clusters through each other: front 1 - back 1 - front 2.
  const std::vector<SideCluster> chain_front = {Cluster(1, 2, {a}), Cluster(2, 1, {a + 3 * e})};
  const std::vector<SideCluster> chain_back = {Cluster(1, 2, {a + 1.5 * e})};
  const SharedCount c = CountSharedApples(chain_front, chain_back, SharedCountOptions());
  ASSERT_EQ(c.groups.size(), 1u);
  EXPECT_EQ(c.total, 3);  // 3 + 2 - min(3, 2)
  // Apples farther apart than the intersection distance are not shared.
  const std::vector<SideCluster> apart = {Cluster(1, 1, {a + Eigen::Vector3d(0.12, 0, 0)})};
  EXPECT_EQ(CountSharedApples(front, apart, SharedCountOptions()).total, 2);
  EXPECT_THROW(CountSharedApples(front, back, SharedCountOptions{-1}), Error);
}

TEST(SharedCountTest, ClustersLinkedToNothingCountTheirUnlinkedCount) {
  // Front 1 and back 1 hold one apple seen from both sides; front 2 is seen
  // from the front only and counts 3 by its side's own rule, 2 in its
  // largest views. The linked clusters keep their count whatever theirs.
  const Eigen::Vector3d a(0, 2.5, 1.5), far(1, 2.5, 1.5), e(0.01, 0, 0);
  std::vector<SideCluster> front = {Cluster(1, 1, {a}), Cluster(2, 2, {far})};
  const std::vector<SideCluster> back = {Cluster(1, 1, {a + e})};
  front[0].count_unlinked = 4;
  front[1].count_unlinked = 3;
  const SharedCount s = CountSharedApples(front, back, SharedCountOptions());
  EXPECT_EQ(s.front_counts, (std::vector<int>{1, 3}));
  EXPECT_EQ(s.back_counts, (std::vector<int>{1}));
  EXPECT_EQ(s.front, 4);
  EXPECT_DOUBLE_EQ(s.shared, 1.0);
  EXPECT_EQ(s.total, 4);  // 4 + 1 - 1
  // Unset (-1), the count stands.
  front[1].count_unlinked = -1;
  EXPECT_EQ(CountSharedApples(front, back, SharedCountOptions()).total, 3);
}

// An edge apple (seen only as slivers at the top edge) with one ray from
// `near` to `far`; its point is a guess along it.
SideCluster EdgeApple(int id, const Eigen::Vector3d& near, const Eigen::Vector3d& far) {
  SideCluster c = Cluster(id, 1, {0.5 * (near + far)});
  c.edge = true;
  c.ray_ends = {near, far};
  return c;
}

TEST(SharedCountTest, EdgeApplesLinkAlongTheirSliversRays) {
  // Front frame, the row 2.5 m across. The back's top edge rises away from
  // its camera path (y = 5): its sliver rays run from y 3.1 (2.45 m up) to
  // 1.5 (2.85 m up), 2.6 m up at the row; the front's the other way.
  const Eigen::Vector3d tracked(0, 2.5, 2.62);  // the front tracks this apple
  const Eigen::Vector3d dx(0.1, 0, 0);
  const std::vector<SideCluster> front = {
      Cluster(1, 1, {tracked}),
      EdgeApple(2, Eigen::Vector3d(0, 1.9, 2.45) + dx, Eigen::Vector3d(0, 3.5, 2.85) + dx),  // also the back's edge apple 2
  };
  const std::vector<SideCluster> back = {
      EdgeApple(1, {0, 3.1, 2.45}, {0, 1.5, 2.85}),  // the sliver of the front's tracked apple
      EdgeApple(2, Eigen::Vector3d(0, 3.1, 2.45) + dx, Eigen::Vector3d(0, 1.5, 2.85) + dx),
  };
  const SharedCount s = CountSharedApples(front, back, SharedCountOptions());
  EXPECT_EQ(s.front, 2);
  EXPECT_EQ(s.back, 2);
  EXPECT_DOUBLE_EQ(s.back_shared[0], 1.0);  // all of it is the tracked apple
  EXPECT_EQ(s.back_edge_on, (std::vector<int>{0, -1}));
  EXPECT_EQ(s.front_edge_on, (std::vector<int>{-1, -1}));
  ASSERT_EQ(s.groups.size(), 1u);  // the two edge apples' rays meet
  EXPECT_EQ(s.groups[0].front, std::vector<int>{1});
  EXPECT_DOUBLE_EQ(s.shared, 2.0);
  EXPECT_EQ(s.total, 2);
  // Beside the tracked apple's line of sight (6 cm) or well below it, the
  // back's sliver is another apple.
  std::vector<SideCluster> beside = back;
  beside[0] = EdgeApple(1, {0.06, 3.1, 2.45}, {0.06, 1.5, 2.85});
  EXPECT_EQ(CountSharedApples(front, beside, SharedCountOptions()).total, 3);
  beside[0] = EdgeApple(1, {0, 3.1, 2.40}, {0, 1.5, 2.80});  // 2.55 m up at the row: the apple 7 cm above
  EXPECT_EQ(CountSharedApples(front, beside, SharedCountOptions()).total, 2);
  beside[0] = EdgeApple(1, {0, 3.1, 2.55}, {0, 1.5, 2.95});  // 2.7 m up: the apple 8 cm below
  EXPECT_EQ(CountSharedApples(front, beside, SharedCountOptions()).total, 3);
  // Two edge apples whose rays do not meet are two apples.
  std::vector<SideCluster> apart = back;
  apart[1] = EdgeApple(2, Eigen::Vector3d(0, 3.1, 2.45) + 2 * dx, Eigen::Vector3d(0, 1.5, 2.85) + 2 * dx);
  EXPECT_EQ(CountSharedApples(front, apart, SharedCountOptions()).total, 3);
  SharedCountOptions bad;
  bad.edge_across = 0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(SharedCountTest, GlimpsedApplesLinkAlongRaysThroughTheirCentre) {
  // The back glimpsed an apple through the leaves: its ray passes through
  // the sphere found for it, 2.6 m across and 1.50 m up (depth a guess).
  SideCluster glimpsed = EdgeApple(1, {0, 2.3, 1.50}, {0, 2.9, 1.50});
  glimpsed.glimpsed = true;
  const std::vector<SideCluster> back = {glimpsed};
  SharedCountOptions o;
  o.glimpse_across = 0.04, o.glimpse_vertical = 0.06;
  // The front tracks the apple, its point 5 cm under the ray: one apple.
  EXPECT_EQ(CountSharedApples({Cluster(1, 1, {{0.01, 2.5, 1.45}})}, back, o).total, 1);
  // ... above it too (a sliver's rule would take it only from 3 cm under).
  EXPECT_EQ(CountSharedApples({Cluster(1, 1, {{0.01, 2.5, 1.55}})}, back, o).total, 1);
  glimpsed.glimpsed = false;
  EXPECT_EQ(CountSharedApples({Cluster(1, 1, {{0.01, 2.5, 1.45}})}, {glimpsed}, o).total, 2);
  // Beside the ray, or farther under it, another apple.
  EXPECT_EQ(CountSharedApples({Cluster(1, 1, {{0.06, 2.5, 1.50}})}, back, o).total, 2);
  EXPECT_EQ(CountSharedApples({Cluster(1, 1, {{0.0, 2.5, 1.42}})}, back, o).total, 2);
  // Near the rays of two front clusters, it is on the nearer one (the later
  // in the list here), whichever comes first.
  const SharedCount two =
      CountSharedApples({Cluster(1, 1, {{0.03, 2.5, 1.50}}), Cluster(2, 1, {{-0.01, 2.6, 1.52}})}, back, o);
  EXPECT_EQ(two.back_edge_on, std::vector<int>{1});
  EXPECT_EQ(two.total, 2);
  o.glimpse_vertical = 0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(SharedCountTest, ClustersLinkAlongALineOfSightThroughAGapInTheLeaves) {
  // Front frame: front cameras at y = 0, back cameras at y = 5, 1.5 m up.
  // The back holds an apple at a (2.8 m across); the front sees it through a
  // gap in the leaves and its points lie where the gap is, 30 cm nearer
  // its cameras on their lines of sight to the apple.
  const Eigen::Vector3d a(0, 2.8, 1.2);
  const std::vector<Eigen::Vector3d> front_cameras = {{-0.3, 0, 1.5}, {0, 0, 1.5}, {0.3, 0, 1.5}};
  const Eigen::Vector3d gap = front_cameras[1] + (a - front_cameras[1]) * (2.5 / 2.8);
  SideCluster seen_through = Cluster(1, 1, {gap});
  seen_through.view_centres = front_cameras;
  SideCluster held = Cluster(1, 1, {a});
  held.view_centres = {{-0.2, 5, 1.5}, {0, 5, 1.5}, {0.2, 5, 1.5}};
  // Another apple the back alone sees, 15 cm beside: not on those lines.
  const SideCluster beside = Cluster(2, 1, {a + Eigen::Vector3d(0.15, 0, 0)});
  const SharedCount s = CountSharedApples({seen_through}, {beside, held}, SharedCountOptions());
  EXPECT_EQ(s.sight_links, 1);
  ASSERT_EQ(s.groups.size(), 1u);
  EXPECT_EQ(s.groups[0].back, std::vector<int>{1});
  EXPECT_EQ(s.total, 2);
  // Off: three apples. Without view centres the line of sight is unknown.
  SharedCountOptions off;
  off.sight_across = 0;
  EXPECT_EQ(CountSharedApples({seen_through}, {beside, held}, off).total, 3);
  SideCluster unknown = seen_through;
  unknown.view_centres.clear();
  EXPECT_EQ(CountSharedApples({unknown}, {beside, held}, SharedCountOptions()).sight_links, 0);
  // A cluster in front of the front's cluster (nearer its cameras) is not
  // behind it; a cluster already linked to one of the other side is not
  // linked again along a line of sight.
  SideCluster nearer = held;
  nearer.points = {gap - Eigen::Vector3d(0, 0.3, 0)};
  nearer.view_centres.clear();
  UpdateClusterExtent(&nearer);
  EXPECT_EQ(CountSharedApples({seen_through}, {nearer}, SharedCountOptions()).sight_links, 0);
  const SideCluster twin = Cluster(3, 1, {gap + Eigen::Vector3d(0.02, 0, 0)});
  const SharedCount linked = CountSharedApples({seen_through}, {twin, held}, SharedCountOptions());
  EXPECT_EQ(linked.sight_links, 0);
  EXPECT_EQ(linked.total, 2);  // front + twin share one, held stands alone
  SharedCountOptions bad;
  bad.sight_max_behind = 0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(MergeTruthTest, TakesTheMergedCountApart) {
  // Visible: front 0-5, back 3-8 (3, 4, 5 from both sides), 9 apples in all.
  const Eigen::Vector3d a(0, 2.5, 1.5), dx(0.5, 0, 0), e(0.02, 0, 0);
  const std::vector<SideCluster> front = {
      Cluster(1, 1, {a}),           // holds 3, linked with back 1 which holds 3
      Cluster(2, 2, {a + dx}),      // holds 4 and 0, linked with back 2 which holds 5: a chance link
      Cluster(3, 1, {a + 2 * dx}),  // holds 5 too, linked to nothing: counted twice
      Cluster(4, 2, {a + 3 * dx}),  // holds 1, counted one above it
      Cluster(5, 1, {a + 4 * dx}),  // on no visible apple
  };
  const std::vector<SideCluster> back = {
      Cluster(1, 1, {a + e}),
      Cluster(2, 1, {a + dx + e}),
      Cluster(3, 1, {a + 5 * dx}),  // holds 6
  };
  const SharedCount s = CountSharedApples(front, back, SharedCountOptions());
  ASSERT_EQ(s.total, 7 + 3 - 2);
  const std::map<int, std::vector<int>> front_credited = {{1, {3}}, {2, {0, 4}}, {3, {5}}, {4, {1}}};
  const std::map<int, std::vector<int>> back_credited = {{1, {3}}, {2, {5}}, {3, {6}}};
  const MergeTruth t = ScoreMergeAgainstTruth(front, back, s, front_credited, back_credited, {0, 1, 2, 3, 4, 5},
                                              {3, 4, 5, 6, 7, 8});
  EXPECT_EQ(t.visible_any, 9);
  EXPECT_EQ(t.visible_both, 3);
  EXPECT_EQ(t.held_front, 5);
  EXPECT_EQ(t.held_back, 3);
  EXPECT_EQ(t.extra_front, 2);  // front 4's second apple, front 5
  EXPECT_EQ(t.extra_back, 0);
  EXPECT_EQ(t.held_by_neither, 3);  // 2, 7, 8
  EXPECT_EQ(t.held_both, 2);        // 3 and 5
  EXPECT_EQ(t.linked, 1);           // 3
  EXPECT_EQ(t.unlinked, 1);         // 5: front 3 and back 2 are not linked
  EXPECT_DOUBLE_EQ(t.shared, 2.0);
  // The terms add up to the merged count's error.
  EXPECT_EQ(t.total - t.visible_any,
            t.extra_front + t.extra_back - t.held_by_neither + t.unlinked + t.linked - static_cast<int>(t.shared));
}

TEST(SharedCountTest, TheIntersectionDistanceGrowsWithTheRegistrationResidual) {
  YieldOptions o;
  Registration r;
  r.matched = 40;
  r.residual = 0.03;  // exact masks: 2.6-3.3 cm; 2.5 x 3 cm stays below the 8 cm floor
  EXPECT_DOUBLE_EQ(IntersectionDistance(o, r), 0.08);
  r.residual = 0.05;  // a detector's noisier fruit points
  EXPECT_DOUBLE_EQ(IntersectionDistance(o, r), 0.125);
  // Too few matched clusters to measure a residual: the floor.
  r.matched = o.registration.min_matched - 1;
  EXPECT_DOUBLE_EQ(IntersectionDistance(o, r), 0.08);
  // 0 turns the widening off.
  r.matched = 40;
  o.intersection_per_residual = 0;
  EXPECT_DOUBLE_EQ(IntersectionDistance(o, r), 0.08);
  o.intersection_per_residual = -1;
  EXPECT_THROW(o.Check(), Error);
}

TEST(SideCloudTest, MissingSideOutputsAreAClearError) {
  try {
    LoadSideCloud("/nonexistent/side", "front");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("side.json is missing"), std::string::npos) << e.what();
  }
}

TEST(SideCloudTest, LoadsKeptAndFallenClusters) {
  const fs::path dir = test::FreshTempDir("side_cloud_fallen");
  WriteTextFileAtomic(dir / "side.json",
                      R"({"count": 3, "row_frame": {"origin": [0, 0, 0], "along": [1, 0, 0], "across": [0, 1, 0],)"
                      R"( "up": [0, 0, 1]}})");
  WriteTextFileAtomic(dir / "clusters.csv",
                      "id,x,y,z,extent_x,extent_y,extent_z,points,count,status\n"
                      "1,0,2,1,0,0,0,2,3,kept\n"
                      "2,1,2,0.04,0,0,0,1,1,fallen\n"
                      "3,2,6,1,0,0,0,1,1,next_row\n"
                      "4,3,2,0.04,0,0,0,0,1,fallen\n");  // no points: left out
  WriteTextFileAtomic(dir / "fruit.ply",
                      "ply\nformat ascii 1.0\nend_header\n0 2 1 0 0 0 1\n0.1 2 1 0 0 0 1\n1 2 0.04 0 0 0 2\n"
                      "2 6 1 0 0 0 3\n");
  SideCloud cloud = LoadSideCloud(dir, "front");
  ASSERT_EQ(cloud.clusters.size(), 1u);
  EXPECT_EQ(cloud.clusters[0].points.size(), 2u);
  EXPECT_EQ(cloud.clusters[0].count, 3);
  ASSERT_EQ(cloud.fallen.size(), 1u);
  EXPECT_EQ(cloud.fallen[0].id, 2);
  EXPECT_TRUE(cloud.fallen[0].centre.isApprox(Eigen::Vector3d(1, 2, 0.04)));
  ScaleSideCloud(&cloud, 2);
  EXPECT_TRUE(cloud.fallen[0].centre.isApprox(Eigen::Vector3d(2, 4, 0.08)));
  // The unlinked count from a named column; a side without it is an error.
  EXPECT_EQ(cloud.clusters[0].count_unlinked, 3);
  WriteTextFileAtomic(dir / "clusters.csv",
                      "id,x,y,z,extent_x,extent_y,extent_z,points,count,status,count_by_pixels,count_by_count\n"
                      "1,0,2,1,0,0,0,2,3,kept,3,4\n");
  EXPECT_EQ(LoadSideCloud(dir, "front", "count_by_count").clusters[0].count_unlinked, 4);
  test::ExpectErrorContains([&] { LoadSideCloud(dir, "front", "count_by_views"); }, "has no column count_by_views");
}

TEST(SideCloudTest, LoadsEdgeApplesWithTheirRays) {
  const fs::path dir = test::FreshTempDir("side_cloud_edge");
  // A row frame shifted by 1 m along x.
  WriteTextFileAtomic(dir / "side.json",
                      R"({"count": 2, "row_frame": {"origin": [1, 0, 0], "along": [1, 0, 0], "across": [0, 1, 0],)"
                      R"( "up": [0, 0, 1]}})");
  WriteTextFileAtomic(dir / "clusters.csv",
                      "id,x,y,z,extent_x,extent_y,extent_z,points,count,status,count_by_pixels,count_by_count,edge\n"
                      "1,1,2,1,0,0,0,1,1,kept,1,1,0\n"
                      "2,2,2.5,2.6,0,0,0,1,1,kept,1,1,1\n");
  WriteTextFileAtomic(dir / "fruit.ply",
                      "ply\nformat ascii 1.0\nend_header\n1 2 1 0 0 0 1\n2 2.5 2.6 0 0 0 2\n");
  WriteTextFileAtomic(dir / "edge_rays.csv",
                      "cluster,frame,column,pixels,near_x,near_y,near_z,far_x,far_y,far_z\n"
                      "2,f7.png,310.5,42,2,1.9,2.45,2,3.5,2.85\n"
                      "1,f7.png,0,0,9,9,9,9,9,9\n");  // not an edge apple: ignored
  SideCloud cloud = LoadSideCloud(dir, "front");
  ASSERT_EQ(cloud.clusters.size(), 2u);
  EXPECT_FALSE(cloud.clusters[0].edge);
  EXPECT_TRUE(cloud.clusters[0].ray_ends.empty());
  ASSERT_TRUE(cloud.clusters[1].edge);
  ASSERT_EQ(cloud.clusters[1].ray_ends.size(), 2u);
  EXPECT_TRUE(cloud.clusters[1].ray_ends[0].isApprox(Eigen::Vector3d(1, 1.9, 2.45)));  // in the row frame
  ScaleSideCloud(&cloud, 2);
  EXPECT_TRUE(cloud.clusters[1].ray_ends[1].isApprox(Eigen::Vector3d(2, 7, 5.7)));
  EXPECT_EQ(WithoutEdgeApples(cloud).clusters.size(), 1u);
  // A glimpsed apple is linked along its rays too, and left out as well.
  WriteTextFileAtomic(dir / "clusters.csv",
                      "id,x,y,z,extent_x,extent_y,extent_z,points,count,status,count_by_pixels,count_by_count,edge,"
                      "glimpsed\n"
                      "1,1,2,1,0,0,0,1,1,kept,1,1,0,0\n"
                      "2,2,2.5,2.6,0,0,0,1,1,kept,1,1,0,1\n");
  const SideCloud with_glimpsed = LoadSideCloud(dir, "front");
  ASSERT_EQ(with_glimpsed.clusters.size(), 2u);
  EXPECT_FALSE(with_glimpsed.clusters[0].glimpsed);
  EXPECT_TRUE(with_glimpsed.clusters[1].glimpsed);
  EXPECT_TRUE(with_glimpsed.clusters[1].edge);
  EXPECT_EQ(with_glimpsed.clusters[1].ray_ends.size(), 2u);
  EXPECT_EQ(WithoutEdgeApples(with_glimpsed).clusters.size(), 1u);
  // The count frames' camera centres from cameras.csv, in the row frame.
  WriteTextFileAtomic(dir / "clusters.csv",
                      "id,x,y,z,extent_x,extent_y,extent_z,points,count,status,height,distance,frames\n"
                      "1,1,2,1,0,0,0,1,1,kept,1,2,f7.png;f9.png;f8.png\n"
                      "2,2,2.5,2.6,0,0,0,1,1,kept,2.6,2.5,f3.png\n");
  WriteTextFileAtomic(dir / "cameras.csv", "frame,x,y,z\nf7.png,1,0,1.5\nf8.png,1.1,0,1.5\nf9.png,1.2,0,1.5\n");
  cloud = LoadSideCloud(dir, "front");
  ASSERT_EQ(cloud.clusters[0].view_centres.size(), 3u);
  EXPECT_TRUE(cloud.clusters[0].view_centres[1].isApprox(Eigen::Vector3d(0.2, 0, 1.5)));
  EXPECT_TRUE(cloud.clusters[1].view_centres.empty());  // f3.png has no camera
  WriteTextFileAtomic(dir / "cameras.csv", "frame,x,y,z\nf7.png,1,0\n");
  test::ExpectErrorContains([&] { LoadSideCloud(dir, "front"); }, "cameras.csv line 2");
  fs::remove(dir / "cameras.csv");
  // A malformed rays file is an error naming it.
  WriteTextFileAtomic(dir / "edge_rays.csv", "cluster,frame\n2,f7.png,1\n");
  test::ExpectErrorContains([&] { LoadSideCloud(dir, "front"); }, "edge_rays.csv line 2");
}

TEST(SideCloudTest, RowFrameTransformMapsTheAxes) {
  // A back side: across = -y, up = z, so along = across x up = -x.
  const Eigen::Isometry3d t = RowFrameTransform({1, 5, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, 1});
  EXPECT_TRUE((t * Eigen::Vector3d(1, 5, 0)).isZero(1e-12));
  EXPECT_TRUE((t * Eigen::Vector3d(0, 5, 2)).isApprox(Eigen::Vector3d(1, 0, 2)));
  EXPECT_TRUE((t * Eigen::Vector3d(1, 3, 0)).isApprox(Eigen::Vector3d(0, 2, 0)));
  EXPECT_THROW(RowFrameTransform({0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 0, 1}), Error);
}

}  // namespace
}  // namespace orchard
