// Losses written for this project (LibTorch has cross-entropy but no class
// weighting from data and no focal loss).
#pragma once

#include <vector>

#include <torch/torch.h>

namespace orchard::nn {

// Class weights inversely proportional to class frequency, normalised to sum
// to 1 (the U-Net paper's weighting against the background majority). Classes
// with zero count get weight 0.
std::vector<double> InverseFrequencyWeights(const std::vector<int64_t>& class_counts);

// Pixel-wise cross-entropy: logits [N, C, H, W], target [N, H, W] (int64), weights [C].
torch::Tensor WeightedCrossEntropy(const torch::Tensor& logits, const torch::Tensor& target,
                                   const std::vector<double>& weights);

// Sigmoid focal loss (Lin et al. 2017) summed over elements: logits and
// targets (0/1) of the same shape. alpha weights positives, gamma focuses on
// hard examples.
torch::Tensor SigmoidFocalLoss(const torch::Tensor& logits, const torch::Tensor& targets, double alpha = 0.25,
                               double gamma = 2.0);

}  // namespace orchard::nn
