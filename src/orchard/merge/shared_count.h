// Counting apples seen from both sides once: inclusion-exclusion over the
// front and back clusters that intersect once both are in one frame.
// Clusters of the two sides whose fruit points come within the intersection
// distance are linked (edge apples: along their rays); each group of linked clusters holds
// |F u B| = |F| + |B| - |F n B| apples, with |F n B| = min(|F|, |B|): the
// side that sees fewer of the group's apples sees a subset of what the other
// side sees. total = sum of all counts - sum of the groups' intersections.
// A cluster linked to nothing on the other side counts its count_unlinked
// (where set: its side's own best-views rule, see YieldOptions).
#pragma once

#include <vector>

#include "orchard/merge/side_cloud.h"

namespace orchard {

struct SharedCountOptions {
  // Fruit points of the two sides this close (m) lie in both clusters. The
  // two sides' points of one apple lie a median 2 cm apart, but a quarter of
  // them more than 6 cm (a partly hidden apple's centre shifts towards its
  // visible part); 8 cm gave the merged counts closest to the truth on the
  // development rows (seed 1, flat seed 2), with little change from 6 to 10.
  double intersection_distance = 0.08;
  // An edge apple (SideCluster::edge: seen only as slivers at the frames'
  // top edge) is linked along its slivers' rays: to a cluster of the other
  // side with a point within edge_across (m) of a ray horizontally and from
  // edge_below under it to edge_above over it (a sliver is the apple's lower
  // part: its centre hangs up to a radius above the frame's edge), and to an
  // edge apple of the other side whose rays pass within edge_across and
  // edge_above of its own (both slivers show the apple's lower part).
  double edge_across = 0.04;
  double edge_below = 0.03;
  double edge_above = 0.08;
  // A glimpsed apple (SideCluster::glimpsed) is linked along its rays, which
  // pass through the sphere found for it: to a cluster of the other side
  // with a point within glimpse_across (m) of a ray horizontally and within
  // glimpse_vertical over or under it.
  double glimpse_across = 0.04;
  double glimpse_vertical = 0.08;
  // A cluster linked to nothing may show a partly hidden apple through a gap
  // in the leaves: its fruit points then lie where the gap is, in front of
  // the apple (the blob moves with the leaves), up to 70 cm nearer its own
  // camera than the other side's cluster of the same apple. Two such
  // clusters are linked (one to one, best first) when the other's centre lies
  // within sight_across (m) of every line of sight from the camera of one's
  // count frames through its centre, from sight_min_behind to
  // sight_max_behind (m) beyond it. On 22 rows with exact masks and true
  // poses (seeds 505-510, 517-524, 601-608) the pairs that held one apple
  // lay 1.1-4.6 cm off, the others mostly 5-6 cm; at 5 cm 15 of 17 links
  // joined the two sides' clusters of one apple (docs/yield.md). 0 = off.
  double sight_across = 0.05;
  double sight_min_behind = 0.04;
  double sight_max_behind = 0.7;
  void Check() const;
};

struct SharedLink {
  int front = 0, back = 0;  // indices into the cluster lists
  // Fraction of each cluster's points within the intersection distance of
  // the other's (for inspection; the count uses the groups).
  double front_fraction = 0, back_fraction = 0;
  bool sight = false;  // linked along a line of sight (SharedCountOptions::sight_across)
};

struct SharedGroup {
  std::vector<int> front, back;  // linked clusters
  int front_count = 0, back_count = 0;
  int shared = 0;  // min(front_count, back_count)
};

struct SharedCount {
  int front = 0, back = 0;  // each side's sum of counts (front_counts, back_counts)
  double shared = 0;        // apples seen from both sides
  int total = 0;            // front + back - shared
  std::vector<SharedLink> links;
  std::vector<SharedGroup> groups;  // groups with clusters from both sides
  // Per cluster: its part of its group's shared apples (the smaller side's
  // clusters share all their apples, the larger side's in proportion).
  std::vector<double> front_shared, back_shared;
  // Per cluster: the count used (count, or count_unlinked when in no group).
  std::vector<int> front_counts, back_counts;
  // Per cluster: for an edge apple on the line of sight of the other side's
  // tracked cluster (all its count shared, in no group), that cluster's
  // index (of several, the one with a point nearest its rays); else -1.
  std::vector<int> front_edge_on, back_edge_on;
  int sight_links = 0;  // links along a line of sight
};

// Both cluster lists in one frame.
SharedCount CountSharedApples(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                              const SharedCountOptions& options);

}  // namespace orchard
