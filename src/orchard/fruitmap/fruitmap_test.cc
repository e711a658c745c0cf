#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/count/counter.h"
#include "orchard/fruitmap/clusters.h"
#include "orchard/fruitmap/fruit_points.h"
#include "orchard/fruitmap/side.h"
#include "orchard/fruitmap/test_views.h"
#include "orchard/fruitmap/triangulation.h"

namespace orchard {
namespace {

using test::ViewAt;

TEST(Triangulation, RecoversKnownPointFromManyViews) {
  const Eigen::Vector3d X(0.3, 0.2, 1.8);
  std::vector<CameraView> views;
  for (int i = 0; i < 6; ++i) views.push_back(ViewAt(-0.4 + 0.15 * i));
  std::vector<const CameraView*> vs;
  std::vector<Eigen::Vector2d> px;
  for (const auto& v : views) {
    Eigen::Vector2d p;
    ASSERT_TRUE(v.Project(X, &p));
    vs.push_back(&v), px.push_back(p);
  }
  Eigen::Vector3d Y;
  ASSERT_TRUE(TriangulatePoint(vs, px, &Y));
  EXPECT_LT((Y - X).norm(), 1e-9);
  EXPECT_LT(ReprojectionError(views[2], Y, px[2]), 1e-6);
  // One pixel of noise in each view moves the point by millimetres, not centimetres.
  for (size_t i = 0; i < px.size(); ++i) px[i].x() += (i % 2 ? 1 : -1);
  ASSERT_TRUE(TriangulatePoint(vs, px, &Y));
  EXPECT_LT((Y - X).norm(), 0.02);
  // A single view, or two views from one place, cannot triangulate.
  EXPECT_FALSE(TriangulatePoint({vs[0]}, {px[0]}, &Y));
  EXPECT_FALSE(TriangulatePoint({vs[0], vs[0]}, {px[0], px[0]}, &Y));
}

TEST(Triangulation, RadialDistortionRoundTrips) {
  CameraView v = ViewAt(0);
  v.k1 = -0.08;
  const Eigen::Vector3d X(0.5, 0.1, 2.2);
  Eigen::Vector2d p;
  ASSERT_TRUE(v.Project(X, &p));
  const Eigen::Vector2d n = v.Normalize(p);
  const Eigen::Vector3d x = v.R * X + v.t;
  EXPECT_NEAR(n.x(), x.x() / x.z(), 1e-9);
  EXPECT_NEAR(n.y(), x.y() / x.z(), 1e-9);
}

TEST(ConnectedComponents3D, LinksChainsAndSeparatesGaps) {
  // Chain a: 0 - 1 - 2 (steps 4 cm), b: two points 30 cm away, c: alone.
  const std::vector<Eigen::Vector3d> pts = {{0, 0, 0},     {0.04, 0, 0},  {0.08, 0, 0},
                                            {0.4, 0, 0},   {0.4, 0.03, 0}, {1, 1, 1}};
  int k = 0;
  const std::vector<int> label = ConnectedComponents3D(pts, 0.05, &k);
  EXPECT_EQ(k, 3);
  EXPECT_EQ(label, (std::vector<int>{0, 0, 0, 1, 1, 2}));
  // A shorter link breaks the chain.
  ConnectedComponents3D(pts, 0.035, &k);
  EXPECT_EQ(k, 5);  // only the 3 cm pair stays linked
  // Cell boundaries and negative coordinates do not split neighbours.
  ConnectedComponents3D({{-0.001, -0.001, -0.001}, {0.001, 0.001, 0.001}}, 0.05, &k);
  EXPECT_EQ(k, 1);
  EXPECT_THROW(ConnectedComponents3D(pts, 0, &k), Error);
}

TEST(MedianOfBestViews, UsesTheThreeViewsWithMostPixels) {
  // Most pixels: frames 4 (900, count 3), 2 (800, count 2), 7 (700, count 5);
  // the partly hidden views with counts 1 are ignored.
  std::vector<ClusterView> views = {{1, 100, 1}, {2, 800, 2}, {3, 200, 1}, {4, 900, 3}, {7, 700, 5}, {9, 50, 1}};
  std::vector<int> chosen;
  EXPECT_EQ(MedianOfBestViews(views, 3, &chosen), 3);
  EXPECT_EQ(chosen, (std::vector<int>{4, 2, 7}));
  EXPECT_EQ(MedianOfBestViews(views, 1), 3);
  EXPECT_EQ(MedianOfBestViews({{1, 10, 2}, {2, 20, 4}}, 3), 4);  // even: upper median
  EXPECT_EQ(MedianOfBestViews({}, 3), 0);
  EXPECT_THROW(MedianOfBestViews(views, 0), Error);
  // By count: frames 7 (5), 4 (3), 2 (2); the tie-break is pixels.
  EXPECT_EQ(MedianOfBestViews(views, 3, &chosen, true), 3);
  EXPECT_EQ(chosen, (std::vector<int>{7, 4, 2}));
  EXPECT_EQ(MedianOfBestViews({{1, 10, 2}, {2, 20, 2}, {3, 5, 1}}, 1, &chosen, true), 2);
  EXPECT_EQ(chosen, (std::vector<int>{2}));
}

// A counter that reads one apple per blob, as a stand-in for a network.
class OneEach : public Counter {
 public:
  BlobCount Count(const cv::Mat&, const cv::Mat1b&) override { return BlobCount{}; }
};

class NoFruit : public Detector {
 public:
  FrameDetection Detect(const cv::Mat&) override { return FrameDetection{}; }
};

TEST(ResolvedBestViews, CountsWhenBlobsAreCountedOneApplePixelsOtherwise) {
  SideInputs masks;  // no detector, no counter
  ClusterOptions o;
  EXPECT_EQ(ResolvedBestViews(o, masks), ClusterOptions::BestViews::kCount);
  OneEach counter;
  SideInputs counted = masks;
  counted.counter = &counter;  // masks read by a counter: its counts are estimates
  EXPECT_EQ(ResolvedBestViews(o, counted), ClusterOptions::BestViews::kPixels);
  NoFruit detector;
  SideInputs boxes = masks;
  boxes.detector = &detector;  // a box detector's blobs, one apple each
  EXPECT_EQ(ResolvedBestViews(o, boxes), ClusterOptions::BestViews::kCount);
  o.best_views_by = ClusterOptions::BestViews::kPixels;
  EXPECT_EQ(ResolvedBestViews(o, masks), ClusterOptions::BestViews::kPixels);
  o.best_views_by = ClusterOptions::BestViews::kCount;
  EXPECT_EQ(ResolvedBestViews(o, counted), ClusterOptions::BestViews::kCount);
}

TEST(ResolvedMinAppleFraction, LargerForInstanceMasksThanForADetectorsBlobs) {
  SideInputs masks;  // no detector: each blob is one apple's visible part
  ClusterOptions o;
  EXPECT_DOUBLE_EQ(ResolvedMinAppleFraction(o, masks), 0.6);
  NoFruit detector;
  SideInputs detected = masks;
  detected.detector = &detector;
  EXPECT_DOUBLE_EQ(ResolvedMinAppleFraction(o, detected), 0.5);
  o.min_apple_fraction = 0;  // given: keep all
  EXPECT_DOUBLE_EQ(ResolvedMinAppleFraction(o, masks), 0);
  o.min_apple_fraction = 0.7;
  EXPECT_DOUBLE_EQ(ResolvedMinAppleFraction(o, detected), 0.7);
}

// Frames of 3D balls (radius radii[i]) rendered as discs into label images.
std::vector<FruitFrame> RenderBalls(const std::vector<CameraView>& views, const std::vector<Eigen::Vector3d>& balls,
                                    const std::vector<double>& radii) {
  std::vector<FruitFrame> frames;
  for (const auto& v : views) {
    FruitFrame f;
    f.labels = cv::Mat1i::zeros(v.height, v.width);
    for (size_t i = 0; i < balls.size(); ++i) {
      const Eigen::Vector3d& b = balls[i];
      Eigen::Vector2d p;
      if (!v.Project(b, &p)) continue;
      const double rad = v.fx * radii[i] / v.Depth(b);
      const int id = static_cast<int>(f.blobs.size()) + 1;
      cv::Mat1b disc = cv::Mat1b::zeros(f.labels.size());
      cv::circle(disc, cv::Point(static_cast<int>(p.x()), static_cast<int>(p.y())), static_cast<int>(rad), 255, -1);
      f.labels.setTo(id, disc);
      Blob blob;
      blob.id = id;
      blob.pixels = cv::countNonZero(disc);
      blob.centroid = {std::floor(p.x()), std::floor(p.y())};
      const cv::Rect box = cv::boundingRect(disc);
      blob.box = Box{static_cast<double>(box.x), static_cast<double>(box.y), static_cast<double>(box.x + box.width),
                     static_cast<double>(box.y + box.height)};
      f.blobs.push_back(blob);
      f.counts.push_back(1);
    }
    frames.push_back(f);
  }
  return frames;
}

// Frames of 3D balls of radius r.
std::vector<FruitFrame> RenderBalls(const std::vector<CameraView>& views, const std::vector<Eigen::Vector3d>& balls,
                                    double r) {
  return RenderBalls(views, balls, std::vector<double>(balls.size(), r));
}

// Fruit-point distances: `points` spread evenly over [from, to).
void AddPoints(std::vector<double>* d, double from, double to, int points) {
  for (int i = 0; i < points; ++i) d->push_back(from + (to - from) * (i + 0.5) / points);
}

TEST(RowFruitDistance, TakesTheNearestStretchOfFruitHoldingEnoughOfIt) {
  // Kept clusters spread over 25 cm bands: (distance, pixels, apples).
  const auto stretch = [](std::vector<RowFruit>* d, double from, double to, double densest_at, double pixels,
                          double apples) {
    for (double x = from + 0.125; x < to; x += 0.25)
      d->push_back({x, std::abs(x - densest_at) < 0.1 ? pixels : pixels / 4, apples});
  };
  // One tree filmed: the next row (5.5-6.5 m) holds more fruit pixels than
  // the tree (2.0-3.0 m), and its densest band more than the tree's.
  std::vector<RowFruit> one_tree;
  stretch(&one_tree, 2.0, 3.0, 2.125, 4000, 10);
  stretch(&one_tree, 5.5, 6.5, 5.625, 5000, 30);
  EXPECT_DOUBLE_EQ(RowFruitDistance(one_tree, 1.0, 0.01, 0.5, 0.25), 2.125);
  // The densest band alone (no aisle to split at) takes the next row.
  EXPECT_DOUBLE_EQ(RowFruitDistance(one_tree, 0, 0.01, 0.5, 0.25), 5.625);
  // Chance pairings in front of the row holding a third of its pixels are not the row.
  std::vector<RowFruit> chance;
  stretch(&chance, 0.0, 1.0, 0.625, 8000, 2);
  stretch(&chance, 2.0, 3.0, 2.375, 24000, 40);
  EXPECT_DOUBLE_EQ(RowFruitDistance(chance, 1.0, 0.01, 0.5, 0.25), 2.375);
  // ... unless a third is enough.
  EXPECT_DOUBLE_EQ(RowFruitDistance(chance, 1.0, 0.01, 0.3, 0), 0.625);
  // Near the camera they can outweigh the row by pixels (seed 497's back),
  // never by apples.
  std::vector<RowFruit> near;
  stretch(&near, 0.25, 1.25, 0.625, 30000, 5);
  stretch(&near, 2.25, 2.75, 2.375, 24000, 80);
  EXPECT_DOUBLE_EQ(RowFruitDistance(near, 1.0, 0.01, 0.5, 0.25), 2.375);
  EXPECT_DOUBLE_EQ(RowFruitDistance(near, 1.0, 0.01, 0.5, 0), 0.625);  // by pixels alone
  // No stretch holds enough of both: the one with the most pixels.
  std::vector<RowFruit> split;
  stretch(&split, 0.25, 1.25, 0.625, 30000, 5);
  stretch(&split, 2.25, 2.75, 2.375, 2000, 80);
  EXPECT_DOUBLE_EQ(RowFruitDistance(split, 1.0, 0.01, 0.5, 0.25), 0.625);
  EXPECT_EQ(RowFruitDistance({}, 1.0, 0.01, 0.5, 0.25), 0);
}

TEST(NextRowGapCut, CutsInTheMiddleOfTheAisleBetweenTheRowAndTheNextRow) {
  std::vector<double> d;
  AddPoints(&d, 1.6, 3.35, 1750);  // the filmed row, row distance 2.1
  AddPoints(&d, 5.0, 6.0, 800);   // the next row's near face
  d.push_back(4.0);               // a stray point in the aisle
  // The first empty bin starts at 3.35 (row distance + 5 bins), the next row at 4.85.
  EXPECT_NEAR(NextRowGapCut(d, 2.1, 1.0, 0.01).value_or(-1), 4.1, 1e-9);
  // A thick round canopy: fruit to 4.0 m, the next row from 6.0 m; the fixed
  // 1.5 m margin would cut at 3.6 m, through the far half of the trees.
  std::vector<double> round;
  AddPoints(&round, 1.5, 4.0, 2500);
  AddPoints(&round, 6.0, 7.0, 800);
  EXPECT_NEAR(NextRowGapCut(round, 1.6, 1.0, 0.01).value_or(-1), 4.975, 1e-9);
  // Gaps shorter than asked for are not the aisle.
  EXPECT_FALSE(NextRowGapCut(round, 1.6, 2.5, 0.01));
}

TEST(NextRowGapCut, WithoutANextRowTheCutLiesBehindTheRowsFruit) {
  std::vector<double> d;
  AddPoints(&d, 1.6, 3.35, 1750);
  d.push_back(3.9);  // stray points, nothing behind
  d.push_back(4.3);
  EXPECT_NEAR(NextRowGapCut(d, 2.1, 1.0, 0.01).value_or(-1), 2.1 + 5 * 0.25 + 0.5, 1e-9);
}

TEST(NextRowGapCut, NoGapWhenFruitRunsOnToTheLastBin) {
  std::vector<double> d;
  AddPoints(&d, 1.6, 6.0, 4400);
  EXPECT_FALSE(NextRowGapCut(d, 2.1, 1.0, 0.01));
  EXPECT_FALSE(NextRowGapCut({}, 2.1, 1.0, 0.01));
  EXPECT_FALSE(NextRowGapCut(d, 2.1, 0.0, 0.01));  // gap 0: the fixed margin
}

TEST(CountFruitClusters, CountsEachBallOnceAndRemovesFallenAndNextRow) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  // Three apples on the tree, one fallen (on the ground, far enough to be in view) and one in the next
  // row 6 m from the cameras.
  const std::vector<Eigen::Vector3d> balls = {
      {-0.2, 0, 1.2}, {0.3, -0.1, 1.6}, {0.7, 0.1, 2.0}, {0.2, 1.0, 0.04}, {0.4, 3.5, 1.4}};
  const std::vector<FruitFrame> frames = RenderBalls(views, balls, 0.04);
  Plane ground;  // z = 0
  ClusterOptions o;
  const ClusterResult r = CountFruitClusters(views, frames, ground, o);
  std::map<std::string, int> status;
  for (const auto& c : r.clusters) status[c.status] += c.count;
  EXPECT_EQ(r.count, 3);
  EXPECT_EQ(status["kept"], 3);
  EXPECT_EQ(status["fallen"], 1);
  EXPECT_EQ(status["next_row"], 1);
  for (const auto& c : r.clusters) {
    if (c.status != "kept") continue;
    double nearest = 1e9;
    for (const auto& b : balls) nearest = std::min(nearest, (c.centre - b).norm());
    EXPECT_LT(nearest, 0.02);
  }
  int seen = 0;
  for (const auto& f : frames) seen += static_cast<int>(f.blobs.size());
  EXPECT_EQ(r.single_frame_sum, seen);
  EXPECT_GT(r.single_frame_sum, 3 * r.count);
}

TEST(CountFruitClusters, GivesTheCountUnderEitherBestViewsRule) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  std::vector<FruitFrame> frames = RenderBalls(views, {{0.2, 0, 1.4}}, 0.04);
  // Counted 2 in the last three frames that see it, which are not its
  // largest views (all alike but for the frame's edge; ties: earlier first).
  int changed = 0;
  for (auto f = frames.rbegin(); f != frames.rend() && changed < 3; ++f)
    if (!f->counts.empty()) f->counts[0] = 2, ++changed;
  ASSERT_EQ(changed, 3);
  ClusterOptions o;
  for (const auto rule : {ClusterOptions::BestViews::kPixels, ClusterOptions::BestViews::kCount}) {
    o.best_views_by = rule;
    const ClusterResult r = CountFruitClusters(views, frames, Plane(), o);
    ASSERT_EQ(r.clusters.size(), 1u);
    const FruitCluster& c = r.clusters[0];
    EXPECT_EQ(c.count_by_pixels, 1);
    EXPECT_EQ(c.count_by_count, 2);
    EXPECT_EQ(c.count, rule == ClusterOptions::BestViews::kCount ? 2 : 1);
  }
}

TEST(CountFruitClusters, BlobsTooSmallForAnAppleAtTheClusterDepthAreRemoved) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  const std::vector<Eigen::Vector3d> balls = {{-0.2, 0, 1.2}, {0.3, -0.1, 1.6}, {0.7, 0.1, 2.0}};
  const std::vector<FruitFrame> frames = RenderBalls(views, balls, 0.04);
  ClusterOptions o;  // kept when a blob shows half an apple of 3 cm radius
  ClusterResult r = CountFruitClusters(views, frames, Plane(), o);
  EXPECT_EQ(r.count, 3);
  for (const auto& c : r.clusters) EXPECT_NEAR(c.apple_radius_seen, 0.04, 0.006);  // discs drawn to whole pixels
  // Blobs showing 4 cm at the clusters' depth where 4.5 cm is the least:
  // as the next row's apples look when paired by chance into this row.
  o.min_apple_fraction = 1.5;
  r = CountFruitClusters(views, frames, Plane(), o);
  std::map<std::string, int> status;
  for (const auto& c : r.clusters) status[c.status] += c.count;
  EXPECT_EQ(r.count, 0);
  EXPECT_EQ(status["small"], 3);
}

// The frame's blobs joined into one blob counted as all of them: a
// detector's blob of touching apples, counted by a counter.
FruitFrame JoinBlobs(const FruitFrame& f) {
  FruitFrame joined;
  joined.labels = cv::Mat1i::zeros(f.labels.size());
  const cv::Mat1b fruit = f.labels > 0;
  if (cv::countNonZero(fruit) == 0) return joined;
  joined.labels.setTo(1, fruit);
  Blob b;
  b.id = 1;
  b.pixels = cv::countNonZero(fruit);
  const cv::Rect box = cv::boundingRect(fruit);
  b.box = Box{static_cast<double>(box.x), static_cast<double>(box.y), static_cast<double>(box.x + box.width),
              static_cast<double>(box.y + box.height)};
  const cv::Moments m = cv::moments(fruit, true);
  b.centroid = {m.m10 / m.m00, m.m01 / m.m00};
  joined.blobs = {b};
  joined.counts = {static_cast<int>(f.blobs.size())};
  return joined;
}

TEST(SplitCountedBlobs, OnePiecePerCountedAppleAtItsDisc) {
  const CameraView v = ViewAt(0);
  // Two touching apples (8 cm apart, radius 4 cm) 2.5 m away: one blob counted 2.
  const std::vector<Eigen::Vector3d> pair = {{-0.04, 0, 1.5}, {0.04, 0, 1.5}};
  FruitFrame frame = JoinBlobs(RenderBalls({v}, pair, 0.04)[0]);
  ASSERT_EQ(frame.blobs.size(), 1u);
  // A lone apple elsewhere, counted 1, and a speck counted 0 stay as they are.
  const FruitFrame lone = RenderBalls({v}, {{0.5, 0, 1.2}, {-0.5, 0, 1.8}}, 0.04)[0];
  for (int i = 0; i < 2; ++i) {
    Blob b = lone.blobs[i];
    b.id = static_cast<int>(frame.blobs.size()) + 1;
    frame.labels.setTo(b.id, lone.labels == i + 1);
    frame.blobs.push_back(b);
    frame.counts.push_back(1 - i);
  }
  FruitFrame before = frame;
  before.labels = frame.labels.clone();
  SplitCountedBlobs(&frame);
  ASSERT_EQ(frame.blobs.size(), 4u);
  EXPECT_EQ(frame.counts, (std::vector<int>{1, 1, 0, 1}));
  EXPECT_EQ(frame.blobs[1].pixels, before.blobs[1].pixels);
  EXPECT_EQ(cv::countNonZero(frame.labels == 2), before.blobs[1].pixels);
  for (const Blob& b : frame.blobs) EXPECT_EQ(cv::countNonZero(frame.labels == b.id), b.pixels) << b.id;
  EXPECT_EQ(frame.blobs[0].pixels + frame.blobs[3].pixels, before.blobs[0].pixels);
  // Each piece's centroid lies near its apple's projected centre (the apples
  // are 16 px apart in the image, 8 px radius).
  for (const auto& X : pair) {
    Eigen::Vector2d p;
    ASSERT_TRUE(v.Project(X, &p));
    double nearest = 1e9;
    for (int id : {1, 4}) {
      const cv::Point2d c = frame.blobs[id - 1].centroid;
      nearest = std::min(nearest, std::hypot(c.x + 0.5 - p.x(), c.y + 0.5 - p.y()));
    }
    EXPECT_LT(nearest, 3.0);
  }
  // The same input splits the same way.
  FruitFrame again = before;
  again.labels = before.labels.clone();
  SplitCountedBlobs(&again);
  EXPECT_EQ(cv::countNonZero(again.labels != frame.labels), 0);
}

TEST(CountFruitClusters, KeepsTheFarHalfOfAThickCanopyAndCutsTheNextRowInTheAisle) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  // A round tree 1.8 m deep (2.2-4.0 m from the cameras) and the next row 6 m away.
  const std::vector<Eigen::Vector3d> balls = {
      {-0.2, -0.3, 1.2}, {0.3, 0.0, 1.6}, {0.6, 0.5, 2.0}, {0.1, 1.0, 1.4}, {0.5, 1.5, 1.8}, {0.4, 3.5, 1.4}};
  const std::vector<FruitFrame> frames = RenderBalls(views, balls, 0.04);
  Plane ground;  // z = 0
  ClusterOptions o;
  ClusterResult r = CountFruitClusters(views, frames, ground, o);
  std::map<std::string, int> status;
  for (const auto& c : r.clusters) status[c.status] += c.count;
  EXPECT_TRUE(r.depth_cutoff_from_gap);
  EXPECT_GT(r.depth_cutoff, 4.0);
  EXPECT_LT(r.depth_cutoff, 6.0);
  EXPECT_EQ(r.count, 5);
  EXPECT_EQ(status["next_row"], 1);
  // The fixed margin (row distance + 1.5 m) cuts the far half's last apple.
  o.next_row_gap = 0;
  r = CountFruitClusters(views, frames, ground, o);
  EXPECT_FALSE(r.depth_cutoff_from_gap);
  EXPECT_EQ(r.count, 4);
}

TEST(CountFruitClusters, TouchingApplesInOneBlobAreLocatedWhenTheBlobIsSplit) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  // Two pairs of touching apples, each pair one blob counted 2 in every frame.
  const std::vector<std::vector<Eigen::Vector3d>> pairs = {{{-0.24, 0, 1.2}, {-0.16, 0, 1.2}},
                                                           {{0.36, -0.1, 1.6}, {0.42, -0.1, 1.65}}};
  std::vector<FruitFrame> frames(views.size());
  for (size_t f = 0; f < views.size(); ++f) {
    frames[f].labels = cv::Mat1i::zeros(views[f].height, views[f].width);
    for (const auto& pair : pairs) {
      FruitFrame one = JoinBlobs(RenderBalls({views[f]}, pair, 0.04)[0]);
      if (one.blobs.empty()) continue;
      Blob b = one.blobs[0];
      b.id = static_cast<int>(frames[f].blobs.size()) + 1;
      frames[f].labels.setTo(b.id, one.labels == 1);
      frames[f].blobs.push_back(b);
      frames[f].counts.push_back(2);
    }
  }
  Plane ground;  // z = 0
  ClusterOptions o;
  o.link_distance = 0.05;  // touching apples' centres are 6-8 cm apart
  std::vector<FruitFrame> split = frames;
  for (auto& f : split) {
    f.labels = f.labels.clone();  // cv::Mat copies share their pixels
    SplitCountedBlobs(&f);
  }
  const auto near_apples = [&](const ClusterResult& r) {
    int located = 0;
    for (const auto& pair : pairs)
      for (const auto& X : pair) {
        bool near = false;
        for (const auto& p : r.points) near = near || (p.xyz - X).norm() < 0.025;
        located += near;
      }
    return located;
  };
  const ClusterResult whole = CountFruitClusters(views, frames, ground, o);
  const ClusterResult pieces = CountFruitClusters(views, split, ground, o);
  // Whole blobs give points between the apples of a pair; pieces give a point
  // at every apple, and the count is the same four.
  EXPECT_EQ(near_apples(whole), 0);
  EXPECT_EQ(near_apples(pieces), 4);
  EXPECT_EQ(pieces.count, 4);
  EXPECT_EQ(pieces.single_frame_sum, whole.single_frame_sum);
}

TEST(BlobNearPoint, ASmallPieceOfAHiddenAppleSupportsItsCentre) {
  const CameraView v = ViewAt(0);
  const Eigen::Vector3d X(0.1, 0, 1.5);  // 2.5 m away: a 3 cm apple is 6 px, 70% of it 4.2 px
  Eigen::Vector2d p;
  ASSERT_TRUE(v.Project(X, &p));
  FruitFrame frame;
  frame.labels = cv::Mat1i::zeros(v.height, v.width);
  Blob piece;  // 20 pixels (equivalent radius 2.5 px) showing 4 px right of the apple's centre
  piece.id = 1, piece.pixels = 20;
  piece.centroid = {p.x() - 0.5 + 4, p.y() - 0.5};
  piece.box = Box{piece.centroid.x - 2, piece.centroid.y - 2, piece.centroid.x + 3, piece.centroid.y + 3};
  Blob other = piece;  // another apple's piece 15 px away
  other.id = 2, other.centroid.x += 11, other.box.x1 += 11, other.box.x2 += 11;
  frame.blobs = {piece, other};
  FruitPointOptions o;
  EXPECT_EQ(BlobNearPoint(v, frame, X, o), 1);
  o.apple_fraction = 0;  // only the piece's own size: its centre is too far
  EXPECT_EQ(BlobNearPoint(v, frame, X, o), 0);
  o.apple_fraction = 0.7;
  EXPECT_EQ(BlobNearPoint(v, frame, X + Eigen::Vector3d(0.07, 0, 0), o), 2);  // 14 px right: the other piece
  EXPECT_EQ(BlobNearPoint(v, frame, X + Eigen::Vector3d(0, 0, 0.05), o), 0);  // 10 px up: neither
  o.apple_radius = 0;
  EXPECT_THROW(o.Check(), Error);
}

FruitPointCandidate CandidateAt(const Eigen::Vector3d& x, int frame, int blob, std::vector<std::pair<int, int>> hits,
                                int in_image) {
  FruitPointCandidate c;
  c.point = {x, frame, blob, static_cast<int>(hits.size())};
  c.in_image = in_image;
  c.hits = std::move(hits);
  c.error = 0.5;
  return c;
}

TEST(ChooseFruitPoints, AChancePairingOnAnotherApplesBlobsGivesWayToTheBlobsNextBest) {
  // Apple A is blob 1 in frames 0-5, apple B blob 2 in frames 2-5.
  const Eigen::Vector3d a(0, 0, 1.5), b(0.3, 0, 1.5);
  std::vector<std::vector<FruitPointCandidate>> per_blob(4);
  per_blob[0] = {CandidateAt(a, 0, 1, {{0, 1}, {1, 1}, {2, 1}, {3, 1}, {4, 1}, {5, 1}}, 6)};
  // B's blob in frame 3: its best pairing is a chance point near the camera
  // that lands on A's blobs in four frames; its next best is B.
  const Eigen::Vector3d chance(0.15, -1.2, 1.5);
  per_blob[1] = {CandidateAt(b, 3, 2, {{2, 2}, {3, 2}, {4, 2}, {5, 2}}, 6),
                 CandidateAt(chance, 3, 2, {{0, 1}, {1, 1}, {2, 1}, {3, 2}, {4, 1}}, 8)};
  // A's blob in frame 2 paired 3 cm from A: agrees with A, kept.
  const Eigen::Vector3d near_a = a + Eigen::Vector3d(0.03, 0, 0);
  per_blob[2] = {CandidateAt(near_a, 2, 1, {{1, 1}, {2, 1}, {3, 1}}, 4)};
  // A's blob in frame 4 paired 20 cm off, with three hits of its own: A
  // explains the blob it starts from, so it keeps no point.
  const Eigen::Vector3d ghost = a + Eigen::Vector3d(0, 0.2, 0);
  per_blob[3] = {CandidateAt(ghost, 4, 1, {{4, 1}, {5, 3}, {6, 3}, {7, 3}}, 5)};

  FruitPointOptions o;
  o.explain_distance = 0;  // off: each blob's strongest
  std::vector<FruitPoint> points = ChooseFruitPoints(per_blob, o);
  ASSERT_EQ(points.size(), 4u);
  EXPECT_TRUE(points[1].xyz.isApprox(chance));
  EXPECT_EQ(points[1].support, 5);
  EXPECT_TRUE(points[3].xyz.isApprox(ghost));

  o.explain_distance = FruitPointOptions().explain_distance;  // the default, 6 cm
  ASSERT_DOUBLE_EQ(o.explain_distance, 0.06);
  points = ChooseFruitPoints(per_blob, o);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_TRUE(points[0].xyz.isApprox(a));
  EXPECT_TRUE(points[1].xyz.isApprox(b));
  EXPECT_EQ(points[1].frame, 3);
  EXPECT_TRUE(points[2].xyz.isApprox(near_a));

  // Closer than 3 cm counts as another apple: the near pairing goes too.
  o.explain_distance = 0.02;
  points = ChooseFruitPoints(per_blob, o);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_TRUE(points[1].xyz.isApprox(b));

  o.explain_distance = -1;
  EXPECT_THROW(ChooseFruitPoints(per_blob, o), Error);
}

// A blob as the side stage makes it from a label image.
Blob BlobOf(const cv::Mat1i& labels, int id) {
  const cv::Mat1b mask = labels == id;
  const cv::Moments m = cv::moments(mask, true);
  const cv::Rect box = cv::boundingRect(mask);
  Blob b;
  b.id = id;
  b.pixels = cv::countNonZero(mask);
  b.centroid = {m.m10 / m.m00, m.m01 / m.m00};
  b.box = Box{static_cast<double>(box.x), static_cast<double>(box.y), static_cast<double>(box.x + box.width),
              static_cast<double>(box.y + box.height)};
  return b;
}

TEST(FitAppleCentre, FindsTheCentreOfAPartlyHiddenAppleAndKeepsTheCentroidOtherwise) {
  const cv::Point2d centre(50, 40);
  const int radius = 12;
  cv::Mat1i labels = cv::Mat1i::zeros(100, 120);
  cv::circle(labels, cv::Point(50, 40), radius, 1, -1);
  // A leaf covers the right half of the apple, another a notch of its lower edge.
  labels(cv::Rect(50, 0, 70, 100)).setTo(0);
  labels(cv::Rect(40, 48, 5, 10)).setTo(0);
  const Blob hidden = BlobOf(labels, 1);
  ASSERT_GT(cv::norm(hidden.centroid - centre), 4.0);
  EXPECT_LT(cv::norm(FitAppleCentre(labels, hidden) - centre), 1.0);

  // A whole apple: its centroid.
  labels.setTo(0);
  cv::circle(labels, cv::Point(50, 40), radius, 2, -1);
  const Blob whole = BlobOf(labels, 2);
  EXPECT_EQ(FitAppleCentre(labels, whole), whole.centroid);
  // Two touching apples in one blob (a colour detector's): no circle holds
  // it, so the centroid.
  cv::circle(labels, cv::Point(72, 40), radius, 2, -1);
  const Blob pair = BlobOf(labels, 2);
  EXPECT_EQ(FitAppleCentre(labels, pair), pair.centroid);
  // Too small to fit.
  labels.setTo(0);
  labels(cv::Rect(10, 10, 2, 2)).setTo(3);
  const Blob speck = BlobOf(labels, 3);
  EXPECT_EQ(FitAppleCentre(labels, speck), speck.centroid);

  FruitFrame frame;
  frame.labels = labels;
  frame.blobs = {Blob{}, Blob{}, speck};
  frame.blobs[0].id = 1, frame.blobs[1].id = 2;
  FitAppleCentres(&frame);
  ASSERT_EQ(frame.apple_centres.size(), 3u);
  EXPECT_EQ(frame.apple_centres[2], speck.centroid);
}

TEST(FitAppleCentre, AnAppleTheFrameCutsIsCentredOnItsOwnOutline) {
  // The frame's top edge cuts an apple whose centre lies 6 px above the
  // frame: the blob's straight top edge is the frame's, not the apple's.
  const int radius = 12;
  cv::Mat1i labels = cv::Mat1i::zeros(100, 120);
  cv::circle(labels, cv::Point(50, -6), radius, 1, -1);
  const Blob cut = BlobOf(labels, 1);
  ASSERT_GT(cut.pixels, 50);
  ASSERT_GT(cv::norm(cut.centroid - cv::Point2d(50, -6)), 6.0);
  EXPECT_LT(cv::norm(FitAppleCentre(labels, cut) - cv::Point2d(50, -6)), 0.6);  // 1.1 px with the edge in the fit
}

TEST(ProjectNearFrame, TakesPointsUpToAnApplesRadiusBeyondTheFrame) {
  const CameraView v = ViewAt(0);  // f = 500 px, 2.5 m from y = 0
  FruitPointOptions o;
  o.apple_radius = 0.05;  // 10 px at 2.5 m
  Eigen::Vector2d p;
  bool inside = false;
  EXPECT_TRUE(ProjectNearFrame(v, Eigen::Vector3d(0, 0, 1.5), o, &p, &inside));
  EXPECT_TRUE(inside);
  // 6 px above the top edge: near; 20 px above: not.
  const double top = 1.5 + 240 * 2.5 / 500;
  EXPECT_TRUE(ProjectNearFrame(v, Eigen::Vector3d(0, 0, top + 6 * 2.5 / 500), o, &p, &inside));
  EXPECT_FALSE(inside);
  EXPECT_NEAR(p.y(), -6, 1e-6);
  EXPECT_FALSE(ProjectNearFrame(v, Eigen::Vector3d(0, 0, top + 20 * 2.5 / 500), o, &p, &inside));
  EXPECT_FALSE(ProjectNearFrame(v, Eigen::Vector3d(0, -3, 1.5), o, &p, &inside));  // behind the camera
}

TEST(CountFruitClusters, FindsAnAppleSeenOnlyThroughGapsInTheLeaves) {
  std::vector<CameraView> views;
  for (int i = 0; i < 24; ++i) views.push_back(ViewAt(-1.2 + 0.1 * i));
  const std::vector<Eigen::Vector3d> balls = {{-0.2, 0, 1.2}, {0.3, -0.1, 1.6}};
  std::vector<FruitFrame> frames = RenderBalls(views, balls, 0.04);
  // The second apple shows in one frame of three, and then only its left
  // half (leaves cover the rest): its piece's centre is off the apple's.
  for (size_t f = 0; f < frames.size(); ++f) {
    FruitFrame& fr = frames[f];
    for (size_t b = 1; b < fr.blobs.size(); ++b) {
      Blob& blob = fr.blobs[b];
      if (f % 3 != 0) {
        fr.labels.setTo(0, fr.labels == blob.id);
        blob.pixels = 0, blob.box = Box{-100, -100, -99, -99}, blob.centroid = {-100, -100};
        continue;
      }
      const int cx = static_cast<int>(blob.centroid.x);
      cv::Mat1i right = fr.labels(cv::Rect(cx, 0, fr.labels.cols - cx, fr.labels.rows));
      right.setTo(0, right == blob.id);
      const cv::Mat1b piece = fr.labels == blob.id;
      const cv::Moments m = cv::moments(piece, true);
      blob.pixels = cv::countNonZero(piece);
      blob.centroid = {m.m10 / m.m00, m.m01 / m.m00};
      blob.box.x2 = cx;
    }
  }
  Plane ground;  // z = 0
  ClusterOptions o;
  ClusterResult r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(r.count, 2);
  EXPECT_EQ(r.glimpsed_apples, 0);  // its fruit points found it
  // The support ratio of earlier versions (60% of the frames around) loses
  // its fruit points; the search for glimpsed apples finds it from its halves.
  o.points.min_support_ratio = 0.6;
  r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(r.count, 2);
  EXPECT_EQ(r.glimpsed_apples, 1);
  const auto glimpsed = std::find_if(r.clusters.begin(), r.clusters.end(), [](const auto& c) { return c.glimpsed; });
  ASSERT_NE(glimpsed, r.clusters.end());
  // Along and up within a few centimetres; across (its depth) the disc of
  // the largest apple leaves some centimetres more.
  EXPECT_NEAR(glimpsed->centre.x(), balls[1].x(), 0.03);
  EXPECT_NEAR(glimpsed->centre.z(), balls[1].z(), 0.03);
  EXPECT_NEAR(glimpsed->centre.y(), balls[1].y(), 0.12);
  EXPECT_EQ(glimpsed->edge_rays.size(), glimpsed->views.size());  // the merge links it along them
  o.glimpsed.enabled = false;
  r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(r.count, 1);
}

TEST(CountFruitClusters, AnAppleWhoseCentreTheAppleInFrontHidesIsCounted) {
  std::vector<CameraView> views;
  for (int i = 0; i < 11; ++i) views.push_back(ViewAt(-1.0 + 0.1 * i));
  // An apple and one behind it, 4 cm to the right and 6 cm farther: in every
  // frame the front apple covers the back one's centre, and the back one
  // shows as a crescent beside it.
  const Eigen::Vector3d front(0, 0, 1.5), back(0.04, 0.06, 1.5);
  std::vector<FruitFrame> frames = RenderBalls(views, {back, front}, 0.04);  // drawn back to front
  for (auto& f : frames) {
    for (auto& b : f.blobs) b = BlobOf(f.labels, b.id);  // what shows of each
    FitAppleCentres(&f);
  }
  Plane ground;  // z = 0
  ClusterOptions o;
  o.link_distance = 0.08;  // the two apples form one cluster
  const auto kept = [](const ClusterResult& r) {
    int n = 0;
    for (const auto& c : r.clusters) n += c.status == "kept";
    return n;
  };
  ClusterResult r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(kept(r), 1);
  EXPECT_EQ(r.count, 2);
  // Voting for the blob under a point first, the back apple's points vote
  // for the front apple's blob and its own crescent goes uncounted.
  o.vote_near_first = false;
  r = CountFruitClusters(views, frames, ground, o);
  EXPECT_EQ(kept(r), 1);
  EXPECT_EQ(r.count, 1);
}

TEST(CountFruitClusters, AFewPointsOnBlobsALargerClusterCoversAreItsAppleAgain) {
  std::vector<CameraView> views;
  for (int i = 0; i < 16; ++i) views.push_back(ViewAt(-0.5 + 0.1 * i));
  // Apple a, and apple b beside it (7 cm to the left). Leaves hide a in
  // frames 5 to 9, and in the last six all of it but a small piece 2.6 cm
  // right of its centre: a's points lie too far from the piece's centre to
  // vote for it.
  const Eigen::Vector3d a(0.2, 0, 1.4), b = a - Eigen::Vector3d(0.07, 0, 0), piece = a + Eigen::Vector3d(0.026, 0, 0);
  std::vector<FruitFrame> frames;
  for (int i = 0; i < 16; ++i)
    frames.push_back(i < 5    ? RenderBalls({views[i]}, {a, b}, 0.04)[0]
                     : i < 10 ? RenderBalls({views[i]}, {b}, 0.04)[0]
                              : RenderBalls({views[i]}, {piece, b}, std::vector<double>{0.015, 0.04})[0]);
  // a's points, b's, and two points of a second track of a through its
  // pieces, 16 cm behind the piece along the line of sight of frame 12.5:
  // they win the pieces' blobs.
  std::vector<FruitPoint> points;
  for (int i = 0; i < 8; ++i) points.push_back({a + Eigen::Vector3d(0.002 * (i % 3), 0, 0.002 * (i / 3)), i, 1, 8});
  for (int i = 0; i < 3; ++i) points.push_back({b + Eigen::Vector3d(0, 0, 0.002 * i), i, 2, 8});
  const Eigen::Vector3d camera(0.75, -2.5, 1.5), second = piece + 0.16 * (piece - camera).normalized();
  for (int i = 0; i < 2; ++i) points.push_back({second + Eigen::Vector3d(0.002 * i, 0, 0), 10 + i, 1, 6});
  Plane ground;  // z = 0
  ClusterOptions o;
  o.min_apple_fraction = 0;  // the pieces are small
  ASSERT_EQ(o.covered_max_points, 0);  // never, by default
  o.find_covers = true;  // reported all the same
  ClusterResult r = CountFruitClusters(views, frames, ground, o, points);
  std::map<std::string, int> status;
  for (const auto& c : r.clusters) status[c.status] += 1;
  ASSERT_EQ(r.clusters.size(), 3u);
  EXPECT_EQ(status["kept"], 3);  // the duplicate join misses it: less than half its votes fall on a's blobs
  EXPECT_EQ(r.count, 3);
  const FruitCluster& again = r.clusters[2];
  EXPECT_EQ(again.points.size(), 2u);
  EXPECT_EQ(again.views.size(), 6u);
  EXPECT_EQ(again.cover_id, r.clusters[0].id);  // found, not acted on
  o.covered_max_points = 7;
  r = CountFruitClusters(views, frames, ground, o, points);
  EXPECT_EQ(r.count, 2);
  EXPECT_EQ(r.clusters[0].status, "kept");
  EXPECT_EQ(r.clusters[1].status, "kept");  // b: a's points lie two radii from its centre
  EXPECT_EQ(r.clusters[1].cover_id, 0);
  EXPECT_EQ(r.clusters[2].status, "covered");
  EXPECT_EQ(r.clusters[2].cover_id, r.clusters[0].id);
  EXPECT_EQ(r.clusters[2].cover_views, 6);
  EXPECT_NEAR(r.clusters[2].cover_distance, 0.16, 0.02);
  // In frame 15 the piece lies farther right, beyond an apple radius from
  // a's points: covered in five of its six views, kept when all are asked for.
  frames[15] = RenderBalls({views[15]}, {a + Eigen::Vector3d(0.04, 0, 0), b}, std::vector<double>{0.015, 0.04})[0];
  r = CountFruitClusters(views, frames, ground, o, points);
  EXPECT_EQ(r.clusters[2].views.size(), 6u);
  EXPECT_EQ(r.clusters[2].cover_views, 5);
  EXPECT_EQ(r.count, 2);
  o.covered_fraction = 1;
  r = CountFruitClusters(views, frames, ground, o, points);
  EXPECT_EQ(r.count, 3);
  // Farther from the cluster covering it than a duplicate lies: kept.
  o.covered_fraction = 0.7;
  o.duplicate_max_distance = 0.1;
  r = CountFruitClusters(views, frames, ground, o, points);
  EXPECT_EQ(r.count, 3);
}

TEST(EvidenceStatus, FewViewsGhostsAndSmallBlobsAreRemoved) {
  ClusterOptions o;
  FruitCluster c;
  c.points = std::vector<int>(8, 0);
  c.count = 1;
  c.views = std::vector<ClusterView>(5, ClusterView{0, 100, 1});
  c.votes_won = 30, c.votes_lost = 20;
  c.apple_radius_seen = 0.04;
  EXPECT_EQ(EvidenceStatus(c, o), "kept");
  c.views.resize(2);  // wins a blob in two frames only: a chance pairing
  EXPECT_EQ(EvidenceStatus(c, o), "few_views");
  c.views.resize(5);
  o.max_lost_fraction = 0.6;  // `orchard yield`'s setting
  EXPECT_EQ(EvidenceStatus(c, o), "kept");
  c.votes_lost = 50;  // its points land mostly on blobs other clusters win
  EXPECT_EQ(EvidenceStatus(c, o), "ghost");
  o.min_points = 9;
  EXPECT_EQ(EvidenceStatus(c, o), "too_few_points");
  o.min_points = 1, c.count = 0;
  EXPECT_EQ(EvidenceStatus(c, o), "no_views");
  o.max_lost_fraction = 1, c.count = 1, c.votes_lost = 0;
  c.apple_radius_seen = 0.02;  // the default apple radius 3 cm, fraction 0.5
  EXPECT_EQ(EvidenceStatus(c, o), "kept");
  c.apple_radius_seen = 0.01;  // no blob as large as half an apple at its depth
  EXPECT_EQ(EvidenceStatus(c, o), "small");
  o.min_apple_fraction = -1;  // auto: a detector's 0.5 when called directly
  EXPECT_EQ(EvidenceStatus(c, o), "small");
  o.min_apple_fraction = -0.5;
  EXPECT_THROW(o.Check(), Error);
  o.min_apple_fraction = 0.5;
  o.max_lost_fraction = 0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(MergeSharedComponents, JoinsADuplicateToTheClusterWhoseBlobsItShares) {
  // Component 0: an apple seen in 4 frames (blob 1, 5 points each).
  // Component 1: the same apple triangulated again 20 cm off; 3 of its 4
  // votes fall on component 0's blobs. Component 2: a neighbour with a blob
  // of its own in every frame and one vote on blob 1.
  std::vector<BlobVotes> votes(4);
  for (int f = 0; f < 4; ++f) {
    votes[f][1][0] = 5;
    votes[f][2][2] = 3;
  }
  for (int f = 0; f < 3; ++f) votes[f][1][1] = 1;
  votes[3][3][1] = 1;
  votes[0][1][2] = 1;
  EXPECT_EQ(MergeSharedComponents(votes, 3, 0.5), (std::vector<int>{0, 0, 2}));
  EXPECT_EQ(MergeSharedComponents(votes, 3, 0.8), (std::vector<int>{0, 1, 2}));  // 3 of 4 is too few
  // A chain: 3 shares with 1, which joins 0; 3 ends in 0 too.
  votes[0][4][3] = 1;
  votes[0][4][1] = 1;
  EXPECT_EQ(MergeSharedComponents(votes, 4, 0.5), (std::vector<int>{0, 0, 2, 0}));
}

TEST(MergeDuplicateComponents, JoinsAClusterThatTakesItsPartnersBlobInOtherFrames) {
  // Component 0: an apple seen in 6 frames (blob 1, 5 points each); in
  // frames 4 and 5 component 1, the same apple triangulated again 20 cm
  // off, has more points on blob 1 and wins it there. Component 2: a
  // neighbouring apple (blob 2, 3 points a frame) whose points also land on
  // blob 1 in frames 0-3; both it and component 0 win a blob in those frames.
  std::vector<BlobVotes> votes(6);
  for (int f = 0; f < 6; ++f) {
    votes[f][1][0] = 5;
    votes[f][2][2] = 3;
  }
  for (int f = 4; f < 6; ++f) votes[f][1][1] = 6;
  for (int f = 0; f < 4; ++f) votes[f][1][2] = 2;
  const std::vector<std::vector<int>> won = {{0, 1, 2, 3}, {4, 5}, {0, 1, 2, 3, 4, 5}};
  const std::vector<Eigen::Vector3d> centres = {{0, 0, 0}, {0, 0.2, 0}, {0.08, 0, 0}};
  // 1 shares all its votes with 0 and never wins a blob where 0 does: joined.
  // 2 shares 8 of 20 (0.4) but wins a blob in 4 of its 6 frames where 0 wins one.
  EXPECT_EQ(MergeDuplicateComponents(votes, won, centres, 0.3, 0.4, 0.5), (std::vector<int>{0, 0, 2}));
  EXPECT_EQ(MergeDuplicateComponents(votes, won, centres, 0.3, 0.7, 0.5), (std::vector<int>{0, 0, 0}));
  EXPECT_EQ(MergeDuplicateComponents(votes, won, centres, 0.5, 0.7, 0.5), (std::vector<int>{0, 0, 2}));  // 0.4 too few
  EXPECT_EQ(MergeDuplicateComponents(votes, won, centres, 0.3, 0.4, 0.1), (std::vector<int>{0, 1, 2}));  // 20 cm off
  ClusterOptions o;
  o.duplicate_shared_fraction = 0.5;
  EXPECT_NO_THROW(o.Check());
  o.duplicate_coview_fraction = 0;
  EXPECT_THROW(o.Check(), Error);
  o.duplicate_coview_fraction = 0.4;
  o.duplicate_max_distance = 0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(ParseGroundPlane, NumbersAndErrors) {
  const Plane p = ParseGroundPlane("0,0,2,-1");
  EXPECT_NEAR(p.normal.z(), 1, 1e-12);
  EXPECT_NEAR(p.d, -0.5, 1e-12);
  EXPECT_THROW(ParseGroundPlane("0,0,1"), Error);
  EXPECT_THROW(ParseGroundPlane("a,b,c,d"), Error);
  EXPECT_THROW(ParseGroundPlane("0,0,0,1"), Error);
}

}  // namespace
}  // namespace orchard
