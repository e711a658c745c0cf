// `orchard demo`: the whole pipeline on a built-in synthetic row: generate a
// row filmed from both sides, run `orchard yield` on it with the shipped
// detector and counter, and print the estimate beside the truth (harvested,
// visible from either side) and the unmerged sum of the two sides.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/cli/side_args.h"
#include "orchard/merge/yield.h"
#include "orchard/synth/synth.h"

namespace orchard {

void AddDemoCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "demo", "Generate a synthetic row, count it from both sides with the shipped models, print it beside the truth");
  struct Args {
    std::string out = "orchard_demo";
    FruitArgs fruit;
    uint64_t seed = 7;
    int trees = 2;
    bool colmap = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--out", a->out, "Output folder (the row in row/, the count in yield/)")->capture_default_str();
  cmd->add_option("--seed", a->seed, "Seed of the synthetic row")->capture_default_str();
  cmd->add_option("--trees", a->trees, "Trees in the row")->capture_default_str();
  cmd->add_flag("--colmap", a->colmap,
                "Poses from COLMAP (minutes per side), the two sides registered from their fruit, instead of the "
                "generator's true poses (one frame for both sides, as RTK-GNSS would give)");
  AddFruitOptions(cmd, &a->fruit);
  cmd->callback([a]() {
    const fs::path out = a->out;
    std::printf("orchard demo: synthetic row (seed %llu, %d trees) filmed from both sides, counted with %s + %s,\n"
                "poses %s. Outputs in %s.\n\n",
                static_cast<unsigned long long>(a->seed), a->trees, a->fruit.detector.c_str(),
                CounterName(a->fruit).c_str(), a->colmap ? "from COLMAP, the sides registered from their fruit"
                           : "from the generator (both sides in one frame)",
                (out / "yield").string().c_str());
    std::fflush(stdout);  // before the stages log to stderr
    synth::SynthOptions synth_options;
    synth_options.seed = a->seed;
    synth_options.scene.num_trees = a->trees;
    synth_options.patch_every = 0;
    const synth::SynthSummary truth = synth::RunSynth(synth_options, out / "row");

    YieldInputs in;
    in.out = out / "yield";
    in.truth = out / "row" / "truth.json";
    FruitTools tools;
    for (const auto& [side, inputs] : {std::pair<std::string, SideInputs*>{"front", &in.front}, {"back", &in.back}}) {
      const fs::path dir = out / "row" / side;
      inputs->input = dir / "images";
      if (!a->colmap) {
        inputs->poses = dir / "sparse";
        inputs->ground = ParseGroundPlane((dir / "scene.json").string());
      }
      SetUpFruit(a->fruit, (dir / "masks").string(), &tools, inputs);
      inputs->truth = dir;  // each side scored against the generator's apples (side.json, report)
    }
    YieldOptions options;
    options.side.colmap.camera_model = "PINHOLE";  // the generator's camera has no distortion
    options.side.colmap.num_threads = a->fruit.threads;
    // The true poses share one frame; registering from the fruit needs more
    // clusters than the shipped detectors find on a two-tree row.
    options.poses_registered = !a->colmap;
    // Both videos film the one row generated here: with COLMAP poses a
    // registration on the canopy alone may be taken (it warns).
    options.row.assume_same_row = true;
    const YieldSummary y = RunYield(in, options);

    auto percent = [](double estimate, double reference) { return reference > 0 ? 100.0 * estimate / reference : 0.0; };
    std::printf("\n%-50s %6s %12s %12s\n", "", "apples", "% harvested", "% visible");
    auto line = [&](const char* name, double n) {
      std::printf("%-50s %6.0f %11.1f%% %11.1f%%\n", name, n, percent(n, truth.harvested), percent(n, truth.visible_any));
    };
    line("truth: harvested (on the row's trees)", truth.harvested);
    line("truth: visible from either side", truth.visible_any);
    line("truth: visible from both sides", truth.visible_both);
    line("estimate: both sides merged", y.total);
    line("  front side", y.front);
    line("  back side", y.back);
    line("  seen from both sides (counted once)", y.shared);
    line("unmerged: sum of the two sides", y.sum_of_sides);
    std::printf("\nalignment of the sides: %d clusters matched, residual %.1f cm\n", y.registration.matched,
                100 * y.registration.residual);
    for (const auto& w : y.warnings) std::printf("warning: %s\n", w.c_str());
    std::printf("outputs: %s (yield.json, report.html, clusters.csv, row.ply), row: %s\n",
                (out / "yield").string().c_str(), (out / "row").string().c_str());
  });
}

}  // namespace orchard
