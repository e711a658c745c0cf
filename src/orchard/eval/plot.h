// Figures for the evaluation reports, drawn by gnuplot (Debian gnuplot-nox)
// run as a child process on a script file; each figure is written as PNG
// (pngcairo) and SVG, atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace orchard {

namespace fs = std::filesystem;

// One named line of a line plot.
struct PlotSeries {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
};

struct LinePlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  double x_min = 0, x_max = 1;  // axis ranges
  double y_min = 0, y_max = 1;
};

// Draws `series` as lines (one per series, legend = names) into `png` and
// `svg`. Throws orchard::Error when gnuplot is missing or fails.
void PlotLines(const std::vector<PlotSeries>& series, const LinePlotOptions& options,
               const fs::path& png, const fs::path& svg);

// Draws `matrix` (rows x cols, row 0 at the top) as a heat map with the value
// printed in each cell; `row_labels` / `col_labels` name the ticks.
void PlotHeatMap(const std::vector<std::vector<double>>& matrix,
                 const std::vector<std::string>& row_labels,
                 const std::vector<std::string>& col_labels, const std::string& title,
                 const std::string& x_label, const std::string& y_label, const fs::path& png,
                 const fs::path& svg);

// Runs `gnuplot` on `script`; throws orchard::Error (with gnuplot's first
// error line) when it cannot be started or fails.
void RunGnuplot(const std::string& script);

}  // namespace orchard
