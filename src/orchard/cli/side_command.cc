// `orchard side`: one side of a row in 3D (frames, poses, fruit points, 3D
// clusters, tracked counts); see docs/side.md.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/cli/side_args.h"
#include "orchard/fruitmap/side.h"

namespace orchard {

void AddSideCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "side", "Count one side of a row in 3D: side.json, clusters.csv, fruit.ply, annotated/ frames");
  struct Args {
    std::string in, out, poses, masks, ground, truth;
    FruitArgs fruit;
    SideOptions options;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--in", a->in, "Video file or folder of frames")->required();
  cmd->add_option("--out", a->out, "Output folder (caches frames/, sparse/, detections/ for reruns)")->required();
  cmd->add_option("--poses", a->poses, "COLMAP text model of the frames (default: run COLMAP)");
  cmd->add_option("--ground-plane", a->ground,
                  "Ground plane nx,ny,nz,d or a json file with ground_plane {normal, d} (default: fit to the sparse points)");
  cmd->add_option("--masks", a->masks, "Instance masks (16-bit, one id per apple) named like the frames");
  cmd->add_option("--truth", a->truth,
                  "The generator's folder of this side (S/front or S/back): score the clusters against its apples "
                  "(found, missed, counted twice; side.json \"truth\", and each cluster's role in truth_clusters.csv)");
  AddFruitOptions(cmd, &a->fruit);
  AddSideOptions(cmd, &a->options);
  cmd->callback([a]() {
    SideInputs in;
    in.input = a->in;
    in.out = a->out;
    in.poses = a->poses;
    in.truth = a->truth;
    if (!a->ground.empty()) in.ground = ParseGroundPlane(a->ground);
    FruitTools tools;
    SetUpFruit(a->fruit, a->masks, &tools, &in);
    a->options.colmap.num_threads = a->fruit.threads;
    const SideSummary s = RunSide(in, a->options);
    std::printf("count %d (single-frame sum %d), %d clusters kept, %d removed, %d frames -> %s\n", s.count,
                s.single_frame_sum, s.clusters_kept, s.clusters_removed, s.frames_used, a->out.c_str());
    for (const auto& w : s.warnings) std::printf("warning: %s\n", w.c_str());
  });
}

}  // namespace orchard
