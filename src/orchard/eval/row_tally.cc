#include "orchard/eval/row_tally.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

void RowTallyOptions::Check() const {
  ORCHARD_CHECK_OPTION(side_tolerance > 0 && row_tolerance > 0, "tolerances must be positive, got ",
                       side_tolerance, " and ", row_tolerance);
}

bool WithinTolerance(double percent, double tolerance) { return std::abs(percent) <= tolerance + 1e-9; }

ErrorSummary SummariseErrors(const std::vector<double>& percent, double tolerance) {
  ErrorSummary s;
  s.n = static_cast<int>(percent.size());
  if (percent.empty()) return s;
  s.min = *std::min_element(percent.begin(), percent.end());
  s.max = *std::max_element(percent.begin(), percent.end());
  for (double e : percent) {
    s.within += WithinTolerance(e, tolerance);
    s.mae += std::abs(e) / s.n;
    s.mean += e / s.n;
  }
  return s;
}

RowTally TallyRows(std::vector<RowOutcome> rows, const RowTallyOptions& options) {
  options.Check();
  RowTally t;
  std::vector<double> sides, merged, of_harvested;
  for (const auto& r : rows) {
    sides.push_back(r.front_percent());
    sides.push_back(r.back_percent());
    merged.push_back(r.row_percent());
    if (r.harvested > 0) of_harvested.push_back(r.row_percent_of_harvested());
  }
  for (double p : of_harvested) t.mean_percent_of_harvested += p / of_harvested.size();
  t.sides = SummariseErrors(sides, options.side_tolerance);
  t.merged = SummariseErrors(merged, options.row_tolerance);
  t.rows = std::move(rows);
  return t;
}

RowOutcome ReadRowOutcome(const fs::path& run) {
  const fs::path file = run / "yield.json";
  if (!fs::exists(file)) Fail(file.string(), ": not found (is ", run.string(), " an `orchard yield` output folder?)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadTextFile(file));
  } catch (const nlohmann::json::parse_error& e) {
    Fail(file.string(), ": not valid json (", e.what(), ")");
  }
  const auto number = [&](const nlohmann::json& o, const char* key, const char* where) {
    if (!o.contains(key) || !o[key].is_number()) Fail(file.string(), ": no number \"", key, "\"", where);
    return o[key].get<double>();
  };
  if (!j.is_object() || !j.contains("truth") || !j["truth"].is_object())
    Fail(file.string(), ": no \"truth\" block (run `orchard yield` with --truth truth.json)");
  const auto& t = j["truth"];
  RowOutcome r;
  r.name = run.filename().empty() ? run.parent_path().filename().string() : run.filename().string();
  r.front = number(j, "front", "");
  r.back = number(j, "back", "");
  r.total = number(j, "total", "");
  r.sum_of_sides = j.contains("sum_of_sides") && j["sum_of_sides"].is_number() ? j["sum_of_sides"].get<double>()
                                                                              : r.front + r.back;
  r.visible_front = number(t, "visible_front", " in \"truth\"");
  r.visible_back = number(t, "visible_back", " in \"truth\"");
  r.visible_any = number(t, "visible_any", " in \"truth\"");
  r.harvested = t.contains("harvested") && t["harvested"].is_number() ? t["harvested"].get<double>() : 0;
  if (r.visible_front <= 0 || r.visible_back <= 0 || r.visible_any <= 0)
    Fail(file.string(), ": the truth has no visible apples on a side (", r.visible_front, " front, ",
         r.visible_back, " back)");
  return r;
}

std::string RowTallyCsv(const RowTally& tally, const RowTallyOptions& options) {
  std::ostringstream s;
  s << "run,front,visible_front,front_percent,back,visible_back,back_percent,total,visible_any,row_percent,"
       "harvested,percent_of_harvested,sum_of_sides,front_within,back_within,row_within\n";
  s.setf(std::ios::fixed);
  s.precision(2);
  for (const auto& r : tally.rows) {
    s << r.name << ',' << r.front << ',' << r.visible_front << ',' << r.front_percent() << ',' << r.back << ','
      << r.visible_back << ',' << r.back_percent() << ',' << r.total << ',' << r.visible_any << ','
      << r.row_percent() << ',' << r.harvested << ',' << (r.harvested > 0 ? r.row_percent_of_harvested() : 0.0)
      << ',' << r.sum_of_sides << ',' << WithinTolerance(r.front_percent(), options.side_tolerance) << ','
      << WithinTolerance(r.back_percent(), options.side_tolerance) << ','
      << WithinTolerance(r.row_percent(), options.row_tolerance) << '\n';
  }
  return s.str();
}

}  // namespace orchard
