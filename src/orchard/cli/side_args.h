// Options shared by `orchard side` and `orchard yield`: the one-side
// pipeline's settings, and the detector and counter that feed it.
#pragma once

#include <memory>
#include <string>

#include "orchard/count/counter.h"
#include "orchard/detect/detector.h"
#include "orchard/fruitmap/side.h"

namespace CLI {
class App;
}

namespace orchard {

struct FruitArgs {
  std::string detector = "gmm", counter = "cnn", model, counter_model;
  int threads = 0;
};

// The detector and counter objects a SideInputs points to.
struct FruitTools {
  std::unique_ptr<Detector> detector;
  std::unique_ptr<Counter> counter;
};

void AddSideOptions(CLI::App* cmd, SideOptions* options);
void AddFruitOptions(CLI::App* cmd, FruitArgs* args);

// Makes the detector and counter (one pair may serve several sides) and
// names them in `in`; `masks` is the instance-mask folder for --detector masks.
void SetUpFruit(const FruitArgs& args, const std::string& masks, FruitTools* tools, SideInputs* in);

}  // namespace orchard
