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

TEST(Box, IoUKnownValues) {
  Box a{0, 0, 10, 10}, b{5, 0, 15, 10};
  EXPECT_DOUBLE_EQ(IoU(a, b), 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(IoU(a, a), 1.0);
  EXPECT_DOUBLE_EQ(IoU(a, Box{20, 20, 30, 30}), 0.0);
  EXPECT_DOUBLE_EQ(IoU(Box{}, Box{}), 0.0);
}

}  // namespace
}  // namespace orchard
