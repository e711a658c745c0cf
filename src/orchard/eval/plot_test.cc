#include "orchard/eval/plot.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

bool HaveGnuplot() { return std::system("gnuplot --version > /dev/null 2>&1") == 0; }

TEST(Plot, LinesAndHeatMapAsPngAndSvg) {
  if (!HaveGnuplot()) GTEST_SKIP() << "gnuplot not installed";
  const fs::path dir = fs::temp_directory_path() / "orchard_eval_plot";
  fs::remove_all(dir);
  PlotLines({{"method 'a'", {0, 0.5, 1}, {1, 0.5, 0}}, {"b", {0, 1}, {0.2, 0.8}}},
            {"Precision", "IoU threshold", "precision"}, dir / "p.png", dir / "p.svg");
  const cv::Mat png = cv::imread((dir / "p.png").string());
  EXPECT_EQ(png.cols, 800);
  EXPECT_EQ(png.rows, 560);
  EXPECT_NE(ReadTextFile(dir / "p.svg").find("<svg"), std::string::npos);
  PlotHeatMap({{1, 2}, {3, 4}}, {"0", "1"}, {"0", "1"}, "confusion", "predicted", "true",
              dir / "h.png", dir / "h.svg");
  EXPECT_FALSE(cv::imread((dir / "h.png").string()).empty());
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 4);  // no temporaries left
}

TEST(Plot, GnuplotErrorsAndMissingGnuplotAreErrors) {
  if (HaveGnuplot()) {
    EXPECT_THROW(RunGnuplot("this is not gnuplot\n"), Error);
  }
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  setenv("PATH", "/nonexistent", 1);
  try {
    RunGnuplot("print 1\n");
    ADD_FAILURE() << "expected an error without gnuplot on PATH";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gnuplot-nox"), std::string::npos) << e.what();
  }
  setenv("PATH", saved.c_str(), 1);
}

}  // namespace
}  // namespace orchard
