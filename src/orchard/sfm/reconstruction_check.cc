#include "orchard/sfm/reconstruction_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Eigenvalues>

#include "orchard/core/error.h"
#include "orchard/core/quantile.h"

namespace orchard {
namespace {

std::string Format(const char* format, double a, double b = 0, double c = 0) {
  char text[256];
  std::snprintf(text, sizeof text, format, a, b, c);
  return text;
}

}  // namespace

void ReconstructionCheckOptions::Check() const {
  ORCHARD_CHECK_OPTION(max_step_ratio > 1, "reconstruction check: max step ratio must be > 1, got ", max_step_ratio);
  ORCHARD_CHECK_OPTION(max_backward_steps >= 0, "reconstruction check: max backward steps must be >= 0, got ",
                       max_backward_steps);
  ORCHARD_CHECK_OPTION(max_bend > 0, "reconstruction check: max bend must be positive, got ", max_bend);
  ORCHARD_CHECK_OPTION(max_height_spread > 0, "reconstruction check: max height spread must be positive, got ",
                       max_height_spread);
  ORCHARD_CHECK_OPTION(max_view_angle_deg > 0 && max_view_angle_deg <= 90,
                       "reconstruction check: max view angle must be in (0, 90] degrees, got ", max_view_angle_deg);
  ORCHARD_CHECK_OPTION(max_reprojection_error_px > 0,
                       "reconstruction check: max reprojection error must be positive, got ", max_reprojection_error_px);
  ORCHARD_CHECK_OPTION(min_path_length >= 0, "reconstruction check: min path length must be >= 0, got ",
                       min_path_length);
  ORCHARD_CHECK_OPTION(below_ground_margin >= 0, "reconstruction check: below ground margin must be >= 0, got ",
                       below_ground_margin);
  ORCHARD_CHECK_OPTION(max_fruit_below_ground > 0 && max_fruit_below_ground <= 1,
                       "reconstruction check: max fruit below ground must be in (0, 1], got ", max_fruit_below_ground);
  ORCHARD_CHECK_OPTION(apple_size_quantile >= 0 && apple_size_quantile <= 1,
                       "reconstruction check: apple size quantile must be in [0, 1], got ", apple_size_quantile);
  ORCHARD_CHECK_OPTION(min_apple_size > 0 && max_apple_size > min_apple_size,
                       "reconstruction check: apple size bounds must satisfy 0 < min < max, got ", min_apple_size,
                       ", ", max_apple_size);
  ORCHARD_CHECK_OPTION(frame_spacing_reference > 0 && min_frame_spacing > 0 && max_frame_spacing > min_frame_spacing,
                       "reconstruction check: frame spacing bounds must satisfy 0 < min < max, got ",
                       min_frame_spacing, ", ", max_frame_spacing);
  ORCHARD_CHECK_OPTION(min_apple_clusters >= 1, "reconstruction check: min apple clusters must be >= 1, got ",
                       min_apple_clusters);
}

ReconstructionCheck CheckReconstruction(const std::vector<CameraView>& views, const Plane& ground,
                                        const ColmapModel* model, const ReconstructionCheckOptions& options) {
  options.Check();
  ReconstructionCheck r;
  r.frames = static_cast<int>(views.size());
  if (views.size() < 2) {
    r.warnings.push_back("fewer than two cameras: nothing to check");
    return r;
  }
  const Eigen::Vector3d up = ground.normal.normalized();
  std::vector<Eigen::Vector3d> centres;
  for (const auto& v : views) centres.push_back(v.Center());
  const size_t n = centres.size();

  // Steps between consecutive frames.
  std::vector<double> steps;
  for (size_t i = 0; i + 1 < n; ++i) steps.push_back((centres[i + 1] - centres[i]).norm());
  for (double s : steps) r.path_length += s;
  r.median_step = Quantile(steps, 0.5);

  // The path's axis in the ground plane (largest principal direction of the
  // centres projected onto it), pointing from the first frame to the last.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : centres) mean += c;
  mean /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& c : centres) {
    const Eigen::Vector3d d = c - mean;
    const Eigen::Vector3d h = d - up.dot(d) * up;
    cov += h * h.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d along = eig.eigenvectors().col(2);
  along = (along - up.dot(along) * up).normalized();
  if (along.dot(centres.back() - centres.front()) < 0) along = -along;
  const Eigen::Vector3d across = up.cross(along).normalized();
  std::vector<double> s(n), off(n);
  for (size_t i = 0; i < n; ++i) {
    s[i] = along.dot(centres[i] - mean);
    off[i] = across.dot(centres[i] - mean);
  }
  r.path_extent = *std::max_element(s.begin(), s.end()) - *std::min_element(s.begin(), s.end());

  const bool moved = r.median_step > 1e-9 && r.path_extent > 1e-9;
  if (!moved) {
    r.warnings.push_back("the cameras hardly move: no reconstruction of the row can come from this sequence");
  } else {
    for (size_t i = 0; i + 1 < n; ++i) {
      std::vector<double> around;
      for (size_t j = i > 5 ? i - 5 : 0; j < std::min(steps.size(), i + 6); ++j)
        if (j != i) around.push_back(steps[j]);
      const double local = around.empty() ? r.median_step : std::max(r.median_step, Quantile(around, 0.5));
      const double ratio = steps[i] / local;
      if (ratio > r.max_step_ratio)
        r.max_step_ratio = ratio, r.longest_step = steps[i], r.longest_step_after = views[i].name;
      const double back = s[i] - s[i + 1];
      r.backward_steps += back > 0.5 * r.median_step && back > 0.01 * r.path_extent;
    }
    double worst_off = 0;
    for (double o : off) worst_off = std::max(worst_off, std::abs(o));
    r.bend = worst_off / r.path_extent;
  }

  // Heights above the ground.
  std::vector<double> heights;
  for (const auto& c : centres) heights.push_back(ground.SignedDistance(c));
  r.height_median = Quantile(heights, 0.5);
  const double h5 = Quantile(heights, 0.05), h95 = Quantile(heights, 0.95);
  r.height_spread = r.height_median > 0 ? (h95 - h5) / r.height_median : 0;

  // Viewing direction in the ground plane against across-the-path.
  Eigen::Vector3d forward = Eigen::Vector3d::Zero();
  for (const auto& v : views) forward += v.Forward();
  forward -= up.dot(forward) * up;
  if (moved && forward.norm() > 1e-9)
    r.view_angle_deg = std::acos(std::min(1.0, std::abs(forward.normalized().dot(across)))) * 180 / M_PI;

  if (model && !model->points3D.empty()) {
    double sum = 0;
    for (const auto& [id, p] : model->points3D) sum += p.error;
    r.reprojection_error_px = sum / static_cast<double>(model->points3D.size());
  }

  // Warnings, one line each, with the likely cause.
  if (moved) {
    if (r.max_step_ratio > options.max_step_ratio)
      r.warnings.push_back(Format("camera path: a jump of %.2f m, %.1f times the steps around it,", r.longest_step,
                                  r.max_step_ratio) +
                           " after frame " + r.longest_step_after + " (frames missing, or the reconstruction broke there)");
    if (r.backward_steps > options.max_backward_steps)
      r.warnings.push_back(std::to_string(r.backward_steps) +
                           " camera steps go back along the row (a reconstruction folded on itself, or frames out of "
                           "order: frames are taken in the order of their names)");
    if (r.bend > options.max_bend)
      r.warnings.push_back(Format("camera path: %.2f m off a straight line over %.2f m along the row", r.bend * r.path_extent,
                                  r.path_extent) +
                           " (a broken reconstruction, or a path that does not follow one row)");
    if (r.view_angle_deg > options.max_view_angle_deg)
      r.warnings.push_back(Format("the cameras look %.0f degrees away from across the row (the method films the row from "
                                  "the side)",
                                  r.view_angle_deg));
  }
  if (r.height_spread > options.max_height_spread)
    r.warnings.push_back(Format("camera heights above the ground plane range from %.2f to %.2f (5th-95th percentile; the "
                                "ground plane, and the scale that rests on it, may be wrong)",
                                h5, h95));
  if (r.reprojection_error_px > options.max_reprojection_error_px)
    r.warnings.push_back(Format("the sparse points' mean reprojection error is %.2f px (check the camera model; motion blur "
                                "or a rolling shutter)",
                                r.reprojection_error_px));
  if (moved && r.path_length < options.min_path_length)
    r.warnings.push_back(Format("the camera path is only %.2f m long", r.path_length));
  return r;
}

void CheckFruitAboveGround(const std::vector<Eigen::Vector3d>& fruit_points, const Plane& ground,
                           const ReconstructionCheckOptions& options, ReconstructionCheck* check) {
  options.Check();
  if (fruit_points.empty()) return;
  int below = 0;
  for (const auto& X : fruit_points) below += ground.SignedDistance(X) < -options.below_ground_margin;
  check->fruit_below_ground = static_cast<double>(below) / static_cast<double>(fruit_points.size());
  if (check->fruit_below_ground > options.max_fruit_below_ground)
    check->warnings.push_back(Format("%.0f%% of the fruit points lie below the ground plane (the plane is wrong, e.g. "
                                     "tilted about the camera path; fallen apples and heights rest on it)",
                                     100 * check->fruit_below_ground));
}

void CheckAppleSize(std::vector<double> single_apple_radii, double apple_radius,
                    const ReconstructionCheckOptions& options, ReconstructionCheck* check) {
  options.Check();
  ORCHARD_CHECK_OPTION(apple_radius > 0, "reconstruction check: apple radius must be positive, got ", apple_radius);
  check->single_apples = static_cast<int>(single_apple_radii.size());
  if (check->single_apples < options.min_apple_clusters) return;
  check->apple_radius = Quantile(std::move(single_apple_radii), options.apple_size_quantile);
  const double ratio = check->apple_radius / apple_radius;
  if (ratio < options.min_apple_size)
    check->warnings.push_back(Format("single apples measure %.1f cm in radius at this scale, under %.2g of the "
                                     "expected %.1f cm: the scale is likely too small (camera height, ground plane); "
                                     "for small fruit give --apple-radius",
                                     100 * check->apple_radius, options.min_apple_size, 100 * apple_radius));
  else if (ratio > options.max_apple_size)
    check->warnings.push_back(Format("single apples measure %.1f cm in radius at this scale, over %.2g times the "
                                     "expected %.1f cm: the scale is likely too large (camera height, ground plane)",
                                     100 * check->apple_radius, options.max_apple_size, 100 * apple_radius));
}

void CheckFrameSpacing(double row_distance, const ReconstructionCheckOptions& options, ReconstructionCheck* check) {
  options.Check();
  if (!(row_distance > 0) || !(check->median_step > 0)) return;
  check->frame_spacing = check->median_step / row_distance;
  const double ratio = check->frame_spacing / options.frame_spacing_reference;
  if (ratio < options.min_frame_spacing)
    check->warnings.push_back(Format("frames %.1f cm apart at %.2f m from the fruit, %.2g of the spacing the 3D stage "
                                     "is tuned to: the count is likely high; keep fewer frames (--step, or "
                                     "--frame-selection motion)",
                                     100 * check->median_step, row_distance, ratio));
  else if (ratio > options.max_frame_spacing)
    check->warnings.push_back(Format("frames %.1f cm apart at %.2f m from the fruit, %.2g times the spacing the 3D "
                                     "stage is tuned to: the count is likely low; keep more frames (a smaller --step "
                                     "or --motion)",
                                     100 * check->median_step, row_distance, ratio));
}

}  // namespace orchard
