#include "orchard/core/file_io.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/box.h"
#include "orchard/core/error.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("core_test_" + name); }

TEST(FileIo, AtomicWriteReplacesAndLeavesNoTemporary) {
  const fs::path dir = TempDir("atomic");
  WriteTextFileAtomic(dir / "sub" / "a.txt", "one");
  WriteTextFileAtomic(dir / "sub" / "a.txt", "two");
  EXPECT_EQ(ReadTextFile(dir / "sub" / "a.txt"), "two");
  int files = 0;
  for (auto& e : fs::directory_iterator(dir / "sub")) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(FileIo, FailedWriteKeepsEarlierResult) {
  const fs::path dir = TempDir("keep");
  WriteTextFileAtomic(dir / "r.txt", "earlier");
  EXPECT_THROW(WriteFileAtomic(dir / "r.txt", [](const fs::path&) { Fail("boom"); }), Error);
  EXPECT_EQ(ReadTextFile(dir / "r.txt"), "earlier");
}

TEST(FileIo, FingerprintFollowsTheBytes) {
  const fs::path dir = TempDir("fingerprint");
  WriteTextFileAtomic(dir / "m", "");
  EXPECT_EQ(FileFingerprint(dir / "m"), "cbf29ce484222325");  // FNV-1a offset basis: no bytes
  WriteTextFileAtomic(dir / "m", "a");
  EXPECT_EQ(FileFingerprint(dir / "m"), "af63dc4c8601ec8c");  // published FNV-1a 64 of "a"
  const std::string big(200000, 'x');  // more than one read buffer
  WriteTextFileAtomic(dir / "m", big);
  const std::string f = FileFingerprint(dir / "m");
  WriteTextFileAtomic(dir / "m", big.substr(1) + "y");
  EXPECT_NE(FileFingerprint(dir / "m"), f);
  EXPECT_EQ(FileFingerprint(dir / "missing"), "");
}

TEST(FileIo, ReadImageErrors) {
  const fs::path dir = TempDir("img");
  EXPECT_THROW(ReadImage(dir / "missing.png"), Error);
  WriteTextFileAtomic(dir / "corrupt.png", "not a png");
  EXPECT_THROW(ReadImage(dir / "corrupt.png"), Error);
  cv::Mat m(4, 5, CV_8UC3, cv::Scalar(1, 2, 3));
  WriteImageAtomic(dir / "ok.png", m);
  EXPECT_EQ(ReadImage(dir / "ok.png").cols, 5);
  auto list = ListImages(dir);
  EXPECT_EQ(list.size(), 2u);  // corrupt.png and ok.png: listing is by extension
  EXPECT_THROW(ListImages(dir / "nope"), Error);
}

TEST(FileIo, NaturalOrderOfFrameNames) {
  EXPECT_TRUE(NaturalLess("frame_9.png", "frame_10.png"));
  EXPECT_FALSE(NaturalLess("frame_10.png", "frame_9.png"));
  EXPECT_TRUE(NaturalLess("frame_0009.png", "frame_0010.png"));  // padded: plain order
  EXPECT_TRUE(NaturalLess("a2b7", "a2b10"));
  EXPECT_TRUE(NaturalLess("row1_frame_99", "row2_frame_1"));
  EXPECT_TRUE(NaturalLess("frame_7", "frame_007"));  // same number: fewer zeros first
  EXPECT_FALSE(NaturalLess("frame_7", "frame_7"));
  EXPECT_TRUE(NaturalLess("frame", "frame_1"));
  EXPECT_TRUE(NaturalLess("Frame_2", "frame_1"));  // other characters bytewise
  EXPECT_EQ(PadDigitRuns("frame_7.png"), "frame_000007.png");
  EXPECT_EQ(PadDigitRuns("row2_f1234567"), "row000002_f1234567");
  EXPECT_EQ(PadDigitRuns("f12", 3), "f012");
  const fs::path dir = TempDir("natural");
  const cv::Mat m(2, 2, CV_8UC3, cv::Scalar(1, 2, 3));
  for (int i : {10, 2, 1, 100, 11}) WriteImageAtomic(dir / ("frame_" + std::to_string(i) + ".png"), m);
  std::vector<std::string> names;
  for (const auto& p : ListImages(dir)) names.push_back(p.filename().string());
  EXPECT_EQ(names, (std::vector<std::string>{"frame_1.png", "frame_2.png", "frame_10.png", "frame_11.png",
                                             "frame_100.png"}));
  fs::remove_all(dir);
}

TEST(FileIo, SplitCsvLine) {
  EXPECT_EQ(SplitCsvLine("id,x,,count"), (std::vector<std::string>{"id", "x", "", "count"}));
  EXPECT_EQ(SplitCsvLine("a,b,"), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(SplitCsvLine(",a"), (std::vector<std::string>{"", "a"}));
  EXPECT_TRUE(SplitCsvLine("").empty());
}

TEST(Box, IoUKnownValues) {
  Box a{0, 0, 10, 10}, b{5, 0, 15, 10};
  EXPECT_DOUBLE_EQ(IoU(a, b), 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(IoU(a, a), 1.0);
  EXPECT_DOUBLE_EQ(IoU(a, Box{20, 20, 30, 30}), 0.0);
  EXPECT_DOUBLE_EQ(IoU(Box{}, Box{}), 0.0);
}

}  // namespace
}  // namespace orchard
