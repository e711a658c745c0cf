#include "orchard/count/cnn_counter.h"

#include <thread>

#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

namespace orchard {

struct CnnCounter::Impl {
  nn::ResNet net{nullptr};
  int input_size = 64;
};

CnnCounter::CnnCounter(const std::filesystem::path& model_path, int threads) : impl_(std::make_unique<Impl>()) {
  const nlohmann::json header = nn::ReadCheckpointHeader(model_path, "counter");
  try {
    impl_->net = nn::ResNet(nn::ResNetOptions::FromJson(header.at("architecture")));
    impl_->input_size = header.at("input_size").get<int>();
  } catch (const nlohmann::json::exception&) {
    Fail("model file ", model_path.string(), " has an incomplete counter header");
  }
  nn::LoadCheckpointWeights(*impl_->net, model_path);
  impl_->net->eval();
  at::set_num_threads(threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

CnnCounter::~CnnCounter() = default;

int CnnCounter::input_size() const { return impl_->input_size; }

std::vector<int> CnnCounter::CountBatch(const std::vector<cv::Mat>& bgr_patches) {
  std::vector<int> counts;
  torch::NoGradGuard no_grad;
  for (size_t begin = 0; begin < bgr_patches.size(); begin += 64) {
    const size_t end = std::min(bgr_patches.size(), begin + 64);
    std::vector<cv::Mat> inputs;
    for (size_t i = begin; i < end; ++i) inputs.push_back(nn::LetterboxPatch(bgr_patches[i], impl_->input_size));
    torch::Tensor predicted = impl_->net->forward(nn::ImagesToTensor(inputs)).argmax(1);
    for (size_t i = 0; i < inputs.size(); ++i) counts.push_back(static_cast<int>(predicted[i].item<int64_t>()));
  }
  return counts;
}

BlobCount CnnCounter::Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) {
  if (!fruit_mask.empty() && fruit_mask.size() != bgr_patch.size()) Fail("fruit mask and patch differ in size");
  BlobCount result;
  result.count = CountBatch({bgr_patch}).at(0);
  return result;
}

}  // namespace orchard
