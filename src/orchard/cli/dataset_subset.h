// The train/test choice shared by the commands that train on or cut data from
// annotated datasets: photos are split with SplitByPhoto(fraction, seed), so
// `orchard train ... --test-fraction F --split-seed S` never trains on the
// photos that `orchard patches|detect ... --subset test` with the same F and S
// evaluates on.
#pragma once

#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

#include "orchard/core/error.h"
#include "orchard/data/split.h"

namespace orchard {

struct SubsetArgs {
  double test_fraction = 0;  // 0 = no split: every photo is in "train" and "all"
  uint64_t split_seed = 1;
  std::string subset = "all";  // train | test | all

  void AddOptions(CLI::App* cmd, const std::string& default_subset) {
    subset = default_subset;
    cmd->add_option("--test-fraction", test_fraction,
                    "Hold out this fraction of the photos of each dataset as the test set (photos never straddle)")
        ->capture_default_str();
    cmd->add_option("--split-seed", split_seed, "Seed of the photo split")->capture_default_str();
    cmd->add_option("--subset", subset, "Which photos to use: train, test or all")->capture_default_str();
  }

  Dataset Select(const Dataset& dataset) const {
    if (subset != "train" && subset != "test" && subset != "all") Fail("--subset must be train, test or all, got '", subset, "'");
    if (subset == "all" || test_fraction <= 0) {
      if (subset == "test") Fail("--subset test needs --test-fraction > 0");
      return dataset;
    }
    DatasetSplit split = SplitByPhoto(dataset, test_fraction, split_seed);
    return subset == "train" ? split.train : split.test;
  }
};

}  // namespace orchard
