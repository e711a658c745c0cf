#include "orchard/merge/face_check.h"

#include <algorithm>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

struct FrameFeatures {
  fs::path path;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

std::vector<FrameFeatures> SampleFeatures(const std::vector<fs::path>& paths, const FaceCheckOptions& o,
                                          const std::string& side) {
  if (paths.empty()) Fail("the ", side, " side has no frames to compare with the other side");
  const int n = static_cast<int>(paths.size());
  const int k = std::min(o.frames, n);
  cv::Ptr<cv::ORB> orb = cv::ORB::create(o.features);
  std::vector<FrameFeatures> out;
  for (int i = 0; i < k; ++i) {
    // Evenly spread, ends included.
    const int index = k == 1 ? 0 : static_cast<int>(static_cast<long long>(i) * (n - 1) / (k - 1));
    FrameFeatures f;
    f.path = paths[index];
    cv::Mat gray = ReadImage(f.path, cv::IMREAD_GRAYSCALE);
    if (gray.cols > 960) cv::resize(gray, gray, cv::Size(), 960.0 / gray.cols, 960.0 / gray.cols, cv::INTER_AREA);
    orb->detectAndCompute(gray, cv::noArray(), f.keypoints, f.descriptors);
    out.push_back(std::move(f));
  }
  return out;
}

int ConsistentMatches(const FrameFeatures& a, const FrameFeatures& b, const FaceCheckOptions& o) {
  if (a.descriptors.rows < 2 || b.descriptors.rows < 2) return 0;
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(a.descriptors, b.descriptors, knn, 2);
  std::vector<cv::Point2f> pa, pb;
  for (const auto& m : knn)
    if (m.size() == 2 && m[0].distance < o.ratio * m[1].distance)
      pa.push_back(a.keypoints[m[0].queryIdx].pt), pb.push_back(b.keypoints[m[0].trainIdx].pt);
  if (pa.size() < 8) return static_cast<int>(pa.size());
  cv::Mat inliers;
  const cv::Mat F = cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, 2.0, 0.99, inliers);
  if (F.empty() || inliers.empty()) return 0;
  return cv::countNonZero(inliers);
}

}  // namespace

void FaceCheckOptions::Check() const {
  ORCHARD_CHECK_OPTION(frames >= 1, "face check frames must be at least 1, got ", frames);
  ORCHARD_CHECK_OPTION(features >= 8, "face check features must be at least 8, got ", features);
  ORCHARD_CHECK_OPTION(ratio > 0 && ratio <= 1, "face check ratio must be in (0, 1], got ", ratio);
  ORCHARD_CHECK_OPTION(max_inliers >= 8, "face check max inliers must be at least 8, got ", max_inliers);
}

FaceCheck CheckOppositeFaces(const std::vector<fs::path>& front_frames, const std::vector<fs::path>& back_frames,
                             const FaceCheckOptions& o) {
  o.Check();
  const std::vector<FrameFeatures> front = SampleFeatures(front_frames, o, "front");
  const std::vector<FrameFeatures> back = SampleFeatures(back_frames, o, "back");
  FaceCheck c;
  c.best_inliers = -1;
  for (const auto& f : front)
    for (const auto& b : back) {
      const int inliers = ConsistentMatches(f, b, o);
      if (inliers > c.best_inliers) c.best_inliers = inliers, c.front_frame = f.path, c.back_frame = b.path;
    }
  c.same_face = c.best_inliers > o.max_inliers;
  return c;
}

}  // namespace orchard
