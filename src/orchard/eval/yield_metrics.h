// Yield accuracy: the estimated number of apples against the true (harvested)
// number, as the study reports it (estimate as a percentage of the truth).
#pragma once

#include <filesystem>

namespace orchard {

namespace fs = std::filesystem;

struct YieldMetrics {
  double truth = 0;
  double estimate = 0;
  double percent_of_truth = 0;  // 100 * estimate / truth
  double error = 0;             // estimate - truth (signed)
  double absolute_error = 0;    // |estimate - truth|
  double relative_error = 0;    // |estimate - truth| / truth
};

// Throws orchard::Error when truth <= 0 (the percentage is undefined) or a
// value is negative or not finite.
YieldMetrics EvaluateYield(double truth, double estimate);

// Reads an apple count from a json file: a bare number (`1234`), or an object
// with "harvested" or "total" (the truth file prefers "harvested", the
// estimate file "total"; either is accepted). Throws naming the file when it
// is not json or has neither.
enum class YieldFileRole { kTruth, kEstimate };
double ReadYieldCount(const fs::path& path, YieldFileRole role);

}  // namespace orchard
