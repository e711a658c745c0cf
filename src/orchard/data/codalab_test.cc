#include <gtest/gtest.h>

#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/test_util.h"

namespace orchard {
namespace {

using testing_data::ErrorOf;
using testing_data::TempDir;
using testing_data::WriteText;
using ::testing::HasSubstr;

TEST(CodaLabDetections, ReadsWithAndWithoutHeader) {
  TempDir dir;
  WriteText(dir / "a.csv", "image,x1,y1,x2,y2,score\ndataset1_back_1.png,1,2,3.5,4,0.75\n\n"
                           "dataset1_back_1.png, 0, 0, 10, 10, 0.5\r\nb.png,5,6,7,8,1\n");
  WriteText(dir / "b.csv", "dataset1_back_1.png,1,2,3.5,4,0.75\n");
  const Predictions a = ReadCodaLabDetections(dir / "a.csv");
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(a.at("dataset1_back_1.png").size(), 2u);
  const ScoredBox& d = a.at("dataset1_back_1.png")[0];
  EXPECT_DOUBLE_EQ(d.box.x1, 1);
  EXPECT_DOUBLE_EQ(d.box.y1, 2);
  EXPECT_DOUBLE_EQ(d.box.x2, 3.5);
  EXPECT_DOUBLE_EQ(d.box.y2, 4);
  EXPECT_DOUBLE_EQ(d.score, 0.75);
  EXPECT_EQ(ReadCodaLabDetections(dir / "b.csv").at("dataset1_back_1.png").size(), 1u);
  // ReadPredictions picks the CodaLab reader for a csv.
  EXPECT_EQ(ReadPredictions(dir / "a.csv", Dataset{}).size(), 2u);
}

TEST(CodaLabDetections, WriteHasNoHeaderAndRoundTrips) {
  TempDir dir;
  Predictions p;
  p["a.png"] = {{Box{1.25, 2, 30, 40.5}, 0.123456789}};
  p["b.png"] = {{Box{0, 0, 1, 1}, 1}, {Box{2, 2, 3, 3}, 0}};
  WriteCodaLabDetections(p, dir / "d.csv");
  EXPECT_EQ(ReadTextFile(dir / "d.csv"),
            "a.png,1.25,2,30,40.5,0.123456789\nb.png,0,0,1,1,1\nb.png,2,2,3,3,0\n");
  const Predictions back = ReadCodaLabDetections(dir / "d.csv");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_DOUBLE_EQ(back.at("a.png")[0].box.y2, 40.5);
  EXPECT_EQ(back.at("b.png").size(), 2u);
}

TEST(CodaLabDetections, MalformedLinesNameLineAndField) {
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {"a.png,1,2,3,4,0.5\na.png,1,2,3\n", "d.csv:2: expected 6 fields"},
      {"a.png,1,2,3,4,0.5\na.png,1,abc,3,4,0.5\n", "d.csv:2: field 'y1': expected a number, got 'abc'"},
      {"a.png,1,2,3,4,0.5\n\na.png,1,2,3,4,nan\n", "d.csv:3: field 'score': expected a number, got 'nan'"},
      {"a.png,5,2,3,4,0.5\n", "d.csv:1: field 'x2'"},
      {"a.png,1,5,3,4,0.5\n", "d.csv:1: field 'y2'"},
      {",1,2,3,4,0.5\n", "d.csv:1: field 'name'"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    WriteText(dir / "d.csv", c.text);
    EXPECT_THAT(ErrorOf([&] { ReadCodaLabDetections(dir / "d.csv"); }), HasSubstr(c.expected)) << c.text;
  }
  TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadCodaLabDetections(dir / "missing.csv"); }),
              HasSubstr("missing.csv"));
}

TEST(CodaLabCounts, RoundTripAndHeader) {
  TempDir dir;
  WriteText(dir / "c.csv", "image,n_gt\ndataset3_back_0.png,60\n\nb.png, 0\n");
  const std::vector<ImageCount> counts = ReadCodaLabCounts(dir / "c.csv");
  ASSERT_EQ(counts.size(), 2u);
  EXPECT_EQ(counts[0].name, "dataset3_back_0.png");
  EXPECT_EQ(counts[0].count, 60);
  EXPECT_EQ(counts[1].count, 0);
  WriteCodaLabCounts(counts, dir / "out.csv");
  EXPECT_EQ(ReadTextFile(dir / "out.csv"), "dataset3_back_0.png,60\nb.png,0\n");
  const auto back = ReadCodaLabCounts(dir / "out.csv");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].name, "b.png");
}

TEST(CodaLabCounts, RealMinneAppleCountsFile) {
  const auto counts =
      ReadCodaLabCounts(fs::path(ORCHARD_SHARED_DATA_DIR) / "minneapple/test_image_counts.csv");
  ASSERT_EQ(counts.size(), 8u);
  EXPECT_EQ(counts[0].name, "dataset3_back_0.png");
  EXPECT_EQ(counts[0].count, 60);
}

TEST(CodaLabCounts, MalformedLines) {
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {"a.png,1\nb.png,2.5\n", "c.csv:2: field 'count': expected a whole number"},
      {"a.png,1\nb.png,-1\n", "c.csv:2: field 'count': expected a count >= 0"},
      {"a.png,1\nb.png,x\n", "c.csv:2: field 'count': expected a number, got 'x'"},
      {"a.png,1\nb.png\n", "c.csv:2: expected 2 fields"},
      {"a.png,1\na.png,2\n", "c.csv:2: field 'name': image 'a.png' is counted twice"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    WriteText(dir / "c.csv", c.text);
    EXPECT_THAT(ErrorOf([&] { ReadCodaLabCounts(dir / "c.csv"); }), HasSubstr(c.expected)) << c.text;
  }
}

}  // namespace
}  // namespace orchard
