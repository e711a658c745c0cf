#include "orchard/core/cpu.h"

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace orchard {
namespace {

namespace fs = std::filesystem;

std::string FirstLine(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

// The tightest CPU quota on this process's cgroup v2 path and its parents
// (a limit may be set on any ancestor); 0 when none.
int CgroupV2Cores() {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  int cores = 0;
  while (std::getline(in, line)) {
    if (line.rfind("0::", 0) != 0) continue;
    fs::path dir = fs::path("/sys/fs/cgroup") / fs::path(line.substr(3)).relative_path();
    for (;;) {
      const int c = CoresFromCgroupCpuMax(FirstLine(dir / "cpu.max"));
      if (c > 0) cores = cores > 0 ? std::min(cores, c) : c;
      if (dir == "/sys/fs/cgroup" || !dir.has_parent_path() || dir.parent_path() == dir) break;
      dir = dir.parent_path();
    }
  }
  return cores;
}

// cgroup v1: the quota of the cpu controller as the process sees it.
int CgroupV1Cores() {
  for (const char* dir : {"/sys/fs/cgroup/cpu", "/sys/fs/cgroup/cpu,cpuacct"}) {
    const std::string quota = FirstLine(fs::path(dir) / "cpu.cfs_quota_us");
    const std::string period = FirstLine(fs::path(dir) / "cpu.cfs_period_us");
    if (quota.empty() || period.empty()) continue;
    const int c = CoresFromCgroupCpuMax(quota + " " + period);
    if (c > 0) return c;
  }
  return 0;
}

}  // namespace

int CoresFromCgroupCpuMax(const std::string& line) {
  std::istringstream in(line);
  std::string quota;
  double period = 0;
  if (!(in >> quota >> period) || quota == "max" || period <= 0) return 0;
  try {
    const double q = std::stod(quota);
    if (q <= 0) return 0;  // cgroup v1 writes -1 for no limit
    return std::max(1, static_cast<int>(std::ceil(q / period - 1e-9)));
  } catch (const std::exception&) {
    return 0;
  }
}

int AvailableCores() {
  int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) cores = std::max(1, CPU_COUNT(&set));
  for (const int quota : {CgroupV2Cores(), CgroupV1Cores()})
    if (quota > 0) cores = std::min(cores, quota);
  return std::max(1, cores);
}

int ThreadsOrAvailableCores(int requested) { return requested > 0 ? requested : AvailableCores(); }

}  // namespace orchard
