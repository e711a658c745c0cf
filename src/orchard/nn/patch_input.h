// How an image patch becomes a network input, shared by training and
// inference so both see exactly the same pixels.
#pragma once

#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <torch/torch.h>

namespace orchard::nn {

// Resizes `bgr` so its longer side is `size`, keeping the aspect ratio, and
// zero-pads it to size x size, centred (the study's input for the counter).
cv::Mat LetterboxPatch(const cv::Mat& bgr, int size);

// Where pixel position `p` of a patch of `patch_size` lands in its letterboxed
// input of side `size` (LetterboxPatch's scale and offset).
cv::Point2f LetterboxPoint(cv::Size patch_size, int size, cv::Point2f p);

// 8-bit BGR images of one size -> [N, 3, H, W] float RGB, scaled to [-1, 1].
torch::Tensor ImagesToTensor(const std::vector<cv::Mat>& bgr_images);

struct PatchAugmentation {
  bool flip = true;             // horizontal flips, p = 0.5
  double max_rotation_deg = 5;  // uniform in [-max, max]
  double max_blur_sigma = 1.0;  // Gaussian smoothing, sigma uniform in [0, max], p = 0.5
};

// A randomly augmented copy of `image` (same size). `points` (pixel
// positions, optional) are moved with the image's flip and rotation.
cv::Mat AugmentPatch(const cv::Mat& image, const PatchAugmentation& augmentation, std::mt19937_64& rng,
                     std::vector<cv::Point2f>* points = nullptr);

}  // namespace orchard::nn
