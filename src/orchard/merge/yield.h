// The whole row: both sides counted in 3D (fruitmap/side.h), registered
// (registration.h), apples seen from both sides counted once
// (shared_count.h), and the row's outputs: yield.json, clusters.csv, row.ply
// and report.html. `orchard yield` and `orchard demo` run it.
#pragma once

#include <filesystem>
#include <string>

#include "orchard/fruitmap/side.h"
#include "orchard/merge/face_check.h"
#include "orchard/merge/registration.h"
#include "orchard/merge/row_registration.h"
#include "orchard/merge/shared_count.h"

namespace orchard {

namespace fs = std::filesystem;

struct YieldOptions {
  // For the merge, each side's clusters need 4 fruit points here (1 for
  // `orchard side`) and ghosts (clusters whose points land mostly on other
  // clusters' blobs) are dropped: a one-side count profits from chance
  // clusters that make up for missed apples, but in the union of two sides
  // both sides' chance clusters add up. 4 points centre the merged totals
  // best (5 ran low, 3 high; docs/yield.md, "Four fruit points"). The
  // per-side counts reported are each side's own count under `orchard side`'s
  // rules, on the same fruit points: the merge's clusters count a side alone low.
  // The merge's clusters are counted in their views with the most fruit
  // pixels (the study's rule) even with instance masks: a group of clusters
  // seen from both sides holds the larger of the two sides' counts, and the
  // larger of two counts from each side's highest views came out high
  // (exact masks: 1 of 5 unseen rows within 2% against 5 of 5; docs/yield.md).
  YieldOptions() {
    side.clusters.min_points = 4;
    side.clusters.max_lost_fraction = 0.6;
    side.clusters.best_views_by = ClusterOptions::BestViews::kPixels;
  }
  SideOptions side;
  RegistrationOptions registration;
  // When the fruit clusters do not register the sides and both have COLMAP's
  // sparse points: level them on their ground and register them on the row
  // (row_registration.h). Its camera height is taken from `side`.
  bool row_registration = true;
  RowRegistrationOptions row;
  // The clusters each side removed as fallen join the kept ones as landmarks
  // for the registration (never counted): apples lying under the row are seen
  // from both sides even where the canopy hides the hanging ones. A thick
  // canopy (seed 354, COLMAP, U-Net) was ambiguous on its fruit (12 matched,
  // 8 elsewhere) and registers with them (19); rows 346-353 move by at most
  // 0.16 deg and 1.2 cm (docs/yield.md).
  bool fallen_landmarks = true;
  // The two videos must show opposite faces of the row (face_check.h); off
  // for the rare rows whose two faces look alike to a feature matcher.
  bool face_check = true;
  FaceCheckOptions faces;
  SharedCountOptions shared;
  // The shared count's intersection distance grows with the reconstruction's
  // error: at least this many times the registration's residual (the RMS
  // distance of the matched cluster centres), when it matched enough clusters
  // to measure one; shared.intersection_distance stays the floor (0 = always
  // the floor). Exact masks leave 2.6-3.3 cm, and the floor of 8 cm was
  // chosen on them; the U-Net's noisier fruit points leave 4.3-5.3 cm, and
  // with 8 cm the merge found a third of the apples both sides see
  // (docs/yield.md).
  double intersection_per_residual = 2.5;
  // A merge cluster linked to nothing on the other side is counted by its
  // side's own best-views rule (ResolvedBestViews of `orchard side`'s
  // options: its highest-count views with instance masks or boxes, its
  // largest views with a counter, where nothing changes), the linked ones in
  // their largest views (above). Its apples are this side's alone, and its
  // largest views can hide one behind another, as a side counted alone
  // showed (side.h). Exact masks, rows 422-475 (emulated from two runs):
  // 42 -> 44 of 54 within 2%, MAE 1.14 -> 1.10%, where counting every merge
  // cluster by count gave 39 (docs/yield.md).
  bool unlinked_by_sides_rule = true;
  // Length (m) of the along-row bins of the yield map.
  double bin_length = 1.0;
  // Take the given poses of both sides as one frame (RTK-GNSS, a SLAM run
  // over both sides, the generator's true poses) instead of registering the
  // sides. Needs given poses for both sides.
  bool poses_registered = false;
  // Annotated sample frames per side shown in the report.
  int report_frames = 2;
  void Check() const;
};

// The shared count's intersection distance: options.shared's, widened to
// intersection_per_residual times the registration's residual when the
// registration matched at least registration.min_matched clusters.
double IntersectionDistance(const YieldOptions& options, const Registration& registration);

struct YieldInputs {
  SideInputs front, back;  // their `out` is ignored: the sides go to OUT/front and OUT/back
  fs::path out;
  // Optional ground truth (the generator's truth.json): compared in
  // yield.json and the report.
  fs::path truth;
  // Optional calibration against harvested rows (`orchard calibrate`,
  // calibration.h): yield.json and the report add the calibrated total. Its
  // detector and counter must be this run's.
  fs::path calibration;
};

struct YieldSummary {
  int total = 0;         // the row's estimate: shared apples counted once
  // Each side's own count (`orchard side`'s rules), their unmerged sum, and
  // the apples seen from both sides that the merge counted once: front +
  // back - total.
  int front = 0, back = 0;
  int sum_of_sides = 0;
  double shared = 0;
  // The merge itself: the counts of each side's merge clusters and the
  // apples the inclusion-exclusion took off (total = merge_front +
  // merge_back - merge_shared).
  int merge_front = 0, merge_back = 0;
  double merge_shared = 0;
  // Of merge_front + merge_back: the apples the merge clusters in no group
  // added by their side's own rule (YieldOptions::unlinked_by_sides_rule).
  int unlinked_added = 0;
  SideSummary front_side, back_side;
  Registration registration;
  // With a calibration: total x its factor, rounded (0 without one).
  int calibrated_total = 0;
  double calibration_factor = 0;
  std::vector<std::string> warnings;  // as in yield.json, each side's prefixed with its name
};

// Runs both sides (resuming from their caches), registers and merges them,
// and writes the outputs atomically into inputs.out. Throws orchard::Error
// with the reason on bad input or when the sides cannot be merged.
YieldSummary RunYield(const YieldInputs& inputs, const YieldOptions& options);

}  // namespace orchard
