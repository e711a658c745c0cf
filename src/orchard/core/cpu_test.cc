#include "orchard/core/cpu.h"

#include <sched.h>

#include <thread>

#include <gtest/gtest.h>

namespace orchard {
namespace {

TEST(Cpu, CgroupCpuMaxLine) {
  EXPECT_EQ(CoresFromCgroupCpuMax("max 100000"), 0);      // no limit
  EXPECT_EQ(CoresFromCgroupCpuMax("200000 100000"), 2);   // two cores
  EXPECT_EQ(CoresFromCgroupCpuMax("150000 100000"), 2);   // 1.5 rounded up
  EXPECT_EQ(CoresFromCgroupCpuMax("50000 100000"), 1);    // half a core is one thread
  EXPECT_EQ(CoresFromCgroupCpuMax("-1 100000"), 0);       // cgroup v1's "no limit"
  EXPECT_EQ(CoresFromCgroupCpuMax(""), 0);                // no file
  EXPECT_EQ(CoresFromCgroupCpuMax("garbage"), 0);
  EXPECT_EQ(CoresFromCgroupCpuMax("x 100000"), 0);
  EXPECT_EQ(CoresFromCgroupCpuMax("100000 0"), 0);
}

TEST(Cpu, AvailableCoresWithinTheMachine) {
  const int cores = AvailableCores();
  EXPECT_GE(cores, 1);
  EXPECT_LE(cores, static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  EXPECT_EQ(ThreadsOrAvailableCores(0), cores);
  EXPECT_EQ(ThreadsOrAvailableCores(-3), cores);
  EXPECT_EQ(ThreadsOrAvailableCores(5), 5);  // asked for: taken as given
}

// A thread pinned to one CPU (as taskset or a scheduler's cpuset pins a job)
// has one core, whatever the machine has.
TEST(Cpu, AffinityMaskLimitsTheCores) {
  int cores = 0;
  std::thread t([&cores] {
    cpu_set_t all;
    CPU_ZERO(&all);
    ASSERT_EQ(sched_getaffinity(0, sizeof(all), &all), 0);
    int first = 0;
    while (!CPU_ISSET(first, &all)) ++first;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
    cores = AvailableCores();
  });
  t.join();
  EXPECT_EQ(cores, 1);
}

}  // namespace
}  // namespace orchard
