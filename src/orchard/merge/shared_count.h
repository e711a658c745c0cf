// Counting apples seen from both sides once: inclusion-exclusion over the
// front and back clusters that intersect once both are in one frame.
// total = sum of front counts + sum of back counts - shared, where each
// intersecting pair shares min(count_front, count_back) weighted by how much
// of the smaller cluster lies in the intersection.
#pragma once

#include <vector>

#include "orchard/merge/side_cloud.h"

namespace orchard {

struct SharedCountOptions {
  // A fruit point lies in the intersection when it is this close (m) to a
  // point of the other side's cluster. The two sides' points of one apple lie
  // a median 2 cm apart, but a quarter of them more than 6 cm (a partly
  // hidden apple's centre shifts towards its visible part); the shared count
  // stopped growing at 8 cm on the development rows (seed 1, flat seed 2).
  double intersection_distance = 0.08;
  void Check() const;
};

struct SharedPair {
  int front = 0, back = 0;  // indices into the cluster lists
  double weight = 0;        // fraction of the smaller cluster in the intersection
  double shared = 0;        // apples counted twice
};

struct SharedCount {
  int front = 0, back = 0;  // each side's sum of counts
  double shared = 0;        // apples seen from both sides
  int total = 0;            // round(front + back - shared)
  std::vector<SharedPair> pairs;
  std::vector<double> front_shared, back_shared;  // per cluster
};

// Both cluster lists in one frame. A cluster's shared apples never exceed
// its count (its pairs are scaled down together when they would).
SharedCount CountSharedApples(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                              const SharedCountOptions& options);

}  // namespace orchard
