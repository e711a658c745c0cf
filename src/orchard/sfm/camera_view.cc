#include "orchard/sfm/camera_view.h"

#include <algorithm>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

bool CameraView::Project(const Eigen::Vector3d& X, Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d x = R * X + t;
  if (x.z() <= 1e-9) return false;
  double u = x.x() / x.z(), v = x.y() / x.z();
  if (k1 != 0) {
    const double f = 1 + k1 * (u * u + v * v);
    u *= f, v *= f;
  }
  *pixel = {fx * u + cx, fy * v + cy};
  return pixel->x() >= 0 && pixel->y() >= 0 && pixel->x() < width && pixel->y() < height;
}

Eigen::Vector2d CameraView::Normalize(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d d((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  if (k1 == 0) return d;
  // Invert d = u * (1 + k1 |u|^2) by fixed-point iteration (converges for the
  // small distortions of real lenses).
  Eigen::Vector2d u = d;
  for (int i = 0; i < 20; ++i) u = d / (1 + k1 * u.squaredNorm());
  return u;
}

std::vector<CameraView> ViewsFromColmapModel(const ColmapModel& model) {
  std::vector<CameraView> views;
  for (const auto& [id, image] : model.images) {
    const auto cam_it = model.cameras.find(image.camera_id);
    if (cam_it == model.cameras.end()) Fail("image ", image.name, " refers to missing camera ", image.camera_id);
    const ColmapCamera& cam = cam_it->second;
    CameraView v;
    v.name = image.name;
    v.width = cam.width, v.height = cam.height;
    const auto& p = cam.params;
    if (cam.model == "SIMPLE_PINHOLE" || cam.model == "SIMPLE_RADIAL" || cam.model == "RADIAL") {
      v.fx = v.fy = p.at(0), v.cx = p.at(1), v.cy = p.at(2);
      if (cam.model != "SIMPLE_PINHOLE") v.k1 = p.at(3);
    } else if (cam.model == "PINHOLE") {
      v.fx = p.at(0), v.fy = p.at(1), v.cx = p.at(2), v.cy = p.at(3);
    } else {
      Fail("camera model ", cam.model, " of image ", image.name,
           " is not supported (use SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL)");
    }
    v.R = image.Rotation();
    v.t = image.tvec;
    views.push_back(std::move(v));
  }
  std::sort(views.begin(), views.end(), [](const CameraView& a, const CameraView& b) { return NaturalLess(a.name, b.name); });
  return views;
}

void ScaleViews(double s, std::vector<CameraView>* views) {
  for (CameraView& v : *views) v.t *= s;
}

}  // namespace orchard
