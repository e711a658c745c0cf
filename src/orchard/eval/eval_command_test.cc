// End-to-end: the built `orchard eval ...` program (env ORCHARD_BIN) against
// the library calls, on the real AppleBBCH81 data and small hand-made files;
// bad inputs must exit with code 1 and a one-line error.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sys/wait.h>

#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/eval/count_metrics.h"
#include "orchard/eval/detection_metrics.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

using nlohmann::json;

std::string Bin() {
  const char* bin = std::getenv("ORCHARD_BIN");
  return bin && fs::exists(bin) ? bin : "";
}

// Runs the program with `args`; returns the exit code, stderr in `err`.
int RunOrchard(const std::string& args, const fs::path& dir, std::string* err = nullptr) {
  const fs::path err_file = dir / "stderr.txt";
  const std::string cmd =
      "'" + Bin() + "' " + args + " > '" + (dir / "stdout.txt").string() + "' 2> '" + err_file.string() + "'";
  const int status = std::system(cmd.c_str());
  if (err) *err = ReadTextFile(err_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path TempDir(const std::string& name) { return test::FreshTempDir("eval_cli_" + name); }

std::string Q(const fs::path& p) { return "'" + p.string() + "'"; }

TEST(EvalCommand, DetectOnAppleBbch81MatchesLibrary) {
  if (Bin().empty()) GTEST_SKIP() << "ORCHARD_BIN not set";
  const fs::path data = fs::path(ORCHARD_SHARED_DATA_DIR) / "applebbch81";
  if (!fs::exists(data)) GTEST_SKIP() << "no " << data;
  const fs::path dir = TempDir("detect");
  const Dataset gt = ReadDataset(data);
  ASSERT_EQ(gt.images.size(), 272u);

  // Ground truth jittered by up to 10 % of the box size, every 6th box dropped,
  // a false positive per 10 images; scores random.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1), score(0, 1);
  Predictions pred;
  int k = 0;
  for (const AnnotatedImage& image : gt.images) {
    auto& boxes = pred[image.name];
    for (const Annotation& a : image.objects) {
      if (++k % 6 == 0) continue;
      const double w = a.box.Width(), h = a.box.Height();
      Box b{a.box.x1 + jitter(rng) * w, a.box.y1 + jitter(rng) * h, a.box.x2 + jitter(rng) * w,
            a.box.y2 + jitter(rng) * h};
      if (b.x2 <= b.x1 || b.y2 <= b.y1) b = a.box;
      boxes.push_back({b, score(rng)});
    }
    if (k % 10 == 0) boxes.push_back({Box{10, 10, 60, 60}, score(rng)});
  }
  WriteCodaLabDetections(pred, dir / "pred.csv");
  const DetectionMetrics expected =
      EvaluateDetections(gt, ReadCodaLabDetections(dir / "pred.csv"));
  // Sanity: a jittered 5/6 of the truth is good but not perfect.
  EXPECT_GT(expected.coco.ap50, 0.5);
  EXPECT_LT(expected.coco.ap50, 0.95);

  ASSERT_EQ(RunOrchard("eval detect --gt " + Q(data) + " --pred mine=" + Q(dir / "pred.csv") +
                    " --out " + Q(dir / "out") + " --no-plots",
                dir),
            0);
  const json j = json::parse(ReadTextFile(dir / "out" / "metrics.json"));
  EXPECT_EQ(j["method"], "mine");
  EXPECT_EQ(j["images"], expected.images);
  EXPECT_EQ(j["gt_boxes"], expected.gt_boxes);
  EXPECT_EQ(j["pred_boxes"], expected.pred_boxes);
  EXPECT_NEAR(j["coco"]["AP"].get<double>(), expected.coco.ap, 1e-12);
  EXPECT_NEAR(j["coco"]["AP50"].get<double>(), expected.coco.ap50, 1e-12);
  EXPECT_NEAR(j["coco"]["AP75"].get<double>(), expected.coco.ap75, 1e-12);
  EXPECT_NEAR(j["coco"]["APs"].get<double>(), expected.coco.aps, 1e-12);
  EXPECT_NEAR(j["coco"]["APm"].get<double>(), expected.coco.apm, 1e-12);
  EXPECT_NEAR(j["coco"]["APl"].get<double>(), expected.coco.apl, 1e-12);
  EXPECT_NEAR(j["f1_at_0.5"].get<double>(), expected.f1_at_05, 1e-12);
  ASSERT_EQ(j["f1"].size(), 99u);
  for (int t = 0; t < 99; ++t) {
    EXPECT_NEAR(j["iou"][t].get<double>(), (t + 1) / 100.0, 1e-15);
    EXPECT_NEAR(j["precision"][t].get<double>(), expected.curve.precision[t], 1e-12);
    EXPECT_NEAR(j["recall"][t].get<double>(), expected.curve.recall[t], 1e-12);
    EXPECT_NEAR(j["f1"][t].get<double>(), expected.curve.f1[t], 1e-12);
  }
  // curves.csv: header + 99 rows.
  std::ifstream csv(dir / "out" / "curves.csv");
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 100);

  // Two methods: one object per name, listed under "methods"; with plots.
  const bool gnuplot = std::system("gnuplot --version > /dev/null 2>&1") == 0;
  ASSERT_EQ(RunOrchard("eval detect --gt " + Q(data) + " --pred a=" + Q(dir / "pred.csv") + " --pred " +
                    Q(dir / "pred.csv") + " --out " + Q(dir / "two") + (gnuplot ? "" : " --no-plots"),
                dir),
            0);
  const json two = json::parse(ReadTextFile(dir / "two" / "metrics.json"));
  EXPECT_EQ(two["methods"], json({"a", "pred"}));
  EXPECT_NEAR(two["pred"]["coco"]["AP"].get<double>(), expected.coco.ap, 1e-12);
  if (gnuplot) {
    for (const char* f : {"precision_iou", "recall_iou", "f1_iou"}) {
      EXPECT_FALSE(cv::imread((dir / "two" / (std::string(f) + ".png")).string()).empty()) << f;
      EXPECT_TRUE(fs::exists(dir / "two" / (std::string(f) + ".svg"))) << f;
    }
  }
}

TEST(EvalCommand, BadInputsExitWithOne) {
  if (Bin().empty()) GTEST_SKIP() << "ORCHARD_BIN not set";
  const fs::path data = fs::path(ORCHARD_SHARED_DATA_DIR) / "applebbch81";
  if (!fs::exists(data)) GTEST_SKIP() << "no " << data;
  const fs::path dir = TempDir("bad");
  WriteTextFileAtomic(dir / "unknown.csv", "no_such_image.jpg,1,1,5,5,0.9\n");
  WriteTextFileAtomic(dir / "corrupt.csv", "DSC_1042_17kv1r16k_0.jpg,1,1,five,5,0.9\n");
  const std::vector<std::string> bad = {
      "eval detect --gt " + Q(data) + " --pred " + Q(dir / "unknown.csv") + " --out " + Q(dir / "o"),
      "eval detect --gt " + Q(data) + " --pred " + Q(dir / "corrupt.csv") + " --out " + Q(dir / "o"),
      "eval detect --gt " + Q(data) + " --pred " + Q(dir / "missing.csv") + " --out " + Q(dir / "o"),
      "eval detect --gt " + Q(dir / "nowhere") + " --pred " + Q(dir / "unknown.csv") + " --out " + Q(dir / "o"),
  };
  for (const std::string& args : bad) {
    std::string err;
    EXPECT_EQ(RunOrchard(args, dir, &err), 1) << args;
    EXPECT_EQ(err.rfind("orchard: error: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  EXPECT_FALSE(fs::exists(dir / "o" / "metrics.json"));
}

TEST(EvalCommand, CountSegmentYield) {
  if (Bin().empty()) GTEST_SKIP() << "ORCHARD_BIN not set";
  const fs::path dir = TempDir("others");
  // Counting: as CountMetrics.ByHand: accuracy 0.6, MAE 0.4.
  WriteTextFileAtomic(dir / "gt.csv", "a.png,0\nb.png,1\nc.png,2\nd.png,6\ne.png,8\n");
  WriteTextFileAtomic(dir / "pred.csv", "a.png,0\nb.png,2\nc.png,2\nd.png,7\ne.png,8\n");
  ASSERT_EQ(RunOrchard("eval count --no-plots --gt " + Q(dir / "gt.csv") + " --pred " + Q(dir / "pred.csv") +
                    " --out " + Q(dir / "count"),
                dir),
            0);
  const json c = json::parse(ReadTextFile(dir / "count" / "metrics.json"));
  EXPECT_DOUBLE_EQ(c["accuracy"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(c["mae"].get<double>(), 0.4);
  EXPECT_EQ(c["confusion"][6][6], 2);
  EXPECT_TRUE(c["accuracy_per_count"][3].is_null());
  WriteTextFileAtomic(dir / "short.csv", "a.png,0\n");
  EXPECT_EQ(RunOrchard("eval count --no-plots --gt " + Q(dir / "gt.csv") + " --pred " + Q(dir / "short.csv") +
                    " --out " + Q(dir / "count2"),
                dir),
            1);

  // Yield: 180 of 200 -> 90 %.
  WriteTextFileAtomic(dir / "truth.json", R"({"harvested": 200})");
  WriteTextFileAtomic(dir / "estimate.json", R"({"total": 180})");
  ASSERT_EQ(RunOrchard("eval yield --truth " + Q(dir / "truth.json") + " --estimate " +
                    Q(dir / "estimate.json") + " --out " + Q(dir / "yield"),
                dir),
            0);
  const json y = json::parse(ReadTextFile(dir / "yield" / "metrics.json"));
  EXPECT_DOUBLE_EQ(y["percent_of_truth"].get<double>(), 90.0);
  EXPECT_DOUBLE_EQ(y["relative_error"].get<double>(), 0.1);
  EXPECT_EQ(RunOrchard("eval yield --truth " + Q(dir / "estimate.json") + "x --estimate " +
                    Q(dir / "estimate.json") + " --out " + Q(dir / "yield2"),
                dir),
            1);

  // Rows: two yield runs with truth; a run without truth is an error and writes nothing.
  WriteTextFileAtomic(dir / "r1" / "yield.json",
                      R"({"total": 196, "front": 103, "back": 100,
                          "truth": {"visible_front": 100, "visible_back": 100, "visible_any": 200, "harvested": 250}})");
  WriteTextFileAtomic(dir / "r2" / "yield.json",
                      R"({"total": 210, "front": 90, "back": 100,
                          "truth": {"visible_front": 100, "visible_back": 100, "visible_any": 200, "harvested": 250}})");
  ASSERT_EQ(RunOrchard("eval rows " + Q(dir / "r1") + " " + Q(dir / "r2") + " --out " + Q(dir / "rows"), dir), 0);
  const json r = json::parse(ReadTextFile(dir / "rows" / "summary.json"));
  EXPECT_EQ(r["sides"]["within"], 3);  // +3, 0, -10, 0
  EXPECT_EQ(r["rows"]["within"], 1);   // -2, +5
  EXPECT_DOUBLE_EQ(r["rows"]["mae_percent"].get<double>(), 3.5);
  EXPECT_NE(ReadTextFile(dir / "rows" / "rows.csv").find("\nr2,"), std::string::npos);
  WriteTextFileAtomic(dir / "r3" / "yield.json", R"({"total": 210, "front": 90, "back": 100})");
  std::string err;
  EXPECT_EQ(RunOrchard("eval rows " + Q(dir / "r1") + " " + Q(dir / "r3") + " --out " + Q(dir / "rows2"), dir, &err),
            1);
  EXPECT_NE(err.find("no \"truth\" block"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "rows2" / "summary.json"));

  // Segmentation: a perfect mask and a missing one.
  fs::create_directories(dir / "gtm");
  fs::create_directories(dir / "pm");
  cv::Mat m = cv::Mat::zeros(8, 8, CV_8U);
  m(cv::Rect(2, 2, 3, 3)).setTo(1);
  cv::imwrite((dir / "gtm" / "a.png").string(), m);
  cv::imwrite((dir / "pm" / "a.png").string(), m * 255);
  ASSERT_EQ(RunOrchard("eval segment --gt " + Q(dir / "gtm") + " --pred " + Q(dir / "pm") + " --out " +
                    Q(dir / "seg"),
                dir),
            0);
  const json s = json::parse(ReadTextFile(dir / "seg" / "metrics.json"));
  EXPECT_EQ(s["mean_iou"].get<double>(), 1.0);
  EXPECT_EQ(s["apple_iou"].get<double>(), 1.0);
  cv::imwrite((dir / "gtm" / "b.png").string(), m);
  EXPECT_EQ(RunOrchard("eval segment --gt " + Q(dir / "gtm") + " --pred " + Q(dir / "pm") + " --out " +
                    Q(dir / "seg2"),
                dir),
            1);
}

}  // namespace
}  // namespace orchard
