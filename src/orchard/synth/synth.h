// `orchard synth`: films a procedural apple-tree row from both sides and
// writes frames with complete ground truth (apple list, per-frame instance
// masks, YOLO labels, true camera poses as COLMAP text models, the ground
// plane and row geometry, counting patches, and the counts a grower would
// harvest). The layout is described in docs/synth.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "orchard/synth/renderer.h"
#include "orchard/synth/scene.h"

namespace orchard::synth {

namespace fs = std::filesystem;

struct CameraPathOptions {
  // Distance of the camera path from the row centre line (m) and height (m).
  double distance = 2.5;
  double height = 1.5;
  // Camera pitch (degrees, negative looks down).
  double pitch_deg = -5;
  // Horizontal field of view (degrees) and image size.
  double hfov_deg = 80;
  int width = 960;
  int height_px = 540;
  // Speed along the row (m/s) and frame rate: one frame every speed/fps metres.
  double speed = 1.0;
  double fps = 8;
  // Random shake of a hand-held / vehicle camera: position (m, sd) and
  // orientation (degrees, sd), drawn per frame.
  double jitter_m = 0.01;
  double jitter_deg = 0.5;
  // "both", "front" or "back".
  std::string sides = "both";

  double FrameStep() const { return speed / fps; }
  void Check() const;
};

struct SynthOptions {
  SceneOptions scene;
  CameraPathOptions camera;
  RenderOptions render;
  std::uint64_t seed = 1;
  // An apple counts as seen in a frame when at least this many of its pixels
  // are unoccluded there; smaller fragments are left out of that frame's mask
  // and labels (as an annotator would). Visible from a side = seen in at
  // least one frame of that side.
  int min_visible_pixels = 20;
  // Counting patches are cut from every n-th frame (0 = no patches).
  int patch_every = 4;
  // Margin around each apple group, as a fraction of the group's larger side.
  double patch_margin = 0.25;
  // Background (count 0) patches per patch frame.
  int background_patches = 2;
  // Worker threads (0 = all cores).
  int threads = 0;
  // Progress lines on stderr.
  bool progress = true;

  void Check() const;
};

struct SynthSummary {
  int harvested = 0;
  int visible_front = 0, visible_back = 0, visible_any = 0, visible_both = 0;
  int fallen = 0;
  int frames_per_side = 0;
  int patches = 0;
};

// Generates the row and writes everything into `out_dir` (created if
// missing; existing files of the same names are replaced atomically).
SynthSummary RunSynth(const SynthOptions& options, const fs::path& out_dir);

}  // namespace orchard::synth
