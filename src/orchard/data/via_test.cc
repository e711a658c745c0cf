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

const char* kVia2Project = R"({
  "_via_settings": {},
  "_via_img_metadata": {
    "b.jpg1234": {"filename": "b.jpg", "size": 1234, "file_attributes": {}, "regions": [
      {"shape_attributes": {"name": "polygon", "all_points_x": [10, 30, 30, 10],
                            "all_points_y": [20, 20, 40, 40]}, "region_attributes": {}},
      {"shape_attributes": {"name": "circle", "cx": 50, "cy": 60, "r": 5}},
      {"shape_attributes": {"name": "ellipse", "cx": 80, "cy": 80, "rx": 6, "ry": 3, "theta": 0}},
      {"shape_attributes": {"name": "rect", "x": 0, "y": 1, "width": 7, "height": 8}}]},
    "a.jpg99": {"filename": "a.jpg", "size": 99, "regions": []}
  }
})";

TEST(Via, Version2ProjectShapes) {
  TempDir dir;
  WriteText(dir / "p.json", kVia2Project);
  EXPECT_EQ(DetectDatasetFormat(dir / "p.json"), DatasetFormat::kVia);
  const Dataset d = ReadVia(dir / "p.json");
  ASSERT_EQ(d.images.size(), 2u);
  EXPECT_EQ(d.images[0].name, "a.jpg");
  EXPECT_EQ(d.images[0].id, 1);
  EXPECT_TRUE(d.images[0].objects.empty());
  const auto& o = d.images[1].objects;
  ASSERT_EQ(o.size(), 4u);
  EXPECT_DOUBLE_EQ(o[0].box.x1, 10);
  EXPECT_DOUBLE_EQ(o[0].box.y2, 40);
  EXPECT_DOUBLE_EQ(o[0].area, 400);
  EXPECT_NEAR(o[1].box.x1, 45, 1e-9);
  EXPECT_NEAR(o[1].box.y2, 65, 1e-9);
  EXPECT_NEAR(o[1].area, M_PI * 25, 1e-9);
  EXPECT_NEAR(o[2].box.x2, 86, 1e-9);
  EXPECT_NEAR(o[2].box.y1, 77, 1e-9);
  EXPECT_DOUBLE_EQ(o[3].box.x2, 7);
  EXPECT_DOUBLE_EQ(o[3].box.y2, 9);
  EXPECT_TRUE(d.has_masks);
  EXPECT_EQ(d.images[1].width, 0);  // no image folder: size unknown
}

TEST(Via, ExportVersion1AndImageFolder) {
  TempDir dir;
  WriteText(dir / "e.json", R"({"a.png5": {"filename": "a.png", "size": 5, "regions": {
      "0": {"shape_attributes": {"name": "rect", "x": 1, "y": 2, "width": 3, "height": 4}}}}})");
  WriteBlankImage(dir / "images/a.png", 32, 24);
  const Dataset d = ReadDataset(dir / "e.json");  // finds images/ beside the json
  ASSERT_EQ(d.images.size(), 1u);
  EXPECT_EQ(d.images[0].width, 32);
  EXPECT_EQ(d.images[0].height, 24);
  ASSERT_EQ(d.images[0].objects.size(), 1u);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].box.x2, 4);
}

TEST(Via, Version3Project) {
  TempDir dir;
  WriteText(dir / "v3.json", R"({"project": {"pid": "x"}, "config": {}, "attribute": {},
    "file": {"1": {"fid": "1", "fname": "a.jpg", "type": 2}},
    "view": {"1": {"fid_list": ["1"]}},
    "metadata": {"1_a": {"vid": "1", "flg": 0, "z": [], "xy": [2, 10, 20, 30, 40], "av": {}},
                 "1_b": {"vid": "1", "flg": 0, "z": [], "xy": [7, 0, 0, 4, 0, 4, 4], "av": {}}}})");
  const Dataset d = ReadDataset(dir / "v3.json");
  ASSERT_EQ(d.images.size(), 1u);
  ASSERT_EQ(d.images[0].objects.size(), 2u);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].box.x2, 40);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].box.y2, 60);
  EXPECT_DOUBLE_EQ(d.images[0].objects[1].area, 8);
}

TEST(Via, MalformedRegionsNameTheField) {
  struct Case {
    std::string json, expected;
  };
  const Case cases[] = {
      {R"({"k": {"filename": "a.jpg", "regions": [{"shape_attributes": {"name": "point", "cx": 1, "cy": 2}}]}})",
       "k.regions[0].shape_attributes.name: unsupported region shape 'point'"},
      {R"({"k": {"filename": "a.jpg", "regions": [{"shape_attributes": {"name": "rect", "x": 1, "y": 2, "width": "w", "height": 1}}]}})",
       "k.regions[0].shape_attributes.width: expected a number"},
      {R"({"k": {"filename": "a.jpg", "regions": [{"shape_attributes": {"name": "rect", "x": 1, "y": 2, "height": 1}}]}})",
       "k.regions[0].shape_attributes: missing field 'width'"},
      {R"({"k": {"filename": "a.jpg", "regions": [{"shape_attributes": {"name": "polygon", "all_points_x": [1, 2], "all_points_y": [1]}}]}})",
       "k.regions[0].shape_attributes: expected all_points_x and all_points_y"},
      {R"({"k": {"filename": "a.jpg", "regions": [{"shape_attributes": {"name": "circle", "cx": 1, "cy": 2, "r": -1}}]}})",
       "expected positive radii"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    WriteText(dir / "bad.json", c.json);
    const std::string message = ErrorOf([&] { ReadVia(dir / "bad.json"); });
    EXPECT_THAT(message, HasSubstr("bad.json: ")) << c.json;
    EXPECT_THAT(message, HasSubstr(c.expected)) << c.json;
  }
  TempDir dir;
  WriteText(dir / "odd.json", R"({"x": 1})");
  EXPECT_THAT(ErrorOf([&] { DetectDatasetFormat(dir / "odd.json"); }),
              HasSubstr("cannot tell the dataset format"));
  WriteText(dir / "list.json", "[]");
  EXPECT_THAT(ErrorOf([&] { DetectDatasetFormat(dir / "list.json"); }), HasSubstr("COCO results"));
}

}  // namespace
}  // namespace orchard
