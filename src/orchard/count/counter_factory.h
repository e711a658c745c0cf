// Builds a counter from its method name (`--counter cnn|gmm`).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "orchard/count/cnn_counter.h"
#include "orchard/count/counter.h"
#include "orchard/count/gmm_counter.h"

namespace orchard {

struct CounterChoice {
  std::string method = "cnn";  // "cnn" (ResNet classifier) or "gmm" (mixture fit with model selection)
  // cnn: the counter model (empty = the shipped models/counter.pt). gmm: an
  // optional colour model json that finds fruit pixels in patches given
  // without a mask.
  std::filesystem::path model;
  CnnCounterOptions cnn;
  GmmCounterOptions gmm;
  int threads = 0;  // 0 = all cores

  void Check() const;
};

std::filesystem::path DefaultCounterModel();

// Throws orchard::Error for an unknown method or a model that cannot be loaded.
std::unique_ptr<Counter> MakeCounter(const CounterChoice& choice);

}  // namespace orchard
