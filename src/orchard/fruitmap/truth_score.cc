#include "orchard/fruitmap/truth_score.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

void TruthScoreOptions::Check() const {
  ORCHARD_CHECK_OPTION(window_px >= 0, "truth window must be >= 0 pixels, got ", window_px);
  ORCHARD_CHECK_OPTION(min_votes >= 1, "truth min votes must be at least 1, got ", min_votes);
}

namespace {

// The apple id (0-based) most common in the window around `pixel`; -1 when
// the window holds no apple.
int AppleAt(const cv::Mat& mask, const Eigen::Vector2d& pixel, int half) {
  // Views project in COLMAP's convention: pixel (i, j) spans [i, i + 1).
  const int u = static_cast<int>(std::floor(pixel.x())), v = static_cast<int>(std::floor(pixel.y()));
  std::map<int, int> seen;
  for (int y = std::max(0, v - half); y <= std::min(mask.rows - 1, v + half); ++y)
    for (int x = std::max(0, u - half); x <= std::min(mask.cols - 1, u + half); ++x)
      if (const int id = mask.at<uint16_t>(y, x); id > 0) ++seen[id - 1];
  int best = -1, best_n = 0;
  for (const auto& [id, n] : seen)
    if (n > best_n) best = id, best_n = n;
  return best;
}

}  // namespace

SideTruthScore CreditApples(const std::vector<ClusterVotes>& clusters, const std::set<int>& visible, int min_votes) {
  SideTruthScore s;
  s.visible = static_cast<int>(visible.size());
  // Pairs by votes, most first; ties by cluster then apple, so the result
  // does not depend on the map's order.
  std::vector<std::tuple<int, int, int>> pairs;  // (-votes, cluster, apple)
  for (size_t k = 0; k < clusters.size(); ++k) {
    s.count += clusters[k].count;
    for (const auto& [apple, n] : clusters[k].votes)
      if (n >= (clusters[k].min_votes > 0 ? clusters[k].min_votes : min_votes) && visible.count(apple))
        pairs.emplace_back(-n, static_cast<int>(k), apple);
  }
  std::sort(pairs.begin(), pairs.end());
  s.clusters.resize(clusters.size());
  std::set<int> found;
  for (const auto& [neg_votes, k, apple] : pairs) {
    ClusterTruth& c = s.clusters[k];
    if (static_cast<int>(c.credited.size()) >= clusters[k].count || found.count(apple)) continue;
    found.insert(apple);
    c.credited.push_back(apple);
  }
  s.found = static_cast<int>(found.size());
  s.missed = s.visible - s.found;
  std::set<int> voted;
  for (const auto& [neg_votes, k, apple] : pairs) voted.insert(apple);
  for (const int apple : visible)
    if (!found.count(apple)) {
      s.missed_ids.push_back(apple);
      if (!voted.count(apple)) ++s.missed_without_points;
    }
  for (size_t k = 0; k < clusters.size(); ++k) {
    ClusterTruth& c = s.clusters[k];
    c.cluster = static_cast<int>(k);
    c.votes = clusters[k].votes;
    const int left = clusters[k].count - static_cast<int>(c.credited.size());
    std::sort(c.credited.begin(), c.credited.end());
    for (const auto& [apple, n] : clusters[k].votes)
      if (n > c.top_votes) c.top_apple = apple, c.top_votes = n;
    c.role = left <= 0 ? "found" : !c.credited.empty() ? "over_counted"
                                 // Credited with nothing: on a visible apple (which another cluster holds) or not.
                                 : c.top_apple >= 0 && visible.count(c.top_apple) ? "duplicate" : "not_visible";
    if (left <= 0) continue;
    (c.role == "over_counted" ? s.over_counted : c.role == "duplicate" ? s.duplicates : s.not_visible) += left;
  }
  return s;
}

SideTruthScore ScoreSideAgainstTruth(const std::vector<CameraView>& views, const std::vector<cv::Mat>& truth_masks,
                                     const std::set<int>& visible, const ClusterResult& result,
                                     const TruthScoreOptions& o) {
  o.Check();
  if (views.size() != truth_masks.size())
    Fail("truth score: ", views.size(), " views but ", truth_masks.size(), " truth masks");
  for (size_t i = 0; i < views.size(); ++i)
    if (truth_masks[i].type() != CV_16UC1 || truth_masks[i].cols != views[i].width ||
        truth_masks[i].rows != views[i].height)
      Fail("truth mask of ", views[i].name, " must be 16-bit, one channel, ", views[i].width, "x", views[i].height);
  std::vector<int> kept;
  std::vector<ClusterVotes> votes;  // per kept cluster
  for (size_t c = 0; c < result.clusters.size(); ++c) {
    const FruitCluster& cluster = result.clusters[c];
    if (cluster.status != "kept") continue;
    kept.push_back(static_cast<int>(c));
    ClusterVotes& v = votes.emplace_back();
    v.count = cluster.count;
    // An edge apple's points lie on its slivers only in their own frames
    // (elsewhere their distance is a guess): one vote each, enough.
    if (cluster.edge || cluster.glimpsed) v.min_votes = 1;
    for (int p : cluster.points)
      for (size_t f = 0; f < views.size(); ++f) {
        if ((cluster.edge || cluster.glimpsed) && static_cast<int>(f) != result.points[p].frame) continue;
        Eigen::Vector2d pixel;
        if (views[f].Depth(result.points[p].xyz) <= 0 || !views[f].Project(result.points[p].xyz, &pixel)) continue;
        if (const int id = AppleAt(truth_masks[f], pixel, o.window_px); id >= 0) ++v.votes[id];
      }
  }
  SideTruthScore s = CreditApples(votes, visible, o.min_votes);
  for (size_t k = 0; k < kept.size(); ++k) s.clusters[k].cluster = kept[k];
  std::map<int, int> views_seen;  // apple id -> views whose mask shows it
  for (const cv::Mat& mask : truth_masks) {
    std::set<int> here;
    for (int y = 0; y < mask.rows; ++y) {
      const uint16_t* row = mask.ptr<uint16_t>(y);
      for (int x = 0; x < mask.cols; ++x)
        if (row[x] > 0) here.insert(row[x] - 1);
    }
    for (const int apple : here) ++views_seen[apple];
  }
  const std::set<int> missed(s.missed_ids.begin(), s.missed_ids.end());
  for (const int apple : visible) {
    const auto it = views_seen.find(apple);
    const int bin = std::min(it == views_seen.end() ? 0 : it->second, SideTruthScore::kViewsSeenBins - 1);
    ++s.visible_by_views_seen[bin];
    if (missed.count(apple)) ++s.missed_by_views_seen[bin];
  }
  return s;
}

std::set<int> ReadVisibleApples(const fs::path& apples_csv, const std::string& side) {
  if (side != "front" && side != "back") Fail("truth side must be front or back, got '", side, "'");
  std::istringstream in(ReadTextFile(apples_csv));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = SplitCsvLine(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) Fail(apples_csv.string(), " has no column '", name, "' (not the generator's apples.csv?)");
    return static_cast<size_t>(it - header.begin());
  };
  const size_t id_col = column("id"), row_col = column("row"), ground_col = column("on_ground"),
               visible_col = column("visible_" + side);
  std::set<int> visible;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    const std::vector<std::string> f = SplitCsvLine(line);
    if (f.size() != header.size()) Fail(apples_csv.string(), " line ", line_no, ": ", f.size(), " fields, header has ", header.size());
    if (f[row_col] == "0" && f[ground_col] == "0" && f[visible_col] == "1") {
      try {
        visible.insert(std::stoi(f[id_col]));
      } catch (const std::exception&) {
        Fail(apples_csv.string(), " line ", line_no, ": id '", f[id_col], "' is not a number");
      }
    }
  }
  return visible;
}

std::set<int> ReadSideVisibleApples(const fs::path& side_dir) {
  const fs::path dir = side_dir.filename().empty() ? side_dir.parent_path() : side_dir;
  if (!fs::is_directory(dir / "masks")) Fail("truth: ", dir.string(), " has no masks/ (give the generator's S/front or S/back)");
  return ReadVisibleApples(dir.parent_path() / "apples.csv", dir.filename().string());
}

}  // namespace orchard
