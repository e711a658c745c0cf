#include "orchard/merge/shared_count.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <tuple>

#include "orchard/core/error.h"

namespace orchard {

void SharedCountOptions::Check() const {
  ORCHARD_CHECK_OPTION(intersection_distance > 0, "intersection distance must be positive, got ",
                       intersection_distance);
  ORCHARD_CHECK_OPTION(glimpse_across > 0 && glimpse_vertical > 0, "glimpse link distances must be positive, got ",
                       glimpse_across, ", ", glimpse_vertical);
  ORCHARD_CHECK_OPTION(edge_across > 0 && edge_below >= 0 && edge_above > 0,
                       "edge link distances must be positive, got ", edge_across, ", ", edge_below, ", ", edge_above);
  ORCHARD_CHECK_OPTION(sight_across >= 0 && sight_min_behind >= 0 && sight_max_behind > sight_min_behind,
                       "line-of-sight link: need sight_across >= 0 and 0 <= sight_min_behind < sight_max_behind, got ",
                       sight_across, ", ", sight_min_behind, ", ", sight_max_behind);
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

constexpr double kNoLink = std::numeric_limits<double>::infinity();

// How far (m, horizontally) p lies from the ray a -> b when it lies where the
// apple of that sliver may hang: within `across` of it horizontally, from
// `below` under it to `above` over it; kNoLink otherwise.
double SliverRayOffset(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double across,
                       double below, double above) {
  const Eigen::Vector2d d = (b - a).head<2>();
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).head<2>().dot(d) / len2, 0.0, 1.0) : 0.0;
  const Eigen::Vector3d q = a + t * (b - a);
  const double dz = p.z() - q.z();
  const double offset = (p - q).head<2>().norm();
  return offset <= across && dz >= -below && dz <= above ? offset : kNoLink;
}

double SliverRaysOffset(const Eigen::Vector3d& p, const SideCluster& edge, double across, double below,
                        double above) {
  double best = kNoLink;
  for (size_t i = 0; i + 1 < edge.ray_ends.size(); i += 2)
    best = std::min(best, SliverRayOffset(p, edge.ray_ends[i], edge.ray_ends[i + 1], across, below, above));
  return best;
}

// Whether an edge apple (`edge`, with rays) and a cluster of the other side
// are one apple (SharedCountOptions::edge_across and the rest): how near (m,
// horizontally) the other's nearest point or ray sample comes to one of its
// rays, kNoLink when none is within the bounds.
double EdgeLinkOffset(const SideCluster& edge, const SideCluster& other, const SharedCountOptions& o) {
  double best = kNoLink;
  if (!other.edge || other.ray_ends.empty()) {
    const double across = edge.glimpsed ? o.glimpse_across : o.edge_across;
    const double below = edge.glimpsed ? o.glimpse_vertical : o.edge_below;
    const double above = edge.glimpsed ? o.glimpse_vertical : o.edge_above;
    for (const auto& p : other.points) best = std::min(best, SliverRaysOffset(p, edge, across, below, above));
    return best;
  }
  // Two edge apples: samples of one's rays every centimetre against the other's.
  for (size_t i = 0; i + 1 < other.ray_ends.size(); i += 2) {
    const Eigen::Vector3d& a = other.ray_ends[i];
    const Eigen::Vector3d& b = other.ray_ends[i + 1];
    const int steps = std::max(1, static_cast<int>((b - a).norm() / 0.01));
    for (int k = 0; k <= steps; ++k)
      best = std::min(best, SliverRaysOffset(a + (b - a) * (static_cast<double>(k) / steps), edge, o.edge_across,
                                             o.edge_above, o.edge_above));
  }
  return best;
}

// How far (m) `behind`'s centre lies from the farthest of the lines of sight
// from `seen`'s view centres through its centre, when it lies within the
// depth window beyond it on all of them; infinity otherwise.
double SightOffset(const SideCluster& seen, const SideCluster& behind, const SharedCountOptions& o) {
  if (seen.view_centres.empty()) return kNoLink;
  double worst = 0;
  const Eigen::Vector3d v = behind.centre - seen.centre;
  for (const auto& c : seen.view_centres) {
    const Eigen::Vector3d ray = seen.centre - c;
    if (ray.norm() <= 0) return kNoLink;
    const double t = v.dot(ray.normalized());
    if (t < o.sight_min_behind || t > o.sight_max_behind) return kNoLink;
    worst = std::max(worst, std::sqrt(std::max(0.0, v.squaredNorm() - t * t)));
  }
  return worst <= o.sight_across ? worst : kNoLink;
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
  const auto is_edge = [](const SideCluster& c) { return c.edge && !c.ray_ends.empty(); };
  // An edge apple on the line of sight of the other side's (tracked) cluster
  // is an apple that cluster holds: all its count is shared, and it joins no
  // group. Edge apples linked only to the other side's edge apples form
  // groups like the rest.
  r.front_edge_on.assign(nf, -1);
  r.back_edge_on.assign(nb, -1);
  std::vector<std::pair<int, int>> edge_pairs;
  // An edge apple near several of the other side's clusters' points is on the nearest.
  std::vector<double> front_edge_offset(nf, kNoLink), back_edge_offset(nb, kNoLink);
  for (int f = 0; f < nf; ++f)
    for (int b = 0; b < nb; ++b) {
      const bool edge_f = is_edge(front[f]), edge_b = is_edge(back[b]);
      if (edge_f || edge_b) {
        const double offset = EdgeLinkOffset(edge_f ? front[f] : back[b], edge_f ? back[b] : front[f], o);
        if (!std::isfinite(offset)) continue;
        r.links.push_back({f, b, 1, 1});
        if (edge_f && edge_b) {
          edge_pairs.emplace_back(f, b);
        } else if (edge_f && offset < front_edge_offset[f]) {
          r.front_edge_on[f] = b;
          front_edge_offset[f] = offset;
        } else if (edge_b && offset < back_edge_offset[b]) {
          r.back_edge_on[b] = f;
          back_edge_offset[b] = offset;
        }
        continue;
      }
      if (!BoxesMeet(front[f], back[b], d)) continue;
      const double in_f = FractionNear(front[f], back[b], d);
      if (in_f <= 0) continue;
      r.links.push_back({f, b, in_f, FractionNear(back[b], front[f], d)});
      parent[Find(parent, f)] = Find(parent, nf + b);
    }
  for (const auto& [f, b] : edge_pairs)
    if (r.front_edge_on[f] < 0 && r.back_edge_on[b] < 0) parent[Find(parent, f)] = Find(parent, nf + b);
  if (o.sight_across > 0) {
    // Clusters linked to nothing (no group, no edge apple on them), paired
    // along lines of sight, closest first, each at most once.
    std::vector<int> members(nf + nb, 0);
    for (int i = 0; i < nf + nb; ++i) ++members[Find(parent, i)];
    std::vector<bool> alone(nf + nb);
    for (int i = 0; i < nf + nb; ++i)
      alone[i] = members[Find(parent, i)] == 1 && !(i < nf ? front[i] : back[i - nf]).edge;
    for (int f = 0; f < nf; ++f)
      if (r.front_edge_on[f] >= 0) alone[nf + r.front_edge_on[f]] = false;
    for (int b = 0; b < nb; ++b)
      if (r.back_edge_on[b] >= 0) alone[r.back_edge_on[b]] = false;
    std::vector<std::tuple<double, int, int>> pairs;
    for (int f = 0; f < nf; ++f) {
      if (!alone[f]) continue;
      for (int b = 0; b < nb; ++b) {
        if (!alone[nf + b]) continue;
        const double offset = std::min(SightOffset(front[f], back[b], o), SightOffset(back[b], front[f], o));
        if (std::isfinite(offset)) pairs.emplace_back(offset, f, b);
      }
    }
    std::sort(pairs.begin(), pairs.end());
    for (const auto& [offset, f, b] : pairs) {
      if (!alone[f] || !alone[nf + b]) continue;
      alone[f] = alone[nf + b] = false;
      SharedLink link{f, b};
      link.sight = true;
      r.links.push_back(link);
      parent[Find(parent, f)] = Find(parent, nf + b);
      ++r.sight_links;
    }
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
  for (int f = 0; f < nf; ++f)
    if (r.front_edge_on[f] >= 0) r.front_shared[f] = front[f].count, r.shared += front[f].count;
  for (int b = 0; b < nb; ++b)
    if (r.back_edge_on[b] >= 0) r.back_shared[b] = back[b].count, r.shared += back[b].count;
  for (auto& [root, g] : groups) {
    const bool on_tracked = g.front.size() + g.back.size() == 1 &&
                            (g.front.empty() ? r.back_edge_on[g.back[0]] : r.front_edge_on[g.front[0]]) >= 0;
    if (on_tracked) continue;
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
