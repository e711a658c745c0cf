// A registered frame as the 3D stages use it: intrinsics and world-to-camera
// pose from a COLMAP model, projection of world points to pixels and back
// projection of pixels to rays. Pixel coordinates follow COLMAP (the centre
// of the top-left pixel is (0.5, 0.5)).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "orchard/sfm/colmap_model.h"

namespace orchard {

struct CameraView {
  std::string name;  // image file name
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0;  // radial distortion (SIMPLE_RADIAL / RADIAL first term), 0 for pinhole
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // world-to-camera
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // Camera axes in world coordinates (COLMAP: x right, y down, z forward).
  Eigen::Vector3d Forward() const { return R.row(2).transpose(); }
  Eigen::Vector3d Down() const { return R.row(1).transpose(); }
  // Pixel of world point X; false when X is behind the camera or the pixel
  // falls outside the image.
  bool Project(const Eigen::Vector3d& X, Eigen::Vector2d* pixel) const;
  // Normalised (undistorted) image coordinates of a pixel: the ray direction in
  // camera coordinates is (x, y, 1).
  Eigen::Vector2d Normalize(const Eigen::Vector2d& pixel) const;
  // Depth of X along the optical axis.
  double Depth(const Eigen::Vector3d& X) const { return R.row(2).dot(X) + t.z(); }
};

// The model's images as views, sorted by image name (the frame order of a
// sequence). Supports the SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL and RADIAL
// camera models (RADIAL's k2 is ignored); throws orchard::Error on others.
std::vector<CameraView> ViewsFromColmapModel(const ColmapModel& model);

// Scales a reconstruction about the world origin (camera centres scale by s,
// rotations stay): t -> s * t.
void ScaleViews(double s, std::vector<CameraView>* views);

}  // namespace orchard
