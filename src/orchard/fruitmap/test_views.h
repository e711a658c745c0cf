// Test helper: the camera the fruitmap tests film a row with.
#pragma once

#include "orchard/sfm/camera_view.h"

namespace orchard::test {

// A camera at (x, -2.5, 1.5) looking along +y (world z up), 640x480, f = 500:
// its top edge meets the plane y = 0 (2.5 m away) 2.7 m up.
inline CameraView ViewAt(double x) {
  CameraView v;
  v.name = "f";
  v.width = 640, v.height = 480;
  v.fx = v.fy = 500, v.cx = 320, v.cy = 240;
  // Camera axes in world: x_cam = +x, y_cam = -z (down), z_cam = +y.
  v.R << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  v.t = -v.R * Eigen::Vector3d(x, -2.5, 1.5);
  return v;
}

}  // namespace orchard::test
