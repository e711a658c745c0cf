// `orchard calibrate`: the factor that turns `orchard yield` totals into
// harvest estimates, from rows that were also harvested or hand-counted; see
// merge/calibration.h and docs/yield.md.
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/core/file_io.h"
#include "orchard/merge/calibration.h"

namespace orchard {

void AddCalibrateCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "Factor from counted to harvested apples, from `orchard yield` runs of harvested rows");
  struct Args {
    std::string table, out;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--table", a->table,
                  "CSV with the header 'yield,harvested': per line a yield.json (or its folder) and that row's "
                  "harvested or hand-counted apples")
      ->required();
  cmd->add_option("--out", a->out, "Calibration file to write (for orchard yield --calibration)")->required();
  cmd->callback([a]() {
    const Calibration c = Calibrate(ReadCalibrationTable(a->table));
    WriteTextFileAtomic(a->out, CalibrationJson(c));
    std::printf("%-50s %9s %9s %7s %14s\n", "run", "estimate", "harvested", "ratio", "left-out error");
    for (size_t i = 0; i < c.runs.size(); ++i) {
      const auto& r = c.runs[i];
      std::printf("%-50s %9.0f %9.0f %7.3f", r.name.c_str(), r.estimate, r.harvested,
                  r.estimate > 0 ? r.harvested / r.estimate : 0.0);
      if (i < c.loo_error_percent.size()) std::printf(" %+13.1f%%", c.loo_error_percent[i]);
      std::printf("\n");
    }
    std::printf("factor %.4f from %zu runs", c.factor, c.runs.size());
    if (c.loo_error_percent.empty())
      std::printf("; one run gives no measure of the factor's error: calibrate on several rows\n");
    else
      std::printf("; each run estimated from the others: mean absolute error %.1f%%\n",
                  c.loo_mean_absolute_error_percent);
    std::printf("-> %s\n", a->out.c_str());
  });
}

}  // namespace orchard
