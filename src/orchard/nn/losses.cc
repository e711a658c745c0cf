#include "orchard/nn/losses.h"

#include "orchard/core/error.h"

namespace orchard::nn {

std::vector<double> InverseFrequencyWeights(const std::vector<int64_t>& class_counts) {
  std::vector<double> weights(class_counts.size(), 0.0);
  double sum = 0;
  for (size_t c = 0; c < class_counts.size(); ++c) {
    if (class_counts[c] > 0) weights[c] = 1.0 / static_cast<double>(class_counts[c]);
    sum += weights[c];
  }
  if (sum <= 0) Fail("no labelled samples to weight classes by");
  for (double& w : weights) w /= sum;
  return weights;
}

torch::Tensor WeightedCrossEntropy(const torch::Tensor& logits, const torch::Tensor& target,
                                   const std::vector<double>& weights) {
  torch::Tensor w = torch::tensor(weights, torch::kFloat32).to(logits.device());
  return torch::nn::functional::cross_entropy(logits, target,
                                              torch::nn::functional::CrossEntropyFuncOptions().weight(w));
}

torch::Tensor SigmoidFocalLoss(const torch::Tensor& logits, const torch::Tensor& targets, double alpha, double gamma) {
  const torch::Tensor p = torch::sigmoid(logits);
  const torch::Tensor ce = torch::binary_cross_entropy_with_logits(logits, targets, {}, {}, at::Reduction::None);
  const torch::Tensor p_t = p * targets + (1 - p) * (1 - targets);
  const torch::Tensor alpha_t = alpha * targets + (1 - alpha) * (1 - targets);
  return (alpha_t * torch::pow(1 - p_t, gamma) * ce).sum();
}

}  // namespace orchard::nn
