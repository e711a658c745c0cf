#include "orchard/sfm/ground_plane.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "orchard/core/error.h"
#include "orchard/core/quantile.h"

namespace orchard {
namespace {

// Least-squares plane through points (smallest principal axis), normal
// oriented along `up`.
Plane FitPlaneLeastSquares(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& up) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Plane plane;
  plane.normal = eig.eigenvectors().col(0).normalized();
  if (plane.normal.dot(up) < 0) plane.normal = -plane.normal;
  plane.d = -plane.normal.dot(mean);
  return plane;
}

}  // namespace

void GroundPlaneOptions::Check() const {
  ORCHARD_CHECK_OPTION(iterations > 0, "ground plane iterations must be positive, got ", iterations);
  ORCHARD_CHECK_OPTION(inlier_fraction > 0 && inlier_fraction < 1, "ground inlier fraction must be in (0, 1), got ",
                       inlier_fraction);
  ORCHARD_CHECK_OPTION(max_tilt_deg > 0 && max_tilt_deg < 90, "ground max tilt must be in (0, 90) degrees, got ",
                       max_tilt_deg);
  ORCHARD_CHECK_OPTION(fine_inlier_fraction >= 0 && fine_inlier_fraction <= inlier_fraction,
                       "ground fine inlier fraction must be in [0, ", inlier_fraction,
                       "] (the first band's fraction), got ", fine_inlier_fraction);
  ORCHARD_CHECK_OPTION(below_penalty >= 0, "ground below penalty must be >= 0, got ", below_penalty);
  ORCHARD_CHECK_OPTION(min_inliers >= 3, "ground min inliers must be at least 3, got ", min_inliers);
}

Plane FitGroundPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& camera_centres,
                     const Eigen::Vector3d& up_in, const GroundPlaneOptions& options, int* num_inliers,
                     const std::vector<Eigen::Vector3d>* above, double above_penalty) {
  options.Check();
  if (camera_centres.empty()) Fail("ground plane: no cameras");
  if (static_cast<int>(points.size()) < options.min_inliers)
    Fail("ground plane: only ", points.size(), " 3D points, need at least ", options.min_inliers,
         " (too little texture on the ground?)");
  const Eigen::Vector3d up = up_in.normalized();
  std::vector<double> ranges;
  for (size_t i = 0; i < points.size(); i += std::max<size_t>(1, points.size() / 500))
    ranges.push_back((points[i] - camera_centres[camera_centres.size() / 2]).norm());
  const double tol = options.inlier_fraction * Quantile(ranges, 0.5);
  const double cos_tilt = std::cos(options.max_tilt_deg * M_PI / 180);
  auto admissible = [&](const Plane& p) {
    if (p.normal.dot(up) < cos_tilt) return false;
    for (const auto& c : camera_centres)
      if (p.SignedDistance(c) <= 0) return false;
    return true;
  };
  auto count_inliers = [&](const Plane& p, double tol) {
    int n = 0;
    for (const auto& x : points) n += std::abs(p.SignedDistance(x)) < tol;
    return n;
  };
  auto score = [&](const Plane& p, double tol) {
    int inliers = 0, below = 0;
    for (const auto& x : points) {
      const double d = p.SignedDistance(x);
      inliers += std::abs(d) < tol, below += d <= -tol;
    }
    int above_below = 0;
    if (above)
      for (const auto& x : *above) above_below += p.SignedDistance(x) <= -tol;
    return inliers - options.below_penalty * below - above_penalty * above_below;
  };
  // The best admissible plane through three of `samples`, scored on all points.
  std::mt19937_64 rng(options.seed);
  auto ransac = [&](const std::vector<Eigen::Vector3d>& samples, double tol, Plane* best) {
    std::uniform_int_distribution<size_t> pick(0, samples.size() - 1);
    double best_score = -1e300;
    bool found = false;
    for (int it = 0; it < options.iterations; ++it) {
      const Eigen::Vector3d& a = samples[pick(rng)];
      const Eigen::Vector3d& b = samples[pick(rng)];
      const Eigen::Vector3d& c = samples[pick(rng)];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (n.norm() < 1e-12) continue;
      Plane p;
      p.normal = n.normalized();
      if (p.normal.dot(up) < 0) p.normal = -p.normal;
      p.d = -p.normal.dot(a);
      if (!admissible(p)) continue;
      const double sc = score(p, tol);
      if (sc > best_score) best_score = sc, *best = p, found = true;
    }
    return found;
  };
  Plane best;
  const int best_count = ransac(points, tol, &best) ? count_inliers(best, tol) : 0;
  if (best_count < options.min_inliers)
    Fail("ground plane: no roughly horizontal plane below the cameras has ", options.min_inliers,
         " supporting points (best: ", best_count, " of ", points.size(), ")");
  // The thin layer of ground points within the wide band (options.fine_inlier_fraction).
  double refine_tol = tol;
  int count = best_count;
  if (options.fine_inlier_fraction > 0) {
    const double fine_tol = options.fine_inlier_fraction * tol / options.inlier_fraction;
    std::vector<Eigen::Vector3d> band;
    for (const auto& x : points)
      if (std::abs(best.SignedDistance(x)) < tol) band.push_back(x);
    Plane fine;
    const int fine_count = ransac(band, fine_tol, &fine) ? count_inliers(fine, fine_tol) : 0;
    if (fine_count >= options.min_inliers) best = fine, refine_tol = fine_tol, count = fine_count;
  }
  // Refine on the inliers (twice, as the inlier set settles).
  for (int round = 0; round < 2; ++round) {
    std::vector<Eigen::Vector3d> inliers;
    for (const auto& x : points)
      if (std::abs(best.SignedDistance(x)) < refine_tol) inliers.push_back(x);
    if (inliers.size() < 3) break;
    const Plane refined = FitPlaneLeastSquares(inliers, up);
    if (!admissible(refined)) break;
    best = refined;
    count = static_cast<int>(inliers.size());
  }
  if (num_inliers) *num_inliers = count;
  return best;
}

Eigen::Vector3d MeanCameraUp(const std::vector<CameraView>& views) {
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const auto& v : views) up -= v.Down();
  if (up.norm() < 1e-12) Fail("cameras have no common up direction");
  return up.normalized();
}

double ScaleFromCameraHeight(const Plane& ground, const std::vector<CameraView>& views, double camera_height) {
  if (!(camera_height > 0)) Fail("camera height must be positive, got ", camera_height);
  if (views.empty()) Fail("scale from camera height: no cameras");
  std::vector<double> heights;
  for (const auto& v : views) heights.push_back(ground.SignedDistance(v.Center()));
  const double h = Quantile(heights, 0.5);
  if (!(h > 0)) Fail("the cameras are not above the ground plane (median height ", h, ")");
  return camera_height / h;
}

}  // namespace orchard
