// report.html of `orchard yield`: one self-contained page (inline SVG, no
// scripts) with the counts, the truth when known, a map of the apples along
// the row, the alignment, sample frames and the per-stage timings.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace orchard {

struct MapCluster {
  std::string side;  // "front" or "back"
  double along = 0, height = 0;  // m, in the row frame
  int count = 0;
  double shared = 0;  // apples of it also counted on the other side
  // Its part of the merged total: count - shared / 2 (each side takes half
  // of what two share), or count - shared for an edge or glimpsed apple on
  // the other side's tracked cluster (its apple is that cluster's).
  double part = 0;
};

// `yield` is the content of yield.json; `frames` are paths of sample frames
// relative to the report.
std::string YieldReportHtml(const nlohmann::json& yield, const std::vector<MapCluster>& clusters,
                            const std::vector<std::string>& frames);

}  // namespace orchard
