#include "orchard/eval/detection_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "orchard/core/error.h"

namespace orchard {
namespace {

constexpr int kNumCocoIou = 10;     // .50:.05:.95
constexpr int kNumRecall = 101;     // 0:.01:1
constexpr size_t kMaxDets = 100;    // maxDets[-1]
constexpr int kNumAreaRanges = 4;   // all, small, medium, large

// np.linspace(start, stop, num): i * ((stop - start) / (num - 1)) + start, the
// last value set to stop. Reproduced so that IoUs equal to a threshold compare
// exactly as in pycocotools.
template <int N>
std::array<double, N> Linspace(double start, double stop) {
  std::array<double, N> values{};
  const double step = (stop - start) / (N - 1);
  for (int i = 0; i < N; ++i) values[i] = static_cast<double>(i) * step + start;
  values[N - 1] = stop;
  return values;
}

// pycocotools Params.areaRng: [0, 1e5^2], [0, 32^2], [32^2, 96^2], [96^2, 1e5^2].
constexpr double kAreaRanges[kNumAreaRanges][2] = {
    {0.0, 1e10}, {0.0, 1024.0}, {1024.0, 9216.0}, {9216.0, 1e10}};

// Indices of `scores` sorted by descending score, ties in input order (numpy
// argsort(-score, kind='mergesort') is stable).
std::vector<size_t> StableOrderByScore(const std::vector<double>& scores) {
  std::vector<size_t> order(scores.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return -scores[a] < -scores[b]; });
  return order;
}

std::vector<double> Scores(const std::vector<ScoredBox>& boxes) {
  std::vector<double> scores;
  scores.reserve(boxes.size());
  for (const ScoredBox& b : boxes) scores.push_back(b.score);
  return scores;
}

bool Finite(const Box& b) {
  return std::isfinite(b.x1) && std::isfinite(b.y1) && std::isfinite(b.x2) && std::isfinite(b.y2);
}

// The detections of one image and one area range after pycocotools'
// evaluateImg (dt already sorted by score and cut to maxDets).
struct ImageAreaResult {
  std::vector<double> dt_scores;
  // [t][d]: matched to a ground truth / ignored.
  std::array<std::vector<char>, kNumCocoIou> dt_matched;
  std::array<std::vector<char>, kNumCocoIou> dt_ignored;
  int num_gt_not_ignored = 0;
};

}  // namespace

double CocoBoxIoU(const Box& detection, const Box& ground_truth) {
  // maskApi.c bbIou with iscrowd 0, boxes as [x, y, w, h].
  const double dx = detection.x1, dy = detection.y1;
  const double dw = detection.x2 - detection.x1, dh = detection.y2 - detection.y1;
  const double gx = ground_truth.x1, gy = ground_truth.y1;
  const double gw = ground_truth.x2 - ground_truth.x1, gh = ground_truth.y2 - ground_truth.y1;
  const double ga = gw * gh, da = dw * dh;
  const double w = std::fmin(dw + dx, gw + gx) - std::fmax(dx, gx);
  if (w <= 0) return 0.0;
  const double h = std::fmin(dh + dy, gh + gy) - std::fmax(dy, gy);
  if (h <= 0) return 0.0;
  const double i = w * h;
  return i / (da + ga - i);
}

std::vector<double> StudyIouThresholds() {
  std::vector<double> thresholds;
  for (int i = 1; i <= 99; ++i) thresholds.push_back(i / 100.0);
  return thresholds;
}

std::vector<DetectionFrame> MakeDetectionFrames(const Dataset& ground_truth,
                                                const Predictions& predictions) {
  if (ground_truth.images.empty()) Fail("the ground truth has no images");

  // Image order: by id as pycocotools sorts imgIds; dataset order breaks ties
  // (readers without ids leave -1 everywhere, then dataset order is kept).
  std::vector<size_t> order(ground_truth.images.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return ground_truth.images[a].id < ground_truth.images[b].id;
  });

  std::vector<DetectionFrame> frames(order.size());
  std::map<const AnnotatedImage*, size_t> frame_of;
  for (size_t f = 0; f < order.size(); ++f) {
    const AnnotatedImage& image = ground_truth.images[order[f]];
    frame_of[&image] = f;
    DetectionFrame& frame = frames[f];
    frame.name = image.name;
    for (const Annotation& object : image.objects) {
      frame.gt_boxes.push_back(object.box);
      frame.gt_areas.push_back(object.area >= 0 ? object.area
                                                : (object.box.x2 - object.box.x1) *
                                                      (object.box.y2 - object.box.y1));
    }
  }

  std::map<size_t, std::string> claimed_by;  // frame -> prediction name
  for (const auto& [name, boxes] : predictions) {
    const AnnotatedImage* image = ground_truth.Find(name);
    if (image == nullptr) {
      Fail("predictions name image '", name,
           "', which is not in the ground truth (or matches several images)");
    }
    const size_t f = frame_of.at(image);
    if (auto it = claimed_by.find(f); it != claimed_by.end()) {
      Fail("predictions name image '", image->name, "' twice, as '", it->second, "' and '", name,
           "'");
    }
    claimed_by[f] = name;
    for (const ScoredBox& b : boxes) {
      if (!std::isfinite(b.score) || !Finite(b.box)) {
        Fail("a prediction for image '", name, "' has a non-finite box or score");
      }
      if (b.box.x2 < b.box.x1 || b.box.y2 < b.box.y1) {
        Fail("a prediction for image '", name, "' has x2 < x1 or y2 < y1");
      }
    }
    frames[f].predictions = boxes;
  }
  return frames;
}

DetectionCurve EvaluateStudyProtocol(const std::vector<DetectionFrame>& frames) {
  if (frames.empty()) Fail("no frames to evaluate");
  DetectionCurve curve;
  curve.iou = StudyIouThresholds();
  const size_t num_t = curve.iou.size();
  curve.precision.assign(num_t, 0.0);
  curve.recall.assign(num_t, 0.0);
  curve.f1.assign(num_t, 0.0);

  for (const DetectionFrame& frame : frames) {
    const std::vector<size_t> order = StableOrderByScore(Scores(frame.predictions));
    const size_t num_gt = frame.gt_boxes.size();
    const size_t num_pred = order.size();
    // IoU of each prediction (in score order) with each ground-truth box.
    std::vector<double> iou(num_pred * num_gt);
    for (size_t p = 0; p < num_pred; ++p) {
      for (size_t g = 0; g < num_gt; ++g) {
        iou[p * num_gt + g] = IoU(frame.predictions[order[p]].box, frame.gt_boxes[g]);
      }
    }
    std::vector<char> taken(num_gt);
    for (size_t t = 0; t < num_t; ++t) {
      const double threshold = curve.iou[t];
      std::fill(taken.begin(), taken.end(), 0);
      size_t tp = 0;
      for (size_t p = 0; p < num_pred; ++p) {
        int best = -1;
        double best_iou = -1;
        for (size_t g = 0; g < num_gt; ++g) {
          const double v = iou[p * num_gt + g];
          if (!taken[g] && v >= threshold && v > best_iou) {
            best = static_cast<int>(g);
            best_iou = v;
          }
        }
        if (best >= 0) {
          taken[best] = 1;
          ++tp;
        }
      }
      const double precision = num_pred == 0 ? 1.0 : static_cast<double>(tp) / num_pred;
      const double recall = num_gt == 0 ? 1.0 : static_cast<double>(tp) / num_gt;
      const double f1 =
          precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0.0;
      curve.precision[t] += precision;
      curve.recall[t] += recall;
      curve.f1[t] += f1;
    }
  }
  const double n = static_cast<double>(frames.size());
  for (size_t t = 0; t < num_t; ++t) {
    curve.precision[t] /= n;
    curve.recall[t] /= n;
    curve.f1[t] /= n;
  }
  return curve;
}

CocoMetrics EvaluateCoco(const std::vector<DetectionFrame>& frames) {
  const std::array<double, kNumCocoIou> iou_thresholds = Linspace<kNumCocoIou>(0.5, 0.95);
  const std::array<double, kNumRecall> recall_thresholds = Linspace<kNumRecall>(0.0, 1.0);

  // evaluate(): per area range, the evaluateImg results of the images in order.
  std::array<std::vector<ImageAreaResult>, kNumAreaRanges> results;
  for (const DetectionFrame& frame : frames) {
    // computeIoU: detections sorted by score (stable), cut to maxDets.
    std::vector<size_t> dt_order = StableOrderByScore(Scores(frame.predictions));
    if (dt_order.size() > kMaxDets) dt_order.resize(kMaxDets);
    const size_t num_dt = dt_order.size();
    const size_t num_gt = frame.gt_boxes.size();
    if (num_dt == 0 && num_gt == 0) continue;  // evaluateImg returns None
    std::vector<double> ious(num_dt * num_gt);
    for (size_t d = 0; d < num_dt; ++d) {
      for (size_t g = 0; g < num_gt; ++g) {
        ious[d * num_gt + g] = CocoBoxIoU(frame.predictions[dt_order[d]].box, frame.gt_boxes[g]);
      }
    }

    for (int a = 0; a < kNumAreaRanges; ++a) {
      const double lo = kAreaRanges[a][0], hi = kAreaRanges[a][1];
      // gt sorted so that ignored ones come last (stable).
      std::vector<char> ignore_orig(num_gt);
      for (size_t g = 0; g < num_gt; ++g) {
        ignore_orig[g] = frame.gt_areas[g] < lo || frame.gt_areas[g] > hi;
      }
      std::vector<size_t> gt_order(num_gt);
      std::iota(gt_order.begin(), gt_order.end(), 0);
      std::stable_sort(gt_order.begin(), gt_order.end(),
                       [&](size_t x, size_t y) { return ignore_orig[x] < ignore_orig[y]; });
      std::vector<char> gt_ignore(num_gt);
      for (size_t g = 0; g < num_gt; ++g) gt_ignore[g] = ignore_orig[gt_order[g]];

      ImageAreaResult result;
      for (size_t d = 0; d < num_dt; ++d) {
        result.dt_scores.push_back(frame.predictions[dt_order[d]].score);
      }
      for (size_t g = 0; g < num_gt; ++g) result.num_gt_not_ignored += !gt_ignore[g];

      for (int t = 0; t < kNumCocoIou; ++t) {
        std::vector<char> gt_matched(num_gt, 0);
        std::vector<char>& dt_matched = result.dt_matched[t];
        std::vector<char>& dt_ignored = result.dt_ignored[t];
        dt_matched.assign(num_dt, 0);
        dt_ignored.assign(num_dt, 0);
        if (num_gt > 0 && num_dt > 0) {
          for (size_t d = 0; d < num_dt; ++d) {
            double best_iou = std::min(iou_thresholds[t], 1 - 1e-10);
            int m = -1;
            for (size_t g = 0; g < num_gt; ++g) {
              if (gt_matched[g]) continue;  // already matched (no crowds)
              // Matched to a regular gt and reached the ignored ones: stop.
              if (m > -1 && !gt_ignore[m] && gt_ignore[g]) break;
              const double v = ious[d * num_gt + gt_order[g]];
              if (v < best_iou) continue;
              best_iou = v;
              m = static_cast<int>(g);
            }
            if (m == -1) continue;
            dt_ignored[d] = gt_ignore[m];
            dt_matched[d] = 1;
            gt_matched[m] = 1;
          }
        }
        // Unmatched detections outside the area range are ignored.
        for (size_t d = 0; d < num_dt; ++d) {
          const Box& box = frame.predictions[dt_order[d]].box;
          const double area = (box.x2 - box.x1) * (box.y2 - box.y1);
          if (!dt_matched[d] && (area < lo || area > hi)) dt_ignored[d] = 1;
        }
      }
      results[a].push_back(std::move(result));
    }
  }

  // accumulate(): precision[t][r] per area range; -1 when not evaluated.
  std::array<double, kNumAreaRanges> mean_all{};
  std::array<double, kNumAreaRanges> mean_50{};
  std::array<double, kNumAreaRanges> mean_75{};
  for (int a = 0; a < kNumAreaRanges; ++a) {
    mean_all[a] = mean_50[a] = mean_75[a] = -1;
    const std::vector<ImageAreaResult>& evals = results[a];
    if (evals.empty()) continue;
    std::vector<double> scores;
    int npig = 0;
    for (const ImageAreaResult& e : evals) {
      scores.insert(scores.end(), e.dt_scores.begin(), e.dt_scores.end());
      npig += e.num_gt_not_ignored;
    }
    if (npig == 0) continue;
    const std::vector<size_t> order = StableOrderByScore(scores);
    const size_t nd = order.size();

    std::array<std::array<double, kNumRecall>, kNumCocoIou> precision{};
    for (int t = 0; t < kNumCocoIou; ++t) {
      std::vector<char> matched, ignored;
      matched.reserve(nd);
      ignored.reserve(nd);
      for (const ImageAreaResult& e : evals) {
        matched.insert(matched.end(), e.dt_matched[t].begin(), e.dt_matched[t].end());
        ignored.insert(ignored.end(), e.dt_ignored[t].begin(), e.dt_ignored[t].end());
      }
      std::vector<double> rc(nd), pr(nd);
      double tp = 0, fp = 0;
      for (size_t i = 0; i < nd; ++i) {
        const size_t j = order[i];
        if (!ignored[j]) (matched[j] ? tp : fp) += 1;
        rc[i] = tp / npig;
        pr[i] = tp / (fp + tp + std::numeric_limits<double>::epsilon());
      }
      // Precision envelope, monotone from the right.
      for (size_t i = nd; i-- > 1;) {
        if (pr[i] > pr[i - 1]) pr[i - 1] = pr[i];
      }
      for (int r = 0; r < kNumRecall; ++r) {
        const size_t idx = std::lower_bound(rc.begin(), rc.end(), recall_thresholds[r]) - rc.begin();
        precision[t][r] = idx < nd ? pr[idx] : 0.0;
      }
    }
    double sum_all = 0;
    for (int t = 0; t < kNumCocoIou; ++t) {
      for (int r = 0; r < kNumRecall; ++r) sum_all += precision[t][r];
    }
    mean_all[a] = sum_all / (kNumCocoIou * kNumRecall);
    // summarize(iouThr=.5 / .75): np.where(iouThr == p.iouThrs) picks index 0 / 5.
    double sum_50 = 0, sum_75 = 0;
    for (int r = 0; r < kNumRecall; ++r) {
      sum_50 += precision[0][r];
      sum_75 += precision[5][r];
    }
    mean_50[a] = sum_50 / kNumRecall;
    mean_75[a] = sum_75 / kNumRecall;
  }

  CocoMetrics metrics;
  metrics.ap = mean_all[0];
  metrics.ap50 = mean_50[0];
  metrics.ap75 = mean_75[0];
  metrics.aps = mean_all[1];
  metrics.apm = mean_all[2];
  metrics.apl = mean_all[3];
  return metrics;
}

DetectionMetrics EvaluateDetections(const Dataset& ground_truth, const Predictions& predictions) {
  const std::vector<DetectionFrame> frames = MakeDetectionFrames(ground_truth, predictions);
  DetectionMetrics metrics;
  metrics.images = static_cast<int>(frames.size());
  for (const DetectionFrame& frame : frames) {
    metrics.gt_boxes += static_cast<int>(frame.gt_boxes.size());
    metrics.pred_boxes += static_cast<int>(frame.predictions.size());
  }
  metrics.coco = EvaluateCoco(frames);
  metrics.curve = EvaluateStudyProtocol(frames);
  metrics.f1_at_05 = metrics.curve.f1[49];  // iou[49] = 0.50
  return metrics;
}

}  // namespace orchard
