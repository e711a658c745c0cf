#include "orchard/nn/copy_paste.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/random.h"

namespace orchard::nn {
void CopyPasteOptions::Check() const {
  ORCHARD_CHECK_OPTION(probability >= 0 && probability <= 1, "copy-paste probability must be in [0, 1], got ",
                       probability);
  ORCHARD_CHECK_OPTION(min_separation > 0 && min_separation <= max_separation,
                       "copy-paste separations must satisfy 0 < min <= max, got ", min_separation, " and ",
                       max_separation);
  ORCHARD_CHECK_OPTION(size_jitter >= 0 && size_jitter < 1, "copy-paste size jitter must be in [0, 1), got ",
                       size_jitter);
  ORCHARD_CHECK_OPTION(margin >= 0 && margin < 0.5, "copy-paste margin must be in [0, 0.5), got ", margin);
  ORCHARD_CHECK_OPTION(min_margin >= 0, "copy-paste minimum margin must be >= 0, got ", min_margin);
}

AppleSprite SpriteFromSingleApplePatch(const cv::Mat& bgr, const CopyPasteOptions& options) {
  if (bgr.empty() || bgr.type() != CV_8UC3) Fail("a sprite needs an 8-bit BGR patch");
  // The patch's longer side is L (1 + 2 margin) for an apple box of longer side L.
  const double longer = std::max(bgr.cols, bgr.rows) / (1 + 2 * options.margin);
  const int m = std::max(options.min_margin, static_cast<int>(std::lround(options.margin * longer)));
  const int w = bgr.cols - 2 * m, h = bgr.rows - 2 * m;
  AppleSprite sprite;
  if (w < 4 || h < 4) return sprite;  // too small to hold an apple: left out by the caller
  sprite.bgr = bgr(cv::Rect(m, m, w, h)).clone();
  sprite.alpha = cv::Mat1f::zeros(h, w);
  cv::ellipse(sprite.alpha, cv::RotatedRect(cv::Point2f((w - 1) / 2.0f, (h - 1) / 2.0f), cv::Size2f(w, h), 0),
              cv::Scalar(1.0), -1);
  cv::GaussianBlur(sprite.alpha, sprite.alpha, cv::Size(0, 0), std::max(0.5, 0.03 * std::min(w, h)));
  sprite.radius = (w + h) / 4.0;
  return sprite;
}

cv::Mat ComposeCluster(const std::vector<const AppleSprite*>& sprites, const cv::Mat& background,
                       const CopyPasteOptions& options, std::mt19937_64& rng, std::vector<cv::Point2f>* centres_out) {
  if (sprites.empty()) Fail("a cluster needs at least one sprite");
  if (background.empty() || background.type() != CV_8UC3) Fail("a cluster needs an 8-bit BGR background");
  // Centres: each new apple touches a random earlier one and keeps its distance from all.
  std::vector<cv::Point2d> centres{{0, 0}};
  for (size_t k = 1; k < sprites.size(); ++k) {
    cv::Point2d best;
    double best_clearance = -1e300;
    for (int attempt = 0; attempt < 50; ++attempt) {
      const size_t j = rng() % k;
      const double angle = UniformIn(rng, 0, 2 * M_PI);
      const double distance =
          (sprites[j]->radius + sprites[k]->radius) * UniformIn(rng, options.min_separation, options.max_separation);
      const cv::Point2d c = centres[j] + distance * cv::Point2d(std::cos(angle), std::sin(angle));
      double clearance = 1e300;  // smallest distance to an earlier apple, relative to the allowed
      for (size_t i = 0; i < k; ++i) {
        clearance = std::min(clearance, cv::norm(c - centres[i]) /
                                            (options.min_separation * (sprites[i]->radius + sprites[k]->radius)));
      }
      if (clearance > best_clearance) best_clearance = clearance, best = c;
      if (clearance >= 1) break;
    }
    centres.push_back(best);
  }
  // The cluster box, then the margin as CountPatchOptions cuts it.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (size_t k = 0; k < sprites.size(); ++k) {
    x0 = std::min(x0, centres[k].x - sprites[k]->bgr.cols / 2.0);
    y0 = std::min(y0, centres[k].y - sprites[k]->bgr.rows / 2.0);
    x1 = std::max(x1, centres[k].x + sprites[k]->bgr.cols / 2.0);
    y1 = std::max(y1, centres[k].y + sprites[k]->bgr.rows / 2.0);
  }
  const double m = std::max<double>(options.min_margin, options.margin * std::max(x1 - x0, y1 - y0));
  const int width = static_cast<int>(std::ceil(x1 - x0 + 2 * m)), height = static_cast<int>(std::ceil(y1 - y0 + 2 * m));
  if (centres_out) {
    centres_out->clear();
    for (const cv::Point2d& c : centres) {
      centres_out->emplace_back(static_cast<float>(c.x - x0 + m - 0.5), static_cast<float>(c.y - y0 + m - 0.5));
    }
  }
  cv::Mat canvas;
  cv::resize(background, canvas, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  canvas.convertTo(canvas, CV_32FC3);
  std::vector<size_t> order(sprites.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), rng);
  for (size_t k : order) {
    cv::Mat bgr = sprites[k]->bgr;
    cv::Mat1f alpha = sprites[k]->alpha;
    if (rng() & 1) {
      cv::flip(bgr, bgr, 1);
      cv::flip(alpha, alpha, 1);
    }
    const int left = static_cast<int>(std::lround(centres[k].x - bgr.cols / 2.0 - x0 + m));
    const int top = static_cast<int>(std::lround(centres[k].y - bgr.rows / 2.0 - y0 + m));
    const cv::Rect target = cv::Rect(left, top, bgr.cols, bgr.rows) & cv::Rect(0, 0, width, height);
    if (target.empty()) continue;
    const cv::Rect source(target.x - left, target.y - top, target.width, target.height);
    cv::Mat apple, weight;
    bgr(source).convertTo(apple, CV_32FC3);
    cv::cvtColor(alpha(source), weight, cv::COLOR_GRAY2BGR);
    cv::Mat region = canvas(target), keep;
    cv::subtract(cv::Scalar::all(1.0), weight, keep);
    cv::Mat blended = region.mul(keep) + apple.mul(weight);
    blended.copyTo(region);
  }
  cv::Mat out;
  canvas.convertTo(out, CV_8UC3);
  return out;
}

CopyPasteSource::CopyPasteSource(const std::vector<cv::Mat>& bgr, const std::vector<int>& counts,
                                 const std::vector<std::string>& photos, const CopyPasteOptions& options)
    : options_(options) {
  options.Check();
  if (bgr.size() != counts.size() || bgr.size() != photos.size()) Fail("copy-paste source: inputs differ in length");
  std::map<std::string, Photo> by_photo;
  for (size_t i = 0; i < bgr.size(); ++i) {
    if (counts[i] == 0) by_photo[photos[i]].backgrounds.push_back(bgr[i]);
    if (counts[i] == 1) {
      AppleSprite sprite = SpriteFromSingleApplePatch(bgr[i], options);
      if (!sprite.bgr.empty()) by_photo[photos[i]].sprites.push_back(std::move(sprite));
    }
  }
  // A photo needs background and at least two different apples.
  for (auto& [name, photo] : by_photo) {
    if (!photo.backgrounds.empty() && photo.sprites.size() >= 2) photos_.push_back(std::move(photo));
  }
}

cv::Mat CopyPasteSource::Compose(int count, std::mt19937_64& rng, std::vector<cv::Point2f>* centres) const {
  if (photos_.empty()) Fail("copy-paste source has no photo with background and single apples");
  if (count < 1) Fail("a composite needs at least one apple, got ", count);
  const Photo& photo = photos_[rng() % photos_.size()];
  std::vector<AppleSprite> resized;
  double first_radius = 0;
  for (int k = 0; k < count; ++k) {
    const AppleSprite& sprite = photo.sprites[rng() % photo.sprites.size()];
    if (k == 0) first_radius = sprite.radius;
    const double scale =
        k == 0 ? 1.0 : first_radius / sprite.radius * UniformIn(rng, 1 - options_.size_jitter, 1 + options_.size_jitter);
    AppleSprite copy;
    const cv::Size size(std::max(4, static_cast<int>(std::lround(sprite.bgr.cols * scale))),
                        std::max(4, static_cast<int>(std::lround(sprite.bgr.rows * scale))));
    cv::resize(sprite.bgr, copy.bgr, size, 0, 0, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
    cv::resize(sprite.alpha, copy.alpha, size, 0, 0, cv::INTER_LINEAR);
    copy.radius = (size.width + size.height) / 4.0;
    resized.push_back(std::move(copy));
  }
  std::vector<const AppleSprite*> chosen;
  for (const AppleSprite& sprite : resized) chosen.push_back(&sprite);
  return ComposeCluster(chosen, photo.backgrounds[rng() % photo.backgrounds.size()], options_, rng, centres);
}

}  // namespace orchard::nn
