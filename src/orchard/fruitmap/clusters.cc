#include "orchard/fruitmap/clusters.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "orchard/core/error.h"

namespace orchard {
namespace {

std::int64_t CellKey(std::int64_t x, std::int64_t y, std::int64_t z) {
  // 21 bits per axis: +-1e6 cells.
  return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
}

}  // namespace

std::vector<int> ConnectedComponents3D(const std::vector<Eigen::Vector3d>& points, double link_distance,
                                       int* num_components) {
  if (!(link_distance > 0)) Fail("link distance must be positive, got ", link_distance);
  const int n = static_cast<int>(points.size());
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  std::vector<Eigen::Vector3i> cells(n);
  for (int i = 0; i < n; ++i) {
    cells[i] = (points[i] / link_distance).array().floor().cast<int>();
    grid[CellKey(cells[i].x(), cells[i].y(), cells[i].z())].push_back(i);
  }
  UnionFind uf(n);
  const double d2 = link_distance * link_distance;
  for (int i = 0; i < n; ++i) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(CellKey(cells[i].x() + dx, cells[i].y() + dy, cells[i].z() + dz));
          if (it == grid.end()) continue;
          for (int j : it->second)
            if (j > i && (points[i] - points[j]).squaredNorm() < d2) uf.Join(i, j);
        }
  }
  std::vector<int> label(n, -1), root_label(n, -1);
  int k = 0;
  for (int i = 0; i < n; ++i) {
    const int r = uf.Find(i);
    if (root_label[r] < 0) root_label[r] = k++;
    label[i] = root_label[r];
  }
  if (num_components) *num_components = k;
  return label;
}

int MedianOfBestViews(std::vector<ClusterView> views, int k, std::vector<int>* chosen, bool by_count) {
  if (k < 1) Fail("best views: k must be at least 1, got ", k);
  std::stable_sort(views.begin(), views.end(), [by_count](const ClusterView& a, const ClusterView& b) {
    if (by_count && a.count != b.count) return a.count > b.count;
    return a.pixels != b.pixels ? a.pixels > b.pixels : a.frame < b.frame;
  });
  if (views.size() > static_cast<size_t>(k)) views.resize(k);
  if (chosen) {
    chosen->clear();
    for (const auto& v : views) chosen->push_back(v.frame);
  }
  if (views.empty()) return 0;
  std::vector<int> counts;
  for (const auto& v : views) counts.push_back(v.count);
  std::sort(counts.begin(), counts.end());
  return counts[counts.size() / 2];
}

}  // namespace orchard
