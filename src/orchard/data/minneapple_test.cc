#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/data/dataset.h"
#include "orchard/data/minneapple.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::ErrorOf;
using testing_data::TempDir;
using testing_data::WriteBlankImage;
using testing_data::WriteText;
using ::testing::HasSubstr;

// A 40x30 id image: id 1 a 10x10 square with a 4x4 hole; id 7 split in two
// pieces; id 3 a single pixel in the bottom-right corner; id 2 on the left border.
cv::Mat TestIds() {
  cv::Mat ids(30, 40, CV_16U, cv::Scalar(0));
  ids(cv::Rect(5, 5, 10, 10)).setTo(1);
  ids(cv::Rect(8, 8, 4, 4)).setTo(0);
  ids(cv::Rect(20, 2, 3, 3)).setTo(7);
  ids(cv::Rect(30, 20, 2, 5)).setTo(7);
  ids.at<uint16_t>(29, 39) = 3;
  ids(cv::Rect(0, 20, 4, 6)).setTo(2);
  return ids;
}

TEST(InstanceMask, HolesAndSplitInstances) {
  cv::Mat ids32;
  TestIds().convertTo(ids32, CV_32S);
  const std::vector<Annotation> objects = InstancesFromMask(ids32, true);
  ASSERT_EQ(objects.size(), 4u);  // ids 1, 2, 3, 7 in that order
  // id 1: box over all pixels, area excludes the hole.
  EXPECT_DOUBLE_EQ(objects[0].box.x1, 5);
  EXPECT_DOUBLE_EQ(objects[0].box.y1, 5);
  EXPECT_DOUBLE_EQ(objects[0].box.x2, 15);
  EXPECT_DOUBLE_EQ(objects[0].box.y2, 15);
  EXPECT_DOUBLE_EQ(objects[0].area, 100 - 16);
  EXPECT_EQ(objects[0].polygons.size(), 1u);  // outer contour only
  // id 2 on the left border.
  EXPECT_DOUBLE_EQ(objects[1].box.x1, 0);
  EXPECT_DOUBLE_EQ(objects[1].box.x2, 4);
  EXPECT_DOUBLE_EQ(objects[1].area, 24);
  // id 3: one pixel in the corner.
  EXPECT_DOUBLE_EQ(objects[2].box.x1, 39);
  EXPECT_DOUBLE_EQ(objects[2].box.x2, 40);
  EXPECT_DOUBLE_EQ(objects[2].box.y2, 30);
  EXPECT_DOUBLE_EQ(objects[2].area, 1);
  ASSERT_EQ(objects[2].polygons.size(), 1u);
  EXPECT_EQ(objects[2].polygons[0].size(), 6u);  // padded to 3 points for COCO
  // id 7: two pieces, one object, one polygon per piece.
  EXPECT_DOUBLE_EQ(objects[3].box.x1, 20);
  EXPECT_DOUBLE_EQ(objects[3].box.y1, 2);
  EXPECT_DOUBLE_EQ(objects[3].box.x2, 32);
  EXPECT_DOUBLE_EQ(objects[3].box.y2, 25);
  EXPECT_DOUBLE_EQ(objects[3].area, 9 + 10);
  EXPECT_EQ(objects[3].polygons.size(), 2u);
}

TEST(InstanceMask, RasterisingContoursGivesBackHoleFreeInstances) {
  cv::Mat ids32;
  TestIds().convertTo(ids32, CV_32S);
  const std::vector<Annotation> objects = InstancesFromMask(ids32, true);
  const cv::Mat back = RasteriseInstances(objects, ids32.size());
  // Same pixels, renumbered 1..4 in id order, except the hole which is filled.
  const int renumber[8] = {0, 1, 2, 3, 0, 0, 0, 4};
  int differences = 0;
  for (int y = 0; y < ids32.rows; ++y) {
    for (int x = 0; x < ids32.cols; ++x) {
      const bool in_hole = x >= 8 && x < 12 && y >= 8 && y < 12;
      const int expected = in_hole ? 1 : renumber[ids32.at<int>(y, x)];
      differences += (back.at<uint16_t>(y, x) != expected);
    }
  }
  EXPECT_EQ(differences, 0);
  // Boxes without polygons fill pixels round(x1)..round(x2)-1.
  const cv::Mat boxes = RasteriseInstances({{Box{1, 2, 4, 3}, -1, {}, 0}}, cv::Size(6, 5));
  EXPECT_EQ(cv::countNonZero(boxes), 3);
  EXPECT_EQ(boxes.at<uint16_t>(2, 1), 1);
  EXPECT_EQ(boxes.at<uint16_t>(2, 3), 1);
  // A degenerate box keeps one pixel; a small box over a big one stays on top
  // whatever the order; a box on the border is clipped.
  const cv::Mat ordered = RasteriseInstances(
      {{Box{2, 2, 3, 3}, -1, {}, 0}, {Box{0, 0, 6, 5}, -1, {}, 0}, {Box{5.2, 4.1, 5.3, 4.1}, -1, {}, 0},
       {Box{4, 3, 9, 9}, -1, {}, 0}},
      cv::Size(6, 5));
  EXPECT_EQ(ordered.at<uint16_t>(2, 2), 1);
  EXPECT_EQ(ordered.at<uint16_t>(0, 0), 2);
  EXPECT_EQ(ordered.at<uint16_t>(4, 5), 3);
  EXPECT_EQ(ordered.at<uint16_t>(3, 4), 4);
  EXPECT_EQ(cv::countNonZero(ordered == 4), 3);  // (4,3) (5,3) (4,4)
}

TEST(InstanceMask, AcceptsEightSixteenBitAndEqualChannels) {
  TempDir dir;
  const cv::Mat ids16 = TestIds();
  cv::Mat ids8;
  ids16.convertTo(ids8, CV_8U);
  cv::Mat ids_rgb;
  cv::cvtColor(ids8, ids_rgb, cv::COLOR_GRAY2BGR);
  cv::imwrite((dir / "m16.png").string(), ids16);
  cv::imwrite((dir / "m8.png").string(), ids8);
  cv::imwrite((dir / "mrgb.png").string(), ids_rgb);
  for (const char* name : {"m16.png", "m8.png", "mrgb.png"}) {
    const cv::Mat ids = ReadInstanceMask(dir / name);
    EXPECT_EQ(ids.type(), CV_32S) << name;
    EXPECT_EQ(ids.at<int>(3, 21), 7) << name;
    EXPECT_EQ(ids.at<int>(29, 39), 3) << name;
  }
  ids_rgb.at<cv::Vec3b>(0, 0) = cv::Vec3b(1, 2, 3);
  cv::imwrite((dir / "colour.png").string(), ids_rgb);
  EXPECT_THAT(ErrorOf([&] { ReadInstanceMask(dir / "colour.png"); }),
              HasSubstr("colour.png is a colour image with unequal channels"));
  WriteText(dir / "broken.png", "not an image");
  EXPECT_THAT(ErrorOf([&] { ReadInstanceMask(dir / "broken.png"); }), HasSubstr("broken.png"));
}

TEST(MinneApple, ReadMatchesImagesToMasksByStem) {
  TempDir dir;
  WriteBlankImage(dir / "images/f1.jpg", 40, 30);
  WriteBlankImage(dir / "images/f2.png", 40, 30);
  cv::imwrite((dir / "masks/f1.png").string(), (fs::create_directories(dir / "masks"), TestIds()));
  cv::imwrite((dir / "masks/f2.png").string(), cv::Mat(30, 40, CV_8U, cv::Scalar(0)));
  const Dataset d = ReadMinneApple(dir.path());
  ASSERT_EQ(d.images.size(), 2u);
  EXPECT_TRUE(d.has_masks);
  EXPECT_EQ(d.images[0].name, "f1.jpg");
  EXPECT_EQ(d.images[0].path, dir / "images/f1.jpg");
  EXPECT_EQ(d.images[0].objects.size(), 4u);
  EXPECT_TRUE(d.images[1].objects.empty());
  EXPECT_EQ(DetectDatasetFormat(dir.path()), DatasetFormat::kMinneApple);
  EXPECT_EQ(ReadDataset(dir.path()).NumObjects(), 4u);
}

TEST(MinneApple, StructuralErrors) {
  {
    TempDir dir;
    WriteBlankImage(dir / "images/f1.jpg", 40, 30);
    fs::create_directories(dir / "masks");
    EXPECT_THAT(ErrorOf([&] { ReadMinneApple(dir.path()); }), HasSubstr("f1.jpg has no mask"));
  }
  {
    TempDir dir;
    WriteBlankImage(dir / "images/f1.jpg", 40, 30);
    fs::create_directories(dir / "masks");
    cv::imwrite((dir / "masks/f1.png").string(), TestIds());
    cv::imwrite((dir / "masks/f9.png").string(), TestIds());
    EXPECT_THAT(ErrorOf([&] { ReadMinneApple(dir.path()); }), HasSubstr("f9.png has no image"));
  }
  {
    TempDir dir;
    WriteBlankImage(dir / "images/f1.jpg", 41, 30);
    fs::create_directories(dir / "masks");
    cv::imwrite((dir / "masks/f1.png").string(), TestIds());
    EXPECT_THAT(ErrorOf([&] { ReadMinneApple(dir.path()); }), HasSubstr("is 40x30 but image"));
  }
  {
    TempDir dir;
    fs::create_directories(dir / "images");
    EXPECT_THAT(ErrorOf([&] { ReadMinneApple(dir.path()); }), HasSubstr("no masks/ folder"));
  }
}

TEST(MinneApple, WriteReadRoundTrip) {
  TempDir dir;
  WriteBlankImage(dir / "src/images/f1.png", 40, 30);
  fs::create_directories(dir / "src/masks");
  cv::Mat no_hole = TestIds();
  no_hole(cv::Rect(8, 8, 4, 4)).setTo(1);
  cv::imwrite((dir / "src/masks/f1.png").string(), no_hole);
  const Dataset d = ReadMinneApple(dir / "src");
  WriteMinneApple(d, dir / "out");
  EXPECT_TRUE(fs::exists(dir / "out/images/f1.png"));
  const Dataset back = ReadMinneApple(dir / "out");
  ASSERT_EQ(back.NumObjects(), d.NumObjects());
  for (size_t k = 0; k < d.images[0].objects.size(); ++k) {
    const Annotation& a = d.images[0].objects[k];
    const Annotation& b = back.images[0].objects[k];
    EXPECT_DOUBLE_EQ(a.box.x1, b.box.x1);
    EXPECT_DOUBLE_EQ(a.box.y1, b.box.y1);
    EXPECT_DOUBLE_EQ(a.box.x2, b.box.x2);
    EXPECT_DOUBLE_EQ(a.box.y2, b.box.y2);
    EXPECT_DOUBLE_EQ(a.area, b.area);
  }
  const cv::Mat written = cv::imread((dir / "out/masks/f1.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(written.depth(), CV_16U);
}

TEST(MinneApple, MasksWithoutImagesFolder) {
  TempDir dir;
  fs::create_directories(dir / "masks");
  cv::imwrite((dir / "masks/f1.png").string(), TestIds());
  const Dataset d = ReadMinneApple(dir.path());
  ASSERT_EQ(d.images.size(), 1u);
  EXPECT_EQ(d.images[0].width, 40);
  EXPECT_TRUE(d.images[0].path.empty());
}

}  // namespace
}  // namespace orchard
