#include "orchard/eval/plot.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

extern char** environ;

namespace orchard {
namespace {

// A gnuplot single-quoted string: '' stands for one quote.
std::string Quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'') out += "''";
    else if (c != '\n') out += c;
  }
  return out + "'";
}

// Terminal settings per output kind.
std::string TerminalFor(const fs::path& path) {
  // noenhanced: method names such as semi_blobs are text, not subscripts.
  if (path.extension() == ".svg") return "set terminal svg size 800,560 dynamic noenhanced font 'Helvetica,14'\n";
  return "set terminal pngcairo size 800,560 noenhanced font 'Helvetica,12'\n";
}

// Writes the figure to `png` and `svg`, each atomically: `body` is the script
// after the terminal and output lines.
void Render(const std::string& body, const fs::path& png, const fs::path& svg) {
  for (const fs::path& out : {png, svg}) {
    WriteFileAtomic(out, [&](const fs::path& tmp) {
      RunGnuplot(TerminalFor(out) + "set output " + Quote(tmp.string()) + "\n" + body +
                 "unset output\n");
    });
  }
}

std::string Number(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

}  // namespace

void RunGnuplot(const std::string& script) {
  char dir_template[] = "/tmp/orchard_gnuplot_XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) Fail("cannot create a temporary folder for gnuplot");
  const fs::path dir = dir_template;
  const fs::path script_path = dir / "figure.gp";
  const fs::path log_path = dir / "gnuplot.log";
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{dir};
  {
    std::ofstream out(script_path);
    out << script;
    if (!out) Fail("cannot write the gnuplot script ", script_path.string());
  }

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::string arg0 = "gnuplot", arg1 = script_path.string();
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    if (rc == ENOENT) {
      Fail("gnuplot is not installed (Debian package gnuplot-nox); it draws the evaluation plots");
    }
    Fail("cannot run gnuplot: ", std::strerror(rc));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) Fail("waiting for gnuplot failed: ", std::strerror(errno));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string first_error;
    std::ifstream log(log_path);
    for (std::string line; std::getline(log, line);) {
      if (!line.empty() && line.find_first_not_of(" ^") != std::string::npos) first_error = line;
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
      Fail("gnuplot is not installed (Debian package gnuplot-nox); it draws the evaluation plots");
    }
    Fail("gnuplot failed: ", first_error.empty() ? "no message" : first_error);
  }
}

void PlotLines(const std::vector<PlotSeries>& series, const LinePlotOptions& options,
               const fs::path& png, const fs::path& svg) {
  if (series.empty()) Fail("nothing to plot for ", png.string());
  std::ostringstream s;
  for (size_t i = 0; i < series.size(); ++i) {
    s << "$series" << i << " << EOD\n";
    for (size_t k = 0; k < series[i].x.size() && k < series[i].y.size(); ++k) {
      s << Number(series[i].x[k]) << ' ' << Number(series[i].y[k]) << '\n';
    }
    s << "EOD\n";
  }
  s << "set title " << Quote(options.title) << "\n"
    << "set xlabel " << Quote(options.x_label) << "\n"
    << "set ylabel " << Quote(options.y_label) << "\n"
    << "set xrange [" << Number(options.x_min) << ":" << Number(options.x_max) << "]\n"
    << "set yrange [" << Number(options.y_min) << ":" << Number(options.y_max) << "]\n"
    << "set grid lc rgb '#d0d0d0'\n"
    << "set key bottom left box opaque\n"
    << "set border lw 1.2\n"
    << "plot ";
  for (size_t i = 0; i < series.size(); ++i) {
    s << (i ? ", " : "") << "$series" << i << " using 1:2 with lines lw 2 dt " << (i % 5 + 1)
      << " title " << Quote(series[i].name);
  }
  s << "\n";
  Render(s.str(), png, svg);
}

void PlotHeatMap(const std::vector<std::vector<double>>& matrix,
                 const std::vector<std::string>& row_labels,
                 const std::vector<std::string>& col_labels, const std::string& title,
                 const std::string& x_label, const std::string& y_label, const fs::path& png,
                 const fs::path& svg) {
  if (matrix.empty()) Fail("nothing to plot for ", png.string());
  const size_t rows = matrix.size(), cols = matrix[0].size();
  double max_value = 0;
  for (const auto& row : matrix) {
    for (double v : row) max_value = std::max(max_value, v);
  }
  std::ostringstream s;
  // Cells as (col, row, value) with row 0 drawn at the top.
  s << "$cells << EOD\n";
  for (size_t r = 0; r < rows; ++r) {
    for (size_t c = 0; c < cols; ++c) s << c << ' ' << r << ' ' << Number(matrix[r][c]) << '\n';
    s << '\n';
  }
  s << "EOD\n";
  s << "set title " << Quote(title) << "\n"
    << "set xlabel " << Quote(x_label) << "\n"
    << "set ylabel " << Quote(y_label) << "\n"
    << "set xrange [-0.5:" << cols - 0.5 << "]\n"
    << "set yrange [" << rows - 0.5 << ":-0.5]\n"
    << "set cbrange [0:" << Number(max_value > 0 ? max_value : 1) << "]\n"
    << "set palette defined (0 '#ffffff', 1 '#08306b')\n"
    << "set size ratio -1\nunset key\nset tics out nomirror\n";
  s << "set xtics (";
  for (size_t c = 0; c < cols; ++c) {
    s << (c ? ", " : "") << Quote(c < col_labels.size() ? col_labels[c] : std::to_string(c)) << " " << c;
  }
  s << ")\nset ytics (";
  for (size_t r = 0; r < rows; ++r) {
    s << (r ? ", " : "") << Quote(r < row_labels.size() ? row_labels[r] : std::to_string(r)) << " " << r;
  }
  s << ")\n";
  // Light text on dark cells.
  s << "plot $cells using 1:2:3 with image, "
    << "$cells using 1:2:(sprintf('%g', $3)):($3 > " << Number(max_value / 2)
    << " ? 0xffffff : 0x000000) with labels tc rgb variable font ',11'\n";
  Render(s.str(), png, svg);
}

}  // namespace orchard
