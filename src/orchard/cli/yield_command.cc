// `orchard yield`: two videos (one per side of a row) in, the row's apple
// count out: both sides in 3D, registered, shared apples counted once; see
// docs/yield.md.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/cli/side_args.h"
#include "orchard/merge/yield.h"

namespace orchard {

void AddYieldCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "yield", "Count a row's apples from both sides: yield.json, clusters.csv, row.ply, report.html");
  struct Args {
    std::string front, back, out, poses_front, poses_back, ground_front, ground_back, masks_front, masks_back, truth,
        calibration;
    FruitArgs fruit;
    YieldOptions options;
  };
  auto a = std::make_shared<Args>();
  YieldOptions& o = a->options;
  cmd->add_option("--front", a->front, "Front side: video file or folder of frames")->required();
  cmd->add_option("--back", a->back, "Back side: video file or folder of frames")->required();
  cmd->add_option("--out", a->out, "Output folder (front/ and back/ keep each side's caches, so a rerun resumes)")
      ->required();
  cmd->add_option("--poses-front", a->poses_front, "COLMAP model of the front frames (default: run COLMAP)");
  cmd->add_option("--poses-back", a->poses_back, "COLMAP model of the back frames (default: run COLMAP)");
  cmd->add_option("--ground-front", a->ground_front, "Front ground plane nx,ny,nz,d or scene.json (default: fitted)");
  cmd->add_option("--ground-back", a->ground_back, "Back ground plane nx,ny,nz,d or scene.json (default: fitted)");
  cmd->add_option("--masks-front", a->masks_front, "Front instance masks (with --detector masks)");
  cmd->add_option("--masks-back", a->masks_back, "Back instance masks (with --detector masks)");
  cmd->add_flag("--poses-registered", o.poses_registered,
                "The given poses of both sides are in one frame (RTK-GNSS, one SLAM run): skip the registration");
  cmd->add_option("--truth", a->truth,
                  "Ground truth json (the generator's truth.json) to compare against; with the generator's side "
                  "folders beside it each side is scored too (yield.json sides.<side>.truth, OUT/<side>/truth_clusters.csv) "
                  "and the merged count taken apart (yield.json truth.merge)");
  cmd->add_option("--calibration", a->calibration,
                  "Calibration from harvested rows (orchard calibrate): also report the calibrated total");
  cmd->add_option("--match-distance", o.registration.match_distance,
                  "Clusters of the two sides closer than this (m) can be the same fruit (registration)")
      ->capture_default_str();
  cmd->add_option("--max-heading", o.registration.max_heading_deg,
                  "Largest angle between the two camera paths (degrees)")
      ->capture_default_str();
  cmd->add_option("--max-scale-change", o.registration.max_scale_change,
                  "The back side's scale is fitted to the front's fruit within 1 +- this (each side's scale comes from "
                  "its own ground fit; 0: take the scales as they are)")
      ->capture_default_str();
  cmd->add_flag("--no-row-registration{false}", o.row_registration,
                "Register the sides from their shared fruit clusters only (no fallback to the row's ground and canopy)");
  cmd->add_flag("--no-fallen-landmarks{false}", o.fallen_landmarks,
                "Register the sides on the fruit on the trees only (not also on the fallen apples both sides see)");
  cmd->add_flag("--same-row", o.row.assume_same_row,
                "Both videos film the same row: when no fruit is clearly seen from both sides, register them on the "
                "canopy's shape alone (it cannot tell rows of one planting apart, so without this the run stops)");
  cmd->add_flag("--no-face-check{false}", o.face_check,
                "Do not check that the two videos show opposite faces of the row (feature matching)");
  cmd->add_option("--face-max-inliers", o.faces.max_inliers,
                  "Matched features between a front and a back frame above which they show the same face")
      ->capture_default_str();
  cmd->add_option("--intersection-distance", o.shared.intersection_distance,
                  "Fruit points of the two sides closer than this (m) are the same apple (shared count); the floor "
                  "when --intersection-per-residual is set")
      ->capture_default_str();
  cmd->add_option("--intersection-per-residual", o.intersection_per_residual,
                  "Widen the intersection distance to this many times the registration's residual (0 = fixed)")
      ->capture_default_str();
  cmd->add_option("--glimpse-link", o.shared.glimpse_across,
                  "A glimpsed apple links to a cluster of the other side with a point this near (m) one of its rays")
      ->capture_default_str();
  cmd->add_option("--glimpse-link-vertical", o.shared.glimpse_vertical,
                  "... and at most this far (m) over or under it")
      ->capture_default_str();
  cmd->add_option("--sight-link", o.shared.sight_across,
                  "Link two clusters linked to nothing when one lies within this (m) of the other's lines of sight, "
                  "behind it: a partly hidden apple seen through a gap in the leaves (0 = off)")
      ->capture_default_str();
  cmd->add_flag("--no-unlinked-sides-rule{false}", o.unlinked_by_sides_rule,
                "Count merge clusters linked to nothing on the other side in their largest views, like the linked "
                "ones, not by their side's own best-views rule");
  cmd->add_option("--bin-length", o.bin_length, "Length of the yield map's bins along the row (m)")
      ->capture_default_str();
  AddFruitOptions(cmd, &a->fruit);
  AddSideOptions(cmd, &o.side);
  cmd->callback([a]() {
    YieldInputs in;
    in.out = a->out;
    in.truth = a->truth;
    in.calibration = a->calibration;
    in.front.input = a->front, in.back.input = a->back;
    in.front.poses = a->poses_front, in.back.poses = a->poses_back;
    if (!a->ground_front.empty()) in.front.ground = ParseGroundPlane(a->ground_front);
    if (!a->ground_back.empty()) in.back.ground = ParseGroundPlane(a->ground_back);
    FruitTools tools;
    SetUpFruit(a->fruit, a->masks_front, &tools, &in.front);
    SetUpFruit(a->fruit, a->masks_back, &tools, &in.back);
    // The generator's row: its sides' folders hold the masks that score each
    // side's clusters (side.json "truth").
    if (!in.truth.empty())
      for (auto [side, inputs] : {std::pair<const char*, SideInputs*>{"front", &in.front}, {"back", &in.back}})
        if (const fs::path dir = fs::path(in.truth).parent_path() / side; fs::is_directory(dir / "masks"))
          inputs->truth = dir;
    a->options.side.colmap.num_threads = a->fruit.threads;
    const YieldSummary y = RunYield(in, a->options);
    std::printf("row: %d apples (front %d, back %d, seen from both sides %.1f; unmerged sum %d) -> %s/yield.json\n",
                y.total, y.front, y.back, y.shared, y.sum_of_sides, a->out.c_str());
    for (const auto& w : y.warnings) std::printf("warning: %s\n", w.c_str());
    if (!in.calibration.empty())
      std::printf("calibrated: %d apples (x%.3f, %s)\n", y.calibrated_total, y.calibration_factor,
                  in.calibration.string().c_str());
  });
}

}  // namespace orchard
