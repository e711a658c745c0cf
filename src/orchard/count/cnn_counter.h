// The CNN cluster counter: a ResNet trained by `orchard train counter` reads a
// blob's patch and says how many apples (0..6) it holds. LibTorch stays in the
// .cc file.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "orchard/count/counter.h"

namespace orchard {

class CnnCounter : public Counter {
 public:
  // Loads a counter model; throws orchard::Error when the file is missing, is
  // not a counter model, or does not match its architecture.
  explicit CnnCounter(const std::filesystem::path& model_path, int threads = 0);
  ~CnnCounter() override;

  // The fruit mask is not used: the network reads the whole patch. Fruits are
  // not located (BlobCount::fruits stays empty).
  BlobCount Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) override;

  // Counts many patches at once (faster than one by one).
  std::vector<int> CountBatch(const std::vector<cv::Mat>& bgr_patches);

  int input_size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace orchard
