// MinneApple's semantic segmentation metrics (segmentation_eval.py of the
// MinneApple benchmark): two classes, background and apple, scored per image
// from the 2x2 pixel confusion matrix and averaged over images.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace orchard {

namespace fs = std::filesystem;

// Scores of one image. With tp_c, gt_c, pred_c the pixels of class c that are
// right, in the ground truth, in the prediction, and N all pixels:
//   IoU_c = tp_c / (gt_c + pred_c - tp_c), accuracy_c = tp_c / gt_c, both only
//   for classes present in the ground truth (gt_c > 0), as MinneApple;
//   mean_iou / mean_accuracy: means over those classes;
//   fw_iou = sum over those classes of (gt_c / N) * IoU_c;
//   pixel_accuracy = (tp_0 + tp_1) / N.
// An image whose ground truth has no apple is scored on background alone and
// its apple_iou / apple_accuracy are NaN (undefined). A prediction with no
// apple on a ground truth with apples gets apple IoU 0.
struct SegmentationScores {
  double mean_iou = 0;
  double fw_iou = 0;
  double apple_iou = 0;
  double pixel_accuracy = 0;
  double mean_accuracy = 0;
  double apple_accuracy = 0;
};

// Scores one image; `ground_truth` and `prediction` are single-channel masks of
// equal size where any non-zero value is apple.
SegmentationScores ScoreSegmentation(const cv::Mat& ground_truth, const cv::Mat& prediction);

struct SegmentationMetrics {
  int images = 0;
  int images_with_apple = 0;  // images whose ground truth has apple pixels
  // Means over all images, except apple_iou / apple_accuracy: means over the
  // images_with_apple (NaN when there are none).
  SegmentationScores mean;
  std::vector<std::string> names;            // per image, in name order
  std::vector<SegmentationScores> per_image;
};

// Reads a mask file as apple / not apple: any non-zero value in any channel is
// apple (instance ids, 0/1 or 0/255 masks). Throws when unreadable.
cv::Mat ReadAppleMask(const fs::path& path);

// Scores every mask in `gt_dir` (or `gt_dir/masks` when that exists, a
// MinneApple dataset folder) against the mask in `pred_dir` with the same stem
// (any image extension). Throws when a prediction is missing, a size differs,
// a mask cannot be read, or `gt_dir` has no masks. Prediction masks without a
// ground truth are ignored (their names are returned in `unmatched`).
SegmentationMetrics EvaluateSegmentation(const fs::path& gt_dir, const fs::path& pred_dir,
                                         std::vector<std::string>* unmatched = nullptr);

}  // namespace orchard
