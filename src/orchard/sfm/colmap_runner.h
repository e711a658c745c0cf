// Camera poses from the COLMAP program (CPU only): feature extraction,
// sequential matching, incremental mapping and conversion to the text format.
// When COLMAP splits the sequence into several models the largest is kept and
// the frames it left out are reported; too few registered frames is an error
// that says why.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "orchard/sfm/colmap_model.h"

namespace orchard {

namespace fs = std::filesystem;

struct ColmapRunnerOptions {
  // The `colmap` executable (looked up in PATH when not absolute).
  std::string colmap = "colmap";
  // One camera for the whole sequence; PINHOLE for undistorted frames,
  // SIMPLE_RADIAL for real lenses.
  std::string camera_model = "SIMPLE_RADIAL";
  // SIFT: 2048 features from the full-resolution octave reconstructs
  // 960x540 frames in ~30 s on 2 cores with sub-millimetre pose error
  // (docs/synth.md); more features cost time without gain.
  int max_num_features = 2048;
  int first_octave = 0;
  // Sequential matching: each frame against this many following frames.
  int overlap = 5;
  // Fewest registered frames for the reconstruction to be usable.
  int min_registered = 5;
  void Check() const;
};

struct ColmapRunResult {
  ColmapModel model;               // the largest model
  fs::path model_dir;              // its text files
  int num_input_images = 0;
  int num_models = 0;              // models COLMAP produced
  std::vector<std::string> unregistered;  // input images not in the model, sorted
};

// Runs COLMAP on the images in `image_dir` with its database, logs and models
// in `workspace` (colmap.log holds COLMAP's output). Throws orchard::Error
// when colmap is missing or fails, when no model is produced, or when fewer
// than min_registered frames are registered.
ColmapRunResult RunColmap(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options);

// True when the colmap executable can be run.
bool ColmapAvailable(const std::string& colmap = "colmap");

}  // namespace orchard
