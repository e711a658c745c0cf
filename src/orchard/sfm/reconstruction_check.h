// Signs that a side's reconstruction is broken, so that a count from it is
// never reported without saying so. A row video is a walk along the row: the
// camera path is nearly straight, moves forward in steady steps, keeps its
// height above the ground and looks across the row. COLMAP can register every
// frame and still break these (a sequence folded back on itself in repetitive
// foliage, frames out of order, a jump where frames are missing, a ground
// plane fitted to the wrong surface, which also gives the wrong scale).
#pragma once

#include <string>
#include <vector>

#include "orchard/sfm/camera_view.h"
#include "orchard/sfm/colmap_model.h"
#include "orchard/sfm/ground_plane.h"

namespace orchard {

struct ReconstructionCheckOptions {
  // A step between consecutive frames longer than this many times the steps
  // around it (the median of the 5 before and after, but at least the
  // sequence's median step) is a jump (frames missing, or the reconstruction
  // broke there); measured locally so that a walk that stops and goes on is
  // no jump. Synthetic rows, true poses and COLMAP: at most 1.4.
  double max_step_ratio = 4;
  // A step that goes back along the path by more than half the median step
  // (and more than 1% of the path's extent) is a backward step: a folded
  // reconstruction or frames out of order. Warn when there is any.
  int max_backward_steps = 0;
  // Largest distance of a camera from the straight line through the path, in
  // the ground plane, as a fraction of the path's extent along the row.
  double max_bend = 0.1;
  // Spread of the cameras' heights above the ground plane (5th to 95th
  // percentile) as a fraction of their median: a ground plane fitted to the
  // wrong surface, or tilted against the path.
  double max_height_spread = 0.2;
  // Largest angle (degrees) between the cameras' mean viewing direction and
  // the direction across the path, in the ground plane: the method films the
  // row from the side.
  double max_view_angle_deg = 45;
  // Mean reprojection error of the sparse points (pixels); COLMAP's own
  // filter keeps points up to 4 px, good sequences average below 1.
  double max_reprojection_error_px = 2;
  // Shortest camera path (m, after scaling) worth a reconstruction.
  double min_path_length = 1.0;
  // Fruit points more than `below_ground_margin` (m) below the ground plane:
  // nothing lies below the ground, so more than this fraction of them means
  // the plane is wrong, e.g. tilted about the path, which the cameras'
  // heights do not show (seed 12's back with --ground-below-penalty 0: 33%;
  // good planes: exact masks 0-0.03%, the U-Net's chance points about 1%).
  double below_ground_margin = 0.1;
  double max_fruit_below_ground = 0.05;
  // The radius single apples (clusters counted one apple) show at their
  // depth, its 75th percentile over the clusters (the chance clusters, most of
  // them small pieces, fill the lower half), against the expected apple
  // radius: outside these fractions of it the scale is likely wrong (a camera
  // height or a ground plane off by 2x or more). Measured against 3 cm on
  // sides at the right scale: exact masks 1.38-1.55x, the U-Net 1.52-2.63x
  // (20 COLMAP sides of seeds 245-254, the flat rows highest; its blobs are
  // larger than the apple). Seed 246's front at scales 2x too large and too
  // small: exact masks 2.69x (passes) and 0.57x, the U-Net 4.0x and 0.88x
  // (passes).
  double apple_size_quantile = 0.75;
  double min_apple_size = 0.6;
  double max_apple_size = 3.5;
  int min_apple_clusters = 10;  // fewer single apples: no check
  // The frames' spacing: the median camera step over the distance to the
  // fruit wall (the row distance the clusters find), i.e. the view change
  // per frame in radians. The 3D stage counts frames (support, partners,
  // views), so it is tuned to a spacing: the synthetic rows' 12.5 cm at
  // about 2.2 m, 0.050-0.062 on 91 default-rate sides. On four fresh rows filmed at 5,
  // 8, 12 and 16 frames per second (spacing 0.083-0.095, 0.053-0.061,
  // 0.035-0.040, 0.027-0.031) the sides' mean error went −2.6, −1.4, +1.2,
  // +3.0%: denser frames count high, sparser ones low. Warn outside these
  // fractions of the reference.
  double frame_spacing_reference = 0.057;
  double min_frame_spacing = 0.6;
  double max_frame_spacing = 1.4;
  void Check() const;
};

struct ReconstructionCheck {
  int frames = 0;
  double path_length = 0;     // sum of the steps (m, in the views' units)
  double path_extent = 0;     // first to last camera along the path's axis
  double median_step = 0;
  double max_step_ratio = 0;  // largest step / the steps around it
  double longest_step = 0;    // that step (m)
  std::string longest_step_after;  // frame name before it
  int backward_steps = 0;
  double bend = 0;            // largest distance off the line / extent
  double height_median = 0;   // cameras' height above the ground
  double height_spread = 0;   // (95th - 5th percentile) / median
  double view_angle_deg = 0;  // mean viewing direction against across-the-path
  double reprojection_error_px = -1;  // mean over the sparse points; -1 without points
  double fruit_below_ground = -1;     // fraction of the fruit points; -1 before CheckFruitAboveGround
  double apple_radius = -1;           // single apples' radius (m, the quantile); -1 before CheckAppleSize or with too few
  int single_apples = 0;              // clusters it is taken over
  double frame_spacing = -1;          // median step / row distance; -1 before CheckFrameSpacing
  std::vector<std::string> warnings;  // one line each; empty when nothing looks wrong
};

// Checks `views` (in frame order) against `ground`, both in metric units (the
// side's scale applied). `model` may be null or hold no 3D points (given
// poses); the reprojection check is then skipped.
ReconstructionCheck CheckReconstruction(const std::vector<CameraView>& views, const Plane& ground,
                                        const ColmapModel* model, const ReconstructionCheckOptions& options);

// Adds the share of `fruit_points` (metric, like `ground`) below the ground
// plane to `check`, and a warning when it is too large.
void CheckFruitAboveGround(const std::vector<Eigen::Vector3d>& fruit_points, const Plane& ground,
                           const ReconstructionCheckOptions& options, ReconstructionCheck* check);

// Adds the `apple_size_quantile` of `single_apple_radii` (the radius each
// cluster counted as one apple shows at its depth, metric) to `check`, and a warning when it is
// far from `apple_radius`: apples have a size, so they tell a gross scale
// error that the camera path cannot show.
void CheckAppleSize(std::vector<double> single_apple_radii, double apple_radius,
                    const ReconstructionCheckOptions& options, ReconstructionCheck* check);

// Adds the frames' spacing (check->median_step over `row_distance`, both
// metric) to `check`, and a warning when it is far from the spacing the 3D
// stage is tuned to, saying how to change it. No-op for a row distance <= 0.
void CheckFrameSpacing(double row_distance, const ReconstructionCheckOptions& options, ReconstructionCheck* check);

}  // namespace orchard
