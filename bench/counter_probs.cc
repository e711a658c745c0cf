// Softmax outputs of a counter on patch folders, for the patch as given and
// for its test-time variants (horizontal flip, rotations of +-5 degrees), one
// CSV row per patch and variant. Decision rules (argmax, flip averaging,
// expected count) are compared on these outputs without rerunning the network.
// A counter with a density head also gives its map's sum (column `density`).
//   counter_probs COUNTER.pt OUT.csv PATCH_DIR...
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <torch/torch.h>

#include "orchard/nn/checkpoint.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

namespace {

cv::Mat Rotate(const cv::Mat& image, double degrees) {
  const cv::Mat rotation = cv::getRotationMatrix2D(cv::Point2f(image.cols / 2.0f, image.rows / 2.0f), degrees, 1.0);
  cv::Mat out;
  cv::warpAffine(image, out, rotation, image.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 4) {
      std::fprintf(stderr, "usage: counter_probs COUNTER.pt OUT.csv PATCH_DIR...\n");
      return 2;
    }
    at::set_num_threads(1);
    const nlohmann::json header = orchard::nn::ReadCheckpointHeader(argv[1], "counter");
    // An ensemble file would load as its first network only.
    if (header.contains("members")) throw std::runtime_error("give a single counter, not an ensemble");
    const int input_size = header.at("input_size").get<int>();
    orchard::nn::ResNet net(orchard::nn::ResNetOptions::FromJson(header.at("architecture")));
    orchard::nn::LoadCheckpointWeights(*net, argv[1]);
    net->eval();
    torch::NoGradGuard no_grad;
    std::ofstream out(argv[2]);
    const bool density = net->options().density_head;
    out << "set,index,count,variant,p0,p1,p2,p3,p4,p5,p6,density\n";
    const char* variants[] = {"plain", "hflip", "rot+5", "rot-5", "vflip"};
    for (int a = 3; a < argc; ++a) {
      const std::vector<orchard::nn::LabelledPatch> patches = orchard::nn::ReadPatchFolder(argv[a]);
      for (int v = 0; v < 5; ++v) {
        std::vector<cv::Mat> inputs;
        for (const auto& p : patches) {
          cv::Mat input = orchard::nn::LetterboxPatch(p.bgr, input_size);
          if (v == 1) cv::flip(input, input, 1);
          if (v == 2) input = Rotate(input, 5);
          if (v == 3) input = Rotate(input, -5);
          if (v == 4) cv::flip(input, input, 0);
          inputs.push_back(input);
        }
        for (size_t begin = 0; begin < inputs.size(); begin += 64) {
          const size_t end = std::min(inputs.size(), begin + 64);
          const torch::Tensor batch = orchard::nn::ImagesToTensor({inputs.begin() + begin, inputs.begin() + end});
          torch::Tensor logits, sums;
          if (density) {
            auto [l, map] = net->ForwardWithDensity(batch);
            logits = l;
            sums = map.sum({1, 2, 3});
          } else {
            logits = net->forward(batch);
          }
          const torch::Tensor probs = torch::softmax(logits, 1);
          for (size_t i = begin; i < end; ++i) {
            out << argv[a] << ',' << i << ',' << patches[i].count << ',' << variants[v];
            for (int k = 0; k < 7; ++k) out << ',' << probs[i - begin][k].item<float>();
            out << ',';
            if (density) out << sums[i - begin].item<float>();
            out << '\n';
          }
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "counter_probs: %s\n", e.what());
    return 1;
  }
  return 0;
}
