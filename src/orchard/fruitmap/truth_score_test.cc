#include "orchard/fruitmap/truth_score.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

// Cameras along x at y = -2.5, looking along +y (world z up), 640x480.
std::vector<CameraView> Views(int n) {
  std::vector<CameraView> views;
  for (int i = 0; i < n; ++i) {
    CameraView v;
    v.name = "frame_" + std::to_string(i) + ".png";
    v.width = 640, v.height = 480;
    v.fx = v.fy = 500, v.cx = 320, v.cy = 240;
    v.R << 1, 0, 0, 0, 0, -1, 0, 1, 0;
    v.t = -v.R * Eigen::Vector3d(-0.3 + 0.1 * i, -2.5, 1.5);
    views.push_back(v);
  }
  return views;
}

// Truth masks with each apple drawn as a disc of `radius` m at its centre.
std::vector<cv::Mat> Masks(const std::vector<CameraView>& views, const std::vector<Eigen::Vector3d>& apples,
                           double radius) {
  std::vector<cv::Mat> masks;
  for (const auto& v : views) {
    cv::Mat1w mask(v.height, v.width, uint16_t{0});
    for (size_t id = 0; id < apples.size(); ++id) {
      Eigen::Vector2d p;
      if (!v.Project(apples[id], &p)) continue;
      const int r = static_cast<int>(v.fx * radius / v.Depth(apples[id]));
      cv::circle(mask, cv::Point(static_cast<int>(p.x()), static_cast<int>(p.y())), r,
                 cv::Scalar(static_cast<double>(id + 1)), cv::FILLED);
    }
    masks.push_back(mask);
  }
  return masks;
}

// A kept cluster of `count` with fruit points at `at`, added to `r`.
void AddCluster(ClusterResult* r, int count, const std::vector<Eigen::Vector3d>& at, const std::string& status = "kept") {
  FruitCluster c;
  c.id = static_cast<int>(r->clusters.size()) + 1;
  c.count = count;
  c.status = status;
  for (const auto& X : at) {
    FruitPoint p;
    p.xyz = X;
    c.points.push_back(static_cast<int>(r->points.size()));
    r->point_cluster.push_back(static_cast<int>(r->clusters.size()));
    r->points.push_back(p);
  }
  if (status == "kept") r->count += count;
  r->clusters.push_back(c);
}

TEST(ScoreSideAgainstTruth, SplitsTheCountIntoFoundMissedDuplicatedAndNotVisible) {
  // Apples 0-3 of the filmed row, 4 of the next row, well apart.
  const std::vector<Eigen::Vector3d> apples = {{-0.4, 0, 1.2}, {0, 0, 1.2}, {0.4, 0, 1.2}, {0, 0, 1.8}, {0.4, 3.5, 1.5}};
  const std::vector<CameraView> views = Views(5);
  const std::vector<cv::Mat> masks = Masks(views, apples, 0.04);
  const std::set<int> visible = {0, 1, 2, 3};
  ClusterResult r;
  AddCluster(&r, 1, {apples[0], apples[0] + Eigen::Vector3d(0.01, 0, 0)});  // apple 0
  AddCluster(&r, 1, {apples[0] + Eigen::Vector3d(0, -0.1, 0)});             // apple 0 again, 10 cm nearer
  AddCluster(&r, 2, {apples[1], apples[1]});                                // apple 1, counted 2
  AddCluster(&r, 1, {apples[4]});                                           // the next row's apple
  AddCluster(&r, 1, {apples[2]}, "few_views");                              // removed: apple 2 is missed
  AddCluster(&r, 1, {apples[3], apples[3]});                                // apple 3
  const SideTruthScore s = ScoreSideAgainstTruth(views, masks, visible, r);
  EXPECT_EQ(s.visible, 4);
  EXPECT_EQ(s.count, 6);
  EXPECT_EQ(s.found, 3);
  EXPECT_EQ(s.missed, 1);
  EXPECT_EQ(s.missed_ids, std::vector<int>{2});
  EXPECT_EQ(s.missed_without_points, 1);  // only a removed cluster holds it
  EXPECT_EQ(s.duplicates, 1);
  EXPECT_EQ(s.over_counted, 1);
  EXPECT_EQ(s.not_visible, 1);
  EXPECT_EQ(s.count - s.visible, s.duplicates + s.over_counted + s.not_visible - s.missed);
  // Per kept cluster (the removed one is left out): its role and apples.
  ASSERT_EQ(s.clusters.size(), 5u);
  const std::vector<std::string> roles = {"found", "duplicate", "over_counted", "not_visible", "found"};
  const std::vector<int> cluster_index = {0, 1, 2, 3, 5};
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(s.clusters[k].role, roles[k]) << k;
    EXPECT_EQ(s.clusters[k].cluster, cluster_index[k]) << k;
  }
  EXPECT_EQ(s.clusters[0].credited, std::vector<int>{0});
  EXPECT_TRUE(s.clusters[1].credited.empty());
  EXPECT_EQ(s.clusters[1].top_apple, 0);  // the apple the first cluster holds
  EXPECT_EQ(s.clusters[2].credited, std::vector<int>{1});
  EXPECT_EQ(s.clusters[3].top_apple, 4);  // the next row's apple
  EXPECT_EQ(s.clusters[4].credited, std::vector<int>{3});
  // Every apple is in all five views; the last bin holds 10 or more.
  std::vector<int> by_views(SideTruthScore::kViewsSeenBins, 0);
  by_views[5] = 4;
  EXPECT_EQ(s.visible_by_views_seen, by_views);
  by_views[5] = 1;
  EXPECT_EQ(s.missed_by_views_seen, by_views);
  // Apple 2 glimpsed in two views only (hidden in the others), apple 3 in none
  // of them (seen in a frame left out).
  std::vector<cv::Mat> glimpsed;
  for (size_t f = 0; f < masks.size(); ++f) {
    cv::Mat1w m = masks[f].clone();
    for (uint16_t& id : m)
      if (id == 4 || (id == 3 && f >= 2)) id = 0;
    glimpsed.push_back(m);
  }
  const SideTruthScore g = ScoreSideAgainstTruth(views, glimpsed, visible, r);
  EXPECT_EQ(g.visible_by_views_seen, (std::vector<int>{1, 0, 1, 0, 0, 2, 0, 0, 0, 0, 0}));
  // Apple 3's points now land on no apple of the masks: missed too.
  EXPECT_EQ(g.missed_by_views_seen, (std::vector<int>{1, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0}));
  // Two touching apples in one cluster counted 2 are both found.
  ClusterResult touching;
  AddCluster(&touching, 2, {apples[0], apples[1]});
  const SideTruthScore t = ScoreSideAgainstTruth(views, masks, {0, 1}, touching);
  EXPECT_EQ(t.found, 2);
  EXPECT_EQ(t.missed + t.duplicates + t.over_counted + t.not_visible, 0);
  // Counted 1, the cluster holds one of them: the other is missed with points.
  ClusterResult low;
  AddCluster(&low, 1, {apples[0], apples[0], apples[1], apples[1], apples[1]});
  const SideTruthScore u = ScoreSideAgainstTruth(views, masks, {0, 1}, low);
  EXPECT_EQ(u.missed_ids, std::vector<int>{0});
  EXPECT_EQ(u.missed_without_points, 0);
}

TEST(CreditApples, MostVotesFirstEachAppleOnceEachClusterUpToItsCount) {
  // Visible 0-3. Cluster 0 (count 2) votes 0: 9, 1: 5, 2: 1 (below min
  // votes); cluster 1 (count 1) votes 1: 7 and takes it before cluster 0;
  // cluster 2 (count 1) votes 0 only, which cluster 0 holds: a duplicate;
  // cluster 3 (count 2) votes 9, not visible.
  std::vector<ClusterVotes> clusters = {
      {2, {{0, 9}, {1, 5}, {2, 1}}}, {1, {{1, 7}}}, {1, {{0, 4}}}, {2, {{9, 30}}}};
  const SideTruthScore s = CreditApples(clusters, {0, 1, 2, 3}, 2);
  ASSERT_EQ(s.clusters.size(), 4u);
  EXPECT_EQ(s.clusters[0].credited, std::vector<int>{0});
  EXPECT_EQ(s.clusters[0].role, "over_counted");
  EXPECT_EQ(s.clusters[1].credited, std::vector<int>{1});
  EXPECT_EQ(s.clusters[1].role, "found");
  EXPECT_EQ(s.clusters[2].role, "duplicate");
  EXPECT_EQ(s.clusters[3].role, "not_visible");
  EXPECT_EQ(s.clusters[3].top_apple, 9);
  EXPECT_EQ(s.count, 6);
  EXPECT_EQ(s.found, 2);
  EXPECT_EQ(s.missed_ids, (std::vector<int>{2, 3}));
  EXPECT_EQ(s.missed_without_points, 2);  // 2's one vote is below min votes
  EXPECT_EQ(s.over_counted, 1);
  EXPECT_EQ(s.duplicates, 1);
  EXPECT_EQ(s.not_visible, 2);
  EXPECT_EQ(s.count - s.visible, s.duplicates + s.over_counted + s.not_visible - s.missed);
  // Counted higher, as the merge may count a cluster, it holds more.
  clusters[2].count = 2;
  clusters[2].votes[3] = 2;
  const SideTruthScore higher = CreditApples(clusters, {0, 1, 2, 3}, 2);
  EXPECT_EQ(higher.clusters[2].credited, std::vector<int>{3});
  EXPECT_EQ(higher.clusters[2].role, "over_counted");
}

TEST(CreditApples, AnEdgeAppleIsCreditedWithTheOneVoteOfItsSliver) {
  // Visible 0, 1. Cluster 1 votes once for apple 1: below min votes, unless
  // it is an edge apple (one vote per sliver, in the sliver's frame).
  std::vector<ClusterVotes> clusters = {{1, {{0, 6}}}, {1, {{1, 1}}}};
  EXPECT_EQ(CreditApples(clusters, {0, 1}, 2).missed, 1);
  clusters[1].min_votes = 1;
  const SideTruthScore s = CreditApples(clusters, {0, 1}, 2);
  EXPECT_EQ(s.missed, 0);
  EXPECT_EQ(s.clusters[1].role, "found");
}

TEST(ScoreSideAgainstTruth, MasksThatDoNotMatchTheViewsFail) {
  const std::vector<CameraView> views = Views(2);
  ClusterResult r;
  EXPECT_THROW(ScoreSideAgainstTruth(views, {cv::Mat1w(480, 640, uint16_t{0})}, {}, r), Error);
  EXPECT_THROW(ScoreSideAgainstTruth(views, {cv::Mat1b(480, 640, uchar{0}), cv::Mat1b(480, 640, uchar{0})}, {}, r),
               Error);
}

TEST(ReadVisibleApples, TakesTheFilmedRowsApplesOffTheGroundSeenFromTheSide) {
  const fs::path dir = test::FreshTempDir("truth_score_test");
  WriteTextFileAtomic(dir / "apples.csv",
                      "id,tree,row,x,y,z,radius,colour,cluster,visible_front,visible_back,on_ground\n"
                      "0,0,0,0,0,1,0.04,red,0,1,0,0\n"
                      "1,0,0,0,0,1,0.04,red,0,0,1,0\n"
                      "2,0,0,0,0,0,0.04,red,-1,1,1,1\n"
                      "3,-1,1,0,3,1,0.04,red,5,1,0,0\n"
                      "4,1,0,0,0,1,0.04,red,1,1,1,0\n");
  EXPECT_EQ(ReadVisibleApples(dir / "apples.csv", "front"), (std::set<int>{0, 4}));
  EXPECT_EQ(ReadVisibleApples(dir / "apples.csv", "back"), (std::set<int>{1, 4}));
  EXPECT_THROW(ReadVisibleApples(dir / "apples.csv", "left"), Error);
  WriteTextFileAtomic(dir / "other.csv", "id,x,y\n0,1,2\n");
  EXPECT_THROW(ReadVisibleApples(dir / "other.csv", "front"), Error);
  WriteTextFileAtomic(dir / "short.csv", "id,row,on_ground,visible_front\n0,0,0\n");
  EXPECT_THROW(ReadVisibleApples(dir / "short.csv", "front"), Error);
  // A side folder of the row, with or without a trailing separator; one
  // without masks/ is not the generator's side.
  fs::create_directories(dir / "front" / "masks");
  fs::create_directories(dir / "back");
  EXPECT_EQ(ReadSideVisibleApples(dir / "front"), (std::set<int>{0, 4}));
  EXPECT_EQ(ReadSideVisibleApples(dir / "front" / ""), (std::set<int>{0, 4}));
  EXPECT_THROW(ReadSideVisibleApples(dir / "back"), Error);
}

}  // namespace
}  // namespace orchard
