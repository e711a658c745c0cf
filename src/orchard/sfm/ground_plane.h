// The ground plane of a row reconstruction and the metric scale it gives:
// a robust (RANSAC) plane fit to 3D points, restricted to planes roughly
// perpendicular to the cameras' up direction and below all cameras, so the
// fruit wall or the camera path never wins; the scale then follows from the
// cameras' known height above the ground.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "orchard/sfm/camera_view.h"

namespace orchard {

// n . X + d = 0 with |n| = 1, n pointing up (towards the cameras).
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double d = 0;
  double SignedDistance(const Eigen::Vector3d& X) const { return normal.dot(X) + d; }
};

struct GroundPlaneOptions {
  // RANSAC hypotheses (three points each).
  int iterations = 2000;
  // Inlier distance as a fraction of the median camera-to-point distance (the
  // reconstruction has no scale yet): 2% is ~5 cm at a 2.5 m working distance.
  double inlier_fraction = 0.02;
  // Largest angle between the plane normal and the cameras' mean up vector:
  // the camera's pitch, as a row is filmed with the camera about level. The
  // ground lay 4.2-5.2 degrees off on 62 COLMAP sides (the generator
  // pitches the camera 5 degrees down); at 30, three of five two-tree rows'
  // backs took a surface rising 19-20 degrees away with more points,
  // scaling them 0.69x (docs/side.md). Raise it for a camera pitched more.
  double max_tilt_deg = 15;
  // A second RANSAC among the first one's inliers, with this tighter
  // inlier distance (same scale as inlier_fraction; 0: none): the ground's
  // points form a thin layer (about 1 cm thick at 3 m), and the wide band of
  // the first fit also takes trunk bases, weeds, low leaves and fallen fruit
  // above it, which tilted the least-squares plane. On 20 sides of true poses
  // with triangulated points the plane under the row went from 13 mm mean /
  // 30 mm largest above the truth (one side tilted 8 deg) to 3 / 7 mm; on 19
  // COLMAP sides the scale from the camera height from 1.5% mean / 8.5%
  // largest off to 0.6% / 1.5% (docs/side.md, forty-second session).
  double fine_inlier_fraction = 0.005;
  // Fewest inliers for a ground plane.
  int min_inliers = 15;
  // A candidate's score is its inliers minus this many times the points
  // well below it (beyond the inlier distance): the ground is the lowest
  // surface, while a plane through the canopy's lower edge has the ground
  // below it. With inliers alone, seed 11's back side took a plane 0.75 m up
  // (scale 2x off) and seed 12's back one tilted by 20 degrees; 0.25 fixes
  // both and leaves seed 11's front as it was (1 moved it by 2%).
  double below_penalty = 0.25;
  std::uint64_t seed = 1;
  void Check() const;
};

// The ground plane of `points`; `up` is the cameras' mean up direction and
// `camera_centres` must all lie above the plane. Throws orchard::Error when
// no plane has enough inliers (too few points on the ground).
// `above` (may be null): points known to lie above the ground (the fruit);
// each one below a candidate plane (beyond the inlier distance) costs
// `above_penalty` inliers, for a refit when a first plane cut through the
// fruit.
Plane FitGroundPlane(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& camera_centres,
                     const Eigen::Vector3d& up, const GroundPlaneOptions& options, int* num_inliers = nullptr,
                     const std::vector<Eigen::Vector3d>* above = nullptr, double above_penalty = 1);

// Mean up direction of the cameras (minus their image y axes), unit length.
Eigen::Vector3d MeanCameraUp(const std::vector<CameraView>& views);

// The factor that makes the median camera height above `ground` equal
// `camera_height` (metres). Throws when the cameras are not above the plane.
double ScaleFromCameraHeight(const Plane& ground, const std::vector<CameraView>& views, double camera_height);

}  // namespace orchard
