// Runs the built `orchard convert` (env ORCHARD_BIN) end to end.
#include <cstdlib>

#include <sys/wait.h>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <nlohmann/json.hpp>

#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::TempDir;
using testing_data::WriteBlankImage;
using testing_data::WriteText;
using ::testing::HasSubstr;

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

RunResult RunOrchard(const std::string& args, const fs::path& log) {
  const char* bin = std::getenv("ORCHARD_BIN");
  const std::string command = std::string("'") + bin + "' " + args + " > '" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = ReadTextFile(log);
  return result;
}

class ConvertCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* bin = std::getenv("ORCHARD_BIN");
    if (bin == nullptr || !fs::exists(bin)) GTEST_SKIP() << "ORCHARD_BIN not set or not built";
  }
  std::string Q(const fs::path& p) { return "'" + p.string() + "'"; }
};

TEST_F(ConvertCommand, MasksToCocoToYoloToMasks) {
  TempDir dir;
  WriteBlankImage(dir / "mn/images/f1.png", 40, 30);
  fs::create_directories(dir / "mn/masks");
  cv::Mat ids(30, 40, CV_16U, cv::Scalar(0));
  ids(cv::Rect(5, 5, 10, 10)).setTo(3);
  ids(cv::Rect(20, 10, 6, 4)).setTo(9);
  cv::imwrite((dir / "mn/masks/f1.png").string(), ids);

  // MinneApple -> COCO (format detected): boxes, pixel areas, polygons.
  RunResult r = RunOrchard("convert --to coco --in " + Q(dir / "mn") + " --out " + Q(dir / "c.json"),
                           dir / "log1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("converted 1 images, 2 objects"));
  const auto json = nlohmann::json::parse(ReadTextFile(dir / "c.json"));
  ASSERT_EQ(json["annotations"].size(), 2u);
  EXPECT_EQ(json["annotations"][0]["bbox"], nlohmann::json::array({5, 5, 10, 10}));
  EXPECT_EQ(json["annotations"][0]["area"], 100);
  EXPECT_EQ(json["annotations"][1]["bbox"], nlohmann::json::array({20, 10, 6, 4}));
  EXPECT_TRUE(json["annotations"][0].contains("segmentation"));

  // COCO -> YOLO (images found beside the json? no: give them).
  r = RunOrchard("convert --from coco --to yolo --in " + Q(dir / "c.json") + " --images " +
                     Q(dir / "mn/images") + " --out " + Q(dir / "yolo"),
                 dir / "log2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "yolo/images/f1.png"));
  const Dataset yolo = ReadYolo(dir / "yolo");
  ASSERT_EQ(yolo.NumObjects(), 2u);
  EXPECT_NEAR(yolo.images[0].objects[1].box.x1, 20, 1e-3);
  EXPECT_NEAR(yolo.images[0].objects[1].box.y2, 14, 1e-3);

  // YOLO -> MinneApple: filled boxes, same pixels as the original masks.
  r = RunOrchard("convert --from yolo --to minneapple --in " + Q(dir / "yolo") + " --out " +
                     Q(dir / "mn2"),
                 dir / "log3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat back = cv::imread((dir / "mn2/masks/f1.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::countNonZero(back != 0), cv::countNonZero(ids != 0));
  EXPECT_EQ(cv::countNonZero((back != 0) != (ids != 0)), 0);
}

TEST_F(ConvertCommand, ViaToCoco) {
  TempDir dir;
  WriteText(dir / "via.json", R"({"a.png123": {"filename": "a.png", "size": 123, "regions": [
      {"shape_attributes": {"name": "rect", "x": 2, "y": 3, "width": 4, "height": 5}}]}})");
  WriteBlankImage(dir / "images/a.png", 20, 20);
  const RunResult r = RunOrchard(
      "convert --to coco --in " + Q(dir / "via.json") + " --out " + Q(dir / "c.json"), dir / "log");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto json = nlohmann::json::parse(ReadTextFile(dir / "c.json"));
  EXPECT_EQ(json["images"][0]["width"], 20);
  EXPECT_EQ(json["annotations"][0]["bbox"], nlohmann::json::array({2, 3, 4, 5}));
}

TEST_F(ConvertCommand, BadInputFailsWithOneLineReason) {
  TempDir dir;
  WriteBlankImage(dir / "y/images/a.png", 10, 10);
  WriteText(dir / "y/labels/a.txt", "0 0.5 0.5 0.1 zz\n");
  struct Case {
    std::string args, expected;
  };
  const Case cases[] = {
      {"convert --to coco --in " + Q(dir / "y") + " --out " + Q(dir / "o.json"),
       "a.txt:1: field 'h': expected a number, got 'zz'"},
      {"convert --to via --in " + Q(dir / "y") + " --out " + Q(dir / "o"), "VIA is read only"},
      {"convert --to pascal --in " + Q(dir / "y") + " --out " + Q(dir / "o"),
       "unknown dataset format 'pascal'"},
      {"convert --from voc --to coco --in " + Q(dir / "y") + " --out " + Q(dir / "o.json"),
       "unknown dataset format 'voc'"},
      {"convert --to coco --in " + Q(dir / "missing") + " --out " + Q(dir / "o.json"),
       "dataset not found"},
      {"convert --to coco --in " + Q(dir / "y") + " --out " + Q(dir / "o"), "must end in .json"},
  };
  for (const Case& c : cases) {
    const RunResult r = RunOrchard(c.args, dir / "log");
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr("orchard: error: ")) << c.args;
    EXPECT_THAT(r.output, HasSubstr(c.expected)) << c.args;
  }
  EXPECT_FALSE(fs::exists(dir / "o.json"));
}

}  // namespace
}  // namespace orchard
