#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::ErrorOf;
using testing_data::TempDir;
using testing_data::WriteBlankImage;
using testing_data::WriteText;
using ::testing::HasSubstr;

const char* kCoco = R"({
  "images": [{"id": 8937340322, "file_name": "sub/b.jpg", "width": 640, "height": 480},
             {"id": 7, "file_name": "a.jpg", "width": 100, "height": 50}],
  "annotations": [
    {"id": 1, "image_id": 7, "category_id": 3248230321, "bbox": [10, 20, 30, 40], "area": 1200},
    {"id": 2, "image_id": 8937340322, "category_id": 1, "bbox": [0, 0, 10, 10],
     "segmentation": [[0, 0, 10, 0, 10, 10, 0, 10]]},
    {"id": 3, "image_id": 7, "category_id": 1, "bbox": [1.5, 2.5, 3, 4], "segmentation": []}
  ],
  "categories": [{"id": 1, "name": "apple"}]
})";

TEST(Coco, KnownAnswerRead) {
  TempDir dir;
  WriteText(dir / "a.json", kCoco);
  const Dataset d = ReadCoco(dir / "a.json");
  ASSERT_EQ(d.images.size(), 2u);
  EXPECT_EQ(d.images[0].name, "a.jpg");  // sorted by name
  EXPECT_EQ(d.images[0].id, 7);
  EXPECT_EQ(d.images[1].name, "b.jpg");  // folders dropped from the name
  EXPECT_EQ(d.images[1].id, 8937340322);
  EXPECT_TRUE(d.images[0].path.empty());
  ASSERT_EQ(d.images[0].objects.size(), 2u);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].box.x2, 40);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].box.y2, 60);
  EXPECT_DOUBLE_EQ(d.images[0].objects[0].area, 1200);
  EXPECT_LT(d.images[0].objects[1].area, 0);  // no area, no polygon: box only
  EXPECT_EQ(d.images[0].objects[0].category, 0);
  ASSERT_EQ(d.images[1].objects.size(), 1u);
  EXPECT_DOUBLE_EQ(d.images[1].objects[0].area, 100);  // from the polygon
  ASSERT_EQ(d.images[1].objects[0].polygons.size(), 1u);
  EXPECT_TRUE(d.has_masks);
  EXPECT_EQ(d.Find("a")->name, "a.jpg");
  EXPECT_EQ(d.Find("b.jpg")->id, 8937340322);
  EXPECT_EQ(d.Find("c"), nullptr);
}

TEST(Coco, ImageFolderResolvesPaths) {
  TempDir dir;
  WriteText(dir / "ann/a.json", kCoco);
  WriteBlankImage(dir / "images/a.jpg", 100, 50);
  WriteBlankImage(dir / "images/b.jpg", 640, 480);
  const Dataset d = ReadCoco(dir / "ann/a.json", dir / "images");
  EXPECT_EQ(d.images[0].path, dir / "images/a.jpg");
  EXPECT_EQ(d.images[1].path, dir / "images/b.jpg");
  // ReadDataset finds ../images by itself.
  const Dataset guessed = ReadDataset(dir / "ann/a.json");
  EXPECT_EQ(guessed.images[0].path, (dir / "images/a.jpg").lexically_normal());
  // A given folder must hold every image.
  fs::remove(dir / "images/b.jpg");
  EXPECT_THAT(ErrorOf([&] { ReadCoco(dir / "ann/a.json", dir / "images"); }),
              HasSubstr("image 'sub/b.jpg' not found"));
  EXPECT_TRUE(ReadDataset(dir / "ann/a.json").images[1].path.empty());
}

TEST(Coco, WriteReadRoundTrip) {
  TempDir dir;
  WriteText(dir / "a.json", kCoco);
  const Dataset d = ReadCoco(dir / "a.json");
  WriteCoco(d, dir / "out/b.json");
  const Dataset back = ReadCoco(dir / "out/b.json");
  ASSERT_EQ(back.images.size(), d.images.size());
  for (size_t i = 0; i < d.images.size(); ++i) {
    EXPECT_EQ(back.images[i].name, d.images[i].name);
    EXPECT_EQ(back.images[i].id, d.images[i].id);
    EXPECT_EQ(back.images[i].width, d.images[i].width);
    ASSERT_EQ(back.images[i].objects.size(), d.images[i].objects.size());
    for (size_t k = 0; k < d.images[i].objects.size(); ++k) {
      const Annotation& a = d.images[i].objects[k];
      const Annotation& b = back.images[i].objects[k];
      EXPECT_DOUBLE_EQ(a.box.x1, b.box.x1);
      EXPECT_DOUBLE_EQ(a.box.y2, b.box.y2);
      EXPECT_EQ(a.polygons, b.polygons);
      EXPECT_DOUBLE_EQ(a.area >= 0 ? a.area : a.box.Area(), b.area);
    }
  }
  // The written file is valid COCO: required keys and a single apple category.
  const auto json = nlohmann::json::parse(ReadTextFile(dir / "out/b.json"));
  EXPECT_TRUE(json.contains("info"));
  EXPECT_EQ(json["categories"].size(), 1u);
  EXPECT_EQ(json["categories"][0]["id"], 1);
  EXPECT_EQ(json["categories"][0]["name"], "apple");
  for (const auto& a : json["annotations"]) {
    for (const char* key : {"id", "image_id", "category_id", "bbox", "area", "iscrowd"}) {
      EXPECT_TRUE(a.contains(key)) << key;
    }
    EXPECT_EQ(a["iscrowd"], 0);
    EXPECT_EQ(a["category_id"], 1);
  }
  int with_segmentation = 0;
  for (const auto& a : json["annotations"]) with_segmentation += a.contains("segmentation");
  EXPECT_EQ(with_segmentation, 1);  // only the annotation that has a polygon
}

TEST(Coco, MalformedFilesNameTheField) {
  struct Case {
    std::string json, expected;
  };
  const Case cases[] = {
      {"{", "invalid JSON"},
      {R"({"images": []})", "missing field 'annotations'"},
      {R"({"images": [{"file_name": "a.jpg"}], "annotations": []})", "images[0]: missing field 'id'"},
      {R"({"images": [{"id": 1, "file_name": 3}], "annotations": []})", "images[0].file_name"},
      {R"({"images": [{"id": 1, "file_name": "a"}, {"id": 1, "file_name": "b"}], "annotations": []})",
       "images[1].id: image id 1 appears more than once"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 2, "bbox": [0,0,1,1]}]})",
       "annotations[0].image_id: no image with id 2"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1, "bbox": [0,0,-1,1]}]})",
       "annotations[0].bbox[2]: expected a width >= 0"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1, "bbox": [0,"x",1,1]}]})",
       "annotations[0].bbox[1]: expected a number"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1, "bbox": [0,0,1]}]})",
       "annotations[0].bbox: expected [x, y, width, height]"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1}]})",
       "annotations[0]: missing field 'bbox'"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1, "bbox": [0,0,1,1], "segmentation": [[1,2,3]]}]})",
       "annotations[0].segmentation[0]: expected a polygon"},
      {R"({"images": [{"id": 1, "file_name": "a"}], "annotations": [{"image_id": 1, "bbox": [0,0,1,1], "iscrowd": 1}]})",
       "annotations[0].iscrowd"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    WriteText(dir / "bad.json", c.json);
    const std::string message = ErrorOf([&] { ReadCoco(dir / "bad.json"); });
    EXPECT_THAT(message, HasSubstr("bad.json")) << c.json;
    EXPECT_THAT(message, HasSubstr(c.expected)) << c.json;
  }
}

TEST(CocoResults, RoundTripThroughGroundTruthIds) {
  TempDir dir;
  WriteText(dir / "gt.json", kCoco);
  const Dataset gt = ReadCoco(dir / "gt.json");
  Predictions p;
  p["a.jpg"] = {{Box{1, 2, 11, 22}, 0.9}, {Box{5, 5, 6, 7}, 0.1}};
  p["b"] = {{Box{0, 0, 3, 3}, 0.5}};  // stem lookup
  WriteCocoResults(p, gt, dir / "res.json");
  const auto json = nlohmann::json::parse(ReadTextFile(dir / "res.json"));
  ASSERT_EQ(json.size(), 3u);
  EXPECT_EQ(json[0]["image_id"], 7);
  EXPECT_EQ(json[2]["image_id"], 8937340322);
  const Predictions back = ReadPredictions(dir / "res.json", gt);
  ASSERT_EQ(back.size(), 2u);
  ASSERT_EQ(back.at("a.jpg").size(), 2u);
  EXPECT_DOUBLE_EQ(back.at("a.jpg")[0].box.x2, 11);
  EXPECT_DOUBLE_EQ(back.at("a.jpg")[0].box.y2, 22);
  EXPECT_DOUBLE_EQ(back.at("a.jpg")[0].score, 0.9);
  EXPECT_EQ(back.at("b.jpg").size(), 1u);

  Predictions unknown;
  unknown["zzz.jpg"] = {{Box{0, 0, 1, 1}, 1}};
  EXPECT_THAT(ErrorOf([&] { WriteCocoResults(unknown, gt, dir / "x.json"); }), HasSubstr("zzz.jpg"));
  WriteText(dir / "bad.json", R"([{"image_id": 99, "bbox": [0,0,1,1], "score": 1}])");
  EXPECT_THAT(ErrorOf([&] { ReadCocoResults(dir / "bad.json", gt); }),
              HasSubstr("[0].image_id: no ground-truth image with id 99"));
  WriteText(dir / "bad2.json", R"([{"image_id": 7, "bbox": [0,0,1,1]}])");
  EXPECT_THAT(ErrorOf([&] { ReadCocoResults(dir / "bad2.json", gt); }),
              HasSubstr("[0]: missing field 'score'"));
}

}  // namespace
}  // namespace orchard
