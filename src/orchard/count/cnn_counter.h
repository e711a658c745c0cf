// The CNN cluster counter: a ResNet trained by `orchard train counter` reads a
// blob's patch and says how many apples (0..6) it holds. LibTorch stays in the
// .cc file.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "orchard/count/counter.h"

namespace orchard {

struct CnnCounterOptions {
  // Average the softmax over the patch and its horizontal mirror before the
  // argmax: a cluster's count does not change when mirrored, and on the
  // held-out photos the average is 0.5-3 points more accurate than one pass
  // for three of four trained counters (models/counter.md). Doubles inference.
  bool flip_average = true;
  // The prior the decision assumes: the training class frequencies (the
  // model header's train_class_counts) to this power. 0: every count equally
  // likely, as a network trained with full class balance (the study's
  // up-sampling) assumes; 1: the training photos' own prior, where single
  // apples dominate (Bayes' rule). A network trained with balance power b
  // learnt frequencies^(1 - b), so its probabilities are weighed by
  // frequencies^(prior_weight - (1 - b)). 1 gets more patches right, but
  // clusters are counted lower and totals fall short; 0 keeps the totals
  // (measured in models/counter.md), and is the pipeline's default too
  // (`--counter-prior-weight`).
  double prior_weight = 0;

  void Check() const;
};

class CnnCounter : public Counter {
 public:
  // Loads a counter model: one network, or an ensemble written by `orchard
  // train counter-ensemble`, whose networks' probabilities are averaged.
  // Throws orchard::Error when the file is missing, is not a counter model,
  // or does not match its architecture.
  explicit CnnCounter(const std::filesystem::path& model_path, int threads = 0, const CnnCounterOptions& options = {});
  ~CnnCounter() override;

  // The fruit mask is not used: the network reads the whole patch. Fruits are
  // not located (BlobCount::fruits stays empty).
  BlobCount Count(const cv::Mat& bgr_patch, const cv::Mat1b& fruit_mask) override;
  // Trained on cluster patches cut with a margin (data/count_patches.h).
  bool ReadsPatchMargin() const override { return true; }
  std::vector<BlobCount> CountMany(const std::vector<cv::Mat>& bgr_patches,
                                   const std::vector<cv::Mat1b>& fruit_masks) override;

  // Counts many patches at once (faster than one by one).
  std::vector<int> CountBatch(const std::vector<cv::Mat>& bgr_patches);
  // The probabilities of the counts 0..6 per patch (flip-averaged when the options say so).
  std::vector<std::vector<float>> CountProbabilities(const std::vector<cv::Mat>& bgr_patches);

  // Input side of the (first) network.
  int input_size() const;
  // Networks whose probabilities are averaged (1 unless the file is an ensemble).
  int num_networks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace orchard
