// Threads above the cores a process may use, measured: the CNN counter's
// patches per second with AvailableCores() threads (what `--threads 0`
// means since the thirty-second session) against the machine's CPU count
// (what it meant before: std::thread::hardware_concurrency, which ignores
// taskset, a scheduler's cpuset and a container's quota) and 4x and 16x the
// available cores, in one run. On a machine whose every CPU is available the
// first two are the same; run it as `taskset -c 0 bench_threads ...` to see a
// job given one CPU of the machine (docs/networks.md, "Threads").
//
//   bench_threads COUNTER.pt PATCH_DIR [PATCHES]
#include <ATen/Parallel.h>

#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/stopwatch.h"
#include "orchard/count/cnn_counter.h"

int main(int argc, char** argv) {
  using namespace orchard;
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_threads COUNTER.pt PATCH_DIR [PATCHES]\n");
    return 2;
  }
  try {
    const size_t max_patches = argc > 3 ? std::stoul(argv[3]) : 400;
    std::vector<cv::Mat> patches;
    for (const fs::path& p : ListImages(argv[2])) {
      patches.push_back(ReadImage(p));
      if (patches.size() == max_patches) break;
    }
    if (patches.empty()) Fail("no patches in ", argv[2]);
    const int available = AvailableCores();
    const int machine = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::printf("machine: %d CPUs, %d available to this process; %zu patches\n", machine, available, patches.size());
    CnnCounter counter(argv[1], available);
    counter.CountBatch({patches.front()});  // warm-up (allocator, thread pool)
    double reference = 0;
    const int runs[] = {available, machine, 4 * available, 16 * available, available};
    const char* what[] = {"available cores (reference)", "machine CPUs", "4x available", "16x available",
                          "available cores again"};
    for (int k = 0; k < 5; ++k) {
      at::set_num_threads(runs[k]);
      Stopwatch stopwatch;
      counter.CountBatch(patches);
      const double s = stopwatch.Lap();
      if (k == 0) reference = s;
      std::printf("%-28s %3d threads: %7.2f s, %7.1f patches/s, %.2fx the reference's time\n", what[k], runs[k], s,
                  patches.size() / s, s / reference);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_threads: %s\n", e.what());
    return 1;
  }
  return 0;
}
