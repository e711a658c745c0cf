#include "orchard/detect/retinanet_detector.h"

#include <opencv2/imgproc.hpp>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/detection_training.h"
#include "orchard/nn/retinanet.h"

namespace orchard {

struct RetinaNetDetector::Impl {
  nn::RetinaNet net{nullptr};
  RetinaNetDetectorOptions options;
};

void RetinaNetDetectorOptions::Check() const {
  ORCHARD_CHECK_OPTION(score_threshold > 0 && score_threshold < 1, "score threshold must be in (0, 1), got ",
                       score_threshold);
  ORCHARD_CHECK_OPTION(nms_iou > 0 && nms_iou <= 1, "NMS IoU must be in (0, 1], got ", nms_iou);
  ORCHARD_CHECK_OPTION(max_detections >= 1, "max detections must be positive, got ", max_detections);
  ORCHARD_CHECK_OPTION(input_scale >= 0.25 && input_scale <= 4, "input scale must be in [0.25, 4], got ", input_scale);
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0, got ", threads);
  blobs.Check();
}

RetinaNetDetector::RetinaNetDetector(const std::filesystem::path& model_path, const RetinaNetDetectorOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  const nlohmann::json header = nn::ReadCheckpointHeader(model_path, "retinanet");
  try {
    impl_->net = nn::RetinaNet(nn::RetinaNetOptions::FromJson(header.at("architecture")));
  } catch (const nlohmann::json::exception&) {
    Fail("model file ", model_path.string(), " has an incomplete RetinaNet header");
  }
  nn::LoadCheckpointWeights(*impl_->net, model_path);
  impl_->net->eval();
  at::set_num_threads(ThreadsOrAvailableCores(options.threads));
}

RetinaNetDetector::~RetinaNetDetector() = default;

FrameDetection RetinaNetDetector::Detect(const cv::Mat& bgr) {
  nn::DecodeOptions decode;
  decode.score_threshold = impl_->options.score_threshold;
  decode.nms_iou = impl_->options.nms_iou;
  decode.max_detections = impl_->options.max_detections;
  const double scale = impl_->options.input_scale;
  std::vector<nn::ScoredApple> apples;
  if (scale == 1) {
    apples = nn::DetectApples(impl_->net, bgr, decode);
  } else {
    if (bgr.empty()) Fail("empty frame");
    cv::Mat resized;
    cv::resize(bgr, resized, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
    apples = nn::DetectApples(impl_->net, resized, decode);
    for (nn::ScoredApple& a : apples) {
      a.box = {a.box.x1 / scale, a.box.y1 / scale, a.box.x2 / scale, a.box.y2 / scale};
    }
  }
  FrameDetection detection;
  detection.mask = cv::Mat1b::zeros(bgr.size());
  detection.labels = cv::Mat1i::zeros(bgr.size());
  // Drawn lowest score first, so the higher-scoring box keeps shared pixels.
  for (size_t i = apples.size(); i-- > 0;) {
    const Box& b = apples[i].box;
    cv::ellipse(detection.labels, cv::RotatedRect(cv::Point2f(b.CenterX(), b.CenterY()), cv::Size2f(b.Width(), b.Height()), 0),
                cv::Scalar(static_cast<int>(i) + 1), cv::FILLED);
  }
  std::vector<int> pixels(apples.size() + 1, 0);
  for (int y = 0; y < detection.labels.rows; ++y) {
    const int* row = detection.labels.ptr<int>(y);
    for (int x = 0; x < detection.labels.cols; ++x) ++pixels[row[x]];
  }
  // Keep boxes with enough pixels, renumbered 1..N in score order.
  std::vector<int> new_id(apples.size() + 1, 0);
  for (size_t i = 0; i < apples.size(); ++i) {
    if (pixels[i + 1] < impl_->options.blobs.min_pixels) continue;
    Blob blob;
    blob.id = static_cast<int>(detection.blobs.size()) + 1;
    blob.box = apples[i].box;
    blob.pixels = pixels[i + 1];
    blob.centroid = cv::Point2d(apples[i].box.CenterX(), apples[i].box.CenterY());
    blob.score = apples[i].score;
    new_id[i + 1] = blob.id;
    detection.blobs.push_back(blob);
  }
  for (int y = 0; y < detection.labels.rows; ++y) {
    int* row = detection.labels.ptr<int>(y);
    uchar* mask = detection.mask.ptr<uchar>(y);
    for (int x = 0; x < detection.labels.cols; ++x) {
      row[x] = new_id[row[x]];
      mask[x] = row[x] > 0 ? 255 : 0;
    }
  }
  return detection;
}

}  // namespace orchard
