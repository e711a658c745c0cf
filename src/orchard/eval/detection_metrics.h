// Detection metrics: the comparative study's protocol (precision / recall / F1
// per frame over IoU thresholds 0.01..0.99, averaged over frames) and the COCO
// box metrics with pycocotools' exact definitions.
#pragma once

#include <string>
#include <vector>

#include "orchard/data/dataset.h"

namespace orchard {

// Precision, recall and F1 against IoU threshold, averaged over frames.
struct DetectionCurve {
  std::vector<double> iou;        // 0.01, 0.02, ..., 0.99 (99 values)
  std::vector<double> precision;  // same length as iou
  std::vector<double> recall;
  std::vector<double> f1;
};

// pycocotools COCOeval.stats[0..5] for one class, maxDets 100.
struct CocoMetrics {
  double ap = 0;    // AP averaged over IoU .50:.05:.95
  double ap50 = 0;  // AP at IoU .50
  double ap75 = 0;  // AP at IoU .75
  double aps = 0;   // small objects (area < 32^2); -1 when there are none, as pycocotools
  double apm = 0;   // medium (32^2 .. 96^2)
  double apl = 0;   // large (> 96^2)
};

struct DetectionMetrics {
  int images = 0;
  int gt_boxes = 0;
  int pred_boxes = 0;
  CocoMetrics coco;
  DetectionCurve curve;
  double f1_at_05 = 0;  // F1 of the curve at IoU 0.5
};

// Evaluates `predictions` against `ground_truth` over all ground-truth images
// (an image without predictions has none). Throws orchard::Error when a
// prediction names an image that is not in the ground truth.
DetectionMetrics EvaluateDetections(const Dataset& ground_truth, const Predictions& predictions);

}  // namespace orchard
