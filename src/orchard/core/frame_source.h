// Frames from a folder of images (sorted by name) or a video file
// (cv::VideoCapture), with a frame step. Frames read from a video are named
// `<video stem>_<frame index, 6 digits>.png` so that per-frame results and
// saved frames line up.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace orchard {

namespace fs = std::filesystem;

struct FrameSourceOptions {
  // Keep every step-th frame (1 = all).
  int step = 1;
  // Stop after this many kept frames (0 = no limit).
  int max_frames = 0;
  void Check() const;
};

struct Frame {
  std::string name;  // image file name, or <video stem>_<index>.png
  int index = 0;     // position in the folder listing / video
  cv::Mat image;     // 8-bit BGR
};

class FrameSource {
 public:
  // `path`: a folder of images or a video file. Throws orchard::Error when the
  // path is missing, the folder holds no images, or the video cannot be opened.
  explicit FrameSource(const fs::path& path, const FrameSourceOptions& options = {});
  // The next kept frame; false at the end. Throws when an image in the folder
  // cannot be decoded.
  bool Next(Frame* frame);
  bool IsVideo() const { return is_video_; }
  const fs::path& Path() const { return path_; }

 private:
  fs::path path_;
  FrameSourceOptions options_;
  bool is_video_ = false;
  std::vector<fs::path> images_;
  cv::VideoCapture video_;
  int next_index_ = 0;
  int kept_ = 0;
};

// "<video stem>_<index, 6 digits>.png", e.g. VideoFrameName("row3.mp4", 42) = "row3_000042.png".
std::string VideoFrameName(const fs::path& video, int index);

}  // namespace orchard
