#include "orchard/nn/models.h"

#include <algorithm>

#include "orchard/core/error.h"

namespace orchard::nn {
namespace {

namespace tnn = torch::nn;

tnn::Sequential ConvBnRelu(int in, int out, int kernel, int stride, bool batch_norm = true) {
  tnn::Sequential seq;
  seq->push_back(tnn::Conv2d(
      tnn::Conv2dOptions(in, out, kernel).stride(stride).padding(kernel / 2).bias(!batch_norm)));
  if (batch_norm) seq->push_back(tnn::BatchNorm2d(out));
  seq->push_back(tnn::ReLU(tnn::ReLUOptions(true)));
  return seq;
}

// The residual shortcut when the shape changes: 1x1 convolution + batch norm.
tnn::Sequential Projection(int in, int out, int stride) {
  return tnn::Sequential(tnn::Conv2d(tnn::Conv2dOptions(in, out, 1).stride(stride).bias(false)), tnn::BatchNorm2d(out));
}

// Residual blocks.
class BasicBlockImpl : public tnn::Module {
 public:
  BasicBlockImpl(int in, int out, int stride) {
    conv1_ = register_module("conv1", tnn::Conv2d(tnn::Conv2dOptions(in, out, 3).stride(stride).padding(1).bias(false)));
    bn1_ = register_module("bn1", tnn::BatchNorm2d(out));
    conv2_ = register_module("conv2", tnn::Conv2d(tnn::Conv2dOptions(out, out, 3).padding(1).bias(false)));
    bn2_ = register_module("bn2", tnn::BatchNorm2d(out));
    if (stride != 1 || in != out) shortcut_ = register_module("shortcut", Projection(in, out, stride));
  }
  torch::Tensor forward(torch::Tensor x) {
    torch::Tensor y = torch::relu(bn1_(conv1_(x)));
    y = bn2_(conv2_(y));
    return torch::relu(y + (shortcut_ ? shortcut_->forward(x) : x));
  }

 private:
  tnn::Conv2d conv1_{nullptr}, conv2_{nullptr};
  tnn::BatchNorm2d bn1_{nullptr}, bn2_{nullptr};
  tnn::Sequential shortcut_{nullptr};
};
TORCH_MODULE(BasicBlock);

class BottleneckImpl : public tnn::Module {
 public:
  static constexpr int kExpansion = 4;
  BottleneckImpl(int in, int width, int stride) {
    const int out = width * kExpansion;
    conv1_ = register_module("conv1", tnn::Conv2d(tnn::Conv2dOptions(in, width, 1).bias(false)));
    bn1_ = register_module("bn1", tnn::BatchNorm2d(width));
    conv2_ = register_module("conv2", tnn::Conv2d(tnn::Conv2dOptions(width, width, 3).stride(stride).padding(1).bias(false)));
    bn2_ = register_module("bn2", tnn::BatchNorm2d(width));
    conv3_ = register_module("conv3", tnn::Conv2d(tnn::Conv2dOptions(width, out, 1).bias(false)));
    bn3_ = register_module("bn3", tnn::BatchNorm2d(out));
    if (stride != 1 || in != out) shortcut_ = register_module("shortcut", Projection(in, out, stride));
  }
  torch::Tensor forward(torch::Tensor x) {
    torch::Tensor y = torch::relu(bn1_(conv1_(x)));
    y = torch::relu(bn2_(conv2_(y)));
    y = bn3_(conv3_(y));
    return torch::relu(y + (shortcut_ ? shortcut_->forward(x) : x));
  }

 private:
  tnn::Conv2d conv1_{nullptr}, conv2_{nullptr}, conv3_{nullptr};
  tnn::BatchNorm2d bn1_{nullptr}, bn2_{nullptr}, bn3_{nullptr};
  tnn::Sequential shortcut_{nullptr};
};
TORCH_MODULE(Bottleneck);

std::vector<int> BlocksPerStage(int depth) {
  switch (depth) {
    case 18: return {2, 2, 2, 2};
    case 34: return {3, 4, 6, 3};
    case 50: return {3, 4, 6, 3};
    default: return {};
  }
}

}  // namespace

void ResNetOptions::Check() const {
  ORCHARD_CHECK_OPTION(depth == 18 || depth == 34 || depth == 50, "ResNet depth must be 18, 34 or 50, got ", depth);
  ORCHARD_CHECK_OPTION(base_width >= 4 && base_width <= 256, "ResNet base width must be in [4, 256], got ", base_width);
  ORCHARD_CHECK_OPTION(in_channels >= 1, "input channels must be positive, got ", in_channels);
  ORCHARD_CHECK_OPTION(num_classes == 0 || num_classes >= 2,
                       "a classifier needs at least 2 classes (0 = no classifier), got ", num_classes);
}

nlohmann::json ResNetOptions::ToJson() const {
  nlohmann::json json = {
      {"depth", depth}, {"base_width", base_width}, {"in_channels", in_channels}, {"num_classes", num_classes}};
  // Written only when on, so files without it read as before.
  if (density_head) json["density_head"] = true;
  return json;
}

ResNetOptions ResNetOptions::FromJson(const nlohmann::json& json) {
  ResNetOptions o;
  o.depth = json.at("depth").get<int>();
  o.base_width = json.at("base_width").get<int>();
  o.in_channels = json.at("in_channels").get<int>();
  o.num_classes = json.at("num_classes").get<int>();
  o.density_head = json.value("density_head", false);
  o.Check();
  return o;
}

ResNetImpl::ResNetImpl(const ResNetOptions& options) : options_(options) {
  options_.Check();
  const int w = options_.base_width;
  // The paper's stem (7x7 stride 2 + max pool) quarters the input at once.
  stem_ = register_module("stem", ConvBnRelu(options_.in_channels, w, 7, 2));
  stem_->push_back(tnn::MaxPool2d(tnn::MaxPool2dOptions(3).stride(2).padding(1)));
  stages_ = register_module("stages", tnn::Sequential());
  const std::vector<int> blocks = BlocksPerStage(options_.depth);
  const bool bottleneck = options_.depth >= 50;
  int in = w;
  for (size_t s = 0; s < blocks.size(); ++s) {
    const int width = w << s;
    for (int b = 0; b < blocks[s]; ++b) {
      const int stride = (b == 0 && s > 0) ? 2 : 1;
      if (bottleneck) {
        stages_->push_back(Bottleneck(in, width, stride));
        in = width * BottleneckImpl::kExpansion;
      } else {
        stages_->push_back(BasicBlock(in, width, stride));
        in = width;
      }
    }
    stage_ends_.push_back(stages_->size());
    if (s == 1 && options_.density_head) {
      density_after_block_ = stages_->size();
      density_ = register_module("density", ConvBnRelu(in, in, 3, 1));
      density_->push_back(tnn::Conv2d(tnn::Conv2dOptions(in, 1, 1)));
    }
  }
  if (options_.num_classes > 0) head_ = register_module("head", tnn::Linear(in, options_.num_classes));
}

torch::Tensor ResNetImpl::Classify(const torch::Tensor& features) {
  if (!head_) Fail("this ResNet is a backbone without a classifier");
  return head_(torch::adaptive_avg_pool2d(features, {1, 1}).flatten(1));
}

torch::Tensor ResNetImpl::forward(torch::Tensor x) { return Classify(stages_->forward(stem_->forward(x))); }

std::pair<torch::Tensor, torch::Tensor> ResNetImpl::ForwardWithDensity(torch::Tensor x) {
  if (!density_) Fail("this ResNet has no density head");
  x = stem_->forward(x);
  torch::Tensor density;
  size_t blocks = 0;
  for (auto& block : *stages_) {
    x = block.forward(x);
    if (++blocks == density_after_block_) density = torch::relu(density_->forward(x));
  }
  return {Classify(x), density};
}

std::vector<torch::Tensor> ResNetImpl::ForwardStages(torch::Tensor x) {
  x = stem_->forward(x);
  std::vector<torch::Tensor> outputs;
  size_t blocks = 0;
  for (auto& block : *stages_) {
    x = block.forward(x);
    ++blocks;
    if (std::find(stage_ends_.begin(), stage_ends_.end(), blocks) != stage_ends_.end()) outputs.push_back(x);
  }
  return outputs;
}

std::vector<int> ResNetImpl::StageChannels() const {
  const int expansion = options_.depth >= 50 ? BottleneckImpl::kExpansion : 1;
  std::vector<int> channels;
  for (size_t s = 0; s < stage_ends_.size(); ++s) channels.push_back((options_.base_width << s) * expansion);
  return channels;
}

void UNetOptions::Check() const {
  ORCHARD_CHECK_OPTION(base_width >= 2 && base_width <= 128, "U-Net base width must be in [2, 128], got ", base_width);
  ORCHARD_CHECK_OPTION(blocks >= 2 && blocks <= 5, "U-Net blocks must be in [2, 5], got ", blocks);
  ORCHARD_CHECK_OPTION(in_channels >= 1, "input channels must be positive, got ", in_channels);
  ORCHARD_CHECK_OPTION(num_classes >= 2, "segmentation needs at least 2 classes, got ", num_classes);
}

nlohmann::json UNetOptions::ToJson() const {
  return {{"base_width", base_width}, {"in_channels", in_channels}, {"num_classes", num_classes},
          {"blocks", blocks}, {"batch_norm", batch_norm}};
}

UNetOptions UNetOptions::FromJson(const nlohmann::json& json) {
  UNetOptions o;
  o.base_width = json.at("base_width").get<int>();
  o.in_channels = json.at("in_channels").get<int>();
  o.num_classes = json.at("num_classes").get<int>();
  o.blocks = json.at("blocks").get<int>();
  o.batch_norm = json.at("batch_norm").get<bool>();
  o.Check();
  return o;
}

UNetImpl::UNetImpl(const UNetOptions& options) : options_(options) {
  options_.Check();
  // VGG-16 contracting path: convolutions per block and channel multipliers.
  const int convs[5] = {2, 2, 3, 3, 3};
  const int mult[5] = {1, 2, 4, 8, 8};
  std::vector<int> channels;
  int in = options_.in_channels;
  for (int b = 0; b < options_.blocks; ++b) {
    const int out = options_.base_width * mult[b];
    tnn::Sequential block;
    for (int c = 0; c < convs[b]; ++c) {
      block->extend(*ConvBnRelu(c == 0 ? in : out, out, 3, 1, options_.batch_norm));
    }
    encoder_.push_back(register_module("enc" + std::to_string(b), block));
    channels.push_back(out);
    in = out;
  }
  // Expanding path: up-convolution, concatenation with the skip, two convolutions.
  for (int b = options_.blocks - 2; b >= 0; --b) {
    const int skip = channels[b];
    auto up = tnn::ConvTranspose2d(tnn::ConvTranspose2dOptions(in, skip, 2).stride(2));
    up_.push_back(register_module("up" + std::to_string(b), up));
    tnn::Sequential block;
    block->extend(*ConvBnRelu(2 * skip, skip, 3, 1, options_.batch_norm));
    block->extend(*ConvBnRelu(skip, skip, 3, 1, options_.batch_norm));
    decoder_.push_back(register_module("dec" + std::to_string(b), block));
    in = skip;
  }
  classifier_ = register_module("classifier", tnn::Conv2d(tnn::Conv2dOptions(in, options_.num_classes, 1)));
}

torch::Tensor UNetImpl::forward(torch::Tensor x) {
  std::vector<torch::Tensor> skips;
  for (size_t b = 0; b < encoder_.size(); ++b) {
    if (b > 0) x = torch::max_pool2d(x, 2);
    x = encoder_[b]->forward(x);
    skips.push_back(x);
  }
  for (size_t i = 0; i < up_.size(); ++i) {
    const torch::Tensor& skip = skips[skips.size() - 2 - i];
    x = up_[i]->forward(x);
    x = decoder_[i]->forward(torch::cat({x, skip}, 1));
  }
  return classifier_(x);
}

int64_t CountParameters(const torch::nn::Module& module) {
  int64_t n = 0;
  for (const auto& p : module.parameters()) n += p.numel();
  return n;
}

}  // namespace orchard::nn
