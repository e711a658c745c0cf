#include "orchard/detect/detector_factory.h"

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/models_dir.h"
#include "orchard/detect/gmm/gmm_detector.h"
#include "orchard/detect/retinanet_detector.h"
#include "orchard/detect/unet_detector.h"

namespace orchard {

void DetectorChoice::Check() const {
  ORCHARD_CHECK_OPTION(method == "gmm" || method == "unet" || method == "retinanet", "unknown detector '", method,
                       "' (available: gmm, unet, retinanet)");
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0, got ", threads);
  blobs.Check();
}

std::filesystem::path DefaultDetectorModel(const std::string& method) {
  if (method == "gmm") return DefaultModelsDir() / "gmm_red.json";
  if (method == "unet") return DefaultModelsDir() / "unet.pt";
  if (method == "retinanet") return DefaultModelsDir() / "retinanet.pt";
  Fail("unknown detector '", method, "' (available: gmm, unet, retinanet)");
}

namespace {

std::filesystem::path ModelFile(const DetectorChoice& choice) {
  return choice.model.empty() ? DefaultDetectorModel(choice.method) : choice.model;
}

GmmDetectorOptions GmmOptions(const DetectorChoice& choice, int threads) {
  GmmDetectorOptions options;
  options.reference_slic = choice.reference_slic;
  options.min_apple_posterior = choice.gmm_min_apple_posterior;
  options.refine_edges = choice.gmm_refine_edges;
  options.blobs = choice.blobs;
  options.num_threads = threads;
  return options;
}

}  // namespace

std::unique_ptr<Detector> MakeDetector(const DetectorChoice& choice) {
  choice.Check();
  const std::filesystem::path model = ModelFile(choice);
  const int threads = ThreadsOrAvailableCores(choice.threads);
  if (choice.method == "gmm") return std::make_unique<GmmDetector>(ReadColourModel(model), GmmOptions(choice, threads));
  if (choice.method == "retinanet") {
    RetinaNetDetectorOptions options;
    options.blobs = choice.blobs;
    options.threads = threads;
    options.score_threshold = choice.retinanet_threshold;
    options.input_scale = choice.retinanet_scale;
    return std::make_unique<RetinaNetDetector>(model, options);
  }
  UNetDetectorOptions options;
  options.blobs = choice.blobs;
  options.threads = threads;
  options.threshold = choice.unet_threshold;
  options.whole_frame = choice.unet_whole_frame;
  return std::make_unique<UNetDetector>(model, options);
}

std::vector<std::unique_ptr<Detector>> MakeFrameDetectors(const DetectorChoice& choice) {
  std::vector<std::unique_ptr<Detector>> detectors;
  if (choice.method != "gmm") {
    detectors.push_back(MakeDetector(choice));
    return detectors;
  }
  choice.Check();
  const ColourModel model = ReadColourModel(ModelFile(choice));
  const int frames_at_once = ThreadsOrAvailableCores(choice.threads);  // read once: it looks at /proc and /sys
  for (int i = 0; i < frames_at_once; ++i)
    detectors.push_back(std::make_unique<GmmDetector>(model, GmmOptions(choice, 1)));
  return detectors;
}

}  // namespace orchard
