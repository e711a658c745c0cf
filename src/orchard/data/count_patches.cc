#include "orchard/data/count_patches.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

#include "orchard/core/error.h"
#include "orchard/core/random.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

bool Touch(const Box& a, const Box& b, double tolerance) {
  return a.x1 <= b.x2 + tolerance && b.x1 <= a.x2 + tolerance && a.y1 <= b.y2 + tolerance &&
         b.y1 <= a.y2 + tolerance;
}

cv::Rect ClampedRect(double x1, double y1, double x2, double y2, int width, int height) {
  const int ix1 = std::clamp(static_cast<int>(std::floor(x1)), 0, width);
  const int iy1 = std::clamp(static_cast<int>(std::floor(y1)), 0, height);
  const int ix2 = std::clamp(static_cast<int>(std::ceil(x2)), 0, width);
  const int iy2 = std::clamp(static_cast<int>(std::ceil(y2)), 0, height);
  return cv::Rect(ix1, iy1, ix2 - ix1, iy2 - iy1);
}

}  // namespace

cv::Rect ClusterPatchRect(const Box& box, int image_width, int image_height, const CountPatchOptions& options) {
  const double m = std::max<double>(options.min_margin, options.margin * std::max(box.Width(), box.Height()));
  return ClampedRect(box.x1 - m, box.y1 - m, box.x2 + m, box.y2 + m, image_width, image_height);
}

void CountPatchOptions::Check() const {
  ORCHARD_CHECK_OPTION(touch_tolerance >= 0, "touch tolerance must be >= 0, got ", touch_tolerance);
  ORCHARD_CHECK_OPTION(margin >= 0 && margin <= 2, "margin must be in [0, 2], got ", margin);
  ORCHARD_CHECK_OPTION(min_margin >= 0, "minimum margin must be >= 0, got ", min_margin);
  ORCHARD_CHECK_OPTION(max_count >= 1, "max count must be >= 1, got ", max_count);
  ORCHARD_CHECK_OPTION(background_per_image >= 0, "background patches per image must be >= 0, got ",
                       background_per_image);
}

std::vector<std::vector<int>> GroupTouchingBoxes(const std::vector<Box>& boxes, double tolerance) {
  const int n = static_cast<int>(boxes.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (Touch(boxes[i], boxes[j], tolerance)) parent[FindRoot(parent, i)] = FindRoot(parent, j);
    }
  }
  std::map<int, std::vector<int>> groups;
  for (int i = 0; i < n; ++i) groups[FindRoot(parent, i)].push_back(i);
  std::vector<std::vector<int>> result;
  for (auto& [root, members] : groups) result.push_back(members);
  std::sort(result.begin(), result.end());  // by smallest member: independent of root choice
  return result;
}

std::vector<CountPatch> MakeCountPatches(const Dataset& dataset, const CountPatchOptions& options) {
  options.Check();
  std::mt19937_64 rng(options.seed);
  auto uniform = [&rng](double lo, double hi) { return UniformIn(rng, lo, hi); };
  std::vector<CountPatch> patches;
  for (const AnnotatedImage& image : dataset.images) {
    if (image.width <= 0 || image.height <= 0) Fail("image size unknown for ", image.name);
    std::vector<Box> boxes;
    for (const Annotation& a : image.objects) boxes.push_back(a.box);
    std::vector<double> sides;
    for (const std::vector<int>& group : GroupTouchingBoxes(boxes, options.touch_tolerance)) {
      Box u = boxes[group[0]];
      bool any_real = false;
      for (int i : group) {
        u = {std::min(u.x1, boxes[i].x1), std::min(u.y1, boxes[i].y1), std::max(u.x2, boxes[i].x2),
             std::max(u.y2, boxes[i].y2)};
        any_real |= std::min(boxes[i].Width(), boxes[i].Height()) >= options.min_box_side;
      }
      if (!any_real || static_cast<int>(group.size()) > options.max_count) continue;
      const cv::Rect crop = ClusterPatchRect(u, image.width, image.height, options);
      if (crop.width < 2 || crop.height < 2) continue;
      std::vector<cv::Point2f> centres;
      for (int i : group) {
        centres.emplace_back(static_cast<float>((boxes[i].x1 + boxes[i].x2) / 2 - crop.x - 0.5),
                             static_cast<float>((boxes[i].y1 + boxes[i].y2) / 2 - crop.y - 0.5));
      }
      patches.push_back({image.name, crop, static_cast<int>(group.size()), std::move(centres)});
      sides.push_back(std::max(crop.width, crop.height));
    }
    // Background windows sized like this image's clusters (or a tenth of the
    // image when it has none), where they overlap no box.
    for (int b = 0; b < options.background_per_image; ++b) {
      for (int attempt = 0; attempt < 50; ++attempt) {
        const double side = sides.empty() ? 0.1 * std::min(image.width, image.height)
                                          : sides[static_cast<size_t>(rng() % sides.size())];
        const double w = side * uniform(0.8, 1.2), h = side * uniform(0.8, 1.2);
        if (w >= image.width || h >= image.height) break;
        const double x = uniform(0, image.width - w), y = uniform(0, image.height - h);
        const cv::Rect crop = ClampedRect(x, y, x + w, y + h, image.width, image.height);
        const Box window{double(crop.x), double(crop.y), double(crop.x + crop.width), double(crop.y + crop.height)};
        const bool free = std::none_of(boxes.begin(), boxes.end(),
                                       [&](const Box& box) { return IntersectionArea(box, window) > 0; });
        if (!free) continue;
        patches.push_back({image.name, crop, 0, {}});
        break;
      }
    }
  }
  return patches;
}

void WriteCountPatches(const Dataset& dataset, const std::vector<CountPatch>& patches, const fs::path& dir) {
  std::map<std::string, int> next_index;
  std::vector<ImageCount> counts;
  std::string current;
  cv::Mat image;
  for (const CountPatch& patch : patches) {
    const AnnotatedImage* source = dataset.Find(patch.image);
    if (!source || source->path.empty()) Fail("no image file for ", patch.image);
    if (patch.image != current) {
      image = ReadImage(source->path);
      current = patch.image;
    }
    const cv::Rect inside = patch.crop & cv::Rect(0, 0, image.cols, image.rows);
    if (inside != patch.crop) Fail("patch outside image ", patch.image);
    const std::string name =
        fs::path(patch.image).stem().string() + "_p" + std::to_string(next_index[patch.image]++) + ".png";
    WriteImageAtomic(dir / "images" / name, image(patch.crop));
    counts.push_back({name, patch.count});
  }
  WriteCodaLabCounts(counts, dir / "counts.csv");
}

}  // namespace orchard
