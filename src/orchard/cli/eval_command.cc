// `orchard eval detect|segment|count|yield`: scores predictions against ground
// truth and writes DIR/metrics.json (plus curves, per-image tables and plots).
//
// metrics.json of `eval detect`, one method (--pred given once):
//   {"method": NAME, "pred_file": FILE, "images": N, "gt_boxes": N, "pred_boxes": N,
//    "coco": {"AP","AP50","AP75","APs","APm","APl"},   (-1 where pycocotools gives -1)
//    "iou": [0.01 .. 0.99], "precision": [99], "recall": [99], "f1": [99], "f1_at_0.5": x}
// Several methods: {"methods": [NAME, ...], NAME: {the object above}, ...}.
// So a script reads j if "images" in j, else j[name] for name in j["methods"].
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "orchard/cli/commands.h"
#include "orchard/cli/dataset_subset.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/eval/count_metrics.h"
#include "orchard/eval/detection_metrics.h"
#include "orchard/eval/plot.h"
#include "orchard/eval/row_tally.h"
#include "orchard/eval/segmentation_metrics.h"
#include "orchard/eval/yield_metrics.h"

namespace orchard {
namespace {

using nlohmann::json;

// NaN (undefined) becomes null in json, as nlohmann writes it.
void WriteJson(const fs::path& path, const json& j) { WriteTextFileAtomic(path, j.dump(2) + "\n"); }

// Fails before any work when plots are wanted and gnuplot cannot run.
void CheckGnuplot(bool plots) {
  if (plots) RunGnuplot("\n");
}

// ----- detect ------------------------------------------------------------------

struct EvalDetectOptions {
  std::string gt;                  // MinneApple folder, YOLO folder or COCO/VIA json
  std::string gt_format;           // empty: detected from the path
  std::vector<std::string> preds;  // [NAME=]FILE, CodaLab csv or COCO results json
  std::string out;                 // output folder
  bool plots = true;               // draw PNG/SVG with gnuplot
  SubsetArgs subset;               // evaluate on these photos only (predictions on others ignored)

  void Check() const {
    ORCHARD_CHECK_OPTION(!gt.empty(), "--gt is required");
    ORCHARD_CHECK_OPTION(!preds.empty(), "--pred is required");
    ORCHARD_CHECK_OPTION(!out.empty(), "--out is required");
    if (!gt_format.empty()) ParseDatasetFormat(gt_format);
  }
};

struct Method {
  std::string name;
  fs::path file;
};

// "NAME=FILE" names a method; a plain FILE (or one that exists as given, even
// with '=' in it) is named by its file stem.
Method ParseMethod(const std::string& arg) {
  const size_t eq = arg.find('=');
  std::error_code ec;
  if (eq != std::string::npos && eq > 0 && !fs::exists(arg, ec)) {
    return {arg.substr(0, eq), arg.substr(eq + 1)};
  }
  return {fs::path(arg).stem().string(), arg};
}

json DetectionJson(const Method& method, const DetectionMetrics& m) {
  json j;
  j["method"] = method.name;
  j["pred_file"] = method.file.string();
  j["images"] = m.images;
  j["gt_boxes"] = m.gt_boxes;
  j["pred_boxes"] = m.pred_boxes;
  j["coco"] = {{"AP", m.coco.ap},   {"AP50", m.coco.ap50}, {"AP75", m.coco.ap75},
               {"APs", m.coco.aps}, {"APm", m.coco.apm},   {"APl", m.coco.apl}};
  j["iou"] = m.curve.iou;
  j["precision"] = m.curve.precision;
  j["recall"] = m.curve.recall;
  j["f1"] = m.curve.f1;
  j["f1_at_0.5"] = m.f1_at_05;
  return j;
}

std::string Fixed(double v, int digits = 3) {
  if (std::isnan(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

void RunEvalDetect(const EvalDetectOptions& options) {
  options.Check();
  CheckGnuplot(options.plots);
  std::vector<Method> methods;
  std::set<std::string> names;
  for (const std::string& arg : options.preds) {
    Method m = ParseMethod(arg);
    if (m.name.empty()) Fail("--pred ", arg, ": empty method name");
    if (!names.insert(m.name).second) {
      Fail("two --pred methods are named '", m.name, "'; name them with NAME=FILE");
    }
    methods.push_back(m);
  }
  const std::optional<DatasetFormat> format =
      options.gt_format.empty() ? std::nullopt : std::optional(ParseDatasetFormat(options.gt_format));
  const Dataset gt = options.subset.Select(ReadDataset(options.gt, format));
  if (gt.images.empty()) Fail("no images in the ground truth ", options.gt);

  std::vector<DetectionMetrics> results;
  for (const Method& method : methods) {
    Predictions predictions = ReadPredictions(method.file, gt);
    if (options.subset.subset != "all") {
      // Predictions on the other side of the split are not evaluated.
      for (auto it = predictions.begin(); it != predictions.end();) {
        it = gt.Find(it->first) ? std::next(it) : predictions.erase(it);
      }
    }
    try {
      results.push_back(EvaluateDetections(gt, predictions));
    } catch (const Error& e) {
      Fail(method.file.string(), ": ", e.what());
    }
  }

  const fs::path out = options.out;
  json metrics;
  if (methods.size() == 1) {
    metrics = DetectionJson(methods[0], results[0]);
  } else {
    metrics["methods"] = json::array();
    for (size_t i = 0; i < methods.size(); ++i) {
      metrics["methods"].push_back(methods[i].name);
      metrics[methods[i].name] = DetectionJson(methods[i], results[i]);
    }
  }
  WriteJson(out / "metrics.json", metrics);

  std::ostringstream csv;
  csv.precision(10);
  csv << "method,iou,precision,recall,f1\n";
  for (size_t i = 0; i < methods.size(); ++i) {
    const DetectionCurve& c = results[i].curve;
    for (size_t t = 0; t < c.iou.size(); ++t) {
      csv << methods[i].name << ',' << c.iou[t] << ',' << c.precision[t] << ',' << c.recall[t]
          << ',' << c.f1[t] << '\n';
    }
  }
  WriteTextFileAtomic(out / "curves.csv", csv.str());

  if (options.plots) {
    const struct {
      const char* file;
      const char* label;
      std::vector<double> DetectionCurve::*values;
    } kinds[] = {{"precision_iou", "Precision", &DetectionCurve::precision},
                 {"recall_iou", "Recall", &DetectionCurve::recall},
                 {"f1_iou", "F1 score", &DetectionCurve::f1}};
    for (const auto& kind : kinds) {
      std::vector<PlotSeries> series;
      for (size_t i = 0; i < methods.size(); ++i) {
        series.push_back({methods[i].name, results[i].curve.iou, results[i].curve.*kind.values});
      }
      LinePlotOptions plot;
      plot.title = std::string(kind.label) + " against IoU threshold (mean over " +
                   std::to_string(results[0].images) + " images)";
      plot.x_label = "IoU threshold";
      plot.y_label = kind.label;
      PlotLines(series, plot, out / (std::string(kind.file) + ".png"),
                out / (std::string(kind.file) + ".svg"));
    }
  }

  std::printf("%-20s %6s %7s %7s %6s %6s %6s %6s %6s %6s %7s\n", "method", "images", "gt",
              "pred", "AP", "AP50", "AP75", "APs", "APm", "APl", "F1@0.5");
  for (size_t i = 0; i < methods.size(); ++i) {
    const DetectionMetrics& m = results[i];
    std::printf("%-20s %6d %7d %7d %6s %6s %6s %6s %6s %6s %7s\n", methods[i].name.c_str(),
                m.images, m.gt_boxes, m.pred_boxes, Fixed(m.coco.ap).c_str(),
                Fixed(m.coco.ap50).c_str(), Fixed(m.coco.ap75).c_str(), Fixed(m.coco.aps).c_str(),
                Fixed(m.coco.apm).c_str(), Fixed(m.coco.apl).c_str(), Fixed(m.f1_at_05).c_str());
  }
  std::printf("wrote %s/metrics.json, curves.csv%s\n", out.string().c_str(),
              options.plots ? ", precision_iou/recall_iou/f1_iou .png .svg" : "");
}

// ----- segment -----------------------------------------------------------------

struct EvalSegmentOptions {
  std::string gt, pred, out;
  void Check() const {
    ORCHARD_CHECK_OPTION(!gt.empty() && !pred.empty() && !out.empty(),
                         "--gt, --pred and --out are required");
  }
};

json ScoresJson(const SegmentationScores& s) {
  return {{"mean_iou", s.mean_iou},           {"fw_iou", s.fw_iou},
          {"apple_iou", s.apple_iou},         {"pixel_accuracy", s.pixel_accuracy},
          {"mean_accuracy", s.mean_accuracy}, {"apple_accuracy", s.apple_accuracy}};
}

void RunEvalSegment(const EvalSegmentOptions& options) {
  options.Check();
  std::vector<std::string> unmatched;
  const SegmentationMetrics m = EvaluateSegmentation(options.gt, options.pred, &unmatched);
  json j = ScoresJson(m.mean);
  j["images"] = m.images;
  j["images_with_apple"] = m.images_with_apple;
  j["unmatched_predictions"] = unmatched;
  j["per_image"] = json::array();
  std::ostringstream csv;
  csv.precision(10);
  csv << "image,mean_iou,fw_iou,apple_iou,pixel_accuracy,mean_accuracy,apple_accuracy\n";
  for (size_t i = 0; i < m.names.size(); ++i) {
    json row = ScoresJson(m.per_image[i]);
    row["image"] = m.names[i];
    j["per_image"].push_back(row);
    const SegmentationScores& s = m.per_image[i];
    csv << m.names[i] << ',' << s.mean_iou << ',' << s.fw_iou << ',' << s.apple_iou << ','
        << s.pixel_accuracy << ',' << s.mean_accuracy << ',' << s.apple_accuracy << '\n';
  }
  WriteJson(fs::path(options.out) / "metrics.json", j);
  WriteTextFileAtomic(fs::path(options.out) / "per_image.csv", csv.str());
  std::printf("images %d (with apple %d)\n", m.images, m.images_with_apple);
  std::printf("mean IoU %s  fw IoU %s  apple IoU %s  pixel acc %s  mean acc %s  apple acc %s\n",
              Fixed(m.mean.mean_iou, 4).c_str(), Fixed(m.mean.fw_iou, 4).c_str(),
              Fixed(m.mean.apple_iou, 4).c_str(), Fixed(m.mean.pixel_accuracy, 4).c_str(),
              Fixed(m.mean.mean_accuracy, 4).c_str(), Fixed(m.mean.apple_accuracy, 4).c_str());
  if (!unmatched.empty()) {
    std::printf("note: %zu prediction masks have no ground truth and were ignored\n",
                unmatched.size());
  }
}

// ----- count -------------------------------------------------------------------

struct EvalCountOptions {
  std::string gt, pred, out;
  bool plots = true;
  void Check() const {
    ORCHARD_CHECK_OPTION(!gt.empty() && !pred.empty() && !out.empty(),
                         "--gt, --pred and --out are required");
  }
};

void RunEvalCount(const EvalCountOptions& options) {
  options.Check();
  CheckGnuplot(options.plots);
  const std::vector<ImageCount> gt = ReadCodaLabCounts(options.gt);
  const std::vector<ImageCount> pred = ReadCodaLabCounts(options.pred);
  CountMetrics m;
  try {
    m = EvaluateCounts(gt, pred);
  } catch (const Error& e) {
    Fail(options.pred, ": ", e.what());
  }
  std::vector<std::string> labels;
  for (int c = 0; c < kNumCountClasses; ++c) {
    labels.push_back(c == kNumCountClasses - 1 ? std::to_string(c) + "+" : std::to_string(c));
  }
  json j;
  j["images"] = m.images;
  j["accuracy"] = m.accuracy;
  j["mae"] = m.mae;
  j["labels"] = labels;
  j["confusion"] = m.confusion;  // rows: true count, columns: predicted count
  j["images_per_count"] = m.images_per_class;
  j["accuracy_per_count"] = m.accuracy_per_class;  // null where no image has that count
  const fs::path out = options.out;
  WriteJson(out / "metrics.json", j);
  if (options.plots) {
    std::vector<std::vector<double>> matrix;
    for (const auto& row : m.confusion) matrix.emplace_back(row.begin(), row.end());
    PlotHeatMap(matrix, labels, labels,
                "Counting confusion (accuracy " + Fixed(m.accuracy) + ", MAE " + Fixed(m.mae) + ")",
                "predicted count", "true count", out / "confusion.png", out / "confusion.svg");
  }
  std::printf("images %d  accuracy %s  MAE %s\n", m.images, Fixed(m.accuracy, 4).c_str(),
              Fixed(m.mae, 4).c_str());
  std::printf("true count   ");
  for (const std::string& l : labels) std::printf("%6s", l.c_str());
  std::printf("\nimages       ");
  for (int n : m.images_per_class) std::printf("%6d", n);
  std::printf("\naccuracy     ");
  for (double a : m.accuracy_per_class) std::printf("%6s", Fixed(a, 2).c_str());
  std::printf("\n");
}

// ----- yield -------------------------------------------------------------------

struct EvalYieldOptions {
  std::string truth, estimate, out;
  void Check() const {
    ORCHARD_CHECK_OPTION(!truth.empty() && !estimate.empty() && !out.empty(),
                         "--truth, --estimate and --out are required");
  }
};

void RunEvalYield(const EvalYieldOptions& options) {
  options.Check();
  const double truth = ReadYieldCount(options.truth, YieldFileRole::kTruth);
  const double estimate = ReadYieldCount(options.estimate, YieldFileRole::kEstimate);
  const YieldMetrics m = EvaluateYield(truth, estimate);
  const json j = {{"truth", m.truth},
                  {"estimate", m.estimate},
                  {"percent_of_truth", m.percent_of_truth},
                  {"error", m.error},
                  {"absolute_error", m.absolute_error},
                  {"relative_error", m.relative_error}};
  WriteJson(fs::path(options.out) / "metrics.json", j);
  std::printf("truth %g  estimate %g  = %.2f %% of truth  (error %+g, relative %.4f)\n", m.truth,
              m.estimate, m.percent_of_truth, m.error, m.relative_error);
}

// ----- rows --------------------------------------------------------------------

struct EvalRowsOptions {
  std::vector<std::string> runs;
  std::string out;
  RowTallyOptions tally;
  void Check() const {
    ORCHARD_CHECK_OPTION(!runs.empty() && !out.empty(), "give the `orchard yield` output folders and --out");
    tally.Check();
  }
};

json SummaryJson(const ErrorSummary& s, double tolerance) {
  return {{"n", s.n}, {"within", s.within}, {"tolerance_percent", tolerance}, {"mae_percent", s.mae},
          {"mean_percent", s.mean}, {"min_percent", s.min}, {"max_percent", s.max}};
}

void RunEvalRows(const EvalRowsOptions& options) {
  options.Check();
  std::vector<RowOutcome> rows;
  for (const auto& run : options.runs) rows.push_back(ReadRowOutcome(run));
  const RowTally t = TallyRows(std::move(rows), options.tally);
  const RowTallyOptions& tol = options.tally;
  for (const auto& r : t.rows) {
    const bool within = WithinTolerance(r.front_percent(), tol.side_tolerance) &&
                        WithinTolerance(r.back_percent(), tol.side_tolerance) &&
                        WithinTolerance(r.row_percent(), tol.row_tolerance);
    std::printf("%-16s front %+6.2f%%  back %+6.2f%%  row %+6.2f%% of visible (%g / %g), %.1f%% of harvested%s\n",
                r.name.c_str(), r.front_percent(), r.back_percent(), r.row_percent(), r.total, r.visible_any,
                r.harvested > 0 ? r.row_percent_of_harvested() : 0.0, within ? "" : "  *");
  }
  std::printf("sides within %g%%: %d of %d (MAE %.2f%%, mean %+.2f%%, %+.1f..%+.1f%%)\n", options.tally.side_tolerance,
              t.sides.within, t.sides.n, t.sides.mae, t.sides.mean, t.sides.min, t.sides.max);
  std::printf("rows within %g%%: %d of %d (MAE %.2f%%, mean %+.2f%%, %+.1f..%+.1f%%), %.1f%% of harvested on average\n",
              options.tally.row_tolerance, t.merged.within, t.merged.n, t.merged.mae, t.merged.mean, t.merged.min,
              t.merged.max, t.mean_percent_of_harvested);
  WriteTextFileAtomic(fs::path(options.out) / "rows.csv", RowTallyCsv(t, options.tally));
  WriteJson(fs::path(options.out) / "summary.json",
            {{"sides", SummaryJson(t.sides, options.tally.side_tolerance)},
             {"rows", SummaryJson(t.merged, options.tally.row_tolerance)},
             {"mean_percent_of_harvested", t.mean_percent_of_harvested}});
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  CLI::App* eval = app.add_subcommand(
      "eval", "Score detections, segmentations, counts or yield estimates against ground truth.");
  eval->require_subcommand(1);

  auto detect = std::make_shared<EvalDetectOptions>();
  CLI::App* d = eval->add_subcommand(
      "detect",
      "Detection metrics: the study's precision/recall/F1 per frame over IoU 0.01..0.99 "
      "(averaged over frames) and pycocotools COCO AP. Writes OUT/metrics.json, curves.csv and "
      "precision/recall/F1 plots (PNG, SVG).");
  d->add_option("--gt", detect->gt, "ground truth: MinneApple folder, YOLO folder or COCO json")
      ->required();
  d->add_option("--gt-format", detect->gt_format,
                "minneapple, yolo, coco or via (default: detected from --gt)");
  detect->subset.AddOptions(d, "all");
  d->add_option("--pred", detect->preds,
                "[NAME=]FILE: CodaLab detections (name,x1,y1,x2,y2,score) or COCO results json; "
                "repeat to compare methods (NAME defaults to the file stem)")
      ->required();
  d->add_option("--out", detect->out, "output folder")->required();
  d->add_flag("!--no-plots", detect->plots, "skip the gnuplot figures");
  d->callback([detect] { RunEvalDetect(*detect); });

  auto segment = std::make_shared<EvalSegmentOptions>();
  CLI::App* s = eval->add_subcommand(
      "segment",
      "MinneApple segmentation metrics per image, averaged over images (masks matched by file "
      "stem; any non-zero pixel is apple).");
  s->add_option("--gt", segment->gt, "ground-truth mask folder (or a MinneApple folder with masks/)")
      ->required();
  s->add_option("--pred", segment->pred, "predicted mask folder")->required();
  s->add_option("--out", segment->out, "output folder")->required();
  s->callback([segment] { RunEvalSegment(*segment); });

  auto count = std::make_shared<EvalCountOptions>();
  CLI::App* c = eval->add_subcommand(
      "count",
      "Counting metrics from CodaLab files (name,count): accuracy, accuracy per true count, MAE, "
      "7x7 confusion matrix (counts above 6 in the 6+ class) and its heat map.");
  c->add_option("--gt", count->gt, "true counts (name,count)")->required();
  c->add_option("--pred", count->pred, "predicted counts (name,count)")->required();
  c->add_option("--out", count->out, "output folder")->required();
  c->add_flag("!--no-plots", count->plots, "skip the gnuplot heat map");
  c->callback([count] { RunEvalCount(*count); });

  auto yield = std::make_shared<EvalYieldOptions>();
  CLI::App* y = eval->add_subcommand(
      "yield",
      "Yield accuracy: estimate as a percentage of the true count. Files are json: a number, or "
      "an object with \"harvested\" or \"total\".");
  y->add_option("--truth", yield->truth, "true count json (\"harvested\" preferred, else \"total\")")
      ->required();
  y->add_option("--estimate", yield->estimate, "estimate json (\"total\", e.g. yield.json)")
      ->required();
  y->add_option("--out", yield->out, "output folder")->required();
  y->callback([yield] { RunEvalYield(*yield); });

  auto rows = std::make_shared<EvalRowsOptions>();
  CLI::App* r = eval->add_subcommand(
      "rows",
      "Tally `orchard yield --truth` runs: each side against its visible apples, each row against the apples "
      "visible from either side; how many fall within the tolerances (rows.csv, summary.json).");
  r->add_option("runs", rows->runs, "`orchard yield` output folders (each with yield.json and its truth block)")
      ->required();
  r->add_option("--out", rows->out, "output folder")->required();
  r->add_option("--side-tolerance", rows->tally.side_tolerance, "a side is within this percent of its visible apples")
      ->capture_default_str();
  r->add_option("--row-tolerance", rows->tally.row_tolerance,
                "a row is within this percent of the apples visible from either side")
      ->capture_default_str();
  r->callback([rows] { RunEvalRows(*rows); });
}

}  // namespace orchard
