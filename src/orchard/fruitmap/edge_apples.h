// Apples seen only as slivers at the frames' top edge. When the canopy
// reaches above the frames, an apple hanging at the top edge shows a few rows
// of pixels (its lower part) in one to four scattered frames: too few, and too
// far from its centre, for a triangulated fruit point (docs/side.md, "What the
// missed apples show"). What a sliver does tell is its column: a disc cut by a
// horizontal line is cut symmetrically, so the sliver's middle is the apple's
// column, and the apple hangs where the frame's top edge meets it. Slivers no
// kept cluster explains are grouped across frames by where their rays cross
// (the camera moves along the row, so two sightings of one apple fix its
// distance), and each group is one apple at the row.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "orchard/fruitmap/fruit_points.h"
#include "orchard/sfm/camera_view.h"

namespace orchard {

struct EdgeAppleOptions {
  // Count apples seen only at the frames' top edge (false: the 3D stage's
  // clusters alone).
  bool enabled = true;
  // A blob is at the top edge when it reaches into the first `edge_rows`
  // rows of pixels.
  int edge_rows = 2;
  // A sighting shows at least this many pixels (its pieces in the frame
  // together). 0 = auto (RunSide decides; FindEdgeSightings takes 0 as 20):
  // 20 for annotated instance masks (the generator's visibility threshold,
  // the smallest piece an annotator marks), 50 for a detector's blobs, whose
  // small pieces at the edge are often leaves: on four default-pipeline rows
  // 18 of the 33 U-Net edge apples from 20 px lay on an apple, 12 of 15
  // from 50 px (docs/side.md, "Apples at the frames' top edge").
  int min_pixels = 0;
  // An apple's radius (m): pieces of one sliver in a frame span at most two
  // radii at the row, and a kept cluster's fruit point explains a sliver when
  // it projects within a radius (at its depth) of the sliver's box vertically
  // and within explain_across times that of its columns: the neighbour of a
  // tracked apple at the edge is not explained by it.
  double apple_radius = 0.04;
  double explain_across = 0.5;
  // Sightings at most this many frames apart may be one apple.
  int window = 13;
  // Where a group's rays cross must lie in the row's fruit: from this far in
  // front of the row distance to this far behind it (m).
  double near_margin = 0.6;
  double far_margin = 1.0;
  // Three or more sightings of one apple: each ray passes this close (m) to
  // the crossing.
  double max_ray_distance = 0.04;
  void Check() const;
};

// A sliver at the top edge in one frame: its pieces' blobs, their pixels and
// the ray through the middle of its columns along the top edge.
struct EdgeSighting {
  int frame = 0;
  std::vector<int> blobs;
  int pixels = 0;
  double column = 0;  // COLMAP pixel x of the sliver's middle
  Eigen::Vector3d origin = Eigen::Vector3d::Zero(), direction = Eigen::Vector3d::UnitZ();
};

// The side's row frame (ClusterResult: origin on the ground under the camera
// path, along, across towards the row, up) and the row distance.
struct RowFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d along = Eigen::Vector3d::UnitX(), across = Eigen::Vector3d::UnitY(),
                  up = Eigen::Vector3d::UnitZ();
  double row_distance = 0;
};

// Slivers at the top edge of every frame that no point of `explained` (the
// kept clusters' fruit points) lies on: a point explains a sliver when it
// projects within an apple's radius (at its depth) of the sliver's box,
// above the frame included. Pieces within two apple radii at the row distance
// are one sliver.
std::vector<EdgeSighting> FindEdgeSightings(const std::vector<CameraView>& views,
                                            const std::vector<FruitFrame>& frames,
                                            const std::vector<Eigen::Vector3d>& explained, const RowFrame& row,
                                            const EdgeAppleOptions& options);

// Where a sighting's ray lies `distance` across the row from the camera path.
Eigen::Vector3d SightingAtDistance(const EdgeSighting& sighting, const RowFrame& row, double distance);

// One apple seen only at the top edge: its sightings and where it hangs (the
// top edge's height at the rays' crossing; a lone sighting at the row
// distance).
struct EdgeApple {
  std::vector<int> sightings;  // indices into the sightings
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> sighting_points;  // each sighting's ray at the apple's distance
  double distance = 0;                           // across the row from the camera path (m)
  bool crossed = false;                          // the distance came from crossing rays
};

// Groups the sightings (in frame order) into apples: a sighting joins the
// group of the nearest earlier frame within the window whose rays it crosses
// in the row's fruit (and, from three sightings on, close to every ray);
// else it starts one. Two sightings in one frame are two apples.
std::vector<EdgeApple> GroupEdgeSightings(const std::vector<EdgeSighting>& sightings, const RowFrame& row,
                                          const EdgeAppleOptions& options);

}  // namespace orchard
