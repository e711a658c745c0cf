// Apples glimpsed through the leaves: small pieces of one apple in scattered
// frames whose centres wander with the leaves in front of them, so no pairing
// of two centres triangulates to a point the other frames support (two thirds
// of a side's misses with exact masks; docs/side.md, "What the misses are").
// What a piece does tell is that it lies inside the apple's disc in every
// frame that shows it. Pieces no cluster explains are searched for a sphere
// of apple size (centres along rays through the disc around a piece, depths
// through the row's fruit and the next row's) whose disc holds a free piece
// in several frames; each such sphere in front of the depth cut-off is one
// apple. Most free pieces are the next row's apples seen through gaps in the
// filmed row's leaves: a gap is a window at the row's depth, and pieces of
// different apples seen through it in successive frames move like one object
// there. They are no wider than a whole apple of the next row, so a piece
// must span a good part of the sphere's disc (min_extent; docs/side.md,
// "Apples glimpsed through the leaves").
#pragma once

#include <vector>

#include <Eigen/Core>

#include "orchard/fruitmap/edge_apples.h"
#include "orchard/fruitmap/fruit_points.h"
#include "orchard/sfm/camera_view.h"

namespace orchard {

struct GlimpsedAppleOptions {
  // Search for glimpsed apples (false: the clusters and edge apples alone)
  // ... also among a detector's blobs (RunSide decides, ResolvedGlimpsedApples).
  // With instance masks it takes the sides within 3% from 103 to 107 of 108
  // (54 rows; docs/side.md). With the U-Net's blobs a quarter of what it
  // adds is a visible apple: the sides come nearer (MAE 8.7 -> 7.0%, all
  // low) but the rows go further off (MAE 5.9 -> 6.2%; 22 rows): off there.
  bool enabled = true;
  bool with_detector = false;
  // A piece shows at least this many pixels (the generator's visibility
  // threshold, the smallest piece an annotator marks).
  int min_pixels = 20;
  // The largest apple's radius (m): a piece lies inside this disc at the
  // sphere's depth (the synthetic rows' apples are 3-5 cm).
  double apple_radius = 0.05;
  // A kept cluster's point explains a piece whose centre lies within this
  // (m, at the point's depth) of the point's projection.
  double explain_radius = 0.04;
  // Frames either side of a piece's frame that may show the same apple.
  int window = 6;
  // A sphere holds a free piece inside its disc in at least this many frames
  // (its own piece's included) and in this fraction of the frames whose
  // image its centre falls into.
  int min_support = 3;
  double min_support_ratio = 0.25;
  // Depth steps (m, across the row) and in-image steps (fraction of the
  // disc's radius) of the search.
  double depth_step = 0.02;
  double offset_step = 0.34;
  // The sphere's centre lies from this far in front of the row distance to
  // the depth cut-off (m).
  double near_margin = 0.3;
  // The search goes on this far (m) behind the depth cut-off, so that
  // spheres there (the next row's apples) take the pieces they explain; only
  // apples in front of the cut-off are counted.
  double far_search = 3.0;
  // A supporting piece's longest chord is at least this many times the
  // disc's radius: three quarters of a 5 cm apple's width. Smaller pieces
  // may be the next row's apples (its pieces are at most a whole apple 5-6 m
  // away). 1.5 against 1.8: sides within 3% 107 against 106 of 108 (54 rows,
  // exact masks; docs/side.md).
  double min_extent = 1.5;
  // Each piece's line of sight through the apple is passed to the merge from
  // this far (m, across the row) in front of the sphere to this far behind:
  // the sphere's depth is loose (the disc of the largest apple), and the
  // other side's cluster of the apple lay up to 0.75 m from it. 0.3 -> 0.6:
  // of 70 rows (exact masks) 8 totals came nearer the truth, 3 went 1 apple
  // farther; 1.0 moved 4 more by 1 apple, 3 of them nearer (docs/yield.md).
  double ray_margin = 0.6;
  void Check() const;
};

// One glimpsed apple: where it hangs and the (frame, blob id) pieces that
// show it, with each piece's ray at the apple's depth.
struct GlimpsedApple {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  std::vector<std::pair<int, int>> pieces;
  std::vector<Eigen::Vector3d> piece_points;
  // Each piece's frame's line of sight through the centre, from ray_margin
  // in front of it to ray_margin behind (pieces whose line of sight does
  // not run across the row have none), and the centre's column there.
  struct SightRay {
    Eigen::Vector3d near = Eigen::Vector3d::Zero(), far = Eigen::Vector3d::Zero();
    double column = 0;
  };
  std::vector<SightRay> rays;
  double distance = 0;  // across the row from the camera path (m)
  double error = 0;     // mean piece-centre offset from the disc's centre / disc radius
};

// The glimpsed apples among the pieces of `frames` that no point of
// `explained` explains, their centres from row.row_distance - near_margin
// to `depth_cutoff` across the row; strongest first, each piece in one apple.
std::vector<GlimpsedApple> FindGlimpsedApples(const std::vector<CameraView>& views,
                                              const std::vector<FruitFrame>& frames,
                                              const std::vector<Eigen::Vector3d>& explained, const RowFrame& row,
                                              double depth_cutoff, const GlimpsedAppleOptions& options);

}  // namespace orchard
