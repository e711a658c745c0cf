#include "orchard/count/cnn_counter.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_ensemble.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

namespace orchard {

struct CnnCounter::Impl {
  std::vector<nn::ResNet> nets;
  std::vector<int> input_sizes;
  nn::CounterEnsemble ensemble{nullptr};  // holds the nets of an ensemble file
  CnnCounterOptions options;
  torch::Tensor prior;  // [1, classes] factors, undefined when the network's prior is the one wanted
};

void CnnCounterOptions::Check() const {
  ORCHARD_CHECK_OPTION(prior_weight >= 0 && prior_weight <= 1, "prior weight must be in [0, 1], got ", prior_weight);
}

CnnCounter::CnnCounter(const std::filesystem::path& model_path, int threads, const CnnCounterOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  const nlohmann::json header = nn::ReadCheckpointHeader(model_path, "counter");
  std::vector<nn::CounterMember> members;
  try {
    members = nn::CounterMembers(header);
  } catch (const Error&) {
    Fail("model file ", model_path.string(), " has an incomplete counter header");
  }
  // A network trained with class balance power b has learnt the prior
  // frequencies^(1 - b); the decision wants frequencies^prior_weight, so the
  // probabilities are weighed by the quotient (logit adjustment).
  const double balance = nn::CounterBalancePower(header);
  const double exponent = options.prior_weight - (1 - balance);
  if (exponent != 0) {
    if (!header.contains("train_class_counts")) Fail("model file ", model_path.string(), " has no class counts for the prior");
    std::vector<double> counts = header.at("train_class_counts").get<std::vector<double>>();
    double total = 0;
    for (double& c : counts) total += c = std::max(c, 1.0);  // a count never seen still gets a chance
    std::vector<float> factors;
    for (double c : counts) factors.push_back(static_cast<float>(std::pow(c / total, exponent)));
    impl_->prior = torch::tensor(factors).unsqueeze(0);
  }
  for (const nn::CounterMember& m : members) impl_->input_sizes.push_back(m.input_size);
  if (header.contains("members")) {
    impl_->ensemble = nn::CounterEnsemble(members);
    nn::LoadCheckpointWeights(*impl_->ensemble, model_path);
    impl_->ensemble->eval();
    impl_->nets = impl_->ensemble->nets;
  } else {
    impl_->nets.push_back(nn::ResNet(members[0].architecture));
    nn::LoadCheckpointWeights(*impl_->nets[0], model_path);
    impl_->nets[0]->eval();
  }
  at::set_num_threads(ThreadsOrAvailableCores(threads));
}

CnnCounter::~CnnCounter() = default;

int CnnCounter::input_size() const { return impl_->input_sizes.front(); }

int CnnCounter::num_networks() const { return static_cast<int>(impl_->nets.size()); }

std::vector<std::vector<float>> CnnCounter::CountProbabilities(const std::vector<cv::Mat>& bgr_patches) {
  std::vector<std::vector<float>> probabilities;
  torch::NoGradGuard no_grad;
  for (size_t begin = 0; begin < bgr_patches.size(); begin += 64) {
    const size_t end = std::min(bgr_patches.size(), begin + 64);
    torch::Tensor p;
    std::map<int, torch::Tensor> batch_of_size;  // letterboxed once per input size, not per network
    for (size_t n = 0; n < impl_->nets.size(); ++n) {
      torch::Tensor& x = batch_of_size[impl_->input_sizes[n]];
      if (!x.defined()) {
        std::vector<cv::Mat> inputs;
        for (size_t i = begin; i < end; ++i) inputs.push_back(nn::LetterboxPatch(bgr_patches[i], impl_->input_sizes[n]));
        x = nn::ImagesToTensor(inputs);
      }
      torch::Tensor q = torch::softmax(impl_->nets[n]->forward(x), 1);
      // Mirroring the letterboxed input is what training's flip augmentation does.
      if (impl_->options.flip_average) q = 0.5 * (q + torch::softmax(impl_->nets[n]->forward(torch::flip(x, {3})), 1));
      p = n == 0 ? q : p + q;
    }
    p = p / static_cast<double>(impl_->nets.size());
    if (impl_->prior.defined()) {
      if (impl_->prior.size(1) != p.size(1)) Fail("class counts of the prior do not match the model's classes");
      p = p * impl_->prior;
      p = p / p.sum(1, true);
    }
    p = p.contiguous();
    for (int64_t i = 0; i < p.size(0); ++i) {
      const float* row = p[i].data_ptr<float>();
      probabilities.emplace_back(row, row + p.size(1));
    }
  }
  return probabilities;
}

std::vector<int> CnnCounter::CountBatch(const std::vector<cv::Mat>& bgr_patches) {
  std::vector<int> counts;
  for (const std::vector<float>& p : CountProbabilities(bgr_patches)) {
    counts.push_back(static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin()));
  }
  return counts;
}

BlobCount CnnCounter::Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) {
  if (!fruit_mask.empty() && fruit_mask.size() != bgr_patch.size()) Fail("fruit mask and patch differ in size");
  BlobCount result;
  result.count = CountBatch({bgr_patch}).at(0);
  return result;
}

std::vector<BlobCount> CnnCounter::CountMany(const std::vector<cv::Mat>& bgr_patches,
                                             const std::vector<cv::Mat1b>& fruit_masks) {
  if (!fruit_masks.empty() && fruit_masks.size() != bgr_patches.size())
    Fail("counter: ", fruit_masks.size(), " fruit masks for ", bgr_patches.size(), " patches");
  for (size_t i = 0; i < fruit_masks.size(); ++i)
    if (!fruit_masks[i].empty() && fruit_masks[i].size() != bgr_patches[i].size())
      Fail("fruit mask and patch differ in size");
  std::vector<BlobCount> counts;
  if (bgr_patches.empty()) return counts;
  for (int c : CountBatch(bgr_patches)) counts.push_back(BlobCount{c, {}});
  return counts;
}

}  // namespace orchard
