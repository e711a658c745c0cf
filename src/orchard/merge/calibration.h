// Calibrating row estimates against harvested counts. The merged total counts
// the apples the two videos see; apples hidden from both sides (10-20% on the
// synthetic rows) and the detector's and counter's systematic errors are not
// in it. Rows (or stretches of row) that were also harvested or hand-counted
// give the ratio of true apples to counted ones, which then scales the other
// rows' estimates: a ratio estimator, the way machine counts are calibrated
// against sample trees. It holds for rows like the calibration rows (variety,
// canopy, growth stage, filming) and for the same detector and counter, which
// `orchard yield --calibration` checks.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace orchard {

namespace fs = std::filesystem;

struct CalibrationRun {
  std::string name;        // where the estimate came from (its yield.json)
  double estimate = 0;     // the run's merged total
  double harvested = 0;    // the true count of the same row or stretch
  std::string detector;    // the run's detector and counter (yield.json settings)
  std::string counter;
};

struct Calibration {
  double factor = 1;  // sum of harvested counts / sum of estimates
  std::string detector, counter;
  std::vector<CalibrationRun> runs;
  // Each run estimated with the factor of the other runs (leave-one-out), in
  // percent of its harvested count: what to expect on a new row. Empty with a
  // single run, which gives a factor but no measure of its error.
  std::vector<double> loo_error_percent;
  double loo_mean_absolute_error_percent = 0;
};

// Throws orchard::Error on no runs, a harvested count <= 0, an estimate < 0
// or a zero sum of estimates, or runs of different detectors or counters.
Calibration Calibrate(const std::vector<CalibrationRun>& runs);

// A run from its yield.json (or the folder holding it) and its true count.
CalibrationRun ReadCalibrationRun(const fs::path& yield, double harvested);

// A CSV with the header `yield,harvested`: per line a yield.json (or its
// folder; relative to the CSV's folder) and that row's harvested count.
std::vector<CalibrationRun> ReadCalibrationTable(const fs::path& csv);

std::string CalibrationJson(const Calibration& calibration);
// Throws orchard::Error naming the file when it is not a calibration.
Calibration ReadCalibration(const fs::path& path);

// A detector or counter name without the model's path: the method and the
// model file's fingerprint ("unet:models/unet.pt@1a2b..." -> "unet@1a2b..."),
// so that a calibration still applies when the models folder moves.
std::string MethodKey(const std::string& name);

}  // namespace orchard
