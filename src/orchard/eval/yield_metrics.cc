#include "orchard/eval/yield_metrics.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

YieldMetrics EvaluateYield(double truth, double estimate) {
  if (!std::isfinite(truth) || truth <= 0) Fail("the true count must be positive, got ", truth);
  if (!std::isfinite(estimate) || estimate < 0) {
    Fail("the estimated count must be a non-negative number, got ", estimate);
  }
  YieldMetrics m;
  m.truth = truth;
  m.estimate = estimate;
  m.percent_of_truth = 100.0 * estimate / truth;
  m.error = estimate - truth;
  m.absolute_error = std::abs(m.error);
  m.relative_error = m.absolute_error / truth;
  return m;
}

double ReadYieldCount(const fs::path& path, YieldFileRole role) {
  const std::string text = ReadTextFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    Fail(path.string(), ": not valid json (", e.what(), ")");
  }
  if (j.is_number()) return j.get<double>();
  if (!j.is_object()) Fail(path.string(), ": expected a number or an object with \"total\" or \"harvested\"");
  const char* first = role == YieldFileRole::kTruth ? "harvested" : "total";
  const char* second = role == YieldFileRole::kTruth ? "total" : "harvested";
  for (const char* key : {first, second}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_number()) Fail(path.string(), ": field \"", key, "\" is not a number");
    return j[key].get<double>();
  }
  Fail(path.string(), ": no \"", first, "\" or \"", second, "\" field");
}

}  // namespace orchard
