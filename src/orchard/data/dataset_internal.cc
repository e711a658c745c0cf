#include "orchard/data/dataset_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/image_size.h"

namespace orchard {
namespace data_internal {

fs::path GuessImageDir(const fs::path& json_path) {
  const fs::path dir = json_path.parent_path().empty() ? fs::path(".") : json_path.parent_path();
  for (const fs::path& candidate : {dir / "images", dir / ".." / "images", dir}) {
    std::error_code ec;
    if (!fs::is_directory(candidate, ec)) continue;
    if (!ListImages(candidate).empty()) return candidate.lexically_normal();
  }
  return {};
}

fs::path ResolveImagePath(const fs::path& image_dir, const std::string& file_name, bool required,
                          const fs::path& source) {
  if (image_dir.empty()) return {};
  std::error_code ec;
  const fs::path direct = image_dir / file_name;
  if (fs::is_regular_file(direct, ec)) return direct;
  const fs::path flat = image_dir / fs::path(file_name).filename();
  if (fs::is_regular_file(flat, ec)) return flat;
  if (required) {
    Fail(source.string(), ": image '", file_name, "' not found in ", image_dir.string());
  }
  return {};
}

cv::Size ReadImageSize(const fs::path& path) { return ReadImageSizeFast(path); }

void CopyFileAtomic(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  if (fs::exists(to, ec) && fs::equivalent(from, to, ec)) return;
  WriteFileAtomic(to, [&](const fs::path& tmp) {
    std::error_code copy_ec;
    fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, copy_ec);
    if (copy_ec) Fail("cannot copy ", from.string(), " to ", to.string(), ": ", copy_ec.message());
  });
}

void EnsureImageSize(AnnotatedImage* image, const std::string& purpose) {
  if (image->width > 0 && image->height > 0) return;
  if (image->path.empty()) {
    Fail("image '", image->name, "' has no known size and no image file; ", purpose,
         " needs it (give the image folder)");
  }
  const cv::Size size = ReadImageSize(image->path);
  image->width = size.width;
  image->height = size.height;
}

double PolygonArea(const std::vector<double>& polygon) {
  const size_t n = polygon.size() / 2;
  double twice = 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t j = (i + 1) % n;
    twice += polygon[2 * i] * polygon[2 * j + 1] - polygon[2 * j] * polygon[2 * i + 1];
  }
  return 0.5 * std::fabs(twice);
}

Box PolygonsBounds(const std::vector<std::vector<double>>& polygons) {
  const double inf = std::numeric_limits<double>::infinity();
  Box box{inf, inf, -inf, -inf};
  for (const auto& polygon : polygons) {
    for (size_t i = 0; i + 1 < polygon.size(); i += 2) {
      box.x1 = std::min(box.x1, polygon[i]);
      box.x2 = std::max(box.x2, polygon[i]);
      box.y1 = std::min(box.y1, polygon[i + 1]);
      box.y2 = std::max(box.y2, polygon[i + 1]);
    }
  }
  if (box.x1 > box.x2) return Box{};
  return box;
}

}  // namespace data_internal
}  // namespace orchard
