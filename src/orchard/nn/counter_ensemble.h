// Counter model files holding several networks whose averaged probabilities
// count: single counters vary a lot with the epoch and seed they were picked
// at (the validation accuracy swings), and averaging them cancels much of it.
// Includes LibTorch (nn/ and the counter's .cc only).
#pragma once

#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "orchard/nn/models.h"

namespace orchard::nn {

namespace fs = std::filesystem;

struct CounterMember {
  ResNetOptions architecture;
  int input_size = 64;
};

// The networks of a counter file: the header's "members", or the one network
// of a file written by `orchard train counter`.
std::vector<CounterMember> CounterMembers(const nlohmann::json& header);

// The class balance power the networks of a counter file were trained with
// (`orchard train counter --balance-power`; 1, every count equally likely,
// for files that do not say). The members of an ensemble share it.
double CounterBalancePower(const nlohmann::json& header);

// The networks of an ensemble file. The first one's modules sit at the top,
// named as in a single counter file, so a program that reads single counters
// only still loads the file (as its first network); the others are member1,
// member2, ...
class CounterEnsembleImpl : public torch::nn::Module {
 public:
  explicit CounterEnsembleImpl(const std::vector<CounterMember>& members);
  std::vector<ResNet> nets;
};
TORCH_MODULE(CounterEnsemble);

// Writes single-network counter files `models` as one ensemble file; its
// class counts (for the counter's prior) are the members' sums. Members
// trained with different class balance powers are refused: their averaged
// probabilities would assume no one prior.
void WriteCounterEnsemble(const std::vector<fs::path>& models, const fs::path& out);

}  // namespace orchard::nn
