#include "orchard/merge/yield.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/frame_source.h"
#include "orchard/core/stopwatch.h"
#include "orchard/fruitmap/truth_score.h"
#include "orchard/merge/calibration.h"
#include "orchard/merge/merge_truth.h"
#include "orchard/merge/report.h"
#include "orchard/merge/side_cloud.h"

namespace orchard {

using Json = nlohmann::json;

void YieldOptions::Check() const {
  side.Check();
  registration.Check();
  row.Check();
  faces.Check();
  shared.Check();
  ORCHARD_CHECK_OPTION(intersection_per_residual >= 0, "intersection per residual must be >= 0, got ",
                       intersection_per_residual);
  ORCHARD_CHECK_OPTION(bin_length > 0, "bin length must be positive, got ", bin_length);
  ORCHARD_CHECK_OPTION(report_frames >= 0, "report frames must be >= 0, got ", report_frames);
}

double IntersectionDistance(const YieldOptions& o, const Registration& registration) {
  if (registration.matched < o.registration.min_matched) return o.shared.intersection_distance;
  return std::max(o.shared.intersection_distance, o.intersection_per_residual * registration.residual);
}

namespace {

Json SideJson(const SideSummary& s, const SideCloud& cloud, const SideInputs& in) {
  Json j = {{"count", s.one_side_count},
            {"merge_clusters_count", s.count},
            {"single_frame_sum", s.single_frame_sum},
            {"frames_used", s.frames_used},
            {"poses", s.poses},
            {"clusters_kept", s.clusters_kept},
            {"clusters_removed", s.clusters_removed},
            {"clusters_loaded", cloud.clusters.size()}};
  // How high its frames reach, and, for a side scored against the
  // generator's truth, where its count comes from (side.json "truth"), so
  // the report can show them beside the counts.
  const Json side = Json::parse(ReadTextFile(in.out / "side.json"), nullptr, false);
  if (!side.is_discarded() && side.contains("frames_reach")) j["frames_reach"] = side.at("frames_reach");
  if (!in.truth.empty() && !side.is_discarded() && side.contains("truth")) j["truth"] = side.at("truth");
  return j;
}

// A side's merge clusters credited again (CreditApples) from their points'
// votes in the side's truth file (side output truth_merge_clusters.json),
// with the counts the merge gave them.
SideTruthScore CreditMergeClusters(const SideInputs& side, const std::vector<SideCluster>& clusters,
                                   const std::set<int>& visible) {
  const fs::path path = side.out / "truth_merge_clusters.json";
  const Json truth = Json::parse(ReadTextFile(path), nullptr, false);
  if (truth.is_discarded() || !truth.contains("votes"))
    Fail("truth: ", path.string(), " is not a merge clusters' truth file with votes (made by an older version?)");
  std::vector<ClusterVotes> votes;
  for (const SideCluster& c : clusters) {
    ClusterVotes& v = votes.emplace_back();
    v.count = c.count;
    if (c.edge) v.min_votes = 1;  // as the side credited it (ScoreSideAgainstTruth)
    const std::string id = std::to_string(c.id);
    if (truth.at("votes").contains(id))
      for (const auto& [apple, n] : truth.at("votes").at(id).items()) v.votes[std::stoi(apple)] = n.get<int>();
  }
  return CreditApples(votes, visible, truth.value("min_votes", TruthScoreOptions().min_votes));
}

std::map<int, std::vector<int>> Credited(const std::vector<SideCluster>& clusters, const SideTruthScore& score) {
  std::map<int, std::vector<int>> credited;
  for (const ClusterTruth& c : score.clusters) credited[clusters[c.cluster].id] = c.credited;
  return credited;
}

// The merged count taken apart against the truth (merge_truth.h), logged in one line.
Json MergeTruthJson(const SideInputs& front, const SideInputs& back, const std::vector<SideCluster>& front_clusters,
                    const std::vector<SideCluster>& back_clusters, const SharedCount& shared) {
  const std::set<int> visible_front = ReadSideVisibleApples(front.truth), visible_back = ReadSideVisibleApples(back.truth);
  const SideTruthScore front_score = CreditMergeClusters(front, front_clusters, visible_front),
                       back_score = CreditMergeClusters(back, back_clusters, visible_back);
  const MergeTruth t = ScoreMergeAgainstTruth(front_clusters, back_clusters, shared, Credited(front_clusters, front_score),
                                              Credited(back_clusters, back_score), visible_front, visible_back);
  // What each side's extra is made of, in the side's own terms (truth_score.h).
  const auto extra_parts = [](const SideTruthScore& side) {
    return Json{{"duplicates", side.duplicates}, {"over_counted", side.over_counted}, {"not_visible", side.not_visible}};
  };
  spdlog::info("truth: merged {} for {} visible: clusters above their apples +{} front, +{} back; held by neither -{}; "
               "held by both sides {} ({} linked, {} not: counted twice), counted once {:.0f}",
               t.total, t.visible_any, t.extra_front, t.extra_back, t.held_by_neither, t.held_both, t.linked,
               t.unlinked, t.shared);
  return {{"visible_any", t.visible_any},
          {"visible_both", t.visible_both},
          {"held_front", t.held_front},
          {"held_back", t.held_back},
          {"held_both", t.held_both},
          {"held_by_neither", t.held_by_neither},
          {"linked", t.linked},
          {"unlinked", t.unlinked},
          {"extra_front", t.extra_front},
          {"extra_back", t.extra_back},
          {"extra_front_parts", extra_parts(front_score)},
          {"extra_back_parts", extra_parts(back_score)},
          {"shared", t.shared},
          {"note", "total - visible_any = extra_front + extra_back - held_by_neither + unlinked + (linked - shared): "
                   "the sides' merge clusters scored against the generator's masks"}};
}

Json AlignmentJson(const Registration& r, const std::string& method) {
  Json j = {{"method", method},
          {"heading_deg", r.heading_deg},
          {"along_m", r.along},
          {"across_m", r.across},
          {"matched", r.matched},
          {"residual_m", r.residual},
          {"chance_matched", r.chance_matched},
          {"back_scale", r.back_scale},
          {"overlap_m", r.overlap},
          {"front_length_m", r.front_length},
          {"back_length_m", r.back_length}};
  if (r.has_profile) j["profile_correlation"] = r.correlation;
  if (r.on_row) {
    j["chance_profile_correlation"] = r.chance_correlation;
    j["across_from"] = r.across_from == Registration::Across::kAssumed
                           ? "assumed: each side sees into the canopy up to its centre plane"
                       : r.across_from == Registration::Across::kTrunks
                           ? "trunks: each side's trunks in its sparse points"
                           : "fruit clusters seen from both sides";
  }
  if (r.trunks_front > 0 || r.trunks_back > 0 || !std::isnan(r.across_trunks)) {
    j["trunks"] = {{"front", r.trunks_front}, {"back", r.trunks_back}};
    if (!std::isnan(r.across_trunks)) j["trunks"]["across_m"] = r.across_trunks;
  }
  return j;
}

// Annotated frames written by the side, evenly spread (paths relative to out).
std::vector<std::string> SampleFrames(const fs::path& out, const std::string& side, int n) {
  std::vector<std::string> picked;
  const fs::path dir = out / side / "annotated";
  if (n <= 0 || !fs::is_directory(dir)) return picked;
  const std::vector<fs::path> all = ListImages(dir);
  if (all.empty()) return picked;
  for (int i = 0; i < n && i < static_cast<int>(all.size()); ++i) {
    const size_t k = all.size() * (2 * i + 1) / (2 * n);
    picked.push_back(side + "/annotated/" + all[std::min(k, all.size() - 1)].filename().string());
  }
  return picked;
}

}  // namespace

YieldSummary RunYield(const YieldInputs& in, const YieldOptions& o) {
  o.Check();
  if (in.out.empty()) Fail("no output folder");
  if (o.poses_registered && (in.front.poses.empty() || in.back.poses.empty()))
    Fail("--poses-registered needs given poses for both sides (--poses-front and --poses-back)");
  if (!in.truth.empty() && !fs::is_regular_file(in.truth)) Fail("truth file ", in.truth.string(), " does not exist");
  // Checked before the long run: a calibration holds only for its detector and counter.
  Calibration calibration;
  if (!in.calibration.empty()) {
    calibration = ReadCalibration(in.calibration);
    if (MethodKey(calibration.detector) != MethodKey(in.front.detector_name) ||
        MethodKey(calibration.counter) != MethodKey(in.front.counter_name))
      Fail("calibration ", in.calibration.string(), " was made with detector '", calibration.detector,
           "' and counter '", calibration.counter, "', this run uses '", in.front.detector_name, "' and '",
           in.front.counter_name, "'");
  }
  fs::create_directories(in.out);
  Stopwatch stopwatch;
  Json timings = Json::object();
  YieldSummary y;

  // 1-2: each side in 3D (resumes from its caches in OUT/<side>/).
  SideInputs front = in.front, back = in.back;
  front.out = in.out / "front", back.out = in.out / "back";
  // Each side is also counted alone under `orchard side`'s cluster rules.
  SideOptions side_options = o.side;
  ClusterOptions one_side = o.side.clusters;
  one_side.min_points = ClusterOptions().min_points;
  one_side.max_lost_fraction = ClusterOptions().max_lost_fraction;
  one_side.best_views_by = ClusterOptions().best_views_by;
  side_options.one_side_clusters = one_side;
  spdlog::info("[yield 1/4] front side: frames, poses, fruit, 3D clusters -> {}", front.out.string());
  y.front_side = RunSide(front, side_options);
  timings["front side"] = stopwatch.Lap();
  spdlog::info("[yield 2/4] back side -> {}", back.out.string());
  y.back_side = RunSide(back, side_options);
  timings["back side"] = stopwatch.Lap();
  for (const auto& [name, s] : {std::pair<std::string, const SideSummary*>{"front", &y.front_side}, {"back", &y.back_side}}) {
    timings[name + ": poses"] = s->poses_s;
    timings[name + ": detection and counting"] = s->fruit_s;
    timings[name + ": 3D clusters"] = s->clusters_s;
  }

  // 3: registration.
  spdlog::info("[yield 3/4] registering the two sides");
  Json face_json;
  if (o.face_check) {
    // Before the registration, which can align a side with its own mirror image.
    const FaceCheck faces = CheckOppositeFaces(y.front_side.frame_paths, y.back_side.frame_paths, o.faces);
    const std::string front_frame = faces.front_frame.filename().string(),
                      back_frame = faces.back_frame.filename().string();
    face_json = {{"best_inliers", faces.best_inliers}, {"max_inliers", o.faces.max_inliers},
                 {"front_frame", front_frame}, {"back_frame", back_frame}};
    if (faces.same_face)
      Fail("the front and back videos show the same face of the row (frames ", front_frame, " and ", back_frame,
           " share ", faces.best_inliers,
           " matched features, opposite faces share few): film the back from the other side of the row");
  }
  // A registration that fails after a side's reconstruction warned says so:
  // the cause is then more likely that side's poses than the row.
  const auto fail_naming_broken_sides = [&](const Error& e) {
    std::string broken;
    for (const auto& [name, s, dir] : {std::tuple<std::string, const SideSummary*, fs::path>{"front", &y.front_side, front.out},
                                       {"back", &y.back_side, back.out}})
      if (!s->warnings.empty())
        broken += "; the " + name + " side's reconstruction warned " + std::to_string(s->warnings.size()) +
                  " time(s) (first: " + s->warnings.front() + "; all in " + (dir / "side.json").string() +
                  "): it is likely broken";
    Fail(e.what(), broken);
  };
  // The column of the sides' clusters.csv that counts a cluster the other side does not link.
  const std::string unlinked_column =
      o.unlinked_by_sides_rule ? std::string("count_by_") + BestViewsName(ResolvedBestViews(one_side, in.front))
                               : std::string("count");
  SideCloud front_cloud = LoadSideCloud(front.out, "front", unlinked_column);
  SideCloud back_cloud = LoadSideCloud(back.out, "back", unlinked_column);
  RowRegistrationOptions row_options = o.row;
  row_options.camera_height = o.side.camera_height;
  Json levelling = Json::object(), merge_warnings = Json::array();
  if (!o.poses_registered) {
    // Ground planes level and coincident, scales alike: the side's own
    // ground fit can take the canopy's lower edge for the ground.
    for (SideCloud* cloud : {&front_cloud, &back_cloud}) {
      // Given poses are metric unless rescaled by the camera height: their
      // scale stays (their points are COLMAP's, triangulated for them).
      const SideInputs& side_in = cloud == &front_cloud ? in.front : in.back;
      const bool metric = !side_in.poses.empty() && !o.side.rescale_given_poses;
      Levelling l;
      try {
        l = LevelOnSparseGround(cloud, row_options, metric);
      } catch (const Error& e) {
        fail_naming_broken_sides(e);
      }
      if (l.ground_points == 0) continue;
      levelling[cloud->name] = {{"changed", l.changed}, {"ground_height_m", l.ground_height},
                                {"tilt_deg", l.tilt_deg}, {"scale", l.scale}, {"ground_points", l.ground_points}};
      if (l.changed) {
        const std::string w = cloud->name + ": its sparse points show the ground " + std::to_string(-l.ground_height) +
                              " m below its ground plane (tilt " + std::to_string(l.tilt_deg) +
                              " deg): re-levelled" +
                              (metric ? std::string(" (given poses: scale kept)")
                                      : " and rescaled by " + std::to_string(l.scale)) +
                              " for the merge (the side's own count used the old plane)";
        spdlog::warn("{}", w);
        merge_warnings.push_back(w);
      }
    }
  }
  std::string method;
  bool fruit_registered = false;  // by RegisterSides (not the given poses nor the row)
  Json given_check;
  // What the registration matches: the kept clusters and, unless turned off,
  // the fallen ones (the apples lying under the row both sides see). Made
  // once for the registrations tried; the given poses' check below needs the
  // back as the fruit registration rescaled it.
  const auto landmarks = [&](const SideCloud& side) {
    // Edge apples' places along their rays are not known: no landmarks.
    const SideCloud without_edges = WithoutEdgeApples(side);
    return o.fallen_landmarks ? WithFallenLandmarks(without_edges) : without_edges;
  };
  const SideCloud front_marks = landmarks(front_cloud), back_marks = landmarks(back_cloud);
  // The transform the given poses imply when both are in one frame.
  const Eigen::Isometry3d given = front_cloud.to_row * back_cloud.to_row.inverse();
  if (o.poses_registered) {
    y.registration = EvaluateAlignment(front_marks, back_marks, given, o.registration);
    method = "given poses in one frame";
  } else {
    const bool both_given = !in.front.poses.empty() && !in.back.poses.empty();
    try {
      y.registration = RegisterSides(front_marks, back_marks, o.registration, both_given ? &given : nullptr);
      method = "fruit clusters seen from both sides (Hough vote + closest points)";
      // The alignment holds for the back side at the scale it found (kept
      // once the canopies agree too).
      SideCloud scaled_back = back_cloud;
      ScaleSideCloud(&scaled_back, y.registration.back_scale);
      if (y.registration.settled_by_given_poses) {
        method += "; not distinct from another alignment, taken as it agrees with the given poses";
        spdlog::info("the fruit clusters' best alignment ({} matched) is not distinct from another ({}); taken as "
                     "it agrees with the given poses", y.registration.matched, y.registration.chance_matched);
      }
      if (o.row_registration) {
        // A few clusters can match by chance: the canopies must agree too.
        const double c = CanopyProfileCorrelation(WithoutEdgeApples(front_cloud), WithoutEdgeApples(scaled_back),
                                                  y.registration.back_to_front, row_options);
        if (!std::isnan(c)) {
          y.registration.has_profile = true, y.registration.correlation = c;
          if (c < row_options.min_correlation)
            Fail("the fruit clusters' alignment (", y.registration.matched,
                 " matched) puts the canopies out of line (profile correlation ", c, ", need ",
                 row_options.min_correlation, ")");
        }
      }
      if (y.registration.back_scale != 1)
        spdlog::info("back side rescaled by {:.3f} to fit the front's fruit", y.registration.back_scale);
      back_cloud = std::move(scaled_back);
      fruit_registered = true;
    } catch (const Error& fruit_error) {
      if (!o.row_registration || front_cloud.sparse.empty() || back_cloud.sparse.empty()) {
        // Given poses have sparse points only when COLMAP triangulated them
        // (SideOptions::triangulate_given_poses, colmap installed).
        if (!both_given) fail_naming_broken_sides(fruit_error);
        fail_naming_broken_sides(Error(std::string(fruit_error.what()) +
                                       " (if the given poses of both sides share one frame, say so with "
                                       "--poses-registered)"));
      }
      spdlog::info("fruit registration failed ({}); registering on the row", fruit_error.what());
      try {
        y.registration = RegisterSidesOnRow(front_marks, back_marks, row_options);
      } catch (const Error& e) {
        fail_naming_broken_sides(e);
      }
      const Registration::Across from = y.registration.across_from;
      method = "row: levelled grounds, canopy profiles along the row, " +
               std::string(from == Registration::Across::kAssumed ? "across assumed (canopy centre plane)"
                           : from == Registration::Across::kTrunks ? "across from the trunks"
                                                                   : "across from shared fruit clusters");
      // Only with --same-row (the row registration stops otherwise): rows of
      // one planting have alike canopy profiles and trunks, so the count
      // rests on the user's word.
      if (from != Registration::Across::kFruit) {
        const std::string w =
            "no fruit clusters clearly seen from both sides: the sides were registered on the canopy's shape (profile "
            "correlation " +
            std::to_string(y.registration.correlation) + ")" +
            (from == Registration::Across::kTrunks ? " and the trunks" : " alone") +
            ", taken as the same row on the user's word (--same-row); neither tells this row from another row of "
            "the same planting";
        spdlog::warn("{}", w);
        merge_warnings.push_back(w);
      }
    }
    if (both_given) {
      // Both sides came with poses: if they share a frame (the generator's
      // true poses, RTK-GNSS), this is the registration's error.
      const Registration g = EvaluateAlignment(front_marks, landmarks(back_cloud), given, o.registration);
      given_check = {{"heading_deg", y.registration.heading_deg - g.heading_deg},
                     {"along_m", y.registration.along - g.along},
                     {"across_m", y.registration.across - g.across},
                     {"note", "solved minus the transform implied by the given poses (meaningful when they share a frame)"}};
    }
  }
  // Each side's trunks, found once with the sides as registered (the back
  // rescaled): a check on the fruit registration's distance across, and the
  // trees of the per-tree counts.
  const std::vector<Trunk> front_trunks = FindTrunks(front_cloud, row_options);
  std::vector<Trunk> back_trunks = FindTrunks(back_cloud, row_options);
  if (fruit_registered) {
    const TrunkAcross trunks = AcrossFromTrunks(front_trunks, back_trunks, row_options);
    y.registration.across_trunks = trunks.across;
    y.registration.trunks_front = trunks.front, y.registration.trunks_back = trunks.back;
    if (std::abs(trunks.across - y.registration.across) > row_options.max_trunk_disagreement) {
      const std::string w = "the fruit clusters put the camera paths " + std::to_string(y.registration.across) +
                            " m apart, the trunks " + std::to_string(trunks.across) +
                            " m: one of them is wrong (chance fruit matches, or posts taken for trunks)";
      spdlog::warn("{}", w);
      merge_warnings.push_back(w);
    }
  }
  timings["registration"] = stopwatch.Lap();
  // Of the matches, how many are fallen apples (reported).
  int matched_fallen = 0;
  if (o.fallen_landmarks) {
    SideCloud front_fallen, back_fallen;
    front_fallen.clusters = front_cloud.fallen, back_fallen.clusters = back_cloud.fallen;
    matched_fallen = EvaluateAlignment(front_fallen, back_fallen, y.registration.back_to_front, o.registration).matched;
  }
  spdlog::info("aligned: heading {:.2f} deg, along {:.3f} m, across {:.3f} m, {} clusters matched ({} fallen), "
               "residual {:.1f} cm",
               y.registration.heading_deg, y.registration.along, y.registration.across, y.registration.matched,
               matched_fallen, 100 * y.registration.residual);

  // 4: shared apples once, outputs.
  spdlog::info("[yield 4/4] counting shared apples once, writing outputs");
  std::vector<SideCluster> back_in_front = back_cloud.clusters;
  for (auto& c : back_in_front)
    MoveCluster(&c, [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return y.registration.back_to_front * p; });
  SharedCountOptions shared_options = o.shared;
  shared_options.intersection_distance = IntersectionDistance(o, y.registration);
  const SharedCount shared = CountSharedApples(front_cloud.clusters, back_in_front, shared_options);
  if (shared.sight_links > 0)
    spdlog::info("clusters linked along a line of sight (an apple seen through a gap in the leaves): {}",
                 shared.sight_links);
  // From here on each cluster's count is the one the merge used.
  for (auto [clusters, counts] : {std::pair{&front_cloud.clusters, &shared.front_counts}, {&back_in_front, &shared.back_counts}})
    for (size_t i = 0; i < clusters->size(); ++i) {
      y.unlinked_added += (*counts)[i] - (*clusters)[i].count;
      (*clusters)[i].count = (*counts)[i];
    }
  y.merge_front = shared.front, y.merge_back = shared.back, y.merge_shared = shared.shared, y.total = shared.total;
  if (y.unlinked_added != 0)
    spdlog::info("merge clusters linked to nothing on the other side, counted by their side's rule ({}): {:+d} apples",
                 unlinked_column, y.unlinked_added);
  y.front = y.front_side.one_side_count, y.back = y.back_side.one_side_count;
  y.sum_of_sides = y.front + y.back;
  y.shared = y.sum_of_sides - y.total;

  // Per-metre map: each cluster's count minus half of what it shares.
  std::vector<MapCluster> map;
  const auto map_cluster = [](const char* side, const SideCluster& c, double shared_part, bool on_tracked) {
    return MapCluster{side, c.centre.x(), c.centre.z(), c.count, shared_part,
                      c.count - (on_tracked ? shared_part : 0.5 * shared_part)};
  };
  for (size_t i = 0; i < front_cloud.clusters.size(); ++i)
    map.push_back(map_cluster("front", front_cloud.clusters[i], shared.front_shared[i], shared.front_edge_on[i] >= 0));
  for (size_t i = 0; i < back_in_front.size(); ++i)
    map.push_back(map_cluster("back", back_in_front[i], shared.back_shared[i], shared.back_edge_on[i] >= 0));
  Json per_metre = Json::array();
  if (!map.empty()) {
    double x0 = map[0].along, x1 = x0;
    for (const auto& m : map) x0 = std::min(x0, m.along), x1 = std::max(x1, m.along);
    x0 = std::floor(x0 / o.bin_length) * o.bin_length;
    const int bins = std::max(1, static_cast<int>(std::ceil((x1 - x0) / o.bin_length + 1e-9)));
    std::vector<double> sum(bins, 0);
    for (const auto& m : map)
      sum[std::min(bins - 1, static_cast<int>((m.along - x0) / o.bin_length))] += m.part;
    for (int b = 0; b < bins; ++b) {
      per_metre.push_back({{"from", x0 + b * o.bin_length}, {"to", x0 + (b + 1) * o.bin_length},
                           {"count", std::round(sum[b] * 10) / 10}});
      // The calibration corrects for apples hidden from both sides, which
      // hang where the seen ones do (as far as the harvested rows tell), so
      // it scales each bin as it scales the total.
      if (!in.calibration.empty()) per_metre.back()["calibrated"] = std::round(sum[b] * calibration.factor * 10) / 10;
    }
  }

  // Per tree, where the sides' sparse points show the trunks: each
  // cluster's share as in the per-metre bins, to the tree whose stretch of
  // row holds it (midway to the neighbouring trees).
  Json per_tree = Json::array();
  double per_tree_outside = 0;
  {
    for (auto& t : back_trunks)
      t.along = (y.registration.back_to_front * Eigen::Vector3d(t.along, t.across, 0)).x();
    const std::vector<RowTree> trees = TreesFromTrunks(front_trunks, back_trunks, 0.5 * row_options.min_trunk_spacing);
    std::vector<double> sum(trees.size(), 0);
    for (const auto& m : map) {
      const int k = TreeAt(trees, m.along, 0.5 * o.bin_length);
      (k >= 0 ? sum[k] : per_tree_outside) += m.part;
    }
    for (size_t k = 0; k < trees.size(); ++k) {
      per_tree.push_back({{"tree", k},
                          {"along_m", trees[k].along},
                          {"trunk_seen_from", trees[k].front && trees[k].back ? "both"
                                              : trees[k].front               ? "front"
                                                                             : "back"},
                          {"count", std::round(sum[k] * 10) / 10}});
      if (!in.calibration.empty()) per_tree.back()["calibrated"] = std::round(sum[k] * calibration.factor * 10) / 10;
    }
  }

  Json warnings = Json::array();
  for (const SideCloud* cloud : {&front_cloud, &back_cloud})
    for (const auto& w : cloud->warnings) warnings.push_back(cloud->name + ": " + w);
  for (const auto& w : merge_warnings) warnings.push_back(w);
  if (y.shared < 0)
    warnings.push_back("the merged total exceeds the sum of the sides' own counts: the sides' counts are not "
                       "consistent with their merge");
  if (o.poses_registered && y.registration.matched < o.registration.min_matched)
    warnings.push_back("the given poses match only " + std::to_string(y.registration.matched) +
                       " clusters across the sides: are they really in one frame?");
  for (const auto& w : warnings) y.warnings.push_back(w.get<std::string>());

  timings["merge"] = stopwatch.Lap();
  Json j = {
      {"total", y.total},
      {"front", y.front},
      {"back", y.back},
      {"sum_of_sides", y.sum_of_sides},
      {"shared", std::round(y.shared * 10) / 10},
      {"merge", {{"front_clusters", y.merge_front},
                 {"back_clusters", y.merge_back},
                 {"shared", std::round(y.merge_shared * 10) / 10},
                 {"unlinked_added", y.unlinked_added},
                 {"sight_links", shared.sight_links},
                 {"note", "total = front_clusters + back_clusters - shared: the sides' clusters kept for the merge "
                          "(" + std::to_string(o.side.clusters.min_points) +
                              " fruit points, ghosts removed) and the apples the inclusion-exclusion counted once; "
                              "unlinked_added: what the clusters linked to nothing on the other side added, counted "
                              "by their side's rule (" + unlinked_column + ") rather than in their largest views; "
                              "front and back above are each side's own count (orchard side's rules)"}}},
      {"per_metre", per_metre},
      {"bin_length_m", o.bin_length},
      {"per_tree", per_tree},
      {"alignment", AlignmentJson(y.registration, method)},
      {"sides", {{"front", SideJson(y.front_side, front_cloud, front)}, {"back", SideJson(y.back_side, back_cloud, back)}}},
      {"warnings", warnings},
      {"version", ORCHARD_VERSION},
  };
  if (!per_tree.empty()) j["per_tree_outside"] = std::round(per_tree_outside * 10) / 10;
  j["alignment"]["matched_fallen"] = matched_fallen;
  if (!given_check.is_null()) j["alignment"]["minus_given_poses"] = given_check;
  if (!levelling.empty()) j["alignment"]["levelling"] = levelling;
  if (!face_json.is_null()) j["alignment"]["face_check"] = face_json;
  j["settings"] = {
      {"front", in.front.input.string()},
      {"back", in.back.input.string()},
      {"detector", in.front.detector_name},
      {"counter", in.front.counter_name},
      {"poses_front", in.front.poses.empty() ? "colmap" : in.front.poses.string()},
      {"poses_back", in.back.poses.empty() ? "colmap" : in.back.poses.string()},
      {"poses_registered", o.poses_registered},
      {"camera_height_m", o.side.camera_height},
      {"link_distance_m", o.side.clusters.link_distance},
      {"split_counted_blobs", o.side.split_counted_blobs},
      {"vote_near_first", o.side.clusters.vote_near_first},
      {"duplicate_shared_fraction", o.side.clusters.duplicate_shared_fraction},
      {"edge_apples", o.side.clusters.edge.enabled},
      {"glimpsed_apples", ResolvedGlimpsedApples(o.side.clusters, in.front)},
      {"edge_min_pixels", ResolvedEdgeMinPixels(o.side.clusters, in.front)},
      {"min_apple_fraction", ResolvedMinAppleFraction(o.side.clusters, in.front)},
      {"covered_max_points", o.side.clusters.covered_max_points},
      {"covered_fraction", o.side.clusters.covered_fraction},
      {"best_views_by", BestViewsName(ResolvedBestViews(o.side.clusters, in.front))},
      {"sides_best_views_by", BestViewsName(ResolvedBestViews(one_side, in.front))},
      {"unlinked_count", unlinked_column},
      {"match_distance_m", o.registration.match_distance},
      {"max_scale_change", o.registration.max_scale_change},
      {"row_registration", o.row_registration},
      {"fallen_landmarks", o.fallen_landmarks},
      {"same_row", o.row.assume_same_row},
      {"intersection_distance_m", shared_options.intersection_distance},
      {"intersection_floor_m", o.shared.intersection_distance},
      {"intersection_per_residual", o.intersection_per_residual},
      {"sight_link_m", o.shared.sight_across},
  };
  if (!in.calibration.empty()) {
    y.calibration_factor = calibration.factor;
    y.calibrated_total = static_cast<int>(std::lround(y.total * calibration.factor));
    j["calibrated"] = {{"total", y.calibrated_total},
                       {"factor", calibration.factor},
                       {"file", in.calibration.string()},
                       {"runs", calibration.runs.size()}};
    if (!calibration.loo_error_percent.empty())
      j["calibrated"]["leave_one_out_mean_absolute_error_percent"] = calibration.loo_mean_absolute_error_percent;
  }
  if (!in.truth.empty()) {
    const Json t = Json::parse(ReadTextFile(in.truth), nullptr, false);
    if (t.is_discarded() || !t.contains("harvested")) Fail("truth file ", in.truth.string(), " has no \"harvested\" count");
    Json truth = {{"file", in.truth.string()}};
    for (const char* k : {"harvested", "visible_any", "visible_both", "visible_front", "visible_back"})
      if (t.contains(k)) truth[k] = t.at(k);
    const double harvested = t.at("harvested").get<double>(), visible = t.value("visible_any", 0.0);
    if (harvested > 0) truth["total_percent_of_harvested"] = 100.0 * y.total / harvested;
    if (harvested > 0 && !in.calibration.empty())
      truth["calibrated_percent_of_harvested"] = 100.0 * y.calibrated_total / harvested;
    if (visible > 0) {
      truth["total_percent_of_visible_any"] = 100.0 * y.total / visible;
      truth["sum_of_sides_percent_of_visible_any"] = 100.0 * y.sum_of_sides / visible;
    }
    // Per tree: the generator's trees stand in order along the front
    // camera's path (it films along +x), as the trunks found do.
    if (!per_tree.empty() && t.contains("per_tree")) {
      const Json& trees = t.at("per_tree");
      if (trees.size() != per_tree.size()) {
        truth["per_tree_note"] = std::to_string(per_tree.size()) + " trees found, " + std::to_string(trees.size()) +
                                 " in the truth: not compared";
      } else {
        Json compared = Json::array();
        double abs_sum = 0;
        int n = 0;
        for (size_t k = 0; k < trees.size(); ++k) {
          const double v = trees[k].value("visible_any", 0.0), c = per_tree[k].at("count").get<double>();
          compared.push_back(
              {{"tree", k}, {"count", c}, {"visible_any", v}, {"harvested", trees[k].value("harvested", 0.0)}});
          if (v > 0) {
            compared.back()["percent_of_visible_any"] = 100.0 * c / v;
            abs_sum += 100.0 * std::abs(c - v) / v, ++n;
          }
        }
        truth["per_tree"] = compared;
        if (n > 0) truth["per_tree_mean_abs_error_percent"] = abs_sum / n;
      }
    }
    if (!front.truth.empty() && !back.truth.empty()) truth["merge"] = MergeTruthJson(front, back, front_cloud.clusters,
                                                                                   back_in_front, shared);
    j["truth"] = truth;
  }

  // clusters.csv and row.ply, both in the front side's row frame.
  std::ostringstream csv, ply;
  csv << "side,id,x,y,z,count,shared,points\n";
  csv.precision(4);
  csv << std::fixed;
  size_t num_points = 0;
  for (const auto& c : front_cloud.clusters) num_points += c.points.size();
  for (const auto& c : back_in_front) num_points += c.points.size();
  ply << "ply\nformat ascii 1.0\ncomment orchard yield: both sides in the front side's row frame (x along, y across, "
         "z up, m); red = seen from both sides\nelement vertex "
      << num_points
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\nproperty uchar side\nproperty int cluster\nproperty float shared\nend_header\n";
  auto write_side = [&](const std::vector<SideCluster>& clusters, const std::vector<double>& shared_of, int side) {
    for (size_t i = 0; i < clusters.size(); ++i) {
      const auto& c = clusters[i];
      csv << (side == 0 ? "front" : "back") << ',' << c.id << ',' << c.centre.x() << ',' << c.centre.y() << ','
          << c.centre.z() << ',' << c.count << ',' << shared_of[i] << ',' << c.points.size() << '\n';
      const int r = shared_of[i] > 0 ? 220 : 30, g = shared_of[i] > 0 ? 30 : (side == 0 ? 170 : 110),
                b = shared_of[i] > 0 ? 30 : (side == 0 ? 110 : 220);
      for (const auto& p : c.points)
        ply << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << r << ' ' << g << ' ' << b << ' ' << side << ' ' << c.id
            << ' ' << shared_of[i] << '\n';
    }
  };
  write_side(front_cloud.clusters, shared.front_shared, 0);
  write_side(back_in_front, shared.back_shared, 1);
  WriteTextFileAtomic(in.out / "clusters.csv", csv.str());
  WriteTextFileAtomic(in.out / "row.ply", ply.str());
  timings["outputs"] = stopwatch.Lap();
  j["timings_s"] = timings;
  std::vector<std::string> frames = SampleFrames(in.out, "front", o.report_frames);
  for (const auto& f : SampleFrames(in.out, "back", o.report_frames)) frames.push_back(f);
  WriteTextFileAtomic(in.out / "report.html", YieldReportHtml(j, map, frames));
  // yield.json last: its presence means the run completed.
  WriteTextFileAtomic(in.out / "yield.json", j.dump(2) + "\n");
  spdlog::info("row: {} apples (front {}, back {}, shared {:.1f}; sum of sides {})", y.total, y.front, y.back,
               y.shared, y.sum_of_sides);
  return y;
}

}  // namespace orchard
