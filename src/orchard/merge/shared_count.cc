#include "orchard/merge/shared_count.h"

#include <algorithm>
#include <map>
#include <numeric>

#include "orchard/core/error.h"

namespace orchard {

void SharedCountOptions::Check() const {
  ORCHARD_CHECK_OPTION(intersection_distance > 0, "intersection distance must be positive, got ",
                       intersection_distance);
}

namespace {

// Fraction of a's points within `d` of some point of b.
double FractionNear(const SideCluster& a, const SideCluster& b, double d) {
  int near = 0;
  for (const auto& p : a.points)
    for (const auto& q : b.points)
      if ((p - q).squaredNorm() <= d * d) {
        ++near;
        break;
      }
  return a.points.empty() ? 0 : static_cast<double>(near) / static_cast<double>(a.points.size());
}

bool BoxesMeet(const SideCluster& a, const SideCluster& b, double margin) {
  for (int i = 0; i < 3; ++i)
    if (a.max[i] + margin < b.min[i] || b.max[i] + margin < a.min[i]) return false;
  return true;
}

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

SharedCount CountSharedApples(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                              const SharedCountOptions& o) {
  o.Check();
  SharedCount r;
  const int nf = static_cast<int>(front.size()), nb = static_cast<int>(back.size());
  const double d = o.intersection_distance;
  std::vector<int> parent(nf + nb);
  std::iota(parent.begin(), parent.end(), 0);
  for (int f = 0; f < nf; ++f)
    for (int b = 0; b < nb; ++b) {
      if (!BoxesMeet(front[f], back[b], d)) continue;
      const double in_f = FractionNear(front[f], back[b], d);
      if (in_f <= 0) continue;
      r.links.push_back({f, b, in_f, FractionNear(back[b], front[f], d)});
      parent[Find(parent, f)] = Find(parent, nf + b);
    }
  std::map<int, SharedGroup> groups;
  for (int i = 0; i < nf + nb; ++i) {
    SharedGroup& g = groups[Find(parent, i)];
    if (i < nf)
      g.front.push_back(i), g.front_count += front[i].count;
    else
      g.back.push_back(i - nf), g.back_count += back[i - nf].count;
  }
  r.front_shared.assign(nf, 0);
  r.back_shared.assign(nb, 0);
  for (const auto& c : front) r.front_counts.push_back(c.count);
  for (const auto& c : back) r.back_counts.push_back(c.count);
  for (auto& [root, g] : groups) {
    if (g.front.empty() || g.back.empty()) {
      for (int f : g.front)
        if (front[f].count_unlinked >= 0) r.front_counts[f] = front[f].count_unlinked;
      for (int b : g.back)
        if (back[b].count_unlinked >= 0) r.back_counts[b] = back[b].count_unlinked;
      continue;
    }
    g.shared = std::min(g.front_count, g.back_count);
    r.shared += g.shared;
    for (int f : g.front)
      if (g.front_count > 0) r.front_shared[f] = g.shared * static_cast<double>(front[f].count) / g.front_count;
    for (int b : g.back)
      if (g.back_count > 0) r.back_shared[b] = g.shared * static_cast<double>(back[b].count) / g.back_count;
    r.groups.push_back(g);
  }
  for (int c : r.front_counts) r.front += c;
  for (int c : r.back_counts) r.back += c;
  r.total = r.front + r.back - static_cast<int>(r.shared);
  return r;
}

}  // namespace orchard
