#include "orchard/data/image_size.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/file_io.h"

namespace orchard {
namespace {

std::uint32_t BigEndian(const unsigned char* p, int bytes) {
  std::uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

std::uint32_t Endian(const unsigned char* p, int bytes, bool little) {
  if (!little) return BigEndian(p, bytes);
  std::uint32_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// EXIF orientation (1..8) from an APP1 payload, 1 when absent or unreadable.
int ExifOrientation(const std::vector<unsigned char>& app1) {
  if (app1.size() < 14 || std::memcmp(app1.data(), "Exif\0\0", 6) != 0) return 1;
  const unsigned char* tiff = app1.data() + 6;
  const size_t size = app1.size() - 6;
  bool little;
  if (tiff[0] == 'I' && tiff[1] == 'I') little = true;
  else if (tiff[0] == 'M' && tiff[1] == 'M') little = false;
  else return 1;
  const std::uint32_t ifd = Endian(tiff + 4, 4, little);
  if (ifd + 2 > size) return 1;
  const std::uint32_t count = Endian(tiff + ifd, 2, little);
  for (std::uint32_t i = 0; i < count; ++i) {
    const size_t entry = ifd + 2 + 12 * i;
    if (entry + 12 > size) return 1;
    if (Endian(tiff + entry, 2, little) == 0x0112) {
      const int orientation = static_cast<int>(Endian(tiff + entry + 8, 2, little));
      return (orientation >= 1 && orientation <= 8) ? orientation : 1;
    }
  }
  return 1;
}

std::optional<cv::Size> JpegSize(std::ifstream& in) {
  int orientation = 1;
  unsigned char marker[2];
  while (in.read(reinterpret_cast<char*>(marker), 2)) {
    if (marker[0] != 0xFF) return std::nullopt;
    const unsigned char type = marker[1];
    if (type == 0xFF) {  // fill byte
      in.seekg(-1, std::ios::cur);
      continue;
    }
    if (type == 0xD8 || (type >= 0xD0 && type <= 0xD7) || type == 0x01) continue;  // no length
    if (type == 0xD9 || type == 0xDA) return std::nullopt;  // end / scan before any frame header
    unsigned char length_bytes[2];
    if (!in.read(reinterpret_cast<char*>(length_bytes), 2)) return std::nullopt;
    const std::uint32_t length = BigEndian(length_bytes, 2);
    if (length < 2) return std::nullopt;
    const bool is_sof = type >= 0xC0 && type <= 0xCF && type != 0xC4 && type != 0xC8 && type != 0xCC;
    if (is_sof) {
      unsigned char sof[5];
      if (length < 7 || !in.read(reinterpret_cast<char*>(sof), 5)) return std::nullopt;
      const int height = static_cast<int>(BigEndian(sof + 1, 2));
      const int width = static_cast<int>(BigEndian(sof + 3, 2));
      if (width <= 0 || height <= 0) return std::nullopt;  // height 0: defined later (DNL)
      return orientation >= 5 ? cv::Size(height, width) : cv::Size(width, height);
    }
    if (type == 0xE1 && orientation == 1) {
      std::vector<unsigned char> payload(length - 2);
      if (!in.read(reinterpret_cast<char*>(payload.data()), payload.size())) return std::nullopt;
      orientation = ExifOrientation(payload);
    } else {
      in.seekg(length - 2, std::ios::cur);
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<cv::Size> ImageSizeFromHeader(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  unsigned char head[24];
  if (!in.read(reinterpret_cast<char*>(head), 24)) return std::nullopt;
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (std::memcmp(head, kPng, 8) == 0 && std::memcmp(head + 12, "IHDR", 4) == 0) {
    const int width = static_cast<int>(BigEndian(head + 16, 4));
    const int height = static_cast<int>(BigEndian(head + 20, 4));
    if (width <= 0 || height <= 0) return std::nullopt;
    return cv::Size(width, height);
  }
  if (head[0] == 0xFF && head[1] == 0xD8) {
    in.seekg(2);
    return JpegSize(in);
  }
  return std::nullopt;
}

cv::Size ReadImageSizeFast(const std::filesystem::path& path) {
  if (const auto size = ImageSizeFromHeader(path)) return *size;
  return ReadImage(path, cv::IMREAD_COLOR).size();
}

}  // namespace orchard
