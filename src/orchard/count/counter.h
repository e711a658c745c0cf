// The counting stage's interface: how many apples are in one blob (a cluster
// of fruit pixels found by a detector), and where. Implemented by the GMM
// counter here and by the CNN counter.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace orchard {

struct Fruit {
  cv::Point2d centre;  // in the patch's pixel coordinates
  double radius = 0;   // pixels
};

struct BlobCount {
  int count = 0;
  std::vector<Fruit> fruits;  // one per counted apple (may be empty for counters that only count)
};

class Counter {
 public:
  virtual ~Counter() = default;
  // `bgr_patch`: the blob's image patch (8-bit BGR); `fruit_mask`: its fruit
  // pixels (non-zero), same size, or empty when the counter must find them
  // itself. Throws orchard::Error on an empty patch or mismatched sizes.
  virtual BlobCount Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) = 0;
  // Whether the counter reads a blob with the margin of its training patches
  // around it (ClusterPatchRect) rather than the blob's own box.
  virtual bool ReadsPatchMargin() const { return false; }
  // Many blobs at once (`fruit_masks` empty, or one per patch). The CNN
  // counter runs them as one batch: one network pass per frame instead of
  // one per blob, which matters most when other jobs share the cores.
  virtual std::vector<BlobCount> CountMany(const std::vector<cv::Mat>& bgr_patches,
                                           const std::vector<cv::Mat1b>& fruit_masks);
};

inline std::vector<BlobCount> Counter::CountMany(const std::vector<cv::Mat>& bgr_patches,
                                                const std::vector<cv::Mat1b>& fruit_masks) {
  std::vector<BlobCount> counts;
  for (size_t i = 0; i < bgr_patches.size(); ++i)
    counts.push_back(Count(bgr_patches[i], fruit_masks.empty() ? cv::Mat1b() : fruit_masks.at(i)));
  return counts;
}

}  // namespace orchard
