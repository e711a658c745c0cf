// Registration of the two sides of a row. Their images share almost no
// features (they show opposite faces of the canopy), so the alignment uses
// the row's geometry instead, as the study does: each side is metric with its
// ground plane at z = 0 and its row frame (x along, y across towards the row,
// z up), which leaves the heading, the offset along the row and the distance
// across it. Those three come from fruit clusters seen from both sides: a
// Hough vote over heading and offset for every pair of clusters at a similar
// height, then an iterative closest-point refinement on the matched centres.
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "orchard/merge/side_cloud.h"

namespace orchard {

struct RegistrationOptions {
  // Cluster centres of the two sides closer than this (m) are taken as the
  // same fruit: a few centimetres of reconstruction error on each side.
  double match_distance = 0.08;
  // Heading search (degrees) around the half turn that makes the sides face
  // each other: camera paths within this angle of parallel.
  double max_heading_deg = 8;
  double heading_step_deg = 0.5;
  // Hough cell of the offset vote (m).
  double cell = 0.05;
  // Plausible distance between the two camera paths (m): a row's width plus
  // the two working distances, from a narrow hedge to a wide tree row.
  double min_path_distance = 1.0;
  double max_path_distance = 30;
  // Fewest clusters matched across the sides for a registration, in number
  // and as a fraction of the side with fewer clusters. Two different 4-tree
  // rows matched up to 10 of about 170 clusters by chance (6%); the same
  // row's sides 65-135 of 150-270 (30-50%) with exact masks.
  int min_matched = 5;
  double min_matched_fraction = 0.12;
  // The best alignment must match this many times as many clusters as the
  // best alignment elsewhere (one that moves the back side's clusters by more
  // than 0.5 m RMS): otherwise the match is chance (two unrelated rows also
  // share a few coincidences).
  double min_distinctness = 2;
  // The back side's scale relative to the front's is searched within
  // 1 +- this, in steps of scale_step. Each side's scale comes from its own
  // camera height over its own ground fit, and COLMAP's sparse ground can put
  // one side 5-12% off (seed 350's back: a path of 5.59 m for 5.0, the
  // front's 5.04), which leaves too few fruit clusters within
  // match_distance at any single scale. 0: the scales are taken as they are.
  double max_scale_change = 0.1;
  double scale_step = 0.02;
  // The sides must overlap along the row by this fraction of the shorter one.
  double min_overlap = 0.5;
  // Refinement rounds (closest points, then a rigid fit).
  int refine_iterations = 20;
  void Check() const;
};

struct Registration {
  // back row frame -> front row frame: a half turn about up plus heading_deg,
  // then (along, across) in the ground plane.
  Eigen::Isometry3d back_to_front = Eigen::Isometry3d::Identity();
  double heading_deg = 0;
  double along = 0;   // offset along the row (m)
  double across = 0;  // distance between the camera paths (m)
  // The back side's scale relative to the front's (RegisterSides): the
  // transform applies to the back cloud scaled by this about its origin.
  double back_scale = 1;
  int matched = 0;         // clusters matched one to one
  double residual = 0;     // RMS distance between matched centres (m)
  int chance_matched = 0;  // best match count of any other alignment
  double overlap = 0;      // along-row overlap of the two sides (m)
  double front_length = 0, back_length = 0;  // along-row extents (m)
  std::vector<std::pair<int, int>> pairs;    // matched (front, back) cluster indices
  // Set by the row registration (row_registration.h), and `correlation` also
  // when a fruit alignment was checked against the canopy (has_profile):
  bool on_row = false;
  bool has_profile = false;
  double correlation = 0;         // the canopy profiles' correlation at `along`
  double chance_correlation = 0;  // their best correlation 0.5 m or more away
  // Where the distance across came from: the fruit both sides see, or,
  // without it and on the user's word (--same-row), the trunks or the
  // centre-plane assumption (row_registration.h).
  enum class Across { kFruit, kTrunks, kAssumed };
  Across across_from = Across::kFruit;
  // The trunks' distance across (AcrossFromTrunks; NaN: too few trunks or
  // no sparse points) and the trunks each side shows, also as a check on a
  // distance the fruit gave.
  double across_trunks = std::nan("");
  int trunks_front = 0, trunks_back = 0;
  // The best alignment was not distinct from another but agreed with the
  // given poses, which settled it (RegisterSides with `given`).
  bool settled_by_given_poses = false;
};

// The transform a (heading, along, across) triple stands for.
Eigen::Isometry3d BackToFrontTransform(double heading_deg, double along, double across);

// Matches, residual and along-row overlap of the sides under a given
// back -> front transform (heading, along and across are read from it).
Registration EvaluateAlignment(const SideCloud& front, const SideCloud& back, const Eigen::Isometry3d& back_to_front,
                               const RegistrationOptions& options);

// Also solves the back side's scale relative to the front's (back_scale,
// within options.max_scale_change): the result's back_to_front and matches
// hold for the back cloud scaled by it (ScaleSideCloud).
// Throws orchard::Error with the reason when the sides cannot be registered:
// too few clusters, no consistent alignment (different rows, unrelated
// videos), or sides that cover different stretches of the row. `given`: the
// back -> front transform that poses given for both sides imply, if any. A
// best alignment that is not distinct from another (dense clusters of a
// regular canopy) is still taken when it agrees with it: two independent
// cues then agree, and the poses need not be in one frame for the call.
Registration RegisterSides(const SideCloud& front, const SideCloud& back, const RegistrationOptions& options,
                           const Eigen::Isometry3d* given = nullptr);

}  // namespace orchard
