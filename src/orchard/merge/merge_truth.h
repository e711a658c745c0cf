// Where a merged row's count comes from, against the synthetic generator's
// truth: each side's clusters kept for the merge are credited with the
// visible apples their fruit points land on (ScoreSideAgainstTruth), and the
// merge's inclusion-exclusion is taken apart into the terms that make
// total - visible_any (docs/yield.md, "Where a merged row's count comes from,
// exactly"):
//   total - visible_any = extra_front + extra_back - held_by_neither
//                         + unlinked + (linked - shared)
// extra_<side>: the side's merge clusters' counts above the apples they hold
// (duplicates, clusters counted high, chance clusters); held_by_neither:
// visible apples no cluster of either side holds; unlinked: apples both sides
// hold in clusters the merge did not link (counted twice); linked - shared:
// apples both sides hold in linked clusters, less what the groups' rule
// counted once (negative: groups of chance links counted as shared).
#pragma once

#include <map>
#include <set>
#include <vector>

#include "orchard/merge/shared_count.h"
#include "orchard/merge/side_cloud.h"

namespace orchard {

struct MergeTruth {
  int visible_any = 0, visible_both = 0;
  int held_front = 0, held_back = 0;  // visible apples each side's merge clusters hold
  int held_both = 0, held_by_neither = 0;
  int linked = 0, unlinked = 0;  // of held_both: in one group, or not
  int extra_front = 0, extra_back = 0;
  double shared = 0;  // the merge's count of apples seen from both sides
  int total = 0;      // the merge's total
};

// `front` and `back` are the clusters given to CountSharedApples (in that
// order) and `shared` its result; `*_credited` maps a cluster id to the
// apples it holds (missing ids hold none); `visible_*` are the apples each
// side shows.
MergeTruth ScoreMergeAgainstTruth(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                                  const SharedCount& shared, const std::map<int, std::vector<int>>& front_credited,
                                  const std::map<int, std::vector<int>>& back_credited,
                                  const std::set<int>& visible_front, const std::set<int>& visible_back);

}  // namespace orchard
