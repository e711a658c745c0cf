#include "orchard/detect/detector_factory.h"

#include <thread>

#include "orchard/core/error.h"
#include "orchard/core/models_dir.h"
#include "orchard/detect/gmm/gmm_detector.h"
#include "orchard/detect/unet_detector.h"

namespace orchard {

void DetectorChoice::Check() const {
  ORCHARD_CHECK_OPTION(method == "gmm" || method == "unet", "unknown detector '", method, "' (available: gmm, unet)");
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0, got ", threads);
  blobs.Check();
}

std::filesystem::path DefaultDetectorModel(const std::string& method) {
  if (method == "gmm") return DefaultModelsDir() / "gmm_red.json";
  if (method == "unet") return DefaultModelsDir() / "unet.pt";
  Fail("unknown detector '", method, "' (available: gmm, unet)");
}

std::unique_ptr<Detector> MakeDetector(const DetectorChoice& choice) {
  choice.Check();
  const std::filesystem::path model = choice.model.empty() ? DefaultDetectorModel(choice.method) : choice.model;
  const int threads = choice.threads > 0 ? choice.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (choice.method == "gmm") {
    GmmDetectorOptions options;
    options.reference_slic = choice.reference_slic;
    options.min_apple_posterior = choice.gmm_min_apple_posterior;
    options.refine_edges = choice.gmm_refine_edges;
    options.blobs = choice.blobs;
    options.num_threads = threads;
    return std::make_unique<GmmDetector>(ReadColourModel(model), options);
  }
  UNetDetectorOptions options;
  options.blobs = choice.blobs;
  options.threads = threads;
  options.threshold = choice.unet_threshold;
  options.whole_frame = choice.unet_whole_frame;
  return std::make_unique<UNetDetector>(model, options);
}

}  // namespace orchard
