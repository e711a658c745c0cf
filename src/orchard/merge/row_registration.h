// Registration of the two sides on the row itself, for sides that share too
// few detected fruit clusters for registration.h (the project's detectors
// find about half of the apples, and few of the same ones from both sides).
// Both sides are first levelled on the ground their sparse points show, so
// that their ground planes coincide and their scales agree; the heading
// comes from the canopy's direction in each row frame, the offset along the
// row from correlating the two sides' canopy profiles (the row's ends and
// gaps are seen from both sides), and the distance across from the fruit
// clusters that both sides see, or, with too few, from the trunks both
// sides' sparse points show, or from an assumption (below).
// The heading is kept at the half turn: each row frame's x axis is fitted to
// its camera path, and the paths run along the row.
// Needs COLMAP's sparse points on both sides (given poses come without).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "orchard/merge/registration.h"
#include "orchard/merge/side_cloud.h"

namespace orchard {

struct RowRegistrationOptions {
  // The camera height (m) each side was scaled to (the side's
  // --camera-height); the levelling keeps the cameras this high above the
  // ground it finds.
  double camera_height = 1.5;
  // The ground is the lowest 5 cm slab of sparse points below the cameras
  // holding this fraction of them, refined as a plane through the points
  // within `ground_layer` (m) of it. The side's own fit can pick the canopy's
  // lower edge instead (seed 11, back: 1.5 m too high, scale off 2x).
  double min_ground_fraction = 0.02;
  double ground_layer = 0.15;
  // A side whose ground lies farther than this (m) from its z = 0, or tilted
  // more than `max_ground_tilt_deg`, is re-levelled (and rescaled).
  double max_ground_offset = 0.1;
  double max_ground_tilt_deg = 1.0;
  // Canopy: sparse points between these heights (m), from the nearest dense
  // layer across the row (the face the camera sees) to `canopy_depth` (m)
  // beyond it, which keeps the next row out.
  double canopy_min_height = 0.3;
  double canopy_max_height = 3.5;
  double canopy_depth = 1.0;
  int min_canopy_points = 100;
  // Along-row profiles: bin (m), Gaussian smoothing (m), largest offset
  // searched (m), and the correlation below which the two sides are taken as
  // different rows or stretches (seed 11's two sides: 0.95; the front of
  // seed 11 with the back of seed 12, a row of the same layout: 0.82).
  double profile_bin = 0.05;
  double profile_smoothing = 0.1;
  double max_along = 4.0;
  double min_correlation = 0.9;
  // The sides' canopies must overlap along the row by this fraction of the
  // shorter one.
  double min_overlap = 0.5;
  // Across: cluster centres closer than `match_distance` (m) are the same
  // fruit; the search covers the along offset +- `along_window` (m) and the
  // distance across from the two canopy faces' sum to `max_thickness` (m)
  // beyond it, in `grid_step` (m). It takes the fruit's answer when it
  // matches at least `min_matched` clusters and `min_distinctness` times as
  // many as any alignment farther than 0.25 m across. Seed 11 (COLMAP, commit
  // 17a4ff3's sides): 7, 10 and 4 matched against 3, 4 and 2 elsewhere put the
  // sides 7, 7 and 15 cm too close (chance matches, and each side's fruit
  // points lie towards its own camera), hence 3x.
  double match_distance = 0.08;
  double along_window = 0.15;
  double max_thickness = 3.0;
  double grid_step = 0.01;
  int min_matched = 3;
  double min_distinctness = 3;
  // Otherwise, when the trunks (below) do not show, each side is assumed to
  // see into the canopy up to the row's centre plane: the centre lies at this
  // quantile of the side's canopy points' distances (chosen on seed 11, the
  // one row with COLMAP runs: 0.95 puts the sides 1 cm from the truth, 0.9 20
  // cm short; through a 0.5 m canopy it puts them 0.25-0.35 m too far apart).
  double centre_quantile = 0.95;
  // Trunks (FindTrunks), the measured alternative to that assumption: the
  // sparse points under the canopy and above the grass, between these
  // heights (m), from the canopy's face to `trunk_depth` (m) beyond it (past
  // the centre of a 3 m canopy; the next row's trunks stand a row spacing
  // farther), binned along the row every `trunk_bin` (m). A trunk is a peak
  // of at least `min_trunk_points` points within `trunk_width` (m) of it and
  // `trunk_contrast` times the band's median, the middle half of them spread
  // over `min_trunk_span` (m) of height (a column: 0.047-0.24 m on the 123
  // trunks of the rows below; a clod's lie within a few cm), at least
  // `min_trunk_spacing` (m) from a stronger peak. On 16 synthetic rows
  // (trunks 4.5 cm in radius with a stake, canopy from 0.5 m, COLMAP) this
  // finds 3-4 of the 4 trunks on every side (docs/yield.md, "Trunks").
  double trunk_min_height = 0.12;
  double trunk_max_height = 0.45;
  double trunk_depth = 1.5;
  double trunk_bin = 0.05;
  double trunk_width = 0.1;
  int min_trunk_points = 8;
  double trunk_contrast = 3;
  double min_trunk_span = 0.04;
  double min_trunk_spacing = 0.5;
  // The distance across comes from the trunks when each side shows this
  // many (the median of each side's trunks' distances).
  int min_trunks = 2;
  // `orchard yield` warns when the fruit's distance across and the trunks'
  // differ by more than this (m): 0.5-6.3 cm on 16 COLMAP rows.
  double max_trunk_disagreement = 0.25;
  // That assumption, and the trunks, hold for any row of the same planting:
  // the sides of two different synthetic rows correlated 0.971 and 0.986, a
  // row's own sides 0.944-0.993 (docs/yield.md). So without fruit seen from
  // both sides the registration stops, unless the user says both videos film
  // the same row.
  bool assume_same_row = false;
  // Turn the back by the angle between the two sides' canopy lines instead
  // of keeping the half turn (off: on seed 11 the lines' angle was 0.97 deg,
  // the truth 0.10 deg).
  bool heading_from_canopy = false;
  double max_heading_deg = 8;
  void Check() const;
};

// A tree trunk in a side's sparse points (row frame, m): where it stands
// along the row, how far its near face is from the camera path, and the
// points that show it.
struct Trunk {
  double along = 0;
  double across = 0;
  int points = 0;
};

// The trunks the side's sparse points show, ordered along the row; none
// without sparse points (given poses) or canopy.
std::vector<Trunk> FindTrunks(const SideCloud& side, const RowRegistrationOptions& options);

// The distance between the two camera paths the sides' trunks (FindTrunks)
// give: the median of each side's trunks' distances, added (the sides face
// each other across the trunks). NaN when a side shows fewer than
// options.min_trunks.
struct TrunkAcross {
  int front = 0, back = 0;  // trunks found
  double across = std::nan("");
};
TrunkAcross AcrossFromTrunks(const std::vector<Trunk>& front, const std::vector<Trunk>& back,
                             const RowRegistrationOptions& options);

// A tree of the row, from the trunks: where it stands along the row (front
// row frame, m) and which sides show its trunk.
struct RowTree {
  double along = 0;
  bool front = false, back = false;
};

// The row's trees from both sides' trunks, the back's already in the front
// frame (Trunk::along only is read): trunks of the two sides within
// `merge_distance` (m) along the row are one tree, at their mean; ordered
// along the row.
std::vector<RowTree> TreesFromTrunks(const std::vector<Trunk>& front, const std::vector<Trunk>& back_in_front,
                                     double merge_distance);

// The tree a position along the row belongs to: the nearest, if it lies
// within half the spacing to the next tree on that side (at the row's ends
// the spacing on the inner side; a lone tree `lone_half_width`); -1 when
// none.
int TreeAt(const std::vector<RowTree>& trees, double along, double lone_half_width);

// What the levelling did to one side.
struct Levelling {
  bool changed = false;
  int ground_points = 0;     // sparse points in the ground layer
  double ground_height = 0;  // the ground found, in the side's frame (m, below the cameras)
  double tilt_deg = 0;       // its tilt against the side's ground plane
  double scale = 1;          // applied to the side's coordinates
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();  // old row frame -> levelled one
};

// Finds the ground in the side's sparse points and, when it is not the
// side's z = 0 plane, moves the side (sparse and fruit points) onto it:
// level, the cameras `camera_height` above it, or, with `keep_scale` (given
// poses taken as metric), level and on it at the side's own scale. No-op
// without sparse points.
Levelling LevelOnSparseGround(SideCloud* side, const RowRegistrationOptions& options, bool keep_scale = false);

// The canopy profiles' correlation along the row with the back placed by
// `back_to_front`: a check on an alignment found from the fruit (few
// clusters can match by chance). NaN when a side has too few sparse canopy
// points.
double CanopyProfileCorrelation(const SideCloud& front, const SideCloud& back, const Eigen::Isometry3d& back_to_front,
                                const RowRegistrationOptions& options);

// Registers the (levelled) sides on the row. Throws orchard::Error with the
// reason when a side has too few sparse canopy points, when the canopy
// profiles do not correlate ("not the same row"), or when the sides cover
// different stretches.
Registration RegisterSidesOnRow(const SideCloud& front, const SideCloud& back, const RowRegistrationOptions& options);

}  // namespace orchard
