// Does the counter's accuracy depend on its BatchNorm running statistics?
// Loads a counter, scores patch sets, recomputes the BatchNorm statistics as
// exact averages over the (unbalanced, unaugmented) training patches, and
// scores again. A diagnostic for the validation swings seen in training
// (models/counter.md).
//   counter_bn_check COUNTER.pt TRAIN_PATCH_DIR[,DIR2...] TEST_PATCH_DIR...
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <torch/torch.h>

#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

namespace {

struct PatchSet {
  std::vector<cv::Mat> inputs;
  std::vector<int> counts;
};

PatchSet ReadPatches(const std::string& dir, int input_size) {
  PatchSet set;
  for (const auto& patch : orchard::nn::ReadPatchFolder(dir)) {
    set.inputs.push_back(orchard::nn::LetterboxPatch(patch.bgr, input_size));
    set.counts.push_back(patch.count);
  }
  return set;
}

double Accuracy(orchard::nn::ResNet& net, const PatchSet& set) {
  torch::NoGradGuard no_grad;
  net->eval();
  int correct = 0;
  for (size_t begin = 0; begin < set.inputs.size(); begin += 64) {
    const size_t end = std::min(set.inputs.size(), begin + 64);
    const std::vector<cv::Mat> batch(set.inputs.begin() + begin, set.inputs.begin() + end);
    const torch::Tensor predicted = net->forward(orchard::nn::ImagesToTensor(batch)).argmax(1);
    for (size_t i = begin; i < end; ++i) correct += predicted[i - begin].item<int64_t>() == set.counts[i];
  }
  return set.inputs.empty() ? 0 : static_cast<double>(correct) / set.inputs.size();
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 4) {
      std::fprintf(stderr, "usage: counter_bn_check COUNTER.pt TRAIN_PATCH_DIR[,DIR2...] TEST_PATCH_DIR...\n");
      return 2;
    }
    const nlohmann::json header = orchard::nn::ReadCheckpointHeader(argv[1], "counter");
    const int input_size = header.at("input_size").get<int>();
    orchard::nn::ResNet net(orchard::nn::ResNetOptions::FromJson(header.at("architecture")));
    orchard::nn::LoadCheckpointWeights(*net, argv[1]);
    PatchSet train;
    std::stringstream dirs(argv[2]);
    std::string dir;
    while (std::getline(dirs, dir, ',')) {
      PatchSet part = ReadPatches(dir, input_size);
      train.inputs.insert(train.inputs.end(), part.inputs.begin(), part.inputs.end());
      train.counts.insert(train.counts.end(), part.counts.begin(), part.counts.end());
    }
    std::vector<PatchSet> tests;
    for (int i = 3; i < argc; ++i) tests.push_back(ReadPatches(argv[i], input_size));
    auto report = [&](const char* what) {
      std::printf("%-36s train %.3f", what, Accuracy(net, train));
      for (int i = 3; i < argc; ++i) std::printf("  %s %.3f (%zu)", argv[i], Accuracy(net, tests[i - 3]), tests[i - 3].inputs.size());
      std::printf("\n");
    };
    report("as saved (running statistics)");
    // Exact averages: momentum unset makes BatchNorm keep a cumulative mean.
    for (auto& module : net->modules(/*include_self=*/false))
      if (auto* bn = module->as<torch::nn::BatchNorm2dImpl>()) {
        bn->reset_running_stats();
        bn->options.momentum(c10::nullopt);
      }
    {
      torch::NoGradGuard no_grad;
      net->train();
      for (size_t begin = 0; begin < train.inputs.size(); begin += 64) {
        const size_t end = std::min(train.inputs.size(), begin + 64);
        net->forward(orchard::nn::ImagesToTensor(std::vector<cv::Mat>(train.inputs.begin() + begin, train.inputs.begin() + end)));
      }
    }
    report("BatchNorm statistics recomputed");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "counter_bn_check: %s\n", e.what());
    return 1;
  }
  return 0;
}
