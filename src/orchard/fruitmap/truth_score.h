// Where a side's count comes from, against the synthetic generator's truth:
// which visible apples the kept clusters found, which they missed, and what
// the rest of the count is (an apple counted twice, a cluster counted above
// the apples it holds, fruit that is not a visible apple of the filmed row).
// A count can be right while missing and duplicating many apples that cancel;
// this shows both terms (docs/side.md, "Where a side's count comes from").
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "orchard/fruitmap/side.h"
#include "orchard/sfm/camera_view.h"

namespace orchard {

namespace fs = std::filesystem;

struct TruthScoreOptions {
  // A fruit point projected into a frame votes for the apple id that is most
  // common in this square (half-width, pixels) of the frame's truth mask: the
  // point of a partly hidden apple lands a pixel or two off its visible piece.
  int window_px = 2;
  // A cluster is credited with an apple only when its points vote for it at
  // least this often (one chance vote is no evidence).
  int min_votes = 2;
  void Check() const;
};

// One kept cluster against the truth.
struct ClusterTruth {
  int cluster = 0;               // index into ClusterResult::clusters
  std::vector<int> credited;     // 0-based ids of the visible apples it was credited with, ascending
  int top_apple = -1;            // the apple its points vote for most (-1: none)
  int top_votes = 0;
  std::map<int, int> votes;      // apple id -> votes of its points (ClusterVotes)
  // "found" (credited with its count), "over_counted" (with some, counted
  // higher), "duplicate" (with none, on a visible apple another cluster
  // holds) or "not_visible".
  std::string role;
};

struct SideTruthScore {
  int visible = 0;       // visible apples of the filmed row, off the ground
  int count = 0;         // the kept clusters' counts summed
  int found = 0;         // visible apples credited to a kept cluster
  int missed = 0;        // visible - found
  // Of the missed: apples no kept cluster's points voted for (the 3D stage has
  // no fruit on them), the rest sit in clusters counted below their apples.
  int missed_without_points = 0;
  std::vector<int> missed_ids;  // 0-based apple ids, ascending
  int duplicates = 0;    // counts of kept clusters credited with no apple, on an apple another cluster holds
  int over_counted = 0;  // counts above the apples credited, of clusters credited with some
  int not_visible = 0;   // counts of clusters on no visible apple (next row, fallen, chance pairings)
  // count - visible = duplicates + over_counted + not_visible - missed.
  // The visible apples and the missed ones by the number of the side's views
  // whose truth mask shows them (index n: n views, the last index: that many
  // or more; 0: in none of these views, only in frames left out). A fruit
  // point needs support in several views (FruitPointOptions::min_support), so
  // apples glimpsed in one or two are beyond the 3D stage: this tells that
  // limit from the misses it could avoid.
  static constexpr int kViewsSeenBins = 11;
  std::vector<int> visible_by_views_seen = std::vector<int>(kViewsSeenBins, 0);
  std::vector<int> missed_by_views_seen = std::vector<int>(kViewsSeenBins, 0);
  std::vector<ClusterTruth> clusters;  // the kept clusters, in order
};

// One cluster's fruit points against the truth: how often they land on each
// apple (0-based id -> points-in-views), and the count it is credited up to.
struct ClusterVotes {
  int count = 0;
  std::map<int, int> votes;
  // Votes an apple needs (0: CreditApples' min_votes). An edge apple
  // (FruitCluster::edge) votes once per sliver, in the sliver's frame: 1.
  int min_votes = 0;
};

// The crediting ScoreSideAgainstTruth does, from the votes: (cluster, apple)
// pairs with at least `min_votes` on a visible apple, most votes first (ties:
// the earlier cluster, then the lower id), each apple once, each cluster up
// to its count. Fills count, visible, found, missed, missed_ids,
// missed_without_points, duplicates, over_counted, not_visible and clusters
// (ClusterTruth::cluster: the index into `clusters`); not the views bins.
// The merge credits its clusters again with the counts it gave them.
SideTruthScore CreditApples(const std::vector<ClusterVotes>& clusters, const std::set<int>& visible, int min_votes);

// Credits each kept cluster of `result` with up to its count of visible
// apples: every fruit point of the cluster is projected into every view and
// votes for the truth mask's apple there; (cluster, apple) pairs are taken in
// order of votes, each apple once, each cluster up to its count. `views[i]`
// and `truth_masks[i]` are the same frame (16-bit, apple id + 1, 0 elsewhere:
// the generator's masks, which leave out an apple's pieces too small to
// annotate); `visible` holds the 0-based ids to find.
SideTruthScore ScoreSideAgainstTruth(const std::vector<CameraView>& views, const std::vector<cv::Mat>& truth_masks,
                                     const std::set<int>& visible, const ClusterResult& result,
                                     const TruthScoreOptions& options = {});

// The 0-based ids of the apples that `side` ("front" or "back") counts as
// visible in the generator's apples.csv: visible_<side> = 1, the filmed row
// (row 0), not on the ground. Fails with a message on a file of another layout.
std::set<int> ReadVisibleApples(const fs::path& apples_csv, const std::string& side);

// The visible apples of a side folder of the generator's row ("S/front" or
// "S/back", a trailing separator allowed): ReadVisibleApples on S/apples.csv
// for that side. Fails with a message when `side_dir` has no masks/.
std::set<int> ReadSideVisibleApples(const fs::path& side_dir);

}  // namespace orchard
