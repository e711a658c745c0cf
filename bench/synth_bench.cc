// Times `orchard synth --seed 1` with default options (four trees, both
// sides) against the goal of one minute on a 2-core machine.
// usage: bench_synth [OUT_DIR] [THREADS]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "orchard/synth/synth.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const fs::path out = argc > 1 ? fs::path(argv[1]) : fs::temp_directory_path() / "orchard_bench_synth";
  orchard::synth::SynthOptions options;  // defaults, as `orchard synth --seed 1`
  options.seed = 1;
  options.progress = false;
  if (argc > 2) options.threads = std::atoi(argv[2]);
  fs::remove_all(out);
  const auto start = std::chrono::steady_clock::now();
  const auto s = orchard::synth::RunSynth(options, out);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("orchard synth --seed 1 (defaults): %d frames per side, both sides, %d patches\n", s.frames_per_side,
              s.patches);
  std::printf("  harvested %d, visible front %d, back %d, any %d, both %d, fallen %d\n", s.harvested,
              s.visible_front, s.visible_back, s.visible_any, s.visible_both, s.fallen);
  std::printf("  %.1f s wall on %u hardware threads (goal: under 60 s on 2 cores): %s\n", seconds,
              std::thread::hardware_concurrency(), seconds < 60 ? "PASS" : "FAIL");
  return 0;
}
