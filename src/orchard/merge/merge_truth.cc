#include "orchard/merge/merge_truth.h"

#include <algorithm>

namespace orchard {

namespace {

// Apple -> index of the cluster holding it, and the clusters' counts above
// what they hold, summed.
std::map<int, int> Holders(const std::vector<SideCluster>& clusters, const std::map<int, std::vector<int>>& credited,
                           int* extra) {
  std::map<int, int> holder;
  *extra = 0;
  for (int i = 0; i < static_cast<int>(clusters.size()); ++i) {
    const auto it = credited.find(clusters[i].id);
    const int held = it == credited.end() ? 0 : static_cast<int>(it->second.size());
    *extra += clusters[i].count - held;
    if (it != credited.end())
      for (const int apple : it->second) holder[apple] = i;
  }
  return holder;
}

}  // namespace

MergeTruth ScoreMergeAgainstTruth(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                                  const SharedCount& shared, const std::map<int, std::vector<int>>& front_credited,
                                  const std::map<int, std::vector<int>>& back_credited,
                                  const std::set<int>& visible_front, const std::set<int>& visible_back) {
  MergeTruth t;
  std::set<int> any = visible_front;
  any.insert(visible_back.begin(), visible_back.end());
  t.visible_any = static_cast<int>(any.size());
  t.visible_both = static_cast<int>(
      std::count_if(visible_front.begin(), visible_front.end(), [&](int a) { return visible_back.count(a) > 0; }));
  const std::map<int, int> in_front = Holders(front, front_credited, &t.extra_front);
  const std::map<int, int> in_back = Holders(back, back_credited, &t.extra_back);
  t.held_front = static_cast<int>(in_front.size()), t.held_back = static_cast<int>(in_back.size());
  // Each cluster's group (-1: linked to nothing on the other side).
  std::vector<int> front_group(front.size(), -1), back_group(back.size(), -1);
  for (int g = 0; g < static_cast<int>(shared.groups.size()); ++g) {
    for (const int f : shared.groups[g].front) front_group[f] = g;
    for (const int b : shared.groups[g].back) back_group[b] = g;
  }
  for (const int apple : any) {
    const auto f = in_front.find(apple), b = in_back.find(apple);
    if (f == in_front.end() && b == in_back.end()) ++t.held_by_neither;
    if (f == in_front.end() || b == in_back.end()) continue;
    ++t.held_both;
    const int g = front_group[f->second];
    // An edge apple on the other side's cluster that holds the same apple is
    // counted once too (all its count shared).
    const auto on = [](const std::vector<int>& edge_on, int i) {
      return i < static_cast<int>(edge_on.size()) ? edge_on[i] : -1;
    };
    if ((g >= 0 && g == back_group[b->second]) || on(shared.front_edge_on, f->second) == b->second ||
        on(shared.back_edge_on, b->second) == f->second)
      ++t.linked;
    else
      ++t.unlinked;
  }
  t.shared = shared.shared;
  t.total = shared.total;
  return t;
}

}  // namespace orchard
