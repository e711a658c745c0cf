// Options shared by `orchard side` and `orchard yield`: the one-side
// pipeline's settings, and the detector and counter that feed it.
#pragma once

#include <memory>
#include <string>

#include "orchard/count/cnn_counter.h"
#include "orchard/count/counter.h"
#include "orchard/detect/detector.h"
#include "orchard/detect/detector_factory.h"
#include "orchard/fruitmap/side.h"

namespace CLI {
class App;
}

namespace orchard {

struct FruitArgs {
  // The U-Net finds green apples too, which the shipped red colour model
  // does not (demo row: 127 of 136 visible apples against 75; eight rows:
  // docs/yield.md); `--detector gmm` is the fast colour detector.
  // counter "auto": one apple per blob for instance masks, else the CNN
  // counter (the study's default; a U-Net blob of touching apples counted
  // as one read seed 246's front 136 of 219 visible apples, the CNN 196).
  std::string detector = "unet", counter = "auto", model, counter_model;
  int threads = 0;
  // Detector blobs smaller than this are dropped. Lower than a photo
  // detector's 100 px: the 3D stage lives on the small pieces of partly
  // hidden apples (20 px is the generator's "visible"), and its multi-view
  // support removes specks (seed 11, U-Net, COLMAP: 163 apples of 237
  // visible with 100 px, 206 with 30, 226 with 15; docs/yield.md).
  int min_blob_pixels = 20;
  double unet_threshold = DetectorChoice().unet_threshold;  // apple probability of a U-Net pixel
  double retinanet_threshold = DetectorChoice().retinanet_threshold;  // score of a RetinaNet box
  double retinanet_scale = DetectorChoice().retinanet_scale;  // frames resized by this for the RetinaNet
  // The colour detector's posterior gate is off here (the KL rule alone):
  // the gate that lifts photo precision (docs/detection.md) costs the 3D
  // stage the pieces of apples the red model half-recognises (demo row:
  // 71 apples of 136 visible without it, 59 with 0.05, 48 with 0.2), and the
  // multi-view support check removes specks instead.
  double gmm_min_apple_posterior = 0;
  // cnn: the prior the counter's decision assumes (CnnCounterOptions).
  double counter_prior_weight = CnnCounterOptions().prior_weight;
};

// The detector and counter objects a SideInputs points to.
struct FruitTools {
  std::unique_ptr<Detector> detector;
  std::unique_ptr<Counter> counter;
};

void AddSideOptions(CLI::App* cmd, SideOptions* options);
void AddFruitOptions(CLI::App* cmd, FruitArgs* args);

// The counter `args` asks for, "auto" resolved.
std::string CounterName(const FruitArgs& args);

// Makes the detector and counter (one pair may serve several sides) and
// names them in `in`; `masks` is the instance-mask folder for --detector masks.
void SetUpFruit(FruitArgs args, const std::string& masks, FruitTools* tools, SideInputs* in);

}  // namespace orchard
