// Tally of `orchard yield` runs on rows with known truth (the synthetic
// generator's `--truth`): each side's count against the apples visible from
// it, the merged total against the apples visible from either side and the
// harvested ones, and how many sides and rows fall within a tolerance. This
// is the measure issues #6 and #7 set (sides within 3%, rows within 2% of
// their visible apples), taken over many fresh seeds at once.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace orchard {

namespace fs = std::filesystem;

// One row's counts and truth, read from its yield.json.
struct RowOutcome {
  std::string name;  // the run folder's name
  double front = 0, back = 0, total = 0, sum_of_sides = 0;
  double visible_front = 0, visible_back = 0, visible_any = 0, harvested = 0;
  // Signed errors in percent: count / truth - 1.
  double front_percent() const { return 100.0 * front / visible_front - 100.0; }
  double back_percent() const { return 100.0 * back / visible_back - 100.0; }
  double row_percent() const { return 100.0 * total / visible_any - 100.0; }
  double row_percent_of_harvested() const { return 100.0 * total / harvested; }
};

struct RowTallyOptions {
  double side_tolerance = 3;  // percent of the side's visible apples (issue #6)
  double row_tolerance = 2;   // percent of the apples visible from either side (issue #7)
  void Check() const;
};

// |percent| <= tolerance, with a hair of slack so that an error printed as
// exactly the tolerance counts as within (103 of 100 is 3.0000000000000036%).
bool WithinTolerance(double percent, double tolerance);

// Signed errors in percent summarised: how many within the tolerance, the
// mean absolute error, the mean, and the extremes.
struct ErrorSummary {
  int n = 0, within = 0;
  double mae = 0, mean = 0, min = 0, max = 0;
};
ErrorSummary SummariseErrors(const std::vector<double>& percent, double tolerance);

struct RowTally {
  std::vector<RowOutcome> rows;
  ErrorSummary sides, merged;  // sides: front and back of every row
  double mean_percent_of_harvested = 0;  // over the rows whose truth gives the harvest
};

RowTally TallyRows(std::vector<RowOutcome> rows, const RowTallyOptions& options);

// Reads `run/yield.json`; throws orchard::Error naming the file when it is
// missing, not json, or has no "truth" block (run without `--truth`) or a
// truth with no visible apples on a side.
RowOutcome ReadRowOutcome(const fs::path& run);

// rows.csv: one line a row (counts, truth, signed errors, within flags).
std::string RowTallyCsv(const RowTally& tally, const RowTallyOptions& options);

}  // namespace orchard
