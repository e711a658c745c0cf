#include "orchard/fruitmap/glimpsed_apples.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {

void GlimpsedAppleOptions::Check() const {
  ORCHARD_CHECK_OPTION(min_pixels >= 1, "glimpse min pixels must be at least 1, got ", min_pixels);
  ORCHARD_CHECK_OPTION(apple_radius > 0 && explain_radius > 0, "glimpse radii must be positive, got ", apple_radius,
                       " and ", explain_radius);
  ORCHARD_CHECK_OPTION(window >= 1, "glimpse window must be at least 1 frame, got ", window);
  ORCHARD_CHECK_OPTION(min_support >= 2, "glimpse min support must be at least 2, got ", min_support);
  ORCHARD_CHECK_OPTION(min_support_ratio > 0 && min_support_ratio <= 1,
                       "glimpse min support ratio must be in (0, 1], got ", min_support_ratio);
  ORCHARD_CHECK_OPTION(depth_step > 0 && offset_step > 0, "glimpse steps must be positive, got ", depth_step, " and ",
                       offset_step);
  ORCHARD_CHECK_OPTION(near_margin >= 0 && far_search >= 0, "glimpse search margins must be >= 0, got ", near_margin,
                       " and ", far_search);
  ORCHARD_CHECK_OPTION(min_extent >= 0, "glimpse min extent must be >= 0, got ", min_extent);
  ORCHARD_CHECK_OPTION(ray_margin > 0, "glimpse ray margin must be positive, got ", ray_margin);
}

namespace {

// A free piece: its centroid (COLMAP pixels), the radius of the disc of its
// area, and its blob.
struct Piece {
  Eigen::Vector2d centre;
  double radius = 0;
  int id = 0;
  double extent = 0;  // its longest chord (pixels)
};

// The longest distance across a blob (pixels, between its pixels' outer
// corners): how wide a piece is whichever way it lies.
double LongestChord(const cv::Mat1i& labels, const Blob& blob) {
  const cv::Rect box = cv::Rect(static_cast<int>(blob.box.x1), static_cast<int>(blob.box.y1),
                                static_cast<int>(blob.box.x2 - blob.box.x1) + 1,
                                static_cast<int>(blob.box.y2 - blob.box.y1) + 1) &
                       cv::Rect(0, 0, labels.cols, labels.rows);
  std::vector<cv::Point> pixels;
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x)
      if (labels(y, x) == blob.id) pixels.emplace_back(x, y);
  if (pixels.empty()) return 0;
  std::vector<cv::Point> hull;
  cv::convexHull(pixels, hull);
  double longest = 0;
  for (size_t i = 0; i < hull.size(); ++i)
    for (size_t j = i + 1; j < hull.size(); ++j) longest = std::max(longest, cv::norm(hull[i] - hull[j]));
  return longest + 1;  // pixel centres to outer edges
}

// The point on the ray from `c` along `dir` that lies `distance` across the
// row; false when the ray does not reach it ahead.
bool AcrossOnRay(const Eigen::Vector3d& c, const Eigen::Vector3d& dir, const RowFrame& row, double distance,
                 Eigen::Vector3d* X) {
  const double speed = row.across.dot(dir);
  if (speed <= 1e-9) return false;
  const double t = (distance - row.across.dot(c - row.origin)) / speed;
  if (t <= 0) return false;
  *X = c + t * dir;
  return true;
}

// ... on the ray through `pixel` of `view`.
bool RayAt(const CameraView& view, const Eigen::Vector2d& pixel, const RowFrame& row, double distance,
           Eigen::Vector3d* X) {
  const Eigen::Vector2d n = view.Normalize(pixel);
  return AcrossOnRay(view.Center(), view.R.transpose() * Eigen::Vector3d(n.x(), n.y(), 1), row, distance, X);
}

struct Sphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double distance = 0;
  int in_image = 0;
  std::vector<std::pair<int, int>> hits;  // (frame, index into the frame's free pieces)
  double error = 0;                       // summed offsets / disc radius
};

// Frames around `frame` whose disc of X holds a free piece (the nearest to
// the disc's centre, relative to its radius).
Sphere Support(const std::vector<CameraView>& views, const std::vector<std::vector<Piece>>& free,
               const Eigen::Vector3d& X, int frame, const GlimpsedAppleOptions& o) {
  Sphere s;
  s.centre = X;
  const int n = static_cast<int>(views.size());
  for (int f = std::max(0, frame - o.window); f <= std::min(n - 1, frame + o.window); ++f) {
    const double z = views[f].Depth(X);
    if (z <= 1e-6) continue;
    Eigen::Vector2d p;
    if (!views[f].Project(X, &p)) continue;
    ++s.in_image;
    const double r = views[f].fx * o.apple_radius / z;
    int best = -1;
    double best_offset = 0;
    for (size_t k = 0; k < free[f].size(); ++k) {
      const double d = (free[f][k].centre - p).norm();
      if (d + free[f][k].radius > r + 1) continue;
      // A piece of an apple this near spans more than a whole apple of the
      // next row: the next row's apples, seen through a gap in the leaves,
      // move like an object at the gap's depth.
      if (free[f][k].extent < o.min_extent * r) continue;
      if (best < 0 || d < best_offset) best = static_cast<int>(k), best_offset = d;
    }
    if (best < 0) continue;
    s.hits.emplace_back(f, best);
    s.error += best_offset / r;
  }
  return s;
}

bool Stronger(const Sphere& a, const Sphere& b) {
  if (a.hits.size() != b.hits.size()) return a.hits.size() > b.hits.size();
  return a.error / std::max<size_t>(1, a.hits.size()) < b.error / std::max<size_t>(1, b.hits.size());
}

}  // namespace

std::vector<GlimpsedApple> FindGlimpsedApples(const std::vector<CameraView>& views,
                                              const std::vector<FruitFrame>& frames,
                                              const std::vector<Eigen::Vector3d>& explained, const RowFrame& row,
                                              double depth_cutoff, const GlimpsedAppleOptions& o) {
  o.Check();
  if (views.size() != frames.size()) Fail("glimpsed apples: ", views.size(), " views but ", frames.size(), " frames");
  const int n = static_cast<int>(frames.size());
  std::vector<std::vector<Piece>> free(n);
  for (int f = 0; f < n; ++f) {
    const CameraView& view = views[f];
    std::vector<std::pair<Eigen::Vector2d, double>> projected;  // pixel, explain radius
    for (const Eigen::Vector3d& X : explained) {
      const double z = view.Depth(X);
      if (z <= 1e-6) continue;
      Eigen::Vector2d p;
      view.Project(X, &p);
      projected.emplace_back(p, view.fx * o.explain_radius / z);
    }
    for (const Blob& b : frames[f].blobs) {
      const Eigen::Vector2d c(b.centroid.x + 0.5, b.centroid.y + 0.5);
      if (b.pixels < o.min_pixels) continue;
      if (std::any_of(projected.begin(), projected.end(),
                      [&](const auto& p) { return (p.first - c).norm() <= p.second; }))
        continue;
      free[f].push_back({c, EquivalentRadius(b), b.id, LongestChord(frames[f].labels, b)});
    }
  }
  // Through the next row too: its apples' pieces are explained by spheres
  // there before chance spheres in the filmed row take them.
  const double lo = row.row_distance - o.near_margin, hi = depth_cutoff + o.far_search;
  // Each free piece's best sphere.
  std::vector<Sphere> best;
  for (int i = 0; i < n; ++i)
    for (const Piece& seed : free[i]) {
      Sphere top;
      for (double D = lo; D <= hi; D += o.depth_step) {
        Eigen::Vector3d X0;
        if (!RayAt(views[i], seed.centre, row, D, &X0)) continue;
        const double z0 = views[i].Depth(X0);
        if (z0 <= 1e-6) continue;
        const double r0 = views[i].fx * o.apple_radius / z0;
        const double reach = std::max(0.0, r0 - seed.radius);
        const double step = std::max(1.0, o.offset_step * r0);
        const int steps = static_cast<int>(reach / step);
        for (int dy = -steps; dy <= steps; ++dy)
          for (int dx = -steps; dx <= steps; ++dx) {
            const Eigen::Vector2d offset(dx * step, dy * step);
            if (offset.norm() > reach + 1e-9) continue;
            Eigen::Vector3d X;
            if (!RayAt(views[i], seed.centre + offset, row, D, &X)) continue;
            Sphere s = Support(views, free, X, i, o);
            s.distance = D;
            if (static_cast<int>(s.hits.size()) < o.min_support ||
                s.hits.size() < o.min_support_ratio * s.in_image)
              continue;
            // The seed must be the piece its own frame holds.
            const auto own = std::find_if(s.hits.begin(), s.hits.end(), [i](const auto& h) { return h.first == i; });
            if (own == s.hits.end() || free[i][own->second].id != seed.id) continue;
            if (top.hits.empty() || Stronger(s, top)) top = std::move(s);
          }
      }
      if (!top.hits.empty()) best.push_back(std::move(top));
    }
  std::stable_sort(best.begin(), best.end(), Stronger);
  // Strongest first; a piece shows one apple, so a sphere keeps only the
  // pieces no stronger sphere took, and must still be supported by them.
  std::set<std::pair<int, int>> used;
  std::vector<GlimpsedApple> apples;
  for (const Sphere& s : best) {
    std::vector<std::pair<int, int>> left;
    for (const auto& h : s.hits)
      if (!used.count(h)) left.push_back(h);
    if (static_cast<int>(left.size()) < o.min_support || left.size() < o.min_support_ratio * s.in_image) continue;
    GlimpsedApple a;
    a.centre = s.centre;
    a.distance = s.distance;
    a.error = s.error / s.hits.size();
    for (const auto& h : left) {
      used.insert(h);
      const Piece& p = free[h.first][h.second];
      a.pieces.emplace_back(h.first, p.id);
      Eigen::Vector3d X;
      a.piece_points.push_back(RayAt(views[h.first], p.centre, row, s.distance, &X) ? X : s.centre);
      // The line of sight through the sphere's centre, for the merge.
      const Eigen::Vector3d camera = views[h.first].Center();
      const Eigen::Vector3d dir = (s.centre - camera).normalized();
      GlimpsedApple::SightRay ray;
      if (!AcrossOnRay(camera, dir, row, s.distance - o.ray_margin, &ray.near) ||
          !AcrossOnRay(camera, dir, row, s.distance + o.ray_margin, &ray.far))
        continue;  // not across the row: no ray to link along
      Eigen::Vector2d pixel;
      views[h.first].Project(s.centre, &pixel);
      ray.column = pixel.x();
      a.rays.push_back(ray);
    }
    apples.push_back(std::move(a));
  }
  return apples;
}

}  // namespace orchard
