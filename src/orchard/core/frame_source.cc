#include "orchard/core/frame_source.h"

#include <cstdio>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

#include <opencv2/imgproc.hpp>

namespace orchard {

void FrameSourceOptions::Check() const {
  ORCHARD_CHECK_OPTION(step >= 1, "frame step must be >= 1, got ", step);
  ORCHARD_CHECK_OPTION(max_frames >= 0, "max_frames must be >= 0, got ", max_frames);
}

FrameSource::FrameSource(const fs::path& path, const FrameSourceOptions& options)
    : path_(path), options_(options) {
  options_.Check();
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("input not found: ", path.string());
  if (fs::is_directory(path, ec)) {
    images_ = ListImages(path);
    if (images_.empty()) Fail("no images (.png .jpg .jpeg .bmp .tif .tiff) in folder ", path.string());
    return;
  }
  is_video_ = true;
  bool opened = false;
  try {
    opened = video_.open(path.string());
  } catch (const cv::Exception&) {
    opened = false;
  }
  if (!opened) Fail("cannot open video ", path.string(), " (not a video, or a codec OpenCV lacks)");
  // Some corrupt files open but yield nothing: detect that now.
  cv::Mat probe;
  if (!video_.read(probe) || probe.empty()) Fail("video ", path.string(), " has no readable frames");
  video_.release();
  video_.open(path.string());
}

bool FrameSource::Next(Frame* frame) {
  if (options_.max_frames > 0 && kept_ >= options_.max_frames) return false;
  if (!is_video_) {
    if (next_index_ >= static_cast<int>(images_.size())) return false;
    const fs::path& p = images_[next_index_];
    frame->index = next_index_;
    frame->name = p.filename().string();
    frame->image = ReadImage(p);
    next_index_ += options_.step;
    ++kept_;
    return true;
  }
  cv::Mat image;
  while (true) {
    if (!video_.read(image) || image.empty()) return false;
    const int index = next_index_++;
    if (index % options_.step != 0) continue;
    frame->index = index;
    frame->name = VideoFrameName(path_, index);
    if (image.channels() == 1) cv::cvtColor(image, frame->image, cv::COLOR_GRAY2BGR);
    else frame->image = image;
    ++kept_;
    return true;
  }
}

std::string VideoFrameName(const fs::path& video, int index) {
  char digits[32];
  std::snprintf(digits, sizeof(digits), "%06d", index);
  return video.stem().string() + "_" + digits + ".png";
}

}  // namespace orchard
