// How many threads "all cores" means for this process.
#pragma once

#include <string>

namespace orchard {

// The cores this process may run on: the CPUs of its affinity mask (taskset,
// a batch scheduler's cpuset), fewer when a cgroup CPU quota (a container's
// --cpus, a job's cgroup) allows less; at least 1.
// std::thread::hardware_concurrency() counts every CPU of the machine: a job
// given 4 CPUs of a 64-CPU node asked LibTorch and COLMAP for 64 threads, and
// threads above the cores slow LibTorch down (one side's CNN counting on one
// CPU: 2.1x as long with 32 threads as with 1; docs/networks.md "Threads").
int AvailableCores();

// `requested` when positive, else AvailableCores(): the meaning of every
// `--threads` option (0 = all cores).
int ThreadsOrAvailableCores(int requested);

// Whole cores a cgroup v2 `cpu.max` line ("QUOTA PERIOD", or "max PERIOD"
// for no limit) allows, rounded up; 0 when it sets no limit or cannot be read.
int CoresFromCgroupCpuMax(const std::string& line);

}  // namespace orchard
