#include "orchard/eval/segmentation_metrics.h"

#include <cmath>
#include <limits>
#include <map>
#include <set>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

SegmentationScores ScoreSegmentation(const cv::Mat& ground_truth, const cv::Mat& prediction) {
  if (ground_truth.size() != prediction.size()) {
    Fail("mask sizes differ: ground truth ", ground_truth.cols, "x", ground_truth.rows,
         ", prediction ", prediction.cols, "x", prediction.rows);
  }
  if (ground_truth.channels() != 1 || prediction.channels() != 1) {
    Fail("ScoreSegmentation needs single-channel masks");
  }
  if (ground_truth.empty()) Fail("empty mask");
  cv::Mat gt = ground_truth != 0, pred = prediction != 0;  // 255 where apple
  const double n = static_cast<double>(gt.total());
  const double gt_apple = cv::countNonZero(gt);
  const double pred_apple = cv::countNonZero(pred);
  cv::Mat both;
  cv::bitwise_and(gt, pred, both);
  const double tp_apple = cv::countNonZero(both);
  // Background: tp_0 = pixels neither calls apple.
  const double gt_bg = n - gt_apple, pred_bg = n - pred_apple;
  const double tp_bg = n - gt_apple - pred_apple + tp_apple;

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double gt_c[2] = {gt_bg, gt_apple}, pred_c[2] = {pred_bg, pred_apple},
               tp_c[2] = {tp_bg, tp_apple};
  double iou[2] = {nan, nan}, acc[2] = {nan, nan};
  double iou_sum = 0, acc_sum = 0, fw = 0;
  int valid = 0;
  for (int c = 0; c < 2; ++c) {
    if (gt_c[c] <= 0) continue;  // class absent from the ground truth
    iou[c] = tp_c[c] / (gt_c[c] + pred_c[c] - tp_c[c]);
    acc[c] = tp_c[c] / gt_c[c];
    iou_sum += iou[c];
    acc_sum += acc[c];
    fw += gt_c[c] / n * iou[c];
    ++valid;
  }
  SegmentationScores s;
  s.mean_iou = iou_sum / valid;
  s.mean_accuracy = acc_sum / valid;
  s.fw_iou = fw;
  s.pixel_accuracy = (tp_bg + tp_apple) / n;
  s.apple_iou = iou[1];
  s.apple_accuracy = acc[1];
  return s;
}

cv::Mat ReadAppleMask(const fs::path& path) {
  const cv::Mat raw = ReadImage(path, cv::IMREAD_UNCHANGED);
  std::vector<cv::Mat> channels;
  cv::split(raw, channels);
  cv::Mat apple = cv::Mat::zeros(raw.size(), CV_8U);
  for (const cv::Mat& c : channels) apple |= (c != 0);
  return apple;
}

SegmentationMetrics EvaluateSegmentation(const fs::path& gt_dir_in, const fs::path& pred_dir,
                                         std::vector<std::string>* unmatched) {
  std::error_code ec;
  fs::path gt_dir = gt_dir_in;
  if (fs::is_directory(gt_dir / "masks", ec)) gt_dir /= "masks";
  if (!fs::is_directory(pred_dir, ec)) Fail("prediction mask folder not found: ", pred_dir.string());
  const std::vector<fs::path> gt_files = ListImages(gt_dir);
  if (gt_files.empty()) Fail("no mask images in ", gt_dir.string());

  std::map<std::string, fs::path> pred_by_stem;
  for (const fs::path& p : ListImages(pred_dir)) {
    const std::string stem = p.stem().string();
    if (pred_by_stem.count(stem)) {
      Fail("two prediction masks for '", stem, "' in ", pred_dir.string(), ": ",
           pred_by_stem[stem].filename().string(), " and ", p.filename().string());
    }
    pred_by_stem[stem] = p;
  }

  SegmentationMetrics metrics;
  std::set<std::string> used;
  double apple_iou_sum = 0, apple_acc_sum = 0;
  for (const fs::path& gt_path : gt_files) {
    const std::string stem = gt_path.stem().string();
    auto it = pred_by_stem.find(stem);
    if (it == pred_by_stem.end()) {
      Fail("no prediction mask for ", gt_path.filename().string(), " in ", pred_dir.string());
    }
    used.insert(stem);
    const cv::Mat gt = ReadAppleMask(gt_path);
    const cv::Mat pred = ReadAppleMask(it->second);
    if (gt.size() != pred.size()) {
      Fail("mask size mismatch for '", stem, "': ground truth ", gt.cols, "x", gt.rows, " (",
           gt_path.string(), "), prediction ", pred.cols, "x", pred.rows, " (",
           it->second.string(), ")");
    }
    const SegmentationScores s = ScoreSegmentation(gt, pred);
    metrics.names.push_back(gt_path.filename().string());
    metrics.per_image.push_back(s);
    metrics.mean.mean_iou += s.mean_iou;
    metrics.mean.fw_iou += s.fw_iou;
    metrics.mean.pixel_accuracy += s.pixel_accuracy;
    metrics.mean.mean_accuracy += s.mean_accuracy;
    if (!std::isnan(s.apple_iou)) {
      ++metrics.images_with_apple;
      apple_iou_sum += s.apple_iou;
      apple_acc_sum += s.apple_accuracy;
    }
  }
  metrics.images = static_cast<int>(metrics.per_image.size());
  const double n = metrics.images;
  metrics.mean.mean_iou /= n;
  metrics.mean.fw_iou /= n;
  metrics.mean.pixel_accuracy /= n;
  metrics.mean.mean_accuracy /= n;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  metrics.mean.apple_iou =
      metrics.images_with_apple ? apple_iou_sum / metrics.images_with_apple : nan;
  metrics.mean.apple_accuracy =
      metrics.images_with_apple ? apple_acc_sum / metrics.images_with_apple : nan;
  if (unmatched) {
    unmatched->clear();
    for (const auto& [stem, path] : pred_by_stem) {
      if (!used.count(stem)) unmatched->push_back(path.filename().string());
    }
  }
  return metrics;
}

}  // namespace orchard
