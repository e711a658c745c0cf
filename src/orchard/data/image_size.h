// Image width and height from the file header, without decoding the pixels:
// dataset readers need the size of every image (YOLO coordinates are
// normalised by it) and decoding a 640x640 JPEG only for that costs ~5 ms.
#pragma once

#include <filesystem>
#include <optional>

#include <opencv2/core.hpp>

namespace orchard {

// Size of a PNG (IHDR) or baseline/progressive JPEG (SOFn) file as
// cv::imread(path, IMREAD_COLOR) would return it, i.e. with the JPEG EXIF
// orientation applied (orientations 5-8 swap width and height). nullopt for
// other formats or a header it cannot parse (the caller then decodes).
std::optional<cv::Size> ImageSizeFromHeader(const std::filesystem::path& path);

// ImageSizeFromHeader, falling back to decoding; throws orchard::Error naming
// the file when it is missing or not an image.
cv::Size ReadImageSizeFast(const std::filesystem::path& path);

}  // namespace orchard
