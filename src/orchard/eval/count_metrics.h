// Counting metrics for per-image (or per-cluster) apple counts, as in the
// MinneApple counting benchmark: exact-match accuracy, accuracy per true
// count, mean absolute error and the 7x7 confusion matrix of counts 0..6.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "orchard/data/dataset.h"

namespace orchard {

// Counts 0..5 have their own class; 6 stands for "6 or more" (the study's
// classes are 0..6): a count above 6 falls into the last row / column of the
// confusion matrix. Accuracy and MAE always use the exact counts, so for the
// 6+ class a near miss (true 8, predicted 7) sits on the diagonal of the
// confusion matrix but counts as wrong in the accuracies.
constexpr int kNumCountClasses = 7;

struct CountMetrics {
  int images = 0;
  double accuracy = 0;  // fraction of images with predicted count == true count
  double mae = 0;       // mean |predicted - true|
  // confusion[true class][predicted class], classes 0..5 and 6 = "6+".
  std::array<std::array<int, kNumCountClasses>, kNumCountClasses> confusion{};
  std::array<int, kNumCountClasses> images_per_class{};  // row sums
  // Exact-match accuracy among the images of each true class; NaN when the
  // class has no image.
  std::array<double, kNumCountClasses> accuracy_per_class{};
};

// Matches predictions to ground truth by name: the exact name, else the name
// without extension on both sides. Throws orchard::Error when an image has no
// prediction or two, a prediction names an unknown image, a name repeats in
// the ground truth, a count is negative, or the ground truth is empty.
CountMetrics EvaluateCounts(const std::vector<ImageCount>& ground_truth,
                            const std::vector<ImageCount>& predictions);

}  // namespace orchard
