#include "orchard/fruitmap/edge_apples.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "orchard/core/error.h"

namespace orchard {

void EdgeAppleOptions::Check() const {
  ORCHARD_CHECK_OPTION(edge_rows >= 1, "edge rows must be at least 1, got ", edge_rows);
  ORCHARD_CHECK_OPTION(min_pixels >= 0, "edge sighting pixels must be >= 0 (0 = auto), got ", min_pixels);
  ORCHARD_CHECK_OPTION(explain_across >= 0, "edge explain-across fraction must be >= 0, got ", explain_across);
  ORCHARD_CHECK_OPTION(apple_radius > 0, "edge apple radius must be positive, got ", apple_radius);
  ORCHARD_CHECK_OPTION(window >= 1, "edge window must be at least 1 frame, got ", window);
  ORCHARD_CHECK_OPTION(near_margin >= 0 && far_margin >= 0, "edge margins must be >= 0, got ", near_margin, " and ",
                       far_margin);
  ORCHARD_CHECK_OPTION(max_ray_distance > 0, "edge ray distance must be positive, got ", max_ray_distance);
}

namespace {

// A point that may explain slivers, as one frame sees it: its pixel (inside
// the image or not) and an apple's radius there.
struct ProjectedPoint {
  Eigen::Vector2d pixel;
  double radius = 0;
};

// Whether the point lies within an apple's radius of the blob's box
// vertically and within across_fraction of that of its columns.
bool ExplainsBlob(const ProjectedPoint& p, const Blob& blob, double across_fraction) {
  const double dx = std::max({blob.box.x1 - p.pixel.x(), 0.0, p.pixel.x() - blob.box.x2});
  const double dy = std::max({blob.box.y1 - p.pixel.y(), 0.0, p.pixel.y() - blob.box.y2});
  return dy <= p.radius && dx <= across_fraction * p.radius;
}

// A sighting's ray in the row's horizontal plane: point and unit direction
// in (along, across) coordinates.
struct Ray2 {
  Eigen::Vector2d point, dir;
  bool valid = false;
};

Ray2 HorizontalRay(const EdgeSighting& s, const RowFrame& row) {
  Ray2 r;
  const Eigen::Vector3d c = s.origin - row.origin;
  r.point = {row.along.dot(c), row.across.dot(c)};
  const Eigen::Vector2d d(row.along.dot(s.direction), row.across.dot(s.direction));
  // Rays that run along the row or away from it meet no fruit.
  if (d.norm() < 1e-9 || d.y() <= 1e-3 * d.norm()) return r;
  r.dir = d.normalized();
  r.valid = true;
  return r;
}

// Least-squares crossing of the rays (in the horizontal plane) and the
// largest distance of a ray from it; false when the rays are parallel or the
// crossing lies behind one of them.
bool Crossing(const std::vector<Ray2>& rays, Eigen::Vector2d* x, double* worst) {
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (const Ray2& r : rays) {
    const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() - r.dir * r.dir.transpose();
    A += P;
    b += P * r.point;
  }
  if (std::abs(A.determinant()) < 1e-9) return false;
  *x = A.inverse() * b;
  *worst = 0;
  for (const Ray2& r : rays) {
    const Eigen::Vector2d v = *x - r.point;
    if (v.dot(r.dir) <= 0) return false;
    *worst = std::max(*worst, (v - v.dot(r.dir) * r.dir).norm());
  }
  return true;
}

}  // namespace

std::vector<EdgeSighting> FindEdgeSightings(const std::vector<CameraView>& views,
                                            const std::vector<FruitFrame>& frames,
                                            const std::vector<Eigen::Vector3d>& explained, const RowFrame& row,
                                            const EdgeAppleOptions& o) {
  o.Check();
  if (views.size() != frames.size()) Fail("edge apples: ", views.size(), " views but ", frames.size(), " frames");
  std::vector<EdgeSighting> sightings;
  for (size_t f = 0; f < frames.size(); ++f) {
    const CameraView& view = views[f];
    std::vector<const Blob*> edge_blobs;
    for (const Blob& b : frames[f].blobs) {
      if (b.box.y1 >= o.edge_rows) continue;
      // In a top corner the side edge cuts the sliver too: its middle is not the apple's column.
      if (b.box.x1 < o.edge_rows || b.box.x2 > view.width - o.edge_rows) continue;
      edge_blobs.push_back(&b);
    }
    if (edge_blobs.empty()) continue;
    // The explaining points projected once per frame, not once per blob.
    std::vector<ProjectedPoint> projected;
    for (const Eigen::Vector3d& X : explained) {
      const double z = view.Depth(X);
      if (z <= 1e-6) continue;
      ProjectedPoint p;
      view.Project(X, &p.pixel);  // the pixel, inside the image or not
      p.radius = view.fx * o.apple_radius / z;
      projected.push_back(p);
    }
    std::vector<const Blob*> pieces;
    for (const Blob* b : edge_blobs)
      if (std::none_of(projected.begin(), projected.end(),
                       [&](const ProjectedPoint& p) { return ExplainsBlob(p, *b, o.explain_across); }))
        pieces.push_back(b);
    if (pieces.empty()) continue;
    // Pieces of one sliver (leaves cut it) lie within an apple's width.
    const double depth = row.row_distance > 0 ? row.row_distance : 2.0;
    const double span = 2 * view.fx * o.apple_radius / depth;
    std::sort(pieces.begin(), pieces.end(), [](const Blob* a, const Blob* b) { return a->box.x1 < b->box.x1; });
    for (size_t i = 0; i < pieces.size();) {
      EdgeSighting s;
      s.frame = static_cast<int>(f);
      double x0 = pieces[i]->box.x1, x1 = pieces[i]->box.x2;
      size_t j = i;
      for (; j < pieces.size() && std::max(x1, pieces[j]->box.x2) - x0 <= std::max(span, pieces[i]->box.Width());
           ++j) {
        x1 = std::max(x1, pieces[j]->box.x2);
        s.blobs.push_back(pieces[j]->id);
        s.pixels += pieces[j]->pixels;
      }
      i = j;
      if (s.pixels < (o.min_pixels > 0 ? o.min_pixels : 20)) continue;
      // Box columns are pixel indices [x_min, x_max): in COLMAP's pixel
      // coordinates the sliver spans x_min..x_max exactly. The ray passes
      // through the top row of pixels (centres at y = 0.5).
      s.column = 0.5 * (x0 + x1);
      const Eigen::Vector2d n = view.Normalize({s.column, 0.5});
      s.origin = view.Center();
      s.direction = (view.R.transpose() * Eigen::Vector3d(n.x(), n.y(), 1)).normalized();
      sightings.push_back(std::move(s));
    }
  }
  return sightings;
}

Eigen::Vector3d SightingAtDistance(const EdgeSighting& s, const RowFrame& row, double distance) {
  return s.origin + (distance - row.across.dot(s.origin - row.origin)) / row.across.dot(s.direction) * s.direction;
}

std::vector<EdgeApple> GroupEdgeSightings(const std::vector<EdgeSighting>& sightings, const RowFrame& row,
                                          const EdgeAppleOptions& o) {
  o.Check();
  std::vector<Ray2> rays;
  for (const EdgeSighting& s : sightings) rays.push_back(HorizontalRay(s, row));
  const double near = row.row_distance - o.near_margin, far = row.row_distance + o.far_margin;
  struct Group {
    std::vector<int> members;
    int last_frame = 0;
  };
  std::vector<Group> groups;
  std::vector<int> order(sightings.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return sightings[a].frame < sightings[b].frame; });
  for (int s : order) {
    if (!rays[s].valid) continue;
    const int frame = sightings[s].frame;
    int best = -1;
    double best_worst = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
      const Group& group = groups[g];
      if (frame - group.last_frame > o.window) continue;
      if (std::any_of(group.members.begin(), group.members.end(),
                      [&](int m) { return sightings[m].frame == frame; }))
        continue;
      std::vector<Ray2> together;
      for (int m : group.members) together.push_back(rays[m]);
      together.push_back(rays[s]);
      Eigen::Vector2d x;
      double worst = 0;
      if (!Crossing(together, &x, &worst)) continue;
      if (x.y() < near || x.y() > far) continue;
      if (together.size() >= 3 && worst > o.max_ray_distance) continue;
      // The group seen most recently; then the one the rays fit best.
      if (best < 0 || group.last_frame > groups[best].last_frame ||
          (group.last_frame == groups[best].last_frame && worst < best_worst))
        best = static_cast<int>(g), best_worst = worst;
    }
    if (best < 0) {
      groups.push_back({{s}, frame});
    } else {
      groups[best].members.push_back(s);
      groups[best].last_frame = frame;
    }
  }
  std::vector<EdgeApple> apples;
  for (const Group& group : groups) {
    EdgeApple a;
    a.sightings = group.members;
    std::vector<Ray2> together;
    for (int m : group.members) together.push_back(rays[m]);
    Eigen::Vector2d x;
    double worst = 0;
    a.crossed = together.size() >= 2 && Crossing(together, &x, &worst);
    a.distance = a.crossed ? x.y() : row.row_distance;
    // Each sighting's ray where it reaches that distance: the apple's lower
    // edge in that frame's top row; the centre hangs at their mean.
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int m : group.members) {
      const EdgeSighting& s = sightings[m];
      a.sighting_points.push_back(SightingAtDistance(s, row, a.distance));
      sum += a.sighting_points.back();
    }
    a.centre = sum / static_cast<double>(group.members.size());
    apples.push_back(std::move(a));
  }
  return apples;
}

}  // namespace orchard
