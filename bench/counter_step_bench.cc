// Where a training step of the CNN counter spends its time: the input
// pipeline (per-patch OpenCV augmentation, then the batch tensor) against the
// network's forward, backward and Adam step, side by side in one process.
// The shipped recipe's network (ResNet-18, width 16, input 96, density head),
// batch 32, on synthetic 96x96 patches (the cost does not depend on content).
//
//   bench_counter_step [steps=20] [batch=32] [input=96] [width=16] [density=1]
#include <cstdio>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <torch/torch.h>

#include "orchard/core/stopwatch.h"
#include "orchard/nn/models.h"
#include "orchard/nn/patch_input.h"

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::stoi(argv[1]) : 20;
  const int batch = argc > 2 ? std::stoi(argv[2]) : 32;
  const int input = argc > 3 ? std::stoi(argv[3]) : 96;
  const int width = argc > 4 ? std::stoi(argv[4]) : 16;
  const bool density = argc > 5 ? std::stoi(argv[5]) != 0 : true;
  if (steps < 1 || batch < 1 || input < 32 || width < 1) {
    std::fprintf(stderr, "usage: bench_counter_step [steps>=1] [batch>=1] [input>=32] [width>=1] [density 0|1]\n");
    return 2;
  }
  at::set_num_threads(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  torch::manual_seed(0);
  std::mt19937_64 rng(0);

  // Patches like the letterboxed training inputs: a coloured disc or two on a
  // dark background, so blur and rotation touch real edges.
  std::vector<cv::Mat> patches;
  for (int i = 0; i < 4 * batch; ++i) {
    cv::Mat p(input, input, CV_8UC3, cv::Scalar(20, 60, 30));
    const int n = 1 + i % 3;
    for (int k = 0; k < n; ++k)
      cv::circle(p, cv::Point(input / 4 + k * input / 4, input / 2), input / 6, cv::Scalar(30, 40, 200), cv::FILLED);
    patches.push_back(p);
  }

  orchard::nn::ResNetOptions options;
  options.depth = 18;
  options.base_width = width;
  options.density_head = density;
  orchard::nn::ResNet net(options);
  net->train();
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(1e-3).betas({0.9, 0.999}));
  const orchard::nn::PatchAugmentation augmentation;

  double prepare_s = 0, network_s = 0;
  for (int step = -2; step < steps; ++step) {  // two warm-up steps, not timed
    orchard::Stopwatch stopwatch;
    std::vector<cv::Mat> images;
    std::vector<int64_t> labels;
    for (int i = 0; i < batch; ++i) {
      const size_t k = rng() % patches.size();
      images.push_back(orchard::nn::AugmentPatch(patches[k], augmentation, rng));
      labels.push_back(static_cast<int64_t>(1 + k % 3));
    }
    const torch::Tensor x = orchard::nn::ImagesToTensor(images), y = torch::tensor(labels, torch::kLong);
    const double prepare = stopwatch.Lap();
    adam.zero_grad();
    torch::Tensor loss;
    if (density) {
      auto [logits, map] = net->ForwardWithDensity(x);
      loss = torch::cross_entropy_loss(logits, y) + torch::smooth_l1_loss(map.sum({1, 2, 3}), y.to(torch::kFloat32));
    } else {
      loss = torch::cross_entropy_loss(net->forward(x), y);
    }
    loss.backward();
    adam.step();
    const double network = stopwatch.Lap();
    if (step >= 0) prepare_s += prepare, network_s += network;
  }
  std::printf("counter training step (ResNet-18 width %d, input %d, %s, batch %d, %d threads, %d steps)\n", width,
              input, density ? "density head" : "no density head", batch, at::get_num_threads(), steps);
  std::printf("  input pipeline (augment + tensor): %.2f ms per step\n", 1000 * prepare_s / steps);
  std::printf("  network (forward, backward, Adam): %.2f ms per step\n", 1000 * network_s / steps);
  std::printf("  input pipeline / whole step: %.3f\n", prepare_s / (prepare_s + network_s));
  return 0;
}
