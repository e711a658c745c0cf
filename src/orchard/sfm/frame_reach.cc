#include "orchard/sfm/frame_reach.h"

#include <algorithm>

#include "orchard/core/quantile.h"

namespace orchard {

FrameReach FramesReachAt(const std::vector<CameraView>& views, const Plane& ground, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& across, double distance) {
  std::vector<double> tops, bottoms;
  for (const auto& v : views) {
    const Eigen::Vector3d centre = v.Center();
    const double to_go = distance - across.dot(centre - origin);
    // The height where the ray through `pixel` meets the plane; false when it
    // runs parallel to the plane or away from it.
    auto height_at_row = [&](const Eigen::Vector2d& pixel, double* height) {
      const Eigen::Vector2d xy = v.Normalize(pixel);
      const Eigen::Vector3d ray = v.R.transpose() * Eigen::Vector3d(xy.x(), xy.y(), 1);
      const double rate = across.dot(ray);
      if (rate <= 1e-9 || to_go <= 0) return false;
      *height = ground.SignedDistance(centre + (to_go / rate) * ray);
      return true;
    };
    double top = 0, bottom = 0;
    if (!height_at_row({v.width / 2.0, 0.0}, &top)) continue;
    // A lower edge that points away from the row (a camera pitched up) shows
    // the row from its top edge down to the ground.
    if (!height_at_row({v.width / 2.0, static_cast<double>(v.height)}, &bottom)) bottom = 0;
    tops.push_back(top);
    bottoms.push_back(std::max(0.0, bottom));
  }
  FrameReach r;
  r.views = static_cast<int>(tops.size());
  if (r.views > 0) {
    r.top = Quantile(tops, 0.5);
    r.bottom = Quantile(bottoms, 0.5);
  }
  return r;
}

}  // namespace orchard
