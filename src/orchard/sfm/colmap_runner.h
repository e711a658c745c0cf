// Camera poses from the COLMAP program (CPU only): feature extraction,
// sequential matching, incremental mapping and conversion to the text format.
// When COLMAP splits the sequence into several models the largest is kept and
// the frames it left out are reported; too few registered frames is an error
// that says why.
#pragma once

#include <filesystem>
#include <functional>
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
  // Sequential matching: each frame against this many following frames,
  // and with quadratic_overlap also against the frames 2^k ahead (k <
  // overlap), COLMAP's default, which bridges a run of blurred frames.
  int overlap = 5;
  bool quadratic_overlap = true;
  // Matching for points of given poses (TriangulateColmapPoints): the poses
  // are held, so no long baselines are needed against drift; 3 following
  // frames, no quadratic pairs: on seed 503's front 41 -> 18 s a side of 41
  // frames (matching 31 -> 10 s), 5,168 -> 5,012 points, the ground fitted
  // as well (docs/side.md, forty-second session).
  int triangulation_overlap = 3;
  // The mapper's random seed (COLMAP's --random_seed). Which model the
  // mapper builds depends on it: on seed 268's back the same matches gave a
  // model folded on itself (29 of 41 frames) with seed 0 and all 41 frames at
  // 0.9 cm pose error with seeds 1 and 2.
  int random_seed = 0;
  // Mapper runs in all (seeds random_seed, random_seed + 1, ...) while the
  // model looks broken (orchard side decides: the reconstruction check's
  // warnings) or leaves more than `retry_unregistered_fraction` of the frames
  // out; the best is kept. Only the mapper runs again, on the same matches:
  // seconds against the minutes of matching on a short row, but minutes on a
  // long video, hence no retry for the odd blurred frame that no seed registers.
  int mapper_attempts = 3;
  double retry_unregistered_fraction = 0.05;
  // Fewest registered frames for the reconstruction to be usable.
  int min_registered = 5;
  // Threads of COLMAP's extraction, matching and mapping; 0 = the cores this
  // process may use (AvailableCores), where COLMAP's own default takes every
  // CPU of the machine. `--threads` of orchard side|yield sets it.
  int num_threads = 0;
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
// in `workspace` (colmap.log holds COLMAP's output): MatchColmapFeatures,
// then MapColmap. Throws orchard::Error when colmap is missing or fails,
// when no model is produced, or when fewer than min_registered frames are
// registered.
ColmapRunResult RunColmap(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options);

// Feature extraction and sequential matching into a fresh `workspace`: all
// images of `image_dir`, or only those named in `only` (when not empty).
// With `known_camera` COLMAP takes its model and parameters instead of
// guessing them from the image size.
void MatchColmapFeatures(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options,
                         const std::vector<std::string>& only = {}, const ColmapCamera* known_camera = nullptr);

// The mapper alone, on the matches MatchColmapFeatures left in `workspace`
// (its earlier models are replaced), with options.random_seed.
ColmapRunResult MapColmap(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options);

// Sparse points for poses COLMAP did not solve (GNSS/IMU, another SLAM, the
// generator's true poses), which carry none: features of the posed frames as
// for the mapper, matched with the next triangulation_overlap frames only (no
// quadratic pairs), then COLMAP's point_triangulator with the
// poses and the camera held. Returns `posed` (its ids, poses and camera) with
// the triangulated points3D and each frame's keypoints as points2D. `posed`
// must have one camera. Throws orchard::Error when colmap is missing or fails
// or when fewer than min_registered frames are posed.
ColmapModel TriangulateColmapPoints(const fs::path& image_dir, const ColmapModel& posed, const fs::path& workspace,
                                    const ColmapRunnerOptions& options);

// Runs `attempt(k)` for k = 0, 1, ... until one reports no problems or
// `max_attempts` have run, and returns the best k: the fewest problems,
// the earliest on ties. `attempt` returns its number of problems or throws
// orchard::Error; an attempt that throws is never the best, and when every
// attempt throws the first one's error is thrown again. For the mapper: a
// model that looks broken is often a matter of the seed.
int BestAttempt(const std::function<int(int)>& attempt, int max_attempts);

// True when the colmap executable can be run.
bool ColmapAvailable(const std::string& colmap = "colmap");

}  // namespace orchard
