#include "orchard/merge/shared_count.h"

#include <algorithm>
#include <cmath>

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

// Scales down the pairs of clusters whose shared apples exceed their count.
void CapShared(const std::vector<SideCluster>& clusters, bool front_side, std::vector<SharedPair>* pairs) {
  std::vector<double> sum(clusters.size(), 0);
  for (const auto& p : *pairs) sum[front_side ? p.front : p.back] += p.shared;
  for (auto& p : *pairs) {
    const int i = front_side ? p.front : p.back;
    if (sum[i] > clusters[i].count) p.shared *= clusters[i].count / sum[i];
  }
}

}  // namespace

SharedCount CountSharedApples(const std::vector<SideCluster>& front, const std::vector<SideCluster>& back,
                              const SharedCountOptions& o) {
  o.Check();
  SharedCount r;
  for (const auto& c : front) r.front += c.count;
  for (const auto& c : back) r.back += c.count;
  const double d = o.intersection_distance;
  for (size_t f = 0; f < front.size(); ++f)
    for (size_t b = 0; b < back.size(); ++b) {
      if (!BoxesMeet(front[f], back[b], d)) continue;
      const double in_f = FractionNear(front[f], back[b], d), in_b = FractionNear(back[b], front[f], d);
      // The smaller cluster's share of the intersection: a single apple seen
      // from both sides is wholly inside a larger cluster on the other side.
      const SideCluster& fc = front[f];
      const SideCluster& bc = back[b];
      double weight;
      if (fc.count != bc.count)
        weight = fc.count < bc.count ? in_f : in_b;
      else
        weight = 0.5 * (in_f + in_b);
      if (weight <= 0) continue;
      r.pairs.push_back({static_cast<int>(f), static_cast<int>(b), weight, weight * std::min(fc.count, bc.count)});
    }
  CapShared(front, true, &r.pairs);
  CapShared(back, false, &r.pairs);
  r.front_shared.assign(front.size(), 0);
  r.back_shared.assign(back.size(), 0);
  for (const auto& p : r.pairs) {
    r.shared += p.shared;
    r.front_shared[p.front] += p.shared;
    r.back_shared[p.back] += p.shared;
  }
  r.total = static_cast<int>(std::lround(r.front + r.back - r.shared));
  return r;
}

}  // namespace orchard
