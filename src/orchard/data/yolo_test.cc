#include <cmath>

#include <gtest/gtest.h>

#include "orchard/data/dataset.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::ErrorOf;
using testing_data::TempDir;
using testing_data::WriteBlankImage;
using testing_data::WriteText;
using ::testing::HasSubstr;

TEST(Yolo, KnownAnswerBoxesInPixels) {
  TempDir dir;
  WriteBlankImage(dir / "images/a.png", 200, 100);
  WriteBlankImage(dir / "images/b.jpg", 50, 40);  // no label file: 0 objects
  WriteText(dir / "labels/a.txt", "0 0.5 0.5 0.2 0.4\n\n0 0.05 0.9 0.1 0.2\n");
  WriteText(dir / "labels/labels.txt", "apple\n");  // a class list, not a label file
  const Dataset d = ReadYolo(dir.path());
  ASSERT_EQ(d.images.size(), 2u);
  EXPECT_EQ(d.images[0].name, "a.png");
  EXPECT_EQ(d.images[0].id, 1);
  EXPECT_EQ(d.images[0].width, 200);
  EXPECT_EQ(d.images[0].height, 100);
  ASSERT_EQ(d.images[0].objects.size(), 2u);
  const Box& b = d.images[0].objects[0].box;
  EXPECT_DOUBLE_EQ(b.x1, 80);
  EXPECT_DOUBLE_EQ(b.x2, 120);
  EXPECT_DOUBLE_EQ(b.y1, 30);
  EXPECT_DOUBLE_EQ(b.y2, 70);
  // On the image border: x from 0 to 20, y from 80 to 100.
  const Box& c = d.images[0].objects[1].box;
  EXPECT_NEAR(c.x1, 0, 1e-9);
  EXPECT_NEAR(c.x2, 20, 1e-9);
  EXPECT_NEAR(c.y2, 100, 1e-9);
  EXPECT_LT(d.images[0].objects[0].area, 0);  // box only
  EXPECT_EQ(d.images[1].name, "b.jpg");
  EXPECT_TRUE(d.images[1].objects.empty());
  EXPECT_EQ(d.NumObjects(), 2u);
  EXPECT_FALSE(d.has_masks);
}

TEST(Yolo, AcceptsDataSubfolder) {
  TempDir dir;
  WriteBlankImage(dir / "data/images/a.png", 10, 10);
  WriteText(dir / "data/labels/a.txt", "0 0.5 0.5 0.2 0.2\n");
  EXPECT_EQ(ReadYolo(dir.path()).NumObjects(), 1u);
  EXPECT_EQ(ReadDataset(dir.path()).NumObjects(), 1u);
  EXPECT_EQ(ReadDataset(dir / "data").NumObjects(), 1u);
}

TEST(Yolo, SegmentationLinesArePolygons) {
  TempDir dir;
  WriteBlankImage(dir / "images/a.png", 100, 100);
  WriteText(dir / "labels/a.txt", "0 0.1 0.1 0.5 0.1 0.5 0.3 0.1 0.3\n");
  const Dataset d = ReadYolo(dir.path());
  ASSERT_EQ(d.NumObjects(), 1u);
  const Annotation& a = d.images[0].objects[0];
  EXPECT_NEAR(a.box.x1, 10, 1e-9);
  EXPECT_NEAR(a.box.x2, 50, 1e-9);
  EXPECT_NEAR(a.box.y2, 30, 1e-9);
  EXPECT_NEAR(a.area, 800, 1e-6);
  EXPECT_TRUE(d.has_masks);
}

struct BadLine {
  std::string line;
  std::string expected;  // substring of the message
};

TEST(Yolo, MalformedLinesNameFileLineAndField) {
  const BadLine cases[] = {
      {"0 abc 0.5 0.1 0.1", ":3: field 'cx': expected a number, got 'abc'"},
      {"0 0.5 0.5 0.1", ":3: expected 5 fields"},
      {"0 0.5 0.5 0.1 0.1 0.9", ":3: expected 5 fields"},
      {"x 0.5 0.5 0.1 0.1", ":3: field 'class': expected a number, got 'x'"},
      {"0.5 0.5 0.5 0.1 0.1", ":3: field 'class': expected a whole number"},
      {"-1 0.5 0.5 0.1 0.1", ":3: field 'class'"},
      {"0 1.5 0.5 0.1 0.1", ":3: field 'cx': expected a value in [0,1], got '1.5'"},
      {"0 0.5 -0.2 0.1 0.1", ":3: field 'cy': expected a value in [0,1]"},
      {"0 0.5 0.5 -0.1 0.1", ":3: field 'w'"},
      {"0 0.5 0.5 0.1 nan", ":3: field 'h': expected a number, got 'nan'"},
      {"0 0.5 0.5 0.1 inf", ":3: field 'h': expected a number"},
      {"0 0.95 0.5 0.5 0.1", ":3: field 'w': box cx=0.95 w=0.5 extends outside the image"},
      {"0 0.1 0.1 0.5 0.1 0.5 zz 0.1 0.3", ":3: field 'y3': expected a number, got 'zz'"},
  };
  for (const BadLine& c : cases) {
    TempDir dir;
    WriteBlankImage(dir / "images/a.png", 10, 10);
    WriteText(dir / "labels/a.txt", "0 0.5 0.5 0.1 0.1\n\n" + c.line + "\n");
    const std::string message = ErrorOf([&] { ReadYolo(dir.path()); });
    EXPECT_THAT(message, HasSubstr("a.txt" + c.expected)) << c.line;
  }
}

TEST(Yolo, ToleratesTinyOvershootAndCarriageReturns) {
  TempDir dir;
  WriteBlankImage(dir / "images/a.png", 10, 10);
  WriteText(dir / "labels/a.txt", "0 0.5 1.0004 0.1 0.0008\r\n");
  EXPECT_EQ(ReadYolo(dir.path()).NumObjects(), 1u);
}

TEST(Yolo, StructuralErrors) {
  {
    TempDir dir;
    fs::create_directories(dir / "labels");
    EXPECT_THAT(ErrorOf([&] { ReadYolo(dir.path()); }), HasSubstr("no images/ folder"));
  }
  {
    TempDir dir;
    fs::create_directories(dir / "labels");
    fs::create_directories(dir / "images");
    EXPECT_THAT(ErrorOf([&] { ReadYolo(dir.path()); }), HasSubstr("no images in"));
  }
  {
    TempDir dir;
    WriteBlankImage(dir / "images/a.png", 10, 10);
    WriteText(dir / "labels/orphan.txt", "0 0.5 0.5 0.1 0.1\n");
    EXPECT_THAT(ErrorOf([&] { ReadYolo(dir.path()); }), HasSubstr("orphan.txt has no image"));
  }
  {
    TempDir dir;
    WriteBlankImage(dir / "images/a.png", 10, 10);
    WriteText(dir / "images/b.png", "not a png");
    fs::create_directories(dir / "labels");
    EXPECT_THAT(ErrorOf([&] { ReadYolo(dir.path()); }), HasSubstr("cannot decode image"));
  }
  {
    TempDir dir;
    EXPECT_THAT(ErrorOf([&] { ReadYolo(dir.path()); }), HasSubstr("no labels/ folder"));
  }
}

TEST(Yolo, WriteReadRoundTrip) {
  TempDir dir;
  Dataset d;
  AnnotatedImage image;
  image.name = "x.png";
  image.width = 640;
  image.height = 480;
  image.objects.push_back({Box{0, 0, 64, 48}, -1, {}, 0});
  image.objects.push_back({Box{100.5, 200.25, 180.75, 300}, -1, {}, 0});
  d.images.push_back(image);
  AnnotatedImage empty;
  empty.name = "y.png";
  empty.width = 640;
  empty.height = 480;
  d.images.push_back(empty);
  WriteYolo(d, dir / "out");
  // No image files were known, so write them for the reader.
  WriteBlankImage(dir / "out/images/x.png", 640, 480);
  WriteBlankImage(dir / "out/images/y.png", 640, 480);
  const Dataset back = ReadYolo(dir / "out");
  ASSERT_EQ(back.images.size(), 2u);
  ASSERT_EQ(back.images[0].objects.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const Box& a = d.images[0].objects[i].box;
    const Box& b = back.images[0].objects[i].box;
    EXPECT_NEAR(a.x1, b.x1, 1e-3);
    EXPECT_NEAR(a.y1, b.y1, 1e-3);
    EXPECT_NEAR(a.x2, b.x2, 1e-3);
    EXPECT_NEAR(a.y2, b.y2, 1e-3);
  }
  EXPECT_TRUE(back.images[1].objects.empty());
  EXPECT_TRUE(fs::exists(dir / "out/labels/y.txt"));
}

TEST(Yolo, WriteNeedsImageSize) {
  TempDir dir;
  Dataset d;
  AnnotatedImage image;
  image.name = "x.png";
  d.images.push_back(image);
  EXPECT_THAT(ErrorOf([&] { WriteYolo(d, dir / "out"); }), HasSubstr("'x.png' has no known size"));
}

}  // namespace
}  // namespace orchard
