#include "orchard/nn/patch_input.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/random.h"

namespace orchard::nn {

namespace {

// The resized patch's place inside the letterboxed input.
cv::Rect LetterboxRect(cv::Size patch_size, int size) {
  const double scale = static_cast<double>(size) / std::max(patch_size.width, patch_size.height);
  const int w = std::clamp(static_cast<int>(std::lround(patch_size.width * scale)), 1, size);
  const int h = std::clamp(static_cast<int>(std::lround(patch_size.height * scale)), 1, size);
  return cv::Rect((size - w) / 2, (size - h) / 2, w, h);
}

}  // namespace

cv::Mat LetterboxPatch(const cv::Mat& bgr, int size) {
  if (bgr.empty()) Fail("empty image patch");
  if (bgr.type() != CV_8UC3) Fail("image patch must be 8-bit BGR");
  const cv::Rect place = LetterboxRect(bgr.size(), size);
  cv::Mat resized;
  cv::resize(bgr, resized, place.size(), 0, 0, std::max(bgr.cols, bgr.rows) > size ? cv::INTER_AREA : cv::INTER_LINEAR);
  cv::Mat out(size, size, CV_8UC3, cv::Scalar::all(0));
  resized.copyTo(out(place));
  return out;
}

cv::Point2f LetterboxPoint(cv::Size patch_size, int size, cv::Point2f p) {
  const cv::Rect place = LetterboxRect(patch_size, size);
  // Pixel centres map as cv::resize maps them.
  return {place.x + (p.x + 0.5f) * place.width / patch_size.width - 0.5f,
          place.y + (p.y + 0.5f) * place.height / patch_size.height - 0.5f};
}

torch::Tensor ImagesToTensor(const std::vector<cv::Mat>& bgr_images) {
  if (bgr_images.empty()) Fail("no images to convert");
  const int h = bgr_images[0].rows, w = bgr_images[0].cols;
  torch::Tensor batch = torch::empty({static_cast<int64_t>(bgr_images.size()), h, w, 3}, torch::kUInt8);
  for (size_t i = 0; i < bgr_images.size(); ++i) {
    const cv::Mat& image = bgr_images[i];
    if (image.rows != h || image.cols != w || image.type() != CV_8UC3) Fail("batch images differ in size or type");
    cv::Mat rgb;
    cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
    std::memcpy(batch[i].data_ptr(), rgb.isContinuous() ? rgb.data : rgb.clone().data, static_cast<size_t>(h) * w * 3);
  }
  return batch.permute({0, 3, 1, 2}).to(torch::kFloat32).div_(127.5).sub_(1.0).contiguous();
}

cv::Mat AugmentPatch(const cv::Mat& image, const PatchAugmentation& augmentation, std::mt19937_64& rng,
                     std::vector<cv::Point2f>* points) {
  cv::Mat out = image.clone();
  if (augmentation.flip && (rng() & 1)) {
    cv::flip(out, out, 1);
    if (points) {
      for (cv::Point2f& p : *points) p.x = out.cols - 1 - p.x;
    }
  }
  if (augmentation.max_rotation_deg > 0) {
    const double angle = UniformIn(rng, -augmentation.max_rotation_deg, augmentation.max_rotation_deg);
    const cv::Mat rotation = cv::getRotationMatrix2D(cv::Point2f(out.cols / 2.0f, out.rows / 2.0f), angle, 1.0);
    cv::warpAffine(out, out, rotation, out.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    if (points && !points->empty()) cv::transform(*points, *points, rotation);
  }
  if (augmentation.max_blur_sigma > 0 && (rng() & 1)) {
    const double sigma = UniformIn(rng, 0.0, augmentation.max_blur_sigma);
    if (sigma > 0.1) cv::GaussianBlur(out, out, cv::Size(0, 0), sigma);
  }
  return out;
}

}  // namespace orchard::nn
