// Network architectures trained from scratch on CPU: a ResNet classifier (the
// cluster counter) and a VGG-style U-Net (the segmentation detector). Both take
// a width multiplier so a narrow version trains on a laptop.
//
// This header includes LibTorch: include it only from nn/ and from the .cc
// files of the detectors and counters that run the networks.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <torch/torch.h>

namespace orchard::nn {

struct ResNetOptions {
  // 18 and 34 use basic blocks, 50 bottleneck blocks (He et al. 2016).
  int depth = 18;
  // Channels of the first stage (64 in the paper). 16 trains on CPU.
  int base_width = 64;
  int in_channels = 3;
  int num_classes = 7;  // counts 0..6; 0 = no classifier (a backbone: ForwardStages)
  // A second output: a density map at 1/8 of the input (after the second
  // stage) whose sum is the count. Trained with the apples' positions as
  // point supervision, it teaches the shared layers where each apple is; the
  // classifier stays the counter's answer.
  bool density_head = false;

  void Check() const;
  nlohmann::json ToJson() const;
  static ResNetOptions FromJson(const nlohmann::json& json);
};

class ResNetImpl : public torch::nn::Module {
 public:
  explicit ResNetImpl(const ResNetOptions& options);
  // [N, C, H, W] float in [0, 1] (normalised by the caller) -> [N, classes] logits.
  torch::Tensor forward(torch::Tensor x);
  // Logits and the density map [N, 1, H/8, W/8] (options().density_head only).
  std::pair<torch::Tensor, torch::Tensor> ForwardWithDensity(torch::Tensor x);
  // The output of each of the four stages (strides 4, 8, 16, 32): the
  // feature pyramid's inputs.
  std::vector<torch::Tensor> ForwardStages(torch::Tensor x);
  // Channels of each stage's output.
  std::vector<int> StageChannels() const;
  const ResNetOptions& options() const { return options_; }

 private:
  // Global average pooling and the linear head: features -> logits.
  torch::Tensor Classify(const torch::Tensor& features);

  ResNetOptions options_;
  torch::nn::Sequential stem_{nullptr};
  torch::nn::Sequential stages_{nullptr};
  torch::nn::Linear head_{nullptr};
  torch::nn::Sequential density_{nullptr};
  size_t density_after_block_ = 0;  // blocks of the first two stages
  std::vector<size_t> stage_ends_;  // blocks up to the end of each stage
};
TORCH_MODULE(ResNet);

struct UNetOptions {
  // Channels of the first encoder block; VGG-16 uses 64 and doubles it per
  // block up to 8x. 8 or 16 trains on CPU.
  int base_width = 64;
  int in_channels = 3;
  int num_classes = 2;  // background, apple
  // Encoder blocks (VGG-16: 5, with 2, 2, 3, 3, 3 convolutions). Inputs must be
  // divisible by 2^(blocks - 1).
  int blocks = 5;
  // Batch normalisation after each convolution: trains far more reliably from
  // scratch than the original VGG without it.
  bool batch_norm = true;

  void Check() const;
  nlohmann::json ToJson() const;
  static UNetOptions FromJson(const nlohmann::json& json);
  int InputMultiple() const { return 1 << (blocks - 1); }
};

class UNetImpl : public torch::nn::Module {
 public:
  explicit UNetImpl(const UNetOptions& options);
  // [N, C, H, W] -> [N, classes, H, W] logits.
  torch::Tensor forward(torch::Tensor x);
  const UNetOptions& options() const { return options_; }

 private:
  UNetOptions options_;
  std::vector<torch::nn::Sequential> encoder_;
  std::vector<torch::nn::ConvTranspose2d> up_;
  std::vector<torch::nn::Sequential> decoder_;
  torch::nn::Conv2d classifier_{nullptr};
};
TORCH_MODULE(UNet);

// Number of trainable parameters.
int64_t CountParameters(const torch::nn::Module& module);

}  // namespace orchard::nn
