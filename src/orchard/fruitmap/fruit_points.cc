#include "orchard/fruitmap/fruit_points.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <random>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/fruitmap/triangulation.h"

namespace orchard {

double EquivalentRadius(const Blob& blob) { return std::sqrt(blob.pixels / M_PI); }

Eigen::Vector2d AppleCentrePixel(const FruitFrame& frame, const Blob& b) {
  // Blob centres are in OpenCV pixel indices; views use COLMAP's +0.5.
  const cv::Point2d c = frame.apple_centres.empty() ? b.centroid : frame.apple_centres[b.id - 1];
  return {c.x + 0.5, c.y + 0.5};
}

namespace {

// Circle through three points; false when they are (nearly) collinear.
bool CircleThrough(const cv::Point2d& a, const cv::Point2d& b, const cv::Point2d& c, cv::Point2d* centre,
                   double* radius) {
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  const double d = 2 * (bx * cy - by * cx);
  if (std::abs(d) < 1e-9) return false;
  const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  const cv::Point2d u((cy * b2 - by * c2) / d, (bx * c2 - cx * b2) / d);
  *centre = a + u;
  *radius = std::hypot(u.x, u.y);
  return true;
}

// Algebraic least-squares circle (Kasa) through `points`.
bool FitCircle(const std::vector<cv::Point2d>& points, cv::Point2d* centre, double* radius) {
  if (points.size() < 3) return false;
  Eigen::MatrixXd A(points.size(), 3);
  Eigen::VectorXd rhs(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    A(i, 0) = points[i].x, A(i, 1) = points[i].y, A(i, 2) = 1;
    rhs(i) = points[i].x * points[i].x + points[i].y * points[i].y;
  }
  const Eigen::Vector3d s = A.colPivHouseholderQr().solve(rhs);
  *centre = {s(0) / 2, s(1) / 2};
  const double r2 = s(2) + centre->x * centre->x + centre->y * centre->y;
  if (!(r2 > 0)) return false;
  *radius = std::sqrt(r2);
  return true;
}

}  // namespace

cv::Point2d FitAppleCentre(const cv::Mat1i& labels, const Blob& blob) {
  // Measured on seed 32's back (generator masks, true projections): the
  // centroid of an apple showing 30-60% of its disc lies 2.1 px (median) from
  // its centre, the fitted circle's 1.2 px; 0.6 against 1.3 px at 60-90%.
  constexpr int kIterations = 200;
  constexpr double kInlierPx = 1.0;      // outline pixel within this of the circle
  constexpr double kMinCoverage = 0.25;  // inliers / circumference
  constexpr double kMinInside = 0.95;    // blob pixels inside the circle
  constexpr double kWholeDisc = 0.85;    // blob area / disc area above which the centroid is kept
  const cv::Rect box = cv::Rect(static_cast<int>(blob.box.x1) - 1, static_cast<int>(blob.box.y1) - 1,
                                static_cast<int>(blob.box.x2 - blob.box.x1) + 2,
                                static_cast<int>(blob.box.y2 - blob.box.y1) + 2) &
                       cv::Rect(0, 0, labels.cols, labels.rows);
  if (blob.pixels < 5 || box.empty()) return blob.centroid;
  const cv::Mat1b mask = labels(box) == blob.id;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::vector<cv::Point2d> outline;
  // Where the frame cuts an apple, the blob's edge is the frame's, not the
  // apple's: a circle fitted through it is pulled off the centre, and the
  // centroid is too (apples at the frame's top edge, 2.2-2.8 m up on the
  // synthetic rows, were nearly half of the apples missed; docs/side.md).
  const auto on_frame_edge = [&labels](int x, int y) {
    return x <= 0 || y <= 0 || x >= labels.cols - 1 || y >= labels.rows - 1;
  };
  for (const auto& contour : contours)
    for (const cv::Point& p : contour)
      if (!on_frame_edge(p.x + box.x, p.y + box.y)) outline.emplace_back(p.x + box.x, p.y + box.y);
  if (outline.size() < 8) return blob.centroid;
  const double equivalent_radius = EquivalentRadius(blob);
  std::mt19937 rng(static_cast<uint32_t>(blob.id * 7919 + blob.pixels));
  std::uniform_int_distribution<size_t> pick(0, outline.size() - 1);
  int best_inliers = 0;
  cv::Point2d best_centre;
  double best_radius = 0;
  // A visible piece is at most the whole disc, and a sliver's circle is too
  // poorly fixed to be worth more than the centroid.
  const auto plausible = [&](double r) { return r >= 0.9 * equivalent_radius && r <= 4 * equivalent_radius; };
  const auto on_circle = [](const cv::Point2d& p, const cv::Point2d& c, double r) {
    return std::abs(std::hypot(p.x - c.x, p.y - c.y) - r) < kInlierPx;
  };
  for (int it = 0; it < kIterations; ++it) {
    cv::Point2d c;
    double r;
    if (!CircleThrough(outline[pick(rng)], outline[pick(rng)], outline[pick(rng)], &c, &r) || !plausible(r)) continue;
    const int inliers =
        static_cast<int>(std::count_if(outline.begin(), outline.end(), [&](const auto& p) { return on_circle(p, c, r); }));
    if (inliers > best_inliers) best_inliers = inliers, best_centre = c, best_radius = r;
  }
  if (best_inliers == 0) return blob.centroid;
  std::vector<cv::Point2d> inliers;
  for (const auto& p : outline)
    if (on_circle(p, best_centre, best_radius)) inliers.push_back(p);
  cv::Point2d centre;
  double radius;
  if (!FitCircle(inliers, &centre, &radius) || !plausible(radius)) centre = best_centre, radius = best_radius;
  if (inliers.size() < kMinCoverage * 2 * M_PI * radius) return blob.centroid;
  if (blob.pixels >= kWholeDisc * M_PI * radius * radius) return blob.centroid;
  int inside = 0;
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x)
      if (mask(y, x)) inside += std::hypot(x + box.x - centre.x, y + box.y - centre.y) <= radius + 1.5;
  if (inside < kMinInside * blob.pixels) return blob.centroid;
  return centre;
}

void FitAppleCentres(FruitFrame* frame) {
  frame->apple_centres.clear();
  for (const Blob& b : frame->blobs) frame->apple_centres.push_back(FitAppleCentre(frame->labels, b));
}

void SplitCountedBlobs(FruitFrame* frame) {
  const size_t n = frame->blobs.size();
  if (frame->counts.size() != n) Fail("split blobs: ", frame->counts.size(), " counts for ", n, " blobs");
  for (size_t i = 0; i < n; ++i) {
    const int k = frame->counts[i];
    const Blob blob = frame->blobs[i];
    if (k < 2 || blob.pixels < 2 * k) continue;
    const cv::Rect box(static_cast<int>(blob.box.x1), static_cast<int>(blob.box.y1),
                       static_cast<int>(blob.box.x2 - blob.box.x1), static_cast<int>(blob.box.y2 - blob.box.y1));
    const bool wide = box.width >= box.height;
    std::vector<cv::Point> pixels;
    for (int y = box.y; y < box.y + box.height; ++y)
      for (int x = box.x; x < box.x + box.width; ++x)
        if (frame->labels(y, x) == blob.id) pixels.emplace_back(x, y);
    if (static_cast<int>(pixels.size()) != blob.pixels)
      Fail("split blobs: blob ", blob.id, " has ", pixels.size(), " pixels in its box, its record ", blob.pixels);
    cv::Mat1f samples(blob.pixels, 2);
    cv::Mat1i labels(blob.pixels, 1);
    for (int r = 0; r < blob.pixels; ++r) {
      const cv::Point p = pixels[r];
      samples(r, 0) = static_cast<float>(p.x), samples(r, 1) = static_cast<float>(p.y);
      // Slabs of equal width along the longer side start the k-means.
      const double t = wide ? (p.x - box.x + 0.5) / box.width : (p.y - box.y + 0.5) / box.height;
      labels(r, 0) = std::min(k - 1, static_cast<int>(t * k));
    }
    cv::Mat centres;
    cv::kmeans(samples, k, labels, cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 0.5), 1,
               cv::KMEANS_USE_INITIAL_LABELS, centres);
    std::vector<std::vector<cv::Point>> piece_pixels(k);
    for (int r = 0; r < blob.pixels; ++r) piece_pixels[labels(r, 0)].push_back(pixels[r]);
    // OpenCV refills an emptied cluster, so this guard should never keep a blob whole.
    if (std::any_of(piece_pixels.begin(), piece_pixels.end(), [](const auto& p) { return p.empty(); })) continue;
    // Piece 0 keeps the blob's id and place; the others become new blobs.
    for (int j = 0; j < k; ++j) {
      Blob b;
      b.id = j == 0 ? blob.id : static_cast<int>(frame->blobs.size()) + 1;
      b.score = blob.score;
      b.pixels = static_cast<int>(piece_pixels[j].size());
      const cv::Rect r = cv::boundingRect(piece_pixels[j]);
      b.box = Box{static_cast<double>(r.x), static_cast<double>(r.y), static_cast<double>(r.x + r.width),
                  static_cast<double>(r.y + r.height)};
      double sx = 0, sy = 0;
      for (const cv::Point& p : piece_pixels[j]) frame->labels(p.y, p.x) = b.id, sx += p.x, sy += p.y;
      b.centroid = {sx / b.pixels, sy / b.pixels};
      if (j == 0) {
        frame->blobs[i] = b, frame->counts[i] = 1;
      } else {
        frame->blobs.push_back(b), frame->counts.push_back(1);
      }
    }
  }
}

BlobCentres::BlobCentres(const FruitFrame& frame, int cell_pixels) : frame_(&frame), cell_(cell_pixels) {
  cols_ = frame.labels.cols / cell_ + 1, rows_ = frame.labels.rows / cell_ + 1;
  grid_.resize(static_cast<size_t>(cols_) * rows_);
  for (size_t i = 0; i < frame.blobs.size(); ++i) {
    const Blob& b = frame.blobs[i];
    if (b.pixels <= 0) continue;
    const Eigen::Vector2d c = AppleCentrePixel(frame, b);
    const int cx = std::clamp(static_cast<int>(c.x()) / cell_, 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(c.y()) / cell_, 0, rows_ - 1);
    grid_[static_cast<size_t>(cy) * cols_ + cx].push_back(static_cast<int>(i));
    max_radius_ = std::max(max_radius_, EquivalentRadius(b));
  }
}

bool ProjectNearFrame(const CameraView& view, const Eigen::Vector3d& X, const FruitPointOptions& o,
                      Eigen::Vector2d* p, bool* inside) {
  const double z = view.Depth(X);
  if (z <= 0) return false;
  *inside = view.Project(X, p);
  if (*inside) return true;
  const double margin = view.fx * o.apple_radius / z;
  return p->x() >= -margin && p->y() >= -margin && p->x() < view.width + margin && p->y() < view.height + margin;
}

int BlobCentres::Near(const CameraView& view, const Eigen::Vector3d& X, const FruitPointOptions& o) const {
  const double z = view.Depth(X);
  Eigen::Vector2d p;
  bool inside = false;
  if (!ProjectNearFrame(view, X, o, &p, &inside)) return 0;
  // By distance, not by the label under the point: a partly hidden apple's
  // centre may fall between its visible pieces. Wrong pairings land on fruit
  // by chance but rarely near the centres of the blobs they land on.
  const double apple_px = o.apple_fraction * view.fx * o.apple_radius / z;
  const double reach = std::max({o.centre_fraction * max_radius_, apple_px, 2.0});
  const int x0 = std::max(0, static_cast<int>((p.x() - reach) / cell_));
  const int x1 = std::min(cols_ - 1, static_cast<int>((p.x() + reach) / cell_));
  const int y0 = std::max(0, static_cast<int>((p.y() - reach) / cell_));
  const int y1 = std::min(rows_ - 1, static_cast<int>((p.y() + reach) / cell_));
  double nearest = 1e300;
  int id = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      for (int i : grid_[static_cast<size_t>(y) * cols_ + x]) {
        const Blob& b = frame_->blobs[i];
        const double tol = std::max({o.centre_fraction * EquivalentRadius(b), apple_px, 2.0});
        const double d = (p - AppleCentrePixel(*frame_, b)).norm();
        if (d <= tol && d < nearest) nearest = d, id = b.id;
      }
  return id;
}

int BlobNearPoint(const CameraView& view, const FruitFrame& frame, const Eigen::Vector3d& X,
                  const FruitPointOptions& o) {
  return BlobCentres(frame).Near(view, X, o);
}

namespace {

struct Support {
  int in_image = 0, hits = 0;
  std::vector<std::pair<int, int>> blobs;  // (frame, blob id) hit
};

Support CheckSupport(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                     const std::vector<BlobCentres>& centres, const Eigen::Vector3d& X, int centre,
                     const FruitPointOptions& o) {
  Support s;
  const int n = static_cast<int>(frames.size());
  for (int f = std::max(0, centre - o.support_window); f <= std::min(n - 1, centre + o.support_window); ++f) {
    const double z = views[f].Depth(X);
    if (z < o.min_depth || z > o.max_depth) continue;
    Eigen::Vector2d p;
    bool inside = false;
    if (!ProjectNearFrame(views[f], X, o, &p, &inside)) continue;
    if (o.centre_fraction <= 0 && !inside) continue;
    ++s.in_image;
    const int id = o.centre_fraction > 0 ? centres[f].Near(views[f], X, o)
                                         : frames[f].labels(static_cast<int>(p.y()), static_cast<int>(p.x()));
    if (id <= 0) continue;
    ++s.hits, s.blobs.emplace_back(f, id);
  }
  return s;
}

bool Accept(const Support& s, const FruitPointOptions& o) {
  return s.hits >= o.min_support && s.hits >= o.min_support_ratio * s.in_image;
}

// Fundamental matrix from view a to view b: x_b^T F x_a = 0 (pixels, no distortion).
Eigen::Matrix3d Fundamental(const CameraView& a, const CameraView& b) {
  const Eigen::Matrix3d R = b.R * a.R.transpose();
  const Eigen::Vector3d t = b.t - R * a.t;
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  Eigen::Matrix3d Ka, Kb;
  Ka << a.fx, 0, a.cx, 0, a.fy, a.cy, 0, 0, 1;
  Kb << b.fx, 0, b.cx, 0, b.fy, b.cy, 0, 0, 1;
  return Kb.inverse().transpose() * tx * R * Ka.inverse();
}

}  // namespace

void FruitPointOptions::Check() const {
  ORCHARD_CHECK_OPTION(min_partner_offset >= 1 && max_partner_offset >= min_partner_offset,
                       "partner offsets must satisfy 1 <= min <= max, got ", min_partner_offset, "..",
                       max_partner_offset);
  ORCHARD_CHECK_OPTION(support_window >= 1, "support window must be at least 1, got ", support_window);
  ORCHARD_CHECK_OPTION(max_error_fraction > 0 && max_error_fraction < 0.5, "max error fraction must be in (0, 0.5), got ",
                       max_error_fraction);
  ORCHARD_CHECK_OPTION(min_support >= 2, "min support must be at least 2, got ", min_support);
  ORCHARD_CHECK_OPTION(min_support_ratio > 0 && min_support_ratio <= 1, "min support ratio must be in (0, 1], got ",
                       min_support_ratio);
  ORCHARD_CHECK_OPTION(centre_fraction >= 0, "centre fraction must be >= 0, got ", centre_fraction);
  ORCHARD_CHECK_OPTION(apple_fraction >= 0 && apple_radius > 0, "apple fraction must be >= 0 and apple radius > 0, got ",
                       apple_fraction, ", ", apple_radius);
  ORCHARD_CHECK_OPTION(explain_distance >= 0, "explain distance must be >= 0, got ", explain_distance);
  ORCHARD_CHECK_OPTION(min_depth > 0 && max_depth > min_depth, "depth range must satisfy 0 < min < max, got ",
                       min_depth, "..", max_depth);
}

namespace {

bool Stronger(const FruitPointCandidate& a, const FruitPointCandidate& b) {
  return a.point.support != b.point.support ? a.point.support > b.point.support : a.error < b.error;
}

}  // namespace

std::vector<FruitPoint> ChooseFruitPoints(std::vector<std::vector<FruitPointCandidate>> per_blob,
                                          const FruitPointOptions& o) {
  o.Check();
  std::vector<FruitPoint> points;
  for (auto& c : per_blob) std::stable_sort(c.begin(), c.end(), Stronger);
  if (o.explain_distance <= 0) {
    for (const auto& c : per_blob)
      if (!c.empty()) points.push_back(c.front().point);
    return points;
  }
  // Queue of (blob, rank of its candidate), strongest first; ties by blob order.
  const auto weaker = [&per_blob](const std::pair<int, int>& a, const std::pair<int, int>& b) {
    const FruitPointCandidate& ca = per_blob[a.first][a.second];
    const FruitPointCandidate& cb = per_blob[b.first][b.second];
    if (Stronger(ca, cb)) return false;
    if (Stronger(cb, ca)) return true;
    return a.first > b.first;
  };
  std::priority_queue<std::pair<int, int>, std::vector<std::pair<int, int>>, decltype(weaker)> queue(weaker);
  for (int b = 0; b < static_cast<int>(per_blob.size()); ++b)
    if (!per_blob[b].empty()) queue.emplace(b, 0);
  std::map<std::pair<int, int>, std::vector<Eigen::Vector3d>> landed;  // (frame, blob id) -> kept points on it
  std::vector<std::pair<int, int>> kept;                               // (blob, rank)
  while (!queue.empty()) {
    const auto [b, rank] = queue.top();
    queue.pop();
    const FruitPointCandidate& c = per_blob[b][rank];
    const auto explained = [&](const std::pair<int, int>& frame_blob) {
      const auto it = landed.find(frame_blob);
      return it != landed.end() && std::none_of(it->second.begin(), it->second.end(), [&](const Eigen::Vector3d& y) {
               return (y - c.point.xyz).norm() <= o.explain_distance;
             });
    };
    // Hits on blobs a stronger point elsewhere explains do not count; nor is
    // a point kept from a blob so explained (only one that agrees with that
    // point, so the apple's points stay together).
    Support free;
    free.in_image = c.in_image;
    free.hits = static_cast<int>(std::count_if(c.hits.begin(), c.hits.end(), [&](const auto& fb) { return !explained(fb); }));
    if (!explained({c.point.frame, c.point.blob_id}) && Accept(free, o)) {
      kept.emplace_back(b, rank);
      for (const auto& fb : c.hits) landed[fb].push_back(c.point.xyz);
    } else if (rank + 1 < static_cast<int>(per_blob[b].size())) {
      queue.emplace(b, rank + 1);
    }
  }
  std::sort(kept.begin(), kept.end());
  for (const auto& [b, rank] : kept) points.push_back(per_blob[b][rank].point);
  return points;
}

std::vector<FruitPoint> TriangulateFruitPoints(const std::vector<CameraView>& views,
                                               const std::vector<FruitFrame>& frames, const FruitPointOptions& o) {
  o.Check();
  if (views.size() != frames.size()) Fail("fruit points: ", views.size(), " views but ", frames.size(), " frames");
  const int n = static_cast<int>(frames.size());
  std::vector<BlobCentres> centres;
  for (const auto& f : frames) centres.emplace_back(f);
  std::vector<std::vector<FruitPointCandidate>> per_blob;  // every blob of every frame, in order
  for (int i = 0; i < n; ++i) {
    const double tol = o.max_error_fraction * views[i].width;
    for (const Blob& blob : frames[i].blobs) {
      const Eigen::Vector2d pi = AppleCentrePixel(frames[i], blob);
      const Eigen::Vector3d hi(pi.x(), pi.y(), 1);
      std::vector<FruitPointCandidate>& candidates = per_blob.emplace_back();
      for (int j = i + o.min_partner_offset; j <= std::min(n - 1, i + o.max_partner_offset); ++j) {
        const Eigen::Matrix3d F = Fundamental(views[i], views[j]);
        const Eigen::Vector3d line = F * hi;
        const double line_norm = line.head<2>().norm();
        if (line_norm < 1e-12) continue;
        for (const Blob& other : frames[j].blobs) {
          const Eigen::Vector2d pj = AppleCentrePixel(frames[j], other);
          if (std::abs(line.dot(Eigen::Vector3d(pj.x(), pj.y(), 1))) / line_norm > tol) continue;
          Eigen::Vector3d X;
          if (!TriangulatePoint({&views[i], &views[j]}, {pi, pj}, &X)) continue;
          if (views[i].Depth(X) < o.min_depth || views[i].Depth(X) > o.max_depth) continue;
          if (views[j].Depth(X) < o.min_depth) continue;
          Support s = CheckSupport(views, frames, centres, X, i, o);
          if (!Accept(s, o)) continue;
          // Refine on the centres of all blobs the point lands on; drop the
          // centres that disagree (a different apple's blob) and re-check.
          for (int round = 0; round < 2; ++round) {
            std::vector<const CameraView*> vs;
            std::vector<Eigen::Vector2d> ps;
            for (const auto& [f, id] : s.blobs) {
              const Eigen::Vector2d c = AppleCentrePixel(frames[f], *frames[f].FindBlob(id));
              if (round > 0 && ReprojectionError(views[f], X, c) > tol) continue;
              vs.push_back(&views[f]), ps.push_back(c);
            }
            Eigen::Vector3d Y;
            if (vs.size() < 2 || !TriangulatePoint(vs, ps, &Y)) break;
            X = Y;
          }
          s = CheckSupport(views, frames, centres, X, i, o);
          // The blob itself must still be hit.
          if (!Accept(s, o) ||
              std::find(s.blobs.begin(), s.blobs.end(), std::make_pair(i, blob.id)) == s.blobs.end())
            continue;
          double error = 0;
          for (const auto& [f, id] : s.blobs) error += ReprojectionError(views[f], X, AppleCentrePixel(frames[f], *frames[f].FindBlob(id)));
          error /= s.hits;
          candidates.push_back({{X, i, blob.id, s.hits}, s.in_image, std::move(s.blobs), error});
        }
      }
    }
  }
  return ChooseFruitPoints(std::move(per_blob), o);
}

}  // namespace orchard
