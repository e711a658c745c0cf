// Which frames of a video or image folder go into the reconstruction: every
// n-th frame, or by image motion (a frame is kept once the median optical-flow
// displacement since the last kept frame reaches a target, so neighbouring
// frames overlap enough for matching without wasting time on near-duplicates).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace orchard {

namespace fs = std::filesystem;

struct FrameSelectionOptions {
  // "step" (every `step`-th frame) or "motion".
  std::string method = "step";
  int step = 1;
  // motion: keep a frame when the median displacement of tracked corners since
  // the last kept frame reaches this fraction of the image width. 3%: the
  // synthetic rows' frames move 3.0-3.6% (8 frames per second), the spacing
  // the 3D stage is tuned to (ReconstructionCheckOptions::frame_spacing_reference;
  // 5% before the twenty-first session kept frames too sparse, counting low).
  double motion_fraction = 0.03;
  // Stop after this many kept frames (0 = no limit).
  int max_frames = 0;
  void Check() const;
};

// Median displacement (pixels) of corners tracked by pyramidal Lucas-Kanade
// from `a` to `b` (8-bit BGR or grey, same size); -1 when nothing could be
// tracked (a blank image).
double MedianFlowDisplacement(const cv::Mat& a, const cv::Mat& b);

// Reads `input` (folder or video), keeps frames by `options` and writes them
// as PNG into `out_dir` (existing files of the same name are kept, so a rerun
// resumes). Returns the kept names in order. Throws orchard::Error when fewer
// than two frames are kept.
std::vector<std::string> SelectFrames(const fs::path& input, const FrameSelectionOptions& options,
                                      const fs::path& out_dir);

}  // namespace orchard
