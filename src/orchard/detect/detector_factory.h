// Builds a detector from its method name, so commands and the pipeline can
// switch detectors with one option (`--detector gmm|unet|retinanet`).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "orchard/detect/detector.h"
#include "orchard/detect/gmm/colour_model.h"

namespace orchard {

struct DetectorChoice {
  // "gmm" (colour mixtures), "unet" (segmentation network) or "retinanet" (box detector)
  std::string method = "gmm";
  // Model file; empty = the shipped default (models/gmm_red.json, models/unet.pt, models/retinanet.pt).
  std::filesystem::path model;
  bool reference_slic = false;  // gmm: OpenCV's SLIC at full resolution (slow reference path)
  bool gmm_refine_edges = true;  // gmm: GmmDetectorOptions::refine_edges (fast path)
  double gmm_min_apple_posterior = kDefaultMinApplePosterior;  // gmm: GmmDetectorOptions::min_apple_posterior
  BlobOptions blobs;
  int threads = 0;  // 0 = all cores
  double unet_threshold = 0.5;
  bool unet_whole_frame = false;  // unet: one pass over the whole frame instead of tiles
  double retinanet_threshold = 0.5;  // retinanet: boxes scoring below this are dropped
  double retinanet_scale = 1;        // retinanet: frames resized by this before the network

  void Check() const;
};

// The model file a method uses by default, inside DefaultModelsDir().
std::filesystem::path DefaultDetectorModel(const std::string& method);

// Throws orchard::Error for an unknown method or a model that cannot be loaded.
std::unique_ptr<Detector> MakeDetector(const DetectorChoice& choice);

// Detectors for DetectFrames (parallel_detection.h): the colour detector as one
// single-threaded detector per thread, so frames run in parallel; the U-Net,
// whose network already uses every thread, as one detector.
std::vector<std::unique_ptr<Detector>> MakeFrameDetectors(const DetectorChoice& choice);

}  // namespace orchard
