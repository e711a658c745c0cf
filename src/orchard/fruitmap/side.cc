#include "orchard/fruitmap/side.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/frame_source.h"
#include "orchard/core/stopwatch.h"
#include "orchard/fruitmap/truth_score.h"
#include "orchard/sfm/colmap_binary.h"

namespace orchard {
namespace {

using Json = nlohmann::json;

// ClusterOptions::min_apple_fraction's auto values: a detector's blobs, and
// instance masks (each blob one apple's visible part).
constexpr double kDetectorMinAppleFraction = 0.5;
constexpr double kInstanceMinAppleFraction = 0.6;


// Unit vectors along the camera path and across it (towards the row), both
// in the ground plane.
void PathAxes(const std::vector<CameraView>& views, const Plane& ground, Eigen::Vector3d* mean, Eigen::Vector3d* along,
              Eigen::Vector3d* across) {
  const Eigen::Vector3d n = ground.normal;
  *mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d forward = Eigen::Vector3d::Zero();
  for (const auto& v : views) *mean += v.Center(), forward += v.Forward();
  *mean /= static_cast<double>(views.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& v : views) cov += (v.Center() - *mean) * (v.Center() - *mean).transpose();
  Eigen::Vector3d u = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
  u -= n * n.dot(u);
  Eigen::Vector3d f = forward - n * n.dot(forward);
  if (u.norm() < 1e-9) u = n.cross(f);  // a single camera position: across = viewing direction
  u.normalize();
  f -= u * u.dot(f);
  if (f.norm() < 1e-9) Fail("the cameras look along their path; cannot tell the row's side");
  *along = u, *across = f.normalized();
}

// Depth bands across the row (m): the row distance and the next-row cut both
// read the fruit's distances from the camera path in these.
constexpr double kDistanceBand = 0.25;

}  // namespace

double RowFruitDistance(const std::vector<RowFruit>& fruit, double gap, double sparse_fraction, double min_share,
                        double min_apple_share) {
  std::map<int, std::pair<double, double>> bands;  // band -> pixels, apples
  for (const auto& f : fruit)
    if (f.distance > 0) {
      auto& b = bands[static_cast<int>(f.distance / kDistanceBand)];
      b.first += f.pixels, b.second += f.apples;
    }
  if (bands.empty()) return 0;
  double fullest = 0;
  for (const auto& [band, b] : bands) fullest = std::max(fullest, b.first);
  // Stretches of fruit: runs of bands above the sparse level, split where
  // at least `gap` m of sparse bands lie between two of them.
  struct Stretch {
    double pixels = 0, apples = 0, densest_pixels = -1;
    int densest = 0;
  };
  std::vector<Stretch> stretches;
  int previous = 0;
  for (const auto& [band, b] : bands) {
    const double pixels = b.first;
    if (pixels <= sparse_fraction * fullest) continue;
    if (stretches.empty() || (gap > 0 && (band - previous - 1) * kDistanceBand >= gap - 1e-9))
      stretches.emplace_back();
    Stretch& s = stretches.back();
    s.pixels += pixels, s.apples += b.second;
    if (pixels > s.densest_pixels) s.densest_pixels = pixels, s.densest = band;
    previous = band;
  }
  double most = 0, most_apples = 0;
  for (const auto& s : stretches) most = std::max(most, s.pixels), most_apples = std::max(most_apples, s.apples);
  for (const auto& s : stretches)
    if (s.pixels >= min_share * most && s.apples >= min_apple_share * most_apples)
      return (s.densest + 0.5) * kDistanceBand;
  // No stretch holds enough of both: the one with the most pixels.
  for (const auto& s : stretches)
    if (s.pixels >= most) return (s.densest + 0.5) * kDistanceBand;
  return 0;  // not reached
}

std::optional<double> NextRowGapCut(const std::vector<double>& point_distances, double row_distance, double gap,
                                    double sparse_fraction) {
  if (gap <= 0) return std::nullopt;
  std::map<int, int> bins;  // bin behind the row distance (negative: in front) -> points
  for (double d : point_distances) ++bins[static_cast<int>(std::floor((d - row_distance) / kDistanceBand))];
  if (bins.empty()) return std::nullopt;
  int fullest = 0;
  for (const auto& [bin, points] : bins) fullest = std::max(fullest, points);
  const auto sparse = [&](int bin) {
    const auto it = bins.find(bin);
    return it == bins.end() || it->second <= sparse_fraction * fullest;
  };
  const int need = static_cast<int>(std::ceil(gap / kDistanceBand - 1e-9));
  const int last = bins.rbegin()->first;
  int run_start = -1;
  for (int bin = 0; bin <= last; ++bin) {
    if (sparse(bin)) {
      if (run_start < 0) run_start = bin;
      continue;
    }
    if (run_start >= 0 && bin - run_start >= need) return row_distance + (run_start + bin) * kDistanceBand / 2;
    run_start = -1;
  }
  // A sparse run with no fruit behind it: no next row in view, the row's
  // fruit ends where the run starts. A full last bin: no gap seen.
  if (run_start < 0) return std::nullopt;
  return row_distance + run_start * kDistanceBand + gap / 2;
}

namespace {

// Each component's point-on-blob votes in all, and its votes on blobs that
// another component also votes for, per other component.
void SharedVotes(const std::vector<BlobVotes>& votes, int k, std::vector<int>* total,
                 std::vector<std::map<int, int>>* shared) {
  total->assign(k, 0);
  shared->assign(k, {});
  for (const auto& frame_votes : votes)
    for (const auto& [blob, by_component] : frame_votes)
      for (const auto& [a, points] : by_component) {
        (*total)[a] += points;
        for (const auto& other : by_component)
          if (other.first != a) (*shared)[a][other.first] += points;
      }
}

// Joins each component to the component with more votes that it shares
// most votes with, when at least `fraction` of its votes are shared and
// accept(component, partner) holds. Each decision rests on the votes alone,
// so the order does not matter. Returns each component's representative.
template <typename Accept>
std::vector<int> JoinSharingComponents(const std::vector<BlobVotes>& votes, int k, double fraction,
                                       const Accept& accept) {
  std::vector<int> total;
  std::vector<std::map<int, int>> shared;
  SharedVotes(votes, k, &total, &shared);
  UnionFind groups(k);
  for (int a = 0; a < k; ++a) {
    int best = -1, best_shared = 0;
    for (const auto& [b, points] : shared[a])
      if (total[b] > total[a] && points > best_shared) best = b, best_shared = points;
    if (best >= 0 && best_shared >= fraction * total[a] && accept(a, best)) groups.Join(a, best);
  }
  std::vector<int> root(k);
  for (int c = 0; c < k; ++c) root[c] = groups.Find(c);
  return root;
}

// For each cluster, the cluster with more points whose points land within an
// apple radius (at the point's depth) of one of its blobs' centres in the
// most of its views (FruitCluster::cover_id, ClusterOptions::covered_fraction).
void FindCoveringClusters(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                          const std::vector<Eigen::Vector3d>& xyz, const ClusterOptions& o, ClusterResult* r) {
  struct Projected {
    Eigen::Vector2d pixel;
    int cluster;
    double apple_px;  // an apple's radius at the point's depth
  };
  std::vector<std::vector<Projected>> projected(frames.size());
  for (size_t f = 0; f < frames.size(); ++f)
    for (size_t i = 0; i < xyz.size(); ++i) {
      const double z = views[f].Depth(xyz[i]);
      Eigen::Vector2d p;
      bool inside = false;
      if (z < o.points.min_depth || !ProjectNearFrame(views[f], xyz[i], o.points, &p, &inside)) continue;
      projected[f].push_back({p, r->point_cluster[i], views[f].fx * o.points.apple_radius / z});
    }
  for (FruitCluster& c : r->clusters) {
    c.cover_id = c.cover_views = 0;
    // Only the rule's small clusters need a cover, unless all are reported.
    if (!o.find_covers && static_cast<int>(c.points.size()) > o.covered_max_points) continue;
    const int self = c.id - 1;
    std::map<int, int> views_covered;  // cluster index -> views
    for (size_t v = 0; v < c.views.size(); ++v) {
      const int f = c.views[v].frame;
      std::set<int> covering;
      for (const int blob : c.view_blobs[v]) {
        const Eigen::Vector2d centre = AppleCentrePixel(frames[f], *frames[f].FindBlob(blob));
        for (const Projected& q : projected[f])
          if (q.cluster != self && r->clusters[q.cluster].points.size() > c.points.size() &&
              (q.pixel - centre).norm() <= q.apple_px)
            covering.insert(q.cluster);
      }
      for (const int h : covering) ++views_covered[h];
    }
    for (const auto& [h, n] : views_covered)
      if (n > c.cover_views) {
        c.cover_id = h + 1, c.cover_views = n;
        c.cover_distance = (r->clusters[h].centre - c.centre).norm();
      }
  }
}

}  // namespace

std::vector<int> MergeSharedComponents(const std::vector<BlobVotes>& votes, int k, double fraction) {
  return JoinSharingComponents(votes, k, fraction, [](int, int) { return true; });
}

std::vector<int> MergeDuplicateComponents(const std::vector<BlobVotes>& votes,
                                          const std::vector<std::vector<int>>& won_frames,
                                          const std::vector<Eigen::Vector3d>& centres, double fraction,
                                          double max_coview_fraction, double max_distance) {
  const auto rarely_seen_together = [&](int a, int partner) {
    if (won_frames[a].empty() || (centres[a] - centres[partner]).norm() > max_distance) return false;
    const std::set<int> partner_frames(won_frames[partner].begin(), won_frames[partner].end());
    int coviews = 0;
    for (int f : won_frames[a]) coviews += static_cast<int>(partner_frames.count(f));
    return coviews < max_coview_fraction * static_cast<double>(won_frames[a].size());
  };
  return JoinSharingComponents(votes, static_cast<int>(won_frames.size()), fraction, rarely_seen_together);
}

void ClusterOptions::Check() const {
  points.Check();
  ORCHARD_CHECK_OPTION(link_distance > 0, "link distance must be positive, got ", link_distance);
  ORCHARD_CHECK_OPTION(frame_scale > 0, "frame scale must be positive, got ", frame_scale);
  ORCHARD_CHECK_OPTION(min_points >= 1, "min cluster points must be at least 1, got ", min_points);
  ORCHARD_CHECK_OPTION(min_views >= 1, "min cluster views must be at least 1, got ", min_views);
  ORCHARD_CHECK_OPTION(max_lost_fraction > 0 && max_lost_fraction <= 1, "max lost fraction must be in (0, 1], got ",
                       max_lost_fraction);
  ORCHARD_CHECK_OPTION(min_apple_fraction >= 0 || min_apple_fraction == -1,
                       "min apple fraction must be >= 0 (or -1: auto), got ", min_apple_fraction);
  ORCHARD_CHECK_OPTION(merge_shared_fraction >= 0 && merge_shared_fraction <= 1,
                       "merge shared fraction must be in [0, 1], got ", merge_shared_fraction);
  ORCHARD_CHECK_OPTION(duplicate_shared_fraction >= 0 && duplicate_shared_fraction <= 1,
                       "duplicate shared fraction must be in [0, 1], got ", duplicate_shared_fraction);
  ORCHARD_CHECK_OPTION(duplicate_coview_fraction > 0 && duplicate_coview_fraction <= 1,
                       "duplicate co-view fraction must be in (0, 1], got ", duplicate_coview_fraction);
  ORCHARD_CHECK_OPTION(duplicate_max_distance > 0, "duplicate max distance must be positive, got ",
                       duplicate_max_distance);
  ORCHARD_CHECK_OPTION(covered_max_points >= 0, "covered max points must be >= 0, got ", covered_max_points);
  ORCHARD_CHECK_OPTION(covered_fraction > 0 && covered_fraction <= 1, "covered fraction must be in (0, 1], got ",
                       covered_fraction);
  ORCHARD_CHECK_OPTION(best_views >= 1, "best views must be at least 1, got ", best_views);
  ORCHARD_CHECK_OPTION(row_distance >= 0, "row distance must be >= 0, got ", row_distance);
  ORCHARD_CHECK_OPTION(row_min_share > 0 && row_min_share <= 1, "row min share must be in (0, 1], got ",
                       row_min_share);
  ORCHARD_CHECK_OPTION(row_min_apple_share >= 0 && row_min_apple_share <= 1,
                       "row min apple share must be in [0, 1], got ", row_min_apple_share);
  ORCHARD_CHECK_OPTION(next_row_gap >= 0, "next-row gap must be >= 0, got ", next_row_gap);
  ORCHARD_CHECK_OPTION(next_row_sparse >= 0 && next_row_sparse < 1, "next-row sparse fraction must be in [0, 1), got ",
                       next_row_sparse);
  ORCHARD_CHECK_OPTION(next_row_margin > 0, "next-row margin must be positive, got ", next_row_margin);
  ORCHARD_CHECK_OPTION(near_margin > 0, "near margin must be positive, got ", near_margin);
  edge.Check();
  glimpsed.Check();
}

ClusterOptions::BestViews ResolvedBestViews(const ClusterOptions& o, const SideInputs& in) {
  if (o.best_views_by != ClusterOptions::BestViews::kAuto) return o.best_views_by;
  // Counts per view are apple instances (instance masks or a box detector's
  // boxes, one apple per blob): take the views that show the most apples.
  return !in.counter ? ClusterOptions::BestViews::kCount : ClusterOptions::BestViews::kPixels;
}

int ResolvedEdgeMinPixels(const ClusterOptions& o, const SideInputs& in) {
  if (o.edge.min_pixels > 0) return o.edge.min_pixels;
  return in.detector ? 50 : 20;
}

double ResolvedMinAppleFraction(const ClusterOptions& o, const SideInputs& in) {
  if (o.min_apple_fraction >= 0) return o.min_apple_fraction;
  return in.detector ? kDetectorMinAppleFraction : kInstanceMinAppleFraction;
}

ClusterOptions ScaledToFrameDensity(ClusterOptions o) {
  const double k = o.frame_scale;
  if (k == 1) return o;
  // Spans in frames (partners, windows) grow k times; n frames over a
  // stretch of the path become k (n - 1) + 1 at k times the density. Both
  // are rounded to whole frames and never fall below one (k < 1: sparser).
  const auto span = [k](int n) { return std::max(1, static_cast<int>(std::lround(k * n))); };
  const auto frames_over = [k](int n) { return std::max(1, static_cast<int>(std::lround(k * (n - 1) + 1))); };
  o.points.max_partner_offset = std::max(o.points.min_partner_offset, span(o.points.max_partner_offset));
  o.points.support_window = span(o.points.support_window);
  o.edge.window = span(o.edge.window);
  o.glimpsed.window = span(o.glimpsed.window);
  o.points.min_support = frames_over(o.points.min_support);
  o.min_points = frames_over(o.min_points);
  o.min_views = frames_over(o.min_views);
  o.glimpsed.min_support = frames_over(o.glimpsed.min_support);
  // The median of the best views is their ((n + 1) / 2)-th highest: that
  // rank counts frames too.
  o.best_views = 2 * frames_over((o.best_views + 1) / 2) - 1;
  o.frame_scale = 1;
  return o;
}

bool ResolvedGlimpsedApples(const ClusterOptions& o, const SideInputs& in) {
  return o.glimpsed.enabled && (!in.detector || o.glimpsed.with_detector);
}

const char* BestViewsName(ClusterOptions::BestViews best_views) {
  switch (best_views) {
    case ClusterOptions::BestViews::kPixels:
      return "pixels";
    case ClusterOptions::BestViews::kCount:
      return "count";
    default:
      return "auto";
  }
}

std::string EvidenceStatus(const FruitCluster& c, const ClusterOptions& o) {
  if (static_cast<int>(c.points.size()) < o.min_points) return "too_few_points";
  if (c.count == 0) return "no_views";
  if (static_cast<int>(c.views.size()) < o.min_views) return "few_views";
  if (c.votes_lost > o.max_lost_fraction * (c.votes_won + c.votes_lost)) return "ghost";
  // Auto (-1) is RunSide's to decide; called directly, a detector's.
  const double min_apple_fraction = o.min_apple_fraction < 0 ? kDetectorMinAppleFraction : o.min_apple_fraction;
  if (c.apple_radius_seen < min_apple_fraction * o.points.apple_radius) return "small";
  return "kept";
}

ClusterResult CountFruitClusters(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                                 const Plane& ground, const ClusterOptions& o) {
  o.Check();
  return CountFruitClusters(views, frames, ground, o, TriangulateFruitPoints(views, frames, o.points));
}

namespace {

// Adds `point` to `r` as a point of the cluster `c`, which `r` will hold next.
void AppendPoint(const FruitPoint& point, FruitCluster* c, ClusterResult* r) {
  c->min = c->min.cwiseMin(point.xyz), c->max = c->max.cwiseMax(point.xyz);
  c->points.push_back(static_cast<int>(r->points.size()));
  r->points.push_back(point);
  r->point_cluster.push_back(static_cast<int>(r->clusters.size()));
}

// The fruit points of the clusters whose status is one of `statuses`: the
// points that explain the pieces of the apples those clusters hold.
std::vector<Eigen::Vector3d> PointsOfClusters(const ClusterResult& r, std::initializer_list<std::string_view> statuses) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& c : r.clusters)
    if (std::find(statuses.begin(), statuses.end(), c.status) != statuses.end())
      for (int i : c.points) points.push_back(r.points[i].xyz);
  return points;
}

// Appends the apples seen only at the frames' top edge (EdgeAppleOptions) to
// `r` as kept clusters of one apple each, after the kept clusters, whose
// points explain the slivers of the apples they hold.
void AddEdgeApples(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames, const Plane& ground,
                   const ClusterOptions& o, ClusterResult* r) {
  // A sliver a counted cluster's point lies on is that cluster's apple; so
  // is one that a cluster too small for these rules lies on (`orchard
  // yield` keeps only clusters of 4 points for the merge, and its slivers
  // are not apples the 3D stage missed).
  const std::vector<Eigen::Vector3d> explained = PointsOfClusters(*r, {"kept", "too_few_points", "covered"});
  const RowFrame row{r->row_origin, r->row_along, r->row_across, r->row_up, r->row_distance};
  if (row.row_distance <= 0) return;  // no kept fruit: nothing tells where the row is
  const std::vector<EdgeSighting> sightings = FindEdgeSightings(views, frames, explained, row, o.edge);
  for (const EdgeApple& a : GroupEdgeSightings(sightings, row, o.edge)) {
    FruitCluster c;
    c.id = static_cast<int>(r->clusters.size()) + 1;
    c.edge = true;
    c.centre = a.centre;
    c.min = c.max = a.sighting_points[0];
    for (size_t i = 0; i < a.sightings.size(); ++i) {
      const EdgeSighting& s = sightings[a.sightings[i]];
      const Eigen::Vector3d& X = a.sighting_points[i];
      AppendPoint({X, s.frame, s.blobs[0], static_cast<int>(a.sightings.size())}, &c, r);
      c.views.push_back({s.frame, s.pixels, 1});
      c.edge_rays.emplace_back(SightingAtDistance(s, row, row.row_distance - o.edge.near_margin),
                               SightingAtDistance(s, row, row.row_distance + o.edge.far_margin));
      c.edge_columns.push_back(s.column);
      c.view_blobs.push_back(s.blobs);
    }
    // A sliver shows one apple: every view counts one.
    c.count = c.count_by_pixels = c.count_by_count = MedianOfBestViews(c.views, o.best_views, &c.count_frames);
    c.height = ground.SignedDistance(c.centre);
    c.distance = a.distance;
    if (c.distance > r->depth_cutoff) c.status = "next_row";
    if (c.status == "kept") r->count += c.count, ++r->edge_apples;
    r->clusters.push_back(std::move(c));
  }
}

// Appends the apples glimpsed through the leaves (GlimpsedAppleOptions) to
// `r` as kept clusters of one apple each, after the kept clusters and edge
// apples, whose points explain the pieces of the apples they hold.
void AddGlimpsedApples(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                       const Plane& ground, const ClusterOptions& o, ClusterResult* r) {
  // A piece a counted cluster's point lies on is that cluster's apple; one a
  // next-row or fallen cluster's point lies on is that apple (the next
  // row's apples, seen through gaps in the leaves, are most of the pieces no
  // kept cluster holds). Pieces of clusters removed for weak evidence stay
  // free: they may be an apple glimpsed too rarely for a cluster.
  const std::vector<Eigen::Vector3d> explained =
      PointsOfClusters(*r, {"kept", "too_few_points", "covered", "next_row", "fallen"});
  const RowFrame row{r->row_origin, r->row_along, r->row_across, r->row_up, r->row_distance};
  if (row.row_distance <= 0) return;
  for (const GlimpsedApple& a : FindGlimpsedApples(views, frames, explained, row, r->depth_cutoff, o.glimpsed)) {
    FruitCluster c;
    c.id = static_cast<int>(r->clusters.size()) + 1;
    c.glimpsed = true;
    c.centre = a.centre;
    c.min = c.max = a.piece_points[0];
    for (size_t i = 0; i < a.pieces.size(); ++i) {
      const auto [f, id] = a.pieces[i];
      const Eigen::Vector3d& X = a.piece_points[i];
      AppendPoint({X, f, id, static_cast<int>(a.pieces.size())}, &c, r);
      c.views.push_back({f, frames[f].FindBlob(id)->pixels, 1});
      c.view_blobs.push_back({id});
    }
    // Its place along the line of sight is the sphere's depth, a guess: the
    // merge links it along the rays (as an edge apple) and the registrations
    // leave it out.
    for (const GlimpsedApple::SightRay& ray : a.rays) {
      c.edge_rays.emplace_back(ray.near, ray.far);
      c.edge_columns.push_back(ray.column);
    }
    c.count = c.count_by_pixels = c.count_by_count = MedianOfBestViews(c.views, o.best_views, &c.count_frames);
    c.height = ground.SignedDistance(c.centre);
    c.distance = a.distance;
    if (c.height < o.fallen_height) c.status = "fallen";
    if (c.distance > r->depth_cutoff) c.status = "next_row";
    if (c.status == "kept") r->count += c.count, ++r->glimpsed_apples;
    r->clusters.push_back(std::move(c));
  }
}

}  // namespace

ClusterResult CountFruitClusters(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                                 const Plane& ground, const ClusterOptions& o, std::vector<FruitPoint> points) {
  o.Check();
  if (views.size() != frames.size()) Fail("clusters: ", views.size(), " views but ", frames.size(), " frames");
  if (views.size() < 2) Fail("clusters: need at least two frames, got ", views.size());
  ClusterResult r;
  for (const auto& f : frames)
    for (int c : f.counts) r.single_frame_sum += c;
  r.points = std::move(points);
  r.triangulated_points = static_cast<int>(r.points.size());
  std::vector<Eigen::Vector3d> xyz;
  for (const auto& p : r.points) xyz.push_back(p.xyz);
  int k = 0;
  r.point_cluster = ConnectedComponents3D(xyz, o.link_distance, &k);
  // Point-on-blob votes of every frame: blob -> component -> points. A point
  // votes for the blob whose centre it is near, else for the blob under it
  // (ClusterOptions::vote_near_first).
  const int n = static_cast<int>(frames.size());
  std::vector<BlobVotes> votes(n);
  for (int f = 0; f < n; ++f) {
    const BlobCentres centres(frames[f]);
    for (size_t i = 0; i < xyz.size(); ++i) {
      Eigen::Vector2d p;
      bool inside = false;
      if (views[f].Depth(xyz[i]) < o.points.min_depth || !ProjectNearFrame(views[f], xyz[i], o.points, &p, &inside))
        continue;
      const int under = inside ? frames[f].labels(static_cast<int>(p.y()), static_cast<int>(p.x())) : 0;
      int id = under;
      if (o.vote_near_first) {
        id = centres.Near(views[f], xyz[i], o.points);
        if (id <= 0) id = under;
      } else if (id <= 0 && o.assign_near) {
        id = centres.Near(views[f], xyz[i], o.points);
      }
      if (id > 0) ++votes[f][id][r.point_cluster[i]];
    }
  }
  // Joins components (merged: each component's representative) and their votes.
  const auto join = [&](const std::vector<int>& merged) {
    std::vector<int> renumber(k, -1);  // keep ids numbered by first point
    int merged_k = 0;
    for (int& c : r.point_cluster) {
      if (renumber[merged[c]] < 0) renumber[merged[c]] = merged_k++;
      c = renumber[merged[c]];
    }
    for (auto& frame_votes : votes)
      for (auto& [blob, by_component] : frame_votes) {
        std::map<int, int> by_cluster;
        for (const auto& [c, points] : by_component) by_cluster[renumber[merged[c]]] += points;
        by_component = std::move(by_cluster);
      }
    k = merged_k;
  };
  if (o.merge_shared_fraction > 0) join(MergeSharedComponents(votes, k, o.merge_shared_fraction));
  // Clusters from the components (again after duplicates join).
  const auto build = [&]() {
    r.clusters.assign(k, FruitCluster());
    for (int c = 0; c < k; ++c) r.clusters[c].id = c + 1;
    for (size_t i = 0; i < xyz.size(); ++i) r.clusters[r.point_cluster[i]].points.push_back(static_cast<int>(i));
    for (auto& c : r.clusters) {
      c.min = c.max = xyz[c.points[0]];
      for (int i : c.points) {
        c.centre += xyz[i];
        c.min = c.min.cwiseMin(xyz[i]), c.max = c.max.cwiseMax(xyz[i]);
      }
      c.centre /= static_cast<double>(c.points.size());
    }
    // Each blob of each frame goes to the cluster with most points landing on
    // it; clusters below the minimum size do not vote.
    const auto votes_here = [&](int cluster) {
      return static_cast<int>(r.clusters[cluster].points.size()) >= o.min_points;
    };
    for (int f = 0; f < n; ++f) {
      std::map<int, size_t> view_of;  // cluster -> index in its views
      for (const auto& [blob, by_cluster] : votes[f]) {
        int best = -1, best_points = 0;  // the first cluster with most points (map order)
        for (const auto& [cluster, points] : by_cluster)
          if (votes_here(cluster) && points > best_points) best = cluster, best_points = points;
        if (best < 0) continue;
        for (const auto& [cluster, points] : by_cluster)
          if (votes_here(cluster))
            (cluster == best ? r.clusters[cluster].votes_won : r.clusters[cluster].votes_lost) += points;
        FruitCluster& c = r.clusters[best];
        if (!view_of.count(best)) {
          view_of[best] = c.views.size();
          c.views.push_back({f, 0, 0});
          c.view_blobs.emplace_back();
        }
        const size_t v = view_of[best];
        const Blob* b = frames[f].FindBlob(blob);
        c.views[v].pixels += b->pixels;
        c.apple_radius_seen =
            std::max(c.apple_radius_seen, EquivalentRadius(*b) * views[f].Depth(c.centre) / views[f].fx);
        c.views[v].count += frames[f].counts[blob - 1];
        c.view_blobs[v].push_back(blob);
      }
    }
  };
  build();
  if (o.duplicate_shared_fraction > 0) {
    std::vector<std::vector<int>> won_frames(k);
    std::vector<Eigen::Vector3d> centres(k);
    for (int c = 0; c < k; ++c) {
      for (const auto& v : r.clusters[c].views) won_frames[c].push_back(v.frame);
      centres[c] = r.clusters[c].centre;
    }
    const std::vector<int> merged =
        MergeDuplicateComponents(votes, won_frames, centres, o.duplicate_shared_fraction, o.duplicate_coview_fraction,
                                 o.duplicate_max_distance);
    for (int c = 0; c < k; ++c) r.duplicates_joined += merged[c] != c;
    if (r.duplicates_joined > 0) {
      join(merged);
      build();
    }
  }
  // A few per cent of a side's time, quadratic in a frame's points: only
  // for the rule, or for `--truth` to report (truth_clusters.csv).
  if (o.covered_max_points > 0 || o.find_covers) FindCoveringClusters(views, frames, xyz, o, &r);
  Eigen::Vector3d mean, along, across;
  PathAxes(views, ground, &mean, &along, &across);
  // Up is the ground normal on the cameras' side; along completes a
  // right-handed frame (along = across x up), whichever way the camera moved.
  r.row_up = ground.SignedDistance(mean) >= 0 ? ground.normal : Eigen::Vector3d(-ground.normal);
  r.row_across = across;
  r.row_along = across.cross(r.row_up).normalized();
  r.row_origin = mean - ground.normal * ground.SignedDistance(mean);
  std::vector<RowFruit> row_fruit;
  for (auto& c : r.clusters) {
    // Both rules' counts; the frames of the one the options chose.
    const bool by_count = o.best_views_by == ClusterOptions::BestViews::kCount;
    c.count_by_pixels = MedianOfBestViews(c.views, o.best_views, by_count ? nullptr : &c.count_frames, false);
    c.count_by_count = MedianOfBestViews(c.views, o.best_views, by_count ? &c.count_frames : nullptr, true);
    c.count = by_count ? c.count_by_count : c.count_by_pixels;
    c.height = ground.SignedDistance(c.centre);
    c.distance = across.dot(c.centre - mean);
    c.status = EvidenceStatus(c, o);
    if (c.status == "kept" && c.height < o.fallen_height) c.status = "fallen";
    if (c.status == "kept")
      row_fruit.push_back(
          {c.distance,
           static_cast<double>(std::max_element(c.views.begin(), c.views.end(), [](const auto& a, const auto& b) {
                                 return a.pixels < b.pixels;
                               })->pixels),
           static_cast<double>(c.count)});
  }
  r.row_distance = o.row_distance > 0
                       ? o.row_distance
                       : RowFruitDistance(row_fruit, o.next_row_gap, o.next_row_sparse, o.row_min_share,
                                          o.row_min_apple_share);
  std::vector<double> point_distances;
  for (const auto& c : r.clusters)
    if (c.status == "kept")
      for (int i : c.points) point_distances.push_back(across.dot(xyz[i] - mean));
  const std::optional<double> gap_cut =
      NextRowGapCut(point_distances, r.row_distance, o.next_row_gap, o.next_row_sparse);
  r.depth_cutoff_from_gap = gap_cut.has_value();
  r.depth_cutoff = gap_cut.value_or(r.row_distance + o.next_row_margin);
  for (auto& c : r.clusters) {
    if (c.status == "kept" && c.distance > r.depth_cutoff) c.status = "next_row";
    // Nothing grows between the camera and the row: clusters there are
    // chance pairings of different apples' blobs.
    if (c.status == "kept" && c.distance < r.row_distance - o.near_margin) c.status = "too_near";
  }
  // A few points that another kept cluster's points cover in most of their
  // views are that cluster's apple triangulated again.
  for (auto& c : r.clusters) {
    if (c.status == "kept" && c.cover_id > 0 && static_cast<int>(c.points.size()) <= o.covered_max_points &&
        c.cover_views >= o.covered_fraction * static_cast<double>(c.views.size()) &&
        c.cover_distance <= o.duplicate_max_distance && r.clusters[c.cover_id - 1].status == "kept")
      c.status = "covered";
  }
  for (const auto& c : r.clusters)
    if (c.status == "kept") r.count += c.count;
  if (o.edge.enabled) AddEdgeApples(views, frames, ground, o, &r);
  if (o.glimpsed.enabled) AddGlimpsedApples(views, frames, ground, o, &r);
  return r;
}

Plane ParseGroundPlane(const std::string& text) {
  Plane plane;
  if (fs::is_regular_file(text)) {
    try {
      const Json j = Json::parse(ReadTextFile(text));
      const Json& g = j.contains("ground_plane") ? j.at("ground_plane") : j;
      const auto n = g.at("normal").get<std::vector<double>>();
      if (n.size() != 3) Fail("ground plane normal in ", text, " must have 3 numbers");
      plane.normal = {n[0], n[1], n[2]};
      plane.d = g.at("d").get<double>();
    } catch (const Json::exception& e) {
      Fail("cannot read a ground plane {\"normal\": [nx, ny, nz], \"d\": d} from ", text, ": ", e.what());
    }
  } else {
    std::vector<double> v;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
      try {
        size_t used = 0;
        v.push_back(std::stod(item, &used));
        if (used != item.size()) v.clear();
      } catch (const std::exception&) {
        Fail("ground plane '", text, "' is neither a file nor four numbers nx,ny,nz,d");
      }
    }
    if (v.size() != 4) Fail("ground plane '", text, "' is neither a file nor four numbers nx,ny,nz,d");
    plane.normal = {v[0], v[1], v[2]};
    plane.d = v[3];
  }
  const double len = plane.normal.norm();
  if (!(len > 0)) Fail("ground plane normal must not be zero");
  plane.normal /= len, plane.d /= len;
  return plane;
}

void SideOptions::Check() const {
  frames.Check();
  colmap.Check();
  ground.Check();
  reconstruction_check.Check();
  clusters.Check();
  ORCHARD_CHECK_OPTION(camera_height > 0, "camera height must be positive, got ", camera_height);
  ORCHARD_CHECK_OPTION(draw_every >= 0, "draw every must be >= 0, got ", draw_every);
  ORCHARD_CHECK_OPTION(sparse_frames_from >= 1, "sparse frames from must be at least 1, got ", sparse_frames_from);
  ORCHARD_CHECK_OPTION(min_sparse_frame_scale > 0 && min_sparse_frame_scale <= 1,
                       "min sparse frame scale must be in (0, 1], got ", min_sparse_frame_scale);
  ORCHARD_CHECK_OPTION(max_refit_scale_change > 1, "max refit scale change must be > 1, got ",
                       max_refit_scale_change);
  if (one_side_clusters) one_side_clusters->Check();
}

bool RefitScaleIsPlausible(double scale, double refit_scale, const SideOptions& options) {
  if (!(scale > 0) || !(refit_scale > 0)) return false;
  const double change = refit_scale / scale;
  return change <= options.max_refit_scale_change && change >= 1 / options.max_refit_scale_change;
}

namespace {

// Frame-local blob ids 1..N (raster order of first pixel) from an instance
// mask, so nothing of the mask's own numbering carries across frames.
FruitFrame FruitFromInstanceMask(const cv::Mat& mask) {
  cv::Mat ids;
  mask.convertTo(ids, CV_32S);
  FruitFrame frame;
  frame.labels = cv::Mat1i::zeros(ids.size());
  std::map<int, int> local;
  struct Acc { double sx = 0, sy = 0; int n = 0, x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1; };
  std::vector<Acc> acc;
  for (int y = 0; y < ids.rows; ++y)
    for (int x = 0; x < ids.cols; ++x) {
      const int id = ids.at<int>(y, x);
      if (id == 0) continue;
      auto it = local.find(id);
      if (it == local.end()) it = local.emplace(id, static_cast<int>(local.size()) + 1).first, acc.emplace_back();
      frame.labels(y, x) = it->second;
      Acc& a = acc[it->second - 1];
      a.sx += x, a.sy += y, ++a.n;
      a.x0 = std::min(a.x0, x), a.y0 = std::min(a.y0, y), a.x1 = std::max(a.x1, x), a.y1 = std::max(a.y1, y);
    }
  for (size_t i = 0; i < acc.size(); ++i) {
    Blob b;
    b.id = static_cast<int>(i) + 1;
    b.pixels = acc[i].n;
    b.centroid = {acc[i].sx / acc[i].n, acc[i].sy / acc[i].n};
    b.box = Box{static_cast<double>(acc[i].x0), static_cast<double>(acc[i].y0), static_cast<double>(acc[i].x1 + 1),
                static_cast<double>(acc[i].y1 + 1)};
    frame.blobs.push_back(b);
  }
  return frame;
}

void CountBlobs(const cv::Mat& image, Counter* counter, FruitFrame* frame) {
  frame->counts.assign(frame->blobs.size(), 1);
  if (!counter) return;
  std::vector<cv::Mat> patches;
  std::vector<cv::Mat1b> fruit;
  for (const Blob& b : frame->blobs) {
    // The blob's own box, even for the CNN counter, whose training patches
    // (and `orchard count --blobs`) have a margin: on seed 11 the margin made
    // it count neighbours in the margin (side 255 of 229 visible, clusters
    // holding one apple counted 2-6 in 22 of 71) where the box gives 222.
    const cv::Rect rect(static_cast<int>(b.box.x1), static_cast<int>(b.box.y1),
                        static_cast<int>(b.box.x2 - b.box.x1), static_cast<int>(b.box.y2 - b.box.y1));
    patches.push_back(image(rect));
    fruit.push_back(frame->labels(rect) == b.id);
  }
  const std::vector<BlobCount> counts = counter->CountMany(patches, fruit);
  for (size_t i = 0; i < counts.size(); ++i) frame->counts[i] = counts[i].count;
}

// A frame's instance mask in `dir`: the one of the same name or, for frames
// SelectFrames wrote with padded numbers, the one whose name pads the same
// (the folder listed once, at the first frame that needs it).
class MaskFinder {
 public:
  explicit MaskFinder(fs::path dir) : dir_(std::move(dir)) {}
  fs::path Find(const std::string& stem) {
    const fs::path same = dir_ / (stem + ".png");
    if (fs::exists(same)) return same;
    if (!listed_) {
      for (const auto& p : ListImages(dir_)) by_padded_stem_.emplace(PadDigitRuns(p.stem().string()), p);
      listed_ = true;
    }
    const auto it = by_padded_stem_.find(PadDigitRuns(stem));
    return it == by_padded_stem_.end() ? same : it->second;
  }

 private:
  fs::path dir_;
  bool listed_ = false;
  std::map<std::string, fs::path> by_padded_stem_;  // the first in natural order
};

// Counts a frame's blobs and caches its detection and counts.
FruitFrame CountAndCache(const SideInputs& in, const cv::Mat& image, FruitFrame frame, const fs::path& cache_dir,
                         const std::string& stem) {
  CountBlobs(image, in.counter, &frame);
  cv::Mat1w ids;
  frame.labels.convertTo(ids, CV_16U);
  WriteImageAtomic(cache_dir / (stem + ".png"), ids);
  WriteTextFileAtomic(cache_dir / (stem + ".json"), Json{{"detector", in.detector_name}, {"counter", in.counter_name},
                                                         {"counts", frame.counts}}.dump() + "\n");
  return frame;
}

// Detections and counts of one frame, from the cache when it was made by the
// same detector and counter (recounted when only the counter differs); `masks`
// finds the instance masks without a detector.
FruitFrame FrameFruit(const SideInputs& in, const fs::path& image_path, const fs::path& cache_dir,
                      MaskFinder* masks) {
  const std::string stem = image_path.stem().string();
  const fs::path cache_png = cache_dir / (stem + ".png"), cache_json = cache_dir / (stem + ".json");
  if (fs::exists(cache_png) && fs::exists(cache_json)) {
    const Json j = Json::parse(ReadTextFile(cache_json), nullptr, false);
    if (!j.is_discarded() && j.value("detector", "") == in.detector_name) {
      FruitFrame frame = FruitFromInstanceMask(ReadImage(cache_png, cv::IMREAD_UNCHANGED));
      const auto counts = j.value("counts", std::vector<int>());
      const bool same_counter = j.value("counter", "") == in.counter_name;
      if (same_counter && counts.size() == frame.blobs.size()) {
        frame.counts = counts;
        return frame;
      }
      // Same detector, another counter: its blobs are counted again, not
      // detected again (detection is most of a side's time).
      if (!same_counter) return CountAndCache(in, ReadImage(image_path), std::move(frame), cache_dir, stem);
    }
  }
  const cv::Mat image = ReadImage(image_path);
  FruitFrame frame;
  if (in.detector) {
    const FrameDetection d = in.detector->Detect(image);
    frame = FruitFromInstanceMask(InstanceMask(d));
  } else {
    const fs::path mask_path = masks->Find(stem);
    if (!fs::exists(mask_path)) Fail("no instance mask for frame ", image_path.filename().string(), " (", mask_path.string(), ")");
    const cv::Mat mask = ReadImage(mask_path, cv::IMREAD_UNCHANGED);
    if (mask.size() != image.size() || mask.channels() != 1)
      Fail("instance mask ", mask_path.string(), " must be one channel of the frame's size");
    frame = FruitFromInstanceMask(mask);
  }
  return CountAndCache(in, image, std::move(frame), cache_dir, stem);
}

cv::Scalar ClusterColour(int id) {
  // Well-spread hues from the golden ratio.
  const double h = std::fmod(id * 0.618033988749895, 1.0) * 180;
  cv::Mat3b hsv(1, 1, cv::Vec3b(static_cast<uchar>(h), 220, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return cv::Scalar(bgr(0, 0)[0], bgr(0, 0)[1], bgr(0, 0)[2]);
}

void WriteOutputs(const fs::path& out, const std::vector<fs::path>& image_paths, const std::vector<FruitFrame>& frames,
                  const std::vector<CameraView>& views, const ClusterResult& r, const SideOptions& o) {
  std::ostringstream csv;
  csv << "id,x,y,z,extent_x,extent_y,extent_z,points,count,status,height,distance,frames,views,votes_won,votes_lost,"
         "apple_radius,count_by_pixels,count_by_count,edge,glimpsed\n";
  csv.precision(4);
  csv << std::fixed;
  for (const auto& c : r.clusters) {
    const Eigen::Vector3d e = c.max - c.min;
    csv << c.id << ',' << c.centre.x() << ',' << c.centre.y() << ',' << c.centre.z() << ',' << e.x() << ',' << e.y()
        << ',' << e.z() << ',' << c.points.size() << ',' << c.count << ',' << c.status << ',' << c.height << ','
        << c.distance << ',';
    for (size_t i = 0; i < c.count_frames.size(); ++i)
      csv << (i ? ";" : "") << image_paths[c.count_frames[i]].filename().string();
    csv << ',' << c.views.size() << ',' << c.votes_won << ',' << c.votes_lost << ',' << c.apple_radius_seen << ','
        << c.count_by_pixels << ',' << c.count_by_count << ',' << (c.edge ? 1 : 0) << ',' << (c.glimpsed ? 1 : 0)
        << '\n';
  }
  WriteTextFileAtomic(out / "clusters.csv", csv.str());
  // Edge apples' rays: written always, so none is left from an earlier run.
  std::ostringstream rays;
  rays << "cluster,frame,column,pixels,near_x,near_y,near_z,far_x,far_y,far_z\n";
  rays.precision(4);
  rays << std::fixed;
  for (const auto& c : r.clusters)
    for (size_t i = 0; i < c.edge_rays.size(); ++i) {
      const auto& [a, b] = c.edge_rays[i];
      rays << c.id << ',' << image_paths[c.views[i].frame].filename().string() << ',' << c.edge_columns[i] << ','
           << c.views[i].pixels << ',' << a.x() << ',' << a.y() << ',' << a.z() << ',' << b.x() << ',' << b.y() << ','
           << b.z() << '\n';
    }
  WriteTextFileAtomic(out / "edge_rays.csv", rays.str());
  // Camera centres of the frames used, in the fruit points' frame: the merge
  // follows a cluster's lines of sight from its count frames (clusters.csv
  // `frames`) to the other side's clusters.
  std::ostringstream cams;
  cams << "frame,x,y,z\n";
  cams.precision(4);
  cams << std::fixed;
  for (size_t i = 0; i < views.size(); ++i) {
    const Eigen::Vector3d c = views[i].Center();
    cams << image_paths[i].filename().string() << ',' << c.x() << ',' << c.y() << ',' << c.z() << '\n';
  }
  WriteTextFileAtomic(out / "cameras.csv", cams.str());
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex " << r.points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\nproperty int cluster\nend_header\n";
  for (size_t i = 0; i < r.points.size(); ++i) {
    const FruitCluster& c = r.clusters[r.point_cluster[i]];
    const cv::Scalar col = c.status == "kept" ? ClusterColour(c.id) : cv::Scalar(128, 128, 128);
    const Eigen::Vector3d& p = r.points[i].xyz;
    ply << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << static_cast<int>(col[2]) << ' ' << static_cast<int>(col[1])
        << ' ' << static_cast<int>(col[0]) << ' ' << c.id << '\n';
  }
  WriteTextFileAtomic(out / "fruit.ply", ply.str());
  if (o.draw_every <= 0) return;
  for (size_t f = 0; f < frames.size(); f += o.draw_every) {
    cv::Mat image = ReadImage(image_paths[f]);
    for (const auto& c : r.clusters) {
      for (size_t v = 0; v < c.views.size(); ++v) {
        if (c.views[v].frame != static_cast<int>(f)) continue;
        const bool kept = c.status == "kept";
        const cv::Scalar col = kept ? ClusterColour(c.id) : cv::Scalar(160, 160, 160);
        cv::Mat1b region = cv::Mat1b::zeros(image.size());
        for (int id : c.view_blobs[v]) region.setTo(255, frames[f].labels == id);
        std::vector<std::vector<cv::Point>> contours;
        cv::findContours(region, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
        cv::drawContours(image, contours, -1, col, 2);
        const cv::Rect box = cv::boundingRect(region);
        // One letter per reason (few_views would clash with fallen).
        const std::string label =
            kept ? std::to_string(c.count) : c.status == "few_views" ? "v" : c.status.substr(0, 1);
        cv::putText(image, label, {box.x, std::max(12, box.y - 3)}, cv::FONT_HERSHEY_SIMPLEX, 0.5, col, 2);
      }
    }
    WriteImageAtomic(out / "annotated" / (image_paths[f].stem().string() + ".jpg"), image);
  }
}

// A pose model made metric: its ground plane (fitted, or given) and the
// scale from the camera height, with the check of the camera path.
struct MetricPoses {
  std::vector<CameraView> model_views, views;  // in the model's frame; in metres
  std::vector<Eigen::Vector3d> pts, centres;   // sparse points and cameras, model frame
  Plane ground;                                // in metres
  std::string ground_source;
  double scale = 1;
  ReconstructionCheck check;
};

// `plane` (model frame) and `model_views` scaled to metres by the camera
// height over the plane, or kept when `rescale` is false.
Plane ScaledToMetres(Plane plane, const std::vector<CameraView>& model_views, bool rescale, double camera_height,
                     std::vector<CameraView>* scaled, double* s) {
  *scaled = model_views;
  *s = rescale ? ScaleFromCameraHeight(plane, *scaled, camera_height) : 1;
  ScaleViews(*s, scaled);
  plane.d *= *s;
  return plane;
}

MetricPoses MakeMetric(const ColmapModel& model, const SideInputs& in, const SideOptions& o, bool rescale) {
  MetricPoses m;
  m.model_views = ViewsFromColmapModel(model);
  if (static_cast<int>(m.model_views.size()) < o.colmap.min_registered)
    Fail("only ", m.model_views.size(), " frames have poses (need ", o.colmap.min_registered, ")");
  Plane ground;
  if (in.ground) {
    ground = *in.ground;
    m.ground_source = "given";
  } else {
    for (const auto& [id, p] : model.points3D) m.pts.push_back(p.xyz);
    for (const auto& v : m.model_views) m.centres.push_back(v.Center());
    if (static_cast<int>(m.pts.size()) < o.ground.min_inliers)
      Fail("the pose model has ", m.pts.size(), " 3D points, too few to fit the ground plane: give the ground plane (orchard side --ground-plane)");
    int inliers = 0;
    ground = FitGroundPlane(m.pts, m.centres, MeanCameraUp(m.model_views), o.ground, &inliers);
    m.ground_source = "fitted to " + std::to_string(inliers) + " of " + std::to_string(m.pts.size()) + " sparse points";
  }
  m.ground = ScaledToMetres(ground, m.model_views, rescale, o.camera_height, &m.views, &m.scale);
  m.check = CheckReconstruction(m.views, m.ground, &model, o.reconstruction_check);
  return m;
}

// Given poses usually carry no points (GNSS/IMU, the generator's): COLMAP
// triangulates them with the poses held (TriangulateColmapPoints), for the
// ground fit, the reconstruction check and the row's trunks. Cached in
// out/sparse with the given model's text as the key (given.txt; frames.txt
// marks the mapper's own models). Without colmap, or with
// o.triangulate_given_poses off, the model stays as given and out/sparse is
// removed, so that no earlier run's points pass for these poses'.
ColmapModel WithSparsePoints(ColmapModel model, const fs::path& image_dir, const SideInputs& in, const SideOptions& o) {
  const fs::path sparse = in.out / "sparse";
  bool triangulate = model.points3D.empty() && o.triangulate_given_poses;
  if (triangulate && !ColmapAvailable(o.colmap.colmap)) {
    spdlog::warn("the given poses carry no 3D points and colmap cannot be run to triangulate them: no trunks, "
                 "and the ground plane must be given");
    triangulate = false;
  }
  if (!triangulate) {
    fs::remove_all(sparse);
    return model;
  }
  const std::string key = ColmapCamerasText(model.cameras) + ColmapImagesText(model.images);
  if (fs::exists(sparse / "given.txt") && ReadTextFile(sparse / "given.txt") == key) {
    spdlog::info("reusing the points triangulated for the given poses in {}", sparse.string());
    return ReadColmapTextModel(sparse);  // the given poses, written with 17 digits
  }
  fs::remove_all(sparse);
  ColmapModel triangulated = TriangulateColmapPoints(image_dir, model, in.out / "colmap", o.colmap);
  WriteColmapTextModel(triangulated, sparse);
  WriteTextFileAtomic(sparse / "given.txt", key);
  return triangulated;
}

// COLMAP on the selected frames: features and matches once, then the mapper
// with seeds random_seed, random_seed + 1, ... while its model has warnings
// or leaves too many frames out (BestAttempt). Each attempt is described in
// `attempts` (seed, frames registered, warnings or the error).
ColmapModel ReconstructSide(const fs::path& image_dir, const SideInputs& in, const SideOptions& o, Json* attempts) {
  const fs::path workspace = in.out / "colmap";
  MatchColmapFeatures(image_dir, workspace, o.colmap);
  std::map<int, ColmapModel> models;
  *attempts = Json::array();
  const int best = BestAttempt(
      [&](int k) {
        ColmapRunnerOptions c = o.colmap;
        c.random_seed += k;
        if (k > 0) spdlog::info("running COLMAP's mapper again, with seed {}", c.random_seed);
        Json a = {{"seed", c.random_seed}};
        try {
          ColmapRunResult run = MapColmap(image_dir, workspace, c);
          const MetricPoses m = MakeMetric(run.model, in, o, true);
          a["registered"] = run.model.images.size();
          a["warnings"] = m.check.warnings;
          attempts->push_back(a);
          models[k] = std::move(run.model);
          const int left_out = static_cast<int>(run.unregistered.size());
          if (m.check.warnings.empty() && left_out <= o.colmap.retry_unregistered_fraction * run.num_input_images)
            return 0;  // good enough: no further run
          // A warning weighs more than every frame left out.
          return static_cast<int>(m.check.warnings.size()) * (run.num_input_images + 1) + left_out;
        } catch (const Error& e) {
          a["error"] = e.what();
          attempts->push_back(a);
          throw;
        }
      },
      o.colmap.mapper_attempts);
  for (auto& a : *attempts) a["kept"] = a.at("seed").get<int>() == o.colmap.random_seed + best;
  if (attempts->size() > 1)
    spdlog::info("kept COLMAP's model of seed {} ({} mapper runs)", o.colmap.random_seed + best, attempts->size());
  return std::move(models.at(best));
}

// Each scored cluster's part in the breakdown, one row per kept cluster of
// `result`: for a duplicate, the cluster that holds its apple and how far
// apart the two lie (where the next rule against duplicates has to look).
void WriteTruthClusters(const fs::path& path, const ClusterResult& result, const SideTruthScore& t) {
  std::map<int, const FruitCluster*> holder;  // apple -> the cluster credited with it
  for (const ClusterTruth& c : t.clusters)
    for (const int apple : c.credited) holder[apple] = &result.clusters[c.cluster];
  std::ostringstream csv;
  csv << "id,x,y,z,count,points,views,votes_won,role,credited,top_apple,top_votes,holder,holder_distance,cover_id,"
         "cover_views,cover_distance\n";
  csv.precision(4);
  csv << std::fixed;
  for (const ClusterTruth& c : t.clusters) {
    const FruitCluster& cluster = result.clusters[c.cluster];
    csv << cluster.id << ',' << cluster.centre.x() << ',' << cluster.centre.y() << ',' << cluster.centre.z() << ','
        << cluster.count << ',' << cluster.points.size() << ',' << cluster.views.size() << ',' << cluster.votes_won
        << ',' << c.role << ',';
    for (size_t i = 0; i < c.credited.size(); ++i) csv << (i ? ";" : "") << c.credited[i];
    csv << ',' << c.top_apple << ',' << c.top_votes << ',';
    const auto h = c.role == "duplicate" ? holder.find(c.top_apple) : holder.end();
    if (h != holder.end())
      csv << h->second->id << ',' << (h->second->centre - cluster.centre).norm();
    else
      csv << ',';
    csv << ',' << cluster.cover_id << ',' << cluster.cover_views << ',' << cluster.cover_distance;
    csv << '\n';
  }
  WriteTextFileAtomic(path, csv.str());
}

// side.json's frames_reach (also copied into yield.json's sides); side.json
// leaves it out when no frame's edge reaches the row.
Json FrameReachJson(const FrameReach& reach, double row_distance) {
  return {{"top_m", reach.top}, {"bottom_m", reach.bottom}, {"at_distance_m", row_distance}, {"views", reach.views},
          {"note", "heights above the ground where the frames' top and bottom edges meet the row (medians over the "
                   "frames): apples above top_m are in no frame and not counted"}};
}

// The side's kept clusters scored against the generator's truth in `truth`
// (S/front or S/back), for side.json (logged in one line) and
// OUT/truth_clusters.csv; the clusters kept for the merge (`merge`, the same
// as `result` when the side has one set of rules) also, for `orchard yield`
// to take the merged count apart: OUT/truth_merge_clusters.json, each
// cluster id (clusters.csv) with the apples it was credited with and its
// points' votes (the merge credits again with the counts it uses).
Json ScoreAgainstTruth(const fs::path& truth, const std::vector<CameraView>& views, const ClusterResult& result,
                       const ClusterResult& merge, const fs::path& out) {
  const std::set<int> visible = ReadSideVisibleApples(truth);
  const fs::path masks_dir = truth / "masks";
  MaskFinder finder(masks_dir);
  std::vector<cv::Mat> masks;
  for (const auto& v : views) {
    const fs::path path = finder.Find(fs::path(v.name).stem().string());
    if (!fs::exists(path)) Fail("truth: no mask for frame ", v.name, " in ", masks_dir.string());
    masks.push_back(ReadImage(path, cv::IMREAD_UNCHANGED));
  }
  const SideTruthScore t = ScoreSideAgainstTruth(views, masks, visible, result);
  WriteTruthClusters(out / "truth_clusters.csv", result, t);
  {
    const SideTruthScore m = &merge == &result ? t : ScoreSideAgainstTruth(views, masks, visible, merge);
    Json credited = Json::object(), role = Json::object(), top_apple = Json::object(), votes = Json::object();
    for (const ClusterTruth& c : m.clusters) {
      const std::string id = std::to_string(merge.clusters[c.cluster].id);
      credited[id] = c.credited, role[id] = c.role, top_apple[id] = c.top_apple;
      // Apple ids as keys: JSON's keys are strings.
      Json v = Json::object();
      for (const auto& [apple, n] : c.votes) v[std::to_string(apple)] = n;
      votes[id] = v;
    }
    WriteTextFileAtomic(out / "truth_merge_clusters.json",
                        Json{{"credited", credited}, {"role", role}, {"top_apple", top_apple}, {"votes", votes},
                             {"min_votes", TruthScoreOptions().min_votes}, {"found", m.found},
                             {"duplicates", m.duplicates},
                             {"over_counted", m.over_counted}, {"not_visible", m.not_visible}}.dump() + "\n");
  }
  const int glimpsed = t.visible_by_views_seen[0] + t.visible_by_views_seen[1] + t.visible_by_views_seen[2];
  const int glimpsed_missed = t.missed_by_views_seen[0] + t.missed_by_views_seen[1] + t.missed_by_views_seen[2];
  spdlog::info("truth: {} counted for {} visible ({:+.1f}%): {} found, {} missed ({} of the {} seen in at most two "
               "views); {} counted twice, {} above a cluster's apples, {} on no visible apple",
               t.count, t.visible, t.visible ? 100.0 * (t.count - t.visible) / t.visible : 0.0, t.found, t.missed,
               glimpsed_missed, glimpsed, t.duplicates, t.over_counted, t.not_visible);
  // masks_dir is S/front/masks (or S/back/masks), whatever separator `truth` ended in.
  return Json{{"apples", (masks_dir.parent_path().parent_path() / "apples.csv").string()}, {"visible", t.visible}, {"count", t.count},
              {"found", t.found}, {"missed", t.missed}, {"missed_without_points", t.missed_without_points},
              {"missed_ids", t.missed_ids}, {"visible_by_views_seen", t.visible_by_views_seen},
              {"missed_by_views_seen", t.missed_by_views_seen}, {"duplicates", t.duplicates},
              {"over_counted", t.over_counted}, {"not_visible", t.not_visible}};
}

}  // namespace

SideSummary RunSide(const SideInputs& in, const SideOptions& o) {
  o.Check();
  if (in.out.empty()) Fail("no output folder");
  if (!fs::exists(in.input)) Fail("input ", in.input.string(), " does not exist");
  if (!in.detector && in.masks.empty()) Fail("give a detector or a folder of instance masks");
  if (!in.detector && !fs::is_directory(in.masks)) Fail("masks folder ", in.masks.string(), " does not exist");
  if (!in.truth.empty()) ReadSideVisibleApples(in.truth);  // a wrong folder fails now, not after the count
  fs::create_directories(in.out);
  Stopwatch stopwatch;
  SideSummary s;
  // Frames and poses.
  ColmapModel model;
  std::vector<std::string> unregistered;
  fs::path image_dir;
  int num_frames = 0;
  bool rescale = o.rescale_given_poses;
  Json mapper_attempts;  // COLMAP's mapper runs (ReconstructSide); null with given poses
  std::string sparse_from = "COLMAP's mapper";  // where the model's 3D points come from (side.json)
  if (!in.poses.empty()) {
    model = ReadColmapModel(in.poses);
    if (fs::is_directory(in.input)) {
      image_dir = in.input;
    } else {
      image_dir = in.out / "frames";
      SelectFrames(in.input, FrameSelectionOptions{}, image_dir);
    }
    if (o.frames.method == "motion") spdlog::warn("frame selection by motion is not applied to given poses; use --step");
    std::set<std::string> names, skipped;
    const std::vector<fs::path> listed = ListImages(image_dir);
    // --step thins given poses too (frames denser than the 3D stage is tuned
    // to count high; CheckFrameSpacing): every step-th frame in name order.
    for (size_t i = 0; i < listed.size(); ++i)
      (i % o.frames.step == 0 ? names : skipped).insert(listed[i].filename().string());
    num_frames = static_cast<int>(names.size());
    for (const auto& [id, image] : model.images)
      if (!names.count(image.name) && !skipped.count(image.name))
        Fail("pose model ", in.poses.string(), " names frame ", image.name, ", which is not in ", image_dir.string());
    for (auto it = model.images.begin(); it != model.images.end();)
      it = skipped.count(it->second.name) ? model.images.erase(it) : std::next(it);
    std::set<std::string> posed;
    for (const auto& [id, image] : model.images) posed.insert(image.name);
    for (const auto& n : names)
      if (!posed.count(n)) unregistered.push_back(n);
    const bool came_with_points = !model.points3D.empty();
    model = WithSparsePoints(std::move(model), image_dir, in, o);
    sparse_from = came_with_points ? "given with the poses"
                  : model.points3D.empty() ? "none" : "triangulated by COLMAP for the given poses";
  } else {
    rescale = true;
    image_dir = in.out / "frames";
    const std::vector<std::string> names = SelectFrames(in.input, o.frames, image_dir);
    num_frames = static_cast<int>(names.size());
    // Remove frames of an earlier selection that this one does not keep.
    const std::set<std::string> keep(names.begin(), names.end());
    for (const auto& p : ListImages(image_dir))
      if (!keep.count(p.filename().string())) fs::remove(p);
    std::ostringstream list;
    for (const auto& n : names) list << n << '\n';
    const fs::path sparse = in.out / "sparse";
    if (fs::exists(sparse / "frames.txt") && ReadTextFile(sparse / "frames.txt") == list.str()) {
      spdlog::info("reusing the reconstruction in {}", sparse.string());
      model = ReadColmapTextModel(sparse);
    } else {
      model = ReconstructSide(image_dir, in, o, &mapper_attempts);
      fs::remove_all(sparse);  // given.txt of a run on given poses would take this model for theirs
      WriteColmapTextModel(model, sparse);
      WriteTextFileAtomic(sparse / "mapper_attempts.json", mapper_attempts.dump(2) + "\n");
      WriteTextFileAtomic(sparse / "frames.txt", list.str());
    }
    if (mapper_attempts.is_null() && fs::exists(sparse / "mapper_attempts.json"))
      mapper_attempts = Json::parse(ReadTextFile(sparse / "mapper_attempts.json"), nullptr, false);
    std::set<std::string> posed;
    for (const auto& [id, image] : model.images) posed.insert(image.name);
    for (const auto& n : names)
      if (!posed.count(n)) unregistered.push_back(n);
  }
  MetricPoses metric = MakeMetric(model, in, o, rescale);
  if (!unregistered.empty())
    spdlog::warn("{} of {} frames have no pose and are left out", unregistered.size(), num_frames);
  std::vector<CameraView> views = metric.views;
  std::vector<CameraView> model_views = metric.model_views;
  const std::vector<Eigen::Vector3d>& pts = metric.pts;
  const std::vector<Eigen::Vector3d>& centres = metric.centres;
  Plane ground = metric.ground;
  std::string ground_source = metric.ground_source;
  double scale = metric.scale;
  ReconstructionCheck check = std::move(metric.check);
  for (const auto& w : check.warnings) spdlog::warn("reconstruction: {}", w);
  s.poses_s = stopwatch.Lap();
  // Fruit per frame (cached).
  std::vector<fs::path> image_paths;
  std::vector<FruitFrame> frames;
  MaskFinder masks(in.masks);
  for (const auto& v : views) {
    image_paths.push_back(image_dir / v.name);
    frames.push_back(FrameFruit(in, image_paths.back(), in.out / "detections", &masks));
    if (o.split_counted_blobs) SplitCountedBlobs(&frames.back());
    if (o.fit_apple_circles) FitAppleCentres(&frames.back());
    if (frames.back().labels.cols != v.width || frames.back().labels.rows != v.height)
      Fail("frame ", v.name, " is ", frames.back().labels.cols, "x", frames.back().labels.rows, ", its camera ",
           v.width, "x", v.height);
    if (frames.size() % 20 == 0) spdlog::info("fruit in {} of {} frames", frames.size(), views.size());
  }
  s.fruit_s = stopwatch.Lap();
  // Every rule set of this side is scaled alike: by the frame_scale given,
  // and by k more when dense frames are all counted or sparse ones scaled
  // (below).
  double frame_scale = o.clusters.frame_scale;
  const auto resolved = [&in, &frame_scale](ClusterOptions c) {
    c.frame_scale = frame_scale;
    c = ScaledToFrameDensity(c);
    c.best_views_by = ResolvedBestViews(c, in);
    c.edge.min_pixels = ResolvedEdgeMinPixels(c, in);
    c.min_apple_fraction = ResolvedMinAppleFraction(c, in);
    c.glimpsed.enabled = ResolvedGlimpsedApples(c, in);
    c.find_covers = c.find_covers || !in.truth.empty();
    return c;
  };
  ClusterOptions clusters = resolved(o.clusters);
  ClusterResult r = CountFruitClusters(views, frames, ground, clusters);
  // Frames much denser than the 3D stage is tuned to count high
  // (CheckFrameSpacing): the side is counted again with its frame counts k
  // times larger, or on every k-th frame; much sparser ones count low, and
  // are counted again with them smaller. The spacing needs the row
  // distance, which only the clusters give.
  int thinned_every = 1;
  // Frame counts k times larger are tuned to frames k times denser.
  const auto spacing_check = [&o, &frame_scale] {
    ReconstructionCheckOptions rc = o.reconstruction_check;
    rc.frame_spacing_reference /= frame_scale;
    return rc;
  };
  const ReconstructionCheckOptions rc = spacing_check();
  // How many times denser than the tuned spacing the frames are (0: unknown).
  const double density = r.row_distance > 0 && check.median_step > 0
                             ? rc.frame_spacing_reference * r.row_distance / check.median_step
                             : 0;
  double frame_rescale = 1;  // the frame counts' further factor
  if (o.dense_frames != DenseFrames::kAll && density * rc.min_frame_spacing > 1) {
    const int k = std::max(2, static_cast<int>(std::lround(density)));
    if (o.dense_frames == DenseFrames::kScale) {
      frame_rescale = k;
    } else {
      thinned_every = k;
      const auto every_kth = [k](auto* v) {
        size_t kept = 0;
        for (size_t i = 0; i < v->size(); i += k, ++kept)
          if (i != kept) (*v)[kept] = std::move((*v)[i]);  // never onto itself: a self-move empties a vector
        v->resize(kept);
      };
      every_kth(&views), every_kth(&model_views), every_kth(&frames), every_kth(&image_paths);
      if (static_cast<int>(views.size()) < o.colmap.min_registered)
        Fail("only ", views.size(), " frames left after keeping every ", k,
             "-th of frames too dense for the 3D stage (need ", o.colmap.min_registered, ")");
      spdlog::info("frames {:.1f} cm apart at {:.2f} m from the fruit: every {}-th used ({} frames)",
                   100 * check.median_step, r.row_distance, k, views.size());
      check = CheckReconstruction(views, ground, &model, o.reconstruction_check);
    }
  } else if (o.sparse_frames == SparseFrames::kScale && density > 0 && density * o.sparse_frames_from < 1) {
    frame_rescale = std::max(o.min_sparse_frame_scale, density);  // too sparse to thin: the frame counts shrink
  }
  if (frame_rescale != 1) {
    frame_scale *= frame_rescale;
    clusters = resolved(o.clusters);
    spdlog::info("frames {:.1f} cm apart at {:.2f} m from the fruit: all {} used, the 3D stage's frame counts {:.2g} "
                 "times as large",
                 100 * check.median_step, r.row_distance, views.size(), frame_scale);
  }
  if (frame_rescale != 1 || thinned_every != 1) r = CountFruitClusters(views, frames, ground, clusters);
  const auto fruit_of = [](const ClusterResult& result) {
    std::vector<Eigen::Vector3d> fruit;
    for (int i = 0; i < result.triangulated_points; ++i) fruit.push_back(result.points[i].xyz);
    return fruit;
  };
  size_t logged = check.warnings.size();  // the path's, logged above
  std::vector<Eigen::Vector3d> fruit = fruit_of(r);
  CheckFruitAboveGround(fruit, ground, o.reconstruction_check, &check);
  if (check.fruit_below_ground > o.reconstruction_check.max_fruit_below_ground && !in.ground &&
      o.refit_ground_below_fruit) {
    for (auto& X : fruit) X /= scale;  // back to the model's frame
    int inliers = 0;
    std::optional<Plane> refit;
    try {
      refit = FitGroundPlane(pts, centres, MeanCameraUp(model_views), o.ground, &inliers, &fruit, 1.0);
    } catch (const Error& e) {  // no plane below the fruit has enough ground points: keep the first fit
      spdlog::warn("reconstruction: no ground plane below the fruit ({})", e.what());
    }
    if (refit) {
      std::vector<CameraView> refit_views;
      double refit_scale = 1;
      const Plane refit_ground =
          ScaledToMetres(*refit, model_views, rescale, o.camera_height, &refit_views, &refit_scale);
      if (!RefitScaleIsPlausible(scale, refit_scale, o)) {  // not counted again: it would not be kept
        char note[240];
        std::snprintf(note, sizeof note,
                      "a ground plane fitted again below the fruit would change the scale %.3g -> %.3g, more than "
                      "%.3gx: the first fit is kept (the reconstruction itself is likely broken)",
                      scale, refit_scale, o.max_refit_scale_change);
        check.warnings.push_back(note);
      } else {
        ClusterResult refit_r = CountFruitClusters(refit_views, frames, refit_ground, clusters);
        ReconstructionCheck refit_check =
            CheckReconstruction(refit_views, refit_ground, &model, o.reconstruction_check);
        CheckFruitAboveGround(fruit_of(refit_r), refit_ground, o.reconstruction_check, &refit_check);
        if (refit_check.fruit_below_ground < check.fruit_below_ground) {
          char note[200];
          std::snprintf(note, sizeof note,
                        "the ground plane was fitted again below the fruit (%.0f%% of the fruit points lay below the "
                        "first fit; scale %.3g -> %.3g)",
                        100 * check.fruit_below_ground, scale, refit_scale);
          refit_check.warnings.insert(refit_check.warnings.begin(), note);
          ground = refit_ground, views = refit_views, scale = refit_scale, r = std::move(refit_r);
          check = std::move(refit_check);
          logged = 0;
          ground_source = "fitted again to " + std::to_string(inliers) + " of " + std::to_string(pts.size()) +
                          " sparse points, below the fruit";
        }
      }
    }
  }
  // Single apples before the size filter too, so a scale too small (every
  // apple filtered as small) still shows.
  std::vector<double> single_apple_radii;
  for (const auto& c : r.clusters)
    if (!c.edge && c.count == 1 && (c.status == "kept" || c.status == "small"))
      single_apple_radii.push_back(c.apple_radius_seen);
  CheckAppleSize(std::move(single_apple_radii), clusters.points.apple_radius, o.reconstruction_check, &check);
  CheckFrameSpacing(r.row_distance, spacing_check(), &check);
  for (size_t i = logged; i < check.warnings.size(); ++i) spdlog::warn("reconstruction: {}", check.warnings[i]);
  s.one_side_count = r.count;
  std::optional<ClusterResult> one_side_result;
  if (o.one_side_clusters) {
    // One row, one distance: found on the clusters above, not again on the
    // other rules' (their densest band moved 25-75 cm on 4 of 186 sides).
    ClusterOptions one_side = resolved(*o.one_side_clusters);
    if (one_side.row_distance <= 0) one_side.row_distance = r.row_distance;
    // The triangulated points only: the edge apples are found again under these rules.
    one_side_result = CountFruitClusters(
        views, frames, ground, one_side,
        std::vector<FruitPoint>(r.points.begin(), r.points.begin() + r.triangulated_points));
    s.one_side_count = one_side_result->count;
  }
  Json truth_json;
  if (!in.truth.empty())
    truth_json = ScoreAgainstTruth(in.truth, views, one_side_result ? *one_side_result : r, r, in.out);
  s.clusters_s = stopwatch.Lap();
  WriteOutputs(in.out, image_paths, frames, views, r, o);
  s.outputs_s = stopwatch.Lap();
  s.count = r.count;
  s.single_frame_sum = r.single_frame_sum;
  s.frames_used = static_cast<int>(views.size());
  s.frames_registered = static_cast<int>(metric.model_views.size());
  s.poses = in.poses.empty() ? "COLMAP" : "given (" + in.poses.string() + ")";
  if (mapper_attempts.is_array() && mapper_attempts.size() > 1) {
    int kept_seed = -1;
    for (const auto& a : mapper_attempts)
      if (a.value("kept", false)) kept_seed = a.at("seed").get<int>();
    s.poses += ", its mapper run " + std::to_string(mapper_attempts.size()) + " times (the first model " +
               (mapper_attempts.front().contains("error") ? "failed" : "had warnings or left frames out") +
               (kept_seed >= 0 ? "; seed " + std::to_string(kept_seed) + " kept)" : ")");
  }
  s.frame_paths = image_paths;
  if (r.row_distance > 0) s.frames_reach = FramesReachAt(views, ground, r.row_origin, r.row_across, r.row_distance);
  std::map<std::string, int> removed;
  for (const auto& c : r.clusters) {
    if (c.status == "kept")
      ++s.clusters_kept;
    else
      ++s.clusters_removed, ++removed[c.status];
  }
  Json warnings = Json::array();
  if (!unregistered.empty())
    warnings.push_back(std::to_string(unregistered.size()) + " of " + std::to_string(num_frames) +
                       " frames have no pose and are left out");
  for (const auto& w : check.warnings) warnings.push_back("reconstruction: " + w);
  if (s.clusters_kept == 0) warnings.push_back("no fruit cluster kept: the count is not meaningful");
  for (const auto& w : warnings) s.warnings.push_back(w.get<std::string>());
  Json j = {
      {"count", s.count},
      {"one_side_count", s.one_side_count},
      {"single_frame_sum", s.single_frame_sum},
      {"frames", {{"input", num_frames}, {"registered", s.frames_registered}, {"used", s.frames_used},
                  {"every", thinned_every}, {"frame_scale", frame_scale},
                  {"unregistered", unregistered}}},
      {"poses", in.poses.empty() ? "colmap" : in.poses.string()},
      {"mapper_attempts", mapper_attempts},
      {"sparse_points", {{"count", model.points3D.size()}, {"from", sparse_from}}},
      {"detector", in.detector_name},
      {"counter", in.counter_name},
      {"best_views_by", BestViewsName(clusters.best_views_by)},
      {"min_apple_fraction", clusters.min_apple_fraction},
      {"covered_max_points", clusters.covered_max_points},
      {"scale", scale},
      {"ground_plane", {{"normal", {ground.normal.x(), ground.normal.y(), ground.normal.z()}}, {"d", ground.d},
                        {"source", ground_source}}},
      {"row_frame", {{"origin", {r.row_origin.x(), r.row_origin.y(), r.row_origin.z()}},
                     {"along", {r.row_along.x(), r.row_along.y(), r.row_along.z()}},
                     {"across", {r.row_across.x(), r.row_across.y(), r.row_across.z()}},
                     {"up", {r.row_up.x(), r.row_up.y(), r.row_up.z()}}}},
      {"reconstruction", {{"path_length", check.path_length}, {"path_extent", check.path_extent},
                          {"median_step", check.median_step}, {"max_step_ratio", check.max_step_ratio},
                          {"backward_steps", check.backward_steps}, {"bend", check.bend},
                          {"height_median", check.height_median}, {"height_spread", check.height_spread},
                          {"view_angle_deg", check.view_angle_deg},
                          {"reprojection_error_px", check.reprojection_error_px},
                          {"fruit_below_ground", check.fruit_below_ground},
                          {"apple_radius", check.apple_radius},
                          {"single_apples", check.single_apples},
                          {"frame_spacing", check.frame_spacing}}},
      {"row_distance", r.row_distance},
      {"depth_cutoff", r.depth_cutoff},
      {"depth_cutoff_from", r.depth_cutoff_from_gap ? "gap" : "margin"},
      {"fruit_points", r.triangulated_points},
      {"clusters", {{"total", r.clusters.size()}, {"kept", s.clusters_kept}, {"removed", removed},
                    {"duplicates_joined", r.duplicates_joined}, {"edge_apples", r.edge_apples},
                    {"glimpsed_apples", r.glimpsed_apples}}},
      {"warnings", warnings},
      {"timings_s", {{"poses", s.poses_s}, {"fruit", s.fruit_s}, {"clusters", s.clusters_s}, {"outputs", s.outputs_s}}},
  };
  if (s.frames_reach.views > 0) j["frames_reach"] = FrameReachJson(s.frames_reach, r.row_distance);
  if (!truth_json.is_null()) j["truth"] = truth_json;
  WriteTextFileAtomic(in.out / "side.json", j.dump(2) + "\n");
  if (s.frames_reach.views > 0)
    spdlog::info("the frames reach {:.2f}-{:.2f} m above the ground at the row ({:.2f} m across); apples above are not "
                 "counted", s.frames_reach.bottom, s.frames_reach.top, r.row_distance);
  spdlog::info("{} apples in {} clusters ({} removed); single-frame sum {}", s.count, s.clusters_kept,
               s.clusters_removed, s.single_frame_sum);
  return s;
}

}  // namespace orchard
