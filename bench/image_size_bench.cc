// Image sizes for dataset readers: header parsing (orchard ImageSizeFromHeader)
// against decoding with cv::imread, on the real AppleBBCH images (or a folder
// given as argv[1]). Prints both times and the ratio.
#include <chrono>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/file_io.h"
#include "orchard/data/image_size.h"

int main(int argc, char** argv) {
  const std::filesystem::path dir =
      argc > 1 ? argv[1] : std::filesystem::path(ORCHARD_SHARED_DATA_DIR) / "applebbch81/data/images";
  const auto images = orchard::ListImages(dir);
  using Clock = std::chrono::steady_clock;
  long long checksum_header = 0, checksum_decode = 0;
  const auto t0 = Clock::now();
  for (const auto& path : images) checksum_header += orchard::ReadImageSizeFast(path).area();
  const auto t1 = Clock::now();
  for (const auto& path : images) checksum_decode += cv::imread(path.string(), cv::IMREAD_COLOR).size().area();
  const auto t2 = Clock::now();
  const double header_s = std::chrono::duration<double>(t1 - t0).count();
  const double decode_s = std::chrono::duration<double>(t2 - t1).count();
  std::printf("%zu images in %s\nheader: %.4f s (%.3f ms/image)\nimread: %.4f s (%.3f ms/image)\n"
              "speed-up: %.0fx, sizes %s\n",
              images.size(), dir.c_str(), header_s, 1e3 * header_s / images.size(), decode_s,
              1e3 * decode_s / images.size(), decode_s / header_s,
              checksum_header == checksum_decode ? "agree" : "DISAGREE");
  return checksum_header == checksum_decode ? 0 : 1;
}
