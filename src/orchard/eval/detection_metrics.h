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

// ----- Lower-level pieces (used by EvaluateDetections and the tests) ---------

// One ground-truth image with the predictions that name it.
struct DetectionFrame {
  std::string name;
  std::vector<Box> gt_boxes;
  // COCO area of each ground-truth object: the mask/polygon area when the
  // annotation has one (Annotation::area >= 0), else the box area w*h.
  std::vector<double> gt_areas;
  std::vector<ScoredBox> predictions;  // in file order
};

// Resolves prediction names to ground-truth images (exact file name, or the
// name without extension, as Dataset::Find) and returns one frame per
// ground-truth image, ordered by image id (then dataset order) as pycocotools
// orders imgIds. Throws orchard::Error for an unknown or ambiguous name, two
// names for one image, or a non-finite / inverted prediction box or score.
std::vector<DetectionFrame> MakeDetectionFrames(const Dataset& ground_truth,
                                                const Predictions& predictions);

// The study's IoU thresholds t_i = i / 100, i = 1..99.
std::vector<double> StudyIouThresholds();

// The study's protocol. In each frame the predictions are taken in descending
// score (ties keep file order: a stable sort), and each takes the unmatched
// ground-truth box of highest IoU if that IoU >= t (ties in IoU: the first
// ground-truth box in dataset order). No score threshold and no limit on the
// number of predictions. Per frame: precision = TP / #pred (1 without
// predictions), recall = TP / #gt (1 without ground truth), F1 = 2PR/(P+R)
// (0 when P + R = 0); each then averaged over all frames. Throws when there
// are no frames.
DetectionCurve EvaluateStudyProtocol(const std::vector<DetectionFrame>& frames);

// pycocotools COCOeval (iouType 'bbox', one category, iscrowd 0, maxDets 100)
// evaluate() + accumulate() + summarize() stats[0..5], line for line. Frames
// must be in imgIds order (MakeDetectionFrames does this): detections with
// equal scores in different images are ranked in that order, as pycocotools'
// stable mergesort does. A ground-truth match is a boolean here, where
// pycocotools stores the matched annotation id (a COCO file with an annotation
// id 0 would make pycocotools count that match as a miss; we do not).
CocoMetrics EvaluateCoco(const std::vector<DetectionFrame>& frames);

// pycocotools' box IoU (maskApi.c bbIou) on [x, y, w, h] = [x1, y1, x2-x1, y2-y1].
double CocoBoxIoU(const Box& detection, const Box& ground_truth);

}  // namespace orchard
