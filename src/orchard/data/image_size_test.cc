#include <fstream>
#include <iterator>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "orchard/core/file_io.h"
#include "orchard/data/image_size.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::ErrorOf;
using testing_data::TempDir;
using testing_data::WriteText;
using ::testing::HasSubstr;

cv::Mat Pattern(int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  cv::randu(m, 0, 255);
  return m;
}

TEST(ImageSize, PngAndJpegHeadersMatchDecoding) {
  TempDir dir;
  const struct {
    const char* name;
    std::vector<int> params;
  } files[] = {{"a.png", {}}, {"b.jpg", {}}, {"c.jpg", {cv::IMWRITE_JPEG_PROGRESSIVE, 1}}};
  for (const auto& f : files) {
    cv::imwrite((dir / f.name).string(), Pattern(37, 21), f.params);
    const auto size = ImageSizeFromHeader(dir / f.name);
    ASSERT_TRUE(size.has_value()) << f.name;
    EXPECT_EQ(*size, cv::Size(37, 21)) << f.name;
  }
  cv::Mat ids16(9, 13, CV_16U, cv::Scalar(300));
  cv::imwrite((dir / "m.png").string(), ids16);
  EXPECT_EQ(ReadImageSizeFast(dir / "m.png"), cv::Size(13, 9));
  // Other formats are decoded.
  cv::imwrite((dir / "d.bmp").string(), Pattern(5, 6));
  EXPECT_FALSE(ImageSizeFromHeader(dir / "d.bmp").has_value());
  EXPECT_EQ(ReadImageSizeFast(dir / "d.bmp"), cv::Size(5, 6));
  WriteText(dir / "e.jpg", "not a jpeg");
  EXPECT_FALSE(ImageSizeFromHeader(dir / "e.jpg").has_value());
  EXPECT_THAT(ErrorOf([&] { ReadImageSizeFast(dir / "e.jpg"); }), HasSubstr("e.jpg"));
  EXPECT_THAT(ErrorOf([&] { ReadImageSizeFast(dir / "none.png"); }), HasSubstr("none.png"));
}

// Inserts an EXIF APP1 segment with the given orientation after SOI.
std::string WithExifOrientation(const std::string& jpeg, int orientation, bool little_endian) {
  std::string tiff = little_endian ? std::string("II*\0\x08\0\0\0", 8) : std::string("MM\0*\0\0\0\x08", 8);
  auto u16 = [&](int v) {
    return little_endian ? std::string{char(v & 0xFF), char(v >> 8)} : std::string{char(v >> 8), char(v & 0xFF)};
  };
  tiff += u16(1);                                                  // one entry
  tiff += u16(0x0112) + u16(3) + (little_endian ? std::string("\1\0\0\0", 4) : std::string("\0\0\0\1", 4));
  tiff += u16(orientation) + u16(0);                               // value
  tiff += std::string(4, '\0');                                    // next IFD
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  const int length = static_cast<int>(payload.size()) + 2;
  const std::string app1 = std::string("\xFF\xE1", 2) + char(length >> 8) + char(length & 0xFF) + payload;
  return jpeg.substr(0, 2) + app1 + jpeg.substr(2);
}

TEST(ImageSize, JpegExifOrientationAsOpenCvApplies) {
  TempDir dir;
  std::vector<unsigned char> buffer;
  cv::imencode(".jpg", Pattern(40, 24), buffer);
  const std::string jpeg(buffer.begin(), buffer.end());
  for (int orientation : {1, 3, 6, 8}) {
    for (bool little : {true, false}) {
      const fs::path path = dir / ("o" + std::to_string(orientation) + (little ? "l" : "b") + ".jpg");
      std::ofstream(path, std::ios::binary) << WithExifOrientation(jpeg, orientation, little);
      const cv::Mat decoded = ReadImage(path, cv::IMREAD_COLOR);
      const auto size = ImageSizeFromHeader(path);
      ASSERT_TRUE(size.has_value());
      EXPECT_EQ(*size, decoded.size()) << orientation << " " << little;
      EXPECT_EQ(*size, orientation >= 5 ? cv::Size(24, 40) : cv::Size(40, 24));
    }
  }
}

TEST(ImageSize, RealImagesMatchDecoding) {
  const fs::path dir = fs::path(ORCHARD_SHARED_DATA_DIR) / "applebbch76/data/images";
  if (!fs::is_directory(dir)) GTEST_SKIP() << "no " << dir;
  const std::vector<fs::path> images = ListImages(dir);
  for (size_t i = 0; i < images.size(); i += 10) {
    const auto size = ImageSizeFromHeader(images[i]);
    ASSERT_TRUE(size.has_value()) << images[i];
    EXPECT_EQ(*size, ReadImage(images[i]).size()) << images[i];
  }
}

}  // namespace
}  // namespace orchard
