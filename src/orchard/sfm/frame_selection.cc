#include "orchard/sfm/frame_selection.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <spdlog/spdlog.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/frame_source.h"

namespace orchard {
namespace {

cv::Mat Grey(const cv::Mat& image) {
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  return grey;
}

}  // namespace

void FrameSelectionOptions::Check() const {
  ORCHARD_CHECK_OPTION(method == "step" || method == "motion", "frame selection must be step or motion, got '",
                       method, "'");
  ORCHARD_CHECK_OPTION(step >= 1, "frame step must be at least 1, got ", step);
  ORCHARD_CHECK_OPTION(motion_fraction > 0 && motion_fraction < 1, "motion fraction must be in (0, 1), got ",
                       motion_fraction);
  ORCHARD_CHECK_OPTION(max_frames >= 0, "max frames must be >= 0, got ", max_frames);
}

double MedianFlowDisplacement(const cv::Mat& a, const cv::Mat& b) {
  const cv::Mat ga = Grey(a), gb = Grey(b);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(ga, corners, 400, 0.01, std::max(4, ga.cols / 60));
  if (corners.empty()) return -1;
  std::vector<cv::Point2f> tracked;
  std::vector<unsigned char> status;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(ga, gb, corners, tracked, status, err, cv::Size(21, 21), 4);
  std::vector<double> d;
  for (size_t i = 0; i < corners.size(); ++i)
    if (status[i]) d.push_back(cv::norm(tracked[i] - corners[i]));
  if (d.empty()) return -1;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

std::vector<std::string> SelectFrames(const fs::path& input, const FrameSelectionOptions& options,
                                      const fs::path& out_dir) {
  options.Check();
  FrameSourceOptions source_options;
  if (options.method == "step") source_options.step = options.step;
  FrameSource source(input, source_options);
  // Frames named without leading zeros (frame_9, frame_10) are read in their
  // natural order, but COLMAP's sequential matcher takes them in plain string
  // order: write them with padded numbers so that both orders agree.
  bool pad = false;
  if (fs::is_directory(input)) {
    std::vector<std::string> listed;
    for (const auto& p : ListImages(input)) listed.push_back(p.filename().string());
    pad = !std::is_sorted(listed.begin(), listed.end());
    if (pad) spdlog::info("frames of {} are numbered without leading zeros: written with padded numbers", input.string());
  }
  std::vector<std::string> names;
  Frame frame;
  cv::Mat last_kept;
  while (source.Next(&frame)) {
    if (options.max_frames > 0 && static_cast<int>(names.size()) >= options.max_frames) break;
    bool keep = true;
    if (options.method == "motion" && !last_kept.empty()) {
      // Track on a copy at most 640 px wide: motion is a fraction of the width.
      const double s = std::min(1.0, 640.0 / frame.image.cols);
      cv::Mat small;
      cv::resize(frame.image, small, cv::Size(), s, s, cv::INTER_AREA);
      const double d = MedianFlowDisplacement(last_kept, small);
      keep = d < 0 || d >= options.motion_fraction * small.cols;
    }
    if (!keep) continue;
    if (options.method == "motion") {
      const double s = std::min(1.0, 640.0 / frame.image.cols);
      cv::resize(frame.image, last_kept, cv::Size(), s, s, cv::INTER_AREA);
    }
    const std::string stem = fs::path(frame.name).stem().string();
    const std::string name = (pad ? PadDigitRuns(stem) : stem) + ".png";
    const fs::path path = out_dir / name;
    if (!fs::exists(path)) WriteImageAtomic(path, frame.image);
    names.push_back(name);
  }
  if (names.size() < 2)
    Fail("only ", names.size(), " frame(s) selected from ", input.string(),
         ": need a sequence (too few frames, or too little motion)");
  return names;
}

}  // namespace orchard
