// Fruit clusters: 3D connected components of the fruit points, and the count
// of a cluster from its best views (the study's rule: the median of the
// counts in the three frames where the cluster shows the most fruit pixels).
#pragma once

#include <algorithm>
#include <numeric>
#include <vector>

#include <Eigen/Core>

namespace orchard {

// Disjoint sets of 0..n-1; a set's representative is its smallest member.
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void Join(int a, int b) {
    a = Find(a), b = Find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Component id (0..K-1, numbered by first point) of each point, where points
// closer than `link_distance` are connected (single linkage, via a hash grid
// of cells of that size). `num_components` gets K.
std::vector<int> ConnectedComponents3D(const std::vector<Eigen::Vector3d>& points, double link_distance,
                                       int* num_components = nullptr);

// A cluster as seen in one frame: the blobs it is assigned there, their fruit
// pixels and the apples counted in them.
struct ClusterView {
  int frame = 0;
  int pixels = 0;
  int count = 0;
};

// The median of the counts of the `k` views with the most pixels (ties:
// the earlier frame first), or with `by_count` of the `k` views with the
// highest counts (ties: most pixels, then the earlier frame); with an even
// number of views, the upper median. `chosen` gets the frames used. 0 when
// there are no views.
int MedianOfBestViews(std::vector<ClusterView> views, int k = 3, std::vector<int>* chosen = nullptr,
                      bool by_count = false);

}  // namespace orchard
