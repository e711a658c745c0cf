// Multi-view triangulation of one 3D point from its pixels in several
// registered frames (linear DLT on normalised coordinates; the usual
// starting point and, with many views, accurate enough for fruit).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "orchard/sfm/camera_view.h"

namespace orchard {

// The point seen at `pixels[i]` in `views[i]` (at least two views). Returns
// false when the views are degenerate (parallel rays, no baseline).
bool TriangulatePoint(const std::vector<const CameraView*>& views, const std::vector<Eigen::Vector2d>& pixels,
                      Eigen::Vector3d* X);

// Pixel distance between the projection of X into `view` and `pixel`; a large
// value (1e9) when X is behind the camera.
double ReprojectionError(const CameraView& view, const Eigen::Vector3d& X, const Eigen::Vector2d& pixel);

}  // namespace orchard
