#include "orchard/merge/calibration.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/text_format.h"

namespace orchard {

using Json = nlohmann::json;

std::string MethodKey(const std::string& name) {
  const size_t colon = name.find(':'), at = name.rfind('@');
  if (colon == std::string::npos || at == std::string::npos || at < colon) return name;
  return name.substr(0, colon) + name.substr(at);
}

Calibration Calibrate(const std::vector<CalibrationRun>& runs) {
  if (runs.empty()) Fail("calibration: no runs");
  Calibration c;
  c.runs = runs;
  c.detector = runs[0].detector, c.counter = runs[0].counter;
  double estimates = 0, harvested = 0;
  for (const auto& r : runs) {
    if (!(r.harvested > 0)) Fail("calibration: ", r.name, ": the harvested count must be positive, got ", r.harvested);
    if (!(r.estimate >= 0) || !std::isfinite(r.estimate))
      Fail("calibration: ", r.name, ": the estimate must be >= 0, got ", r.estimate);
    if (MethodKey(r.detector) != MethodKey(c.detector) || MethodKey(r.counter) != MethodKey(c.counter))
      Fail("calibration: ", r.name, " was counted with detector '", r.detector, "' and counter '", r.counter, "', ",
           runs[0].name, " with '", c.detector, "' and '", c.counter, "': calibrate each combination on its own");
    estimates += r.estimate, harvested += r.harvested;
  }
  if (estimates <= 0) Fail("calibration: the runs counted no apples");
  c.factor = harvested / estimates;
  if (runs.size() < 2) return c;
  double sum_abs = 0;
  for (const auto& r : runs) {
    const double others = estimates - r.estimate;
    // Without this run the others must still have counted something.
    const double factor = others > 0 ? (harvested - r.harvested) / others : c.factor;
    const double e = 100.0 * (r.estimate * factor - r.harvested) / r.harvested;
    c.loo_error_percent.push_back(e);
    sum_abs += std::abs(e);
  }
  c.loo_mean_absolute_error_percent = sum_abs / static_cast<double>(runs.size());
  return c;
}

CalibrationRun ReadCalibrationRun(const fs::path& yield, double harvested) {
  const fs::path file = fs::is_directory(yield) ? yield / "yield.json" : yield;
  if (!fs::is_regular_file(file)) Fail("calibration: ", file.string(), " does not exist (a yield.json or its folder)");
  const Json j = Json::parse(ReadTextFile(file), nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("total") || !j["total"].is_number())
    Fail("calibration: ", file.string(), " is not an `orchard yield` result (no \"total\")");
  CalibrationRun r;
  r.name = file.string();
  r.estimate = j["total"].get<double>();
  r.harvested = harvested;
  if (j.contains("settings") && j["settings"].is_object()) {
    r.detector = j["settings"].value("detector", "");
    r.counter = j["settings"].value("counter", "");
  }
  return r;
}

std::vector<CalibrationRun> ReadCalibrationTable(const fs::path& csv) {
  const std::vector<data_internal::TextLine> lines = data_internal::ReadNonEmptyLines(csv);
  if (lines.empty() || lines[0].text.rfind("yield,harvested", 0) != 0)
    Fail("calibration table ", csv.string(), " must start with the header 'yield,harvested'");
  std::vector<CalibrationRun> runs;
  for (size_t i = 1; i < lines.size(); ++i) {
    const auto& line = lines[i];
    // The count is after the last comma, so a path may hold commas.
    const size_t comma = line.text.rfind(',');
    if (comma == std::string::npos)
      Fail(csv.string(), ":", line.number, ": expected 'yield,harvested', got '", line.text, "'");
    const std::vector<std::string> count = data_internal::SplitFields(line.text.substr(comma + 1));
    const double harvested =
        data_internal::ParseNumber(count.size() == 1 ? count[0] : line.text.substr(comma + 1), csv, line.number,
                                   "harvested");
    fs::path yield = line.text.substr(0, comma);
    if (yield.is_relative()) yield = csv.parent_path() / yield;
    runs.push_back(ReadCalibrationRun(yield, harvested));
  }
  if (runs.empty()) Fail("calibration table ", csv.string(), " lists no runs");
  return runs;
}

std::string CalibrationJson(const Calibration& c) {
  Json runs = Json::array();
  for (size_t i = 0; i < c.runs.size(); ++i) {
    const auto& r = c.runs[i];
    Json run = {{"yield", r.name}, {"estimate", r.estimate}, {"harvested", r.harvested}};
    if (r.estimate > 0) run["ratio"] = r.harvested / r.estimate;
    if (i < c.loo_error_percent.size()) run["leave_one_out_error_percent"] = c.loo_error_percent[i];
    runs.push_back(run);
  }
  Json j = {{"factor", c.factor}, {"detector", c.detector}, {"counter", c.counter}, {"runs", runs}};
  if (!c.loo_error_percent.empty()) j["leave_one_out_mean_absolute_error_percent"] = c.loo_mean_absolute_error_percent;
  return j.dump(2) + "\n";
}

Calibration ReadCalibration(const fs::path& path) {
  const Json j = Json::parse(ReadTextFile(path), nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("factor") || !j["factor"].is_number() ||
      !j.contains("runs") || !j["runs"].is_array())
    Fail(path.string(), " is not a calibration (made by `orchard calibrate`)");
  Calibration c;
  try {
    c.factor = j.at("factor").get<double>();
    c.detector = j.value("detector", "");
    c.counter = j.value("counter", "");
    for (const auto& r : j.at("runs")) {
      CalibrationRun run;
      run.name = r.at("yield").get<std::string>();
      run.estimate = r.at("estimate").get<double>();
      run.harvested = r.at("harvested").get<double>();
      run.detector = c.detector, run.counter = c.counter;
      c.runs.push_back(run);
      if (r.contains("leave_one_out_error_percent"))
        c.loo_error_percent.push_back(r.at("leave_one_out_error_percent").get<double>());
    }
    c.loo_mean_absolute_error_percent = j.value("leave_one_out_mean_absolute_error_percent", 0.0);
  } catch (const Json::exception& e) {
    Fail(path.string(), " is not a calibration: ", e.what());
  }
  if (!(c.factor > 0) || !std::isfinite(c.factor)) Fail(path.string(), ": the factor must be positive, got ", c.factor);
  return c;
}

}  // namespace orchard
