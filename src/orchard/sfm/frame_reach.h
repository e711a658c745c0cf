// How high the frames reach on the filmed row: the heights above the ground
// where the frames' top and bottom edges meet the row. Apples hanging above
// the top edge are in no frame, so no method counts them; the generator's
// default 16:9 frames end 2.4 m up under a 3.0 m canopy and see 83-90% of
// the harvested apples (docs/yield.md, "Frames that show the canopy's top").
// A user compares the reach with the canopy's height.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "orchard/sfm/camera_view.h"
#include "orchard/sfm/ground_plane.h"

namespace orchard {

struct FrameReach {
  // Medians over the views (m above the ground, once the poses are metric).
  // bottom is 0 when the lower edge meets the ground before the row.
  double top = 0, bottom = 0;
  int views = 0;  // views whose top edge reaches the row (0: top and bottom unset)
};

// Where each view's top and bottom edges, at the image's middle column, meet
// the vertical plane `distance` across from `origin` along `across` (the
// side's row frame: origin on the ground under the camera path, across
// towards the filmed row). Views facing away from the plane are left out.
FrameReach FramesReachAt(const std::vector<CameraView>& views, const Plane& ground, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& across, double distance);

}  // namespace orchard
