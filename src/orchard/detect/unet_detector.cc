#include "orchard/detect/unet_detector.h"

#include <opencv2/imgproc.hpp>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

namespace orchard {

struct UNetDetector::Impl {
  nn::UNet net{nullptr};
  UNetDetectorOptions options;
  int multiple = 1;  // the network's input sides must be multiples of this
};

void UNetDetectorOptions::Check() const {
  ORCHARD_CHECK_OPTION(tile >= 0, "tile must be >= 0 (0 = the model's), got ", tile);
  ORCHARD_CHECK_OPTION(batch >= 1, "batch must be >= 1, got ", batch);
  ORCHARD_CHECK_OPTION(threshold > 0 && threshold < 1, "threshold must be in (0, 1), got ", threshold);
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0, got ", threads);
  blobs.Check();
}

UNetDetector::UNetDetector(const std::filesystem::path& model_path, const UNetDetectorOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  const nlohmann::json header = nn::ReadCheckpointHeader(model_path, "unet");
  try {
    impl_->net = nn::UNet(nn::UNetOptions::FromJson(header.at("architecture")));
    if (impl_->options.tile == 0) impl_->options.tile = header.at("tile").get<int>();
  } catch (const nlohmann::json::exception&) {
    Fail("model file ", model_path.string(), " has an incomplete U-Net header");
  }
  const int multiple = impl_->multiple = impl_->net->options().InputMultiple();
  if (impl_->options.tile % multiple != 0) {
    Fail("U-Net tile ", impl_->options.tile, " is not a multiple of ", multiple, " as this network needs");
  }
  nn::LoadCheckpointWeights(*impl_->net, model_path);
  impl_->net->eval();
  at::set_num_threads(ThreadsOrAvailableCores(options.threads));
}

UNetDetector::~UNetDetector() = default;

cv::Mat1f UNetDetector::AppleProbability(const cv::Mat& bgr) {
  if (bgr.empty()) Fail("empty frame");
  if (bgr.type() != CV_8UC3) Fail("frame must be 8-bit BGR");
  torch::NoGradGuard no_grad;
  if (impl_->options.whole_frame) {
    const int m = impl_->multiple;
    cv::Mat padded;
    cv::copyMakeBorder(bgr, padded, 0, (bgr.rows + m - 1) / m * m - bgr.rows, 0, (bgr.cols + m - 1) / m * m - bgr.cols,
                       cv::BORDER_CONSTANT, cv::Scalar::all(0));
    const torch::Tensor apple =
        torch::softmax(impl_->net->forward(nn::ImagesToTensor({padded})), 1).select(1, 1)[0].contiguous();
    return cv::Mat1f(padded.rows, padded.cols, apple.data_ptr<float>())(cv::Rect(0, 0, bgr.cols, bgr.rows)).clone();
  }
  const int tile = impl_->options.tile;
  // Zero-pad to whole tiles; tiles do not overlap.
  const int cols = (bgr.cols + tile - 1) / tile, rows = (bgr.rows + tile - 1) / tile;
  cv::Mat padded;
  cv::copyMakeBorder(bgr, padded, 0, rows * tile - bgr.rows, 0, cols * tile - bgr.cols, cv::BORDER_CONSTANT,
                     cv::Scalar::all(0));
  cv::Mat1f probability(padded.size(), 0.0f);
  std::vector<cv::Rect> rects;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) rects.emplace_back(c * tile, r * tile, tile, tile);
  }
  for (size_t begin = 0; begin < rects.size(); begin += impl_->options.batch) {
    const size_t end = std::min(rects.size(), begin + impl_->options.batch);
    std::vector<cv::Mat> tiles;
    for (size_t i = begin; i < end; ++i) tiles.push_back(padded(rects[i]).clone());
    const torch::Tensor apple =
        torch::softmax(impl_->net->forward(nn::ImagesToTensor(tiles)), 1).select(1, 1).contiguous();
    for (size_t i = begin; i < end; ++i) {
      cv::Mat1f view(tile, tile, apple[i - begin].data_ptr<float>());
      view.copyTo(probability(rects[i]));
    }
  }
  return probability(cv::Rect(0, 0, bgr.cols, bgr.rows)).clone();
}

FrameDetection UNetDetector::Detect(const cv::Mat& bgr) {
  const cv::Mat1f probability = AppleProbability(bgr);
  FrameDetection detection = ExtractBlobs(probability > impl_->options.threshold, impl_->options.blobs);
  ScoreBlobs(probability, &detection);
  return detection;
}

}  // namespace orchard
