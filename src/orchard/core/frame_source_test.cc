#include "orchard/core/frame_source.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

class FrameSourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("orchard_frames_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Frame i is a flat grey of level 20 * i.
  static cv::Mat FrameImage(int i) { return cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(20 * i)); }
  fs::path dir_;
};

TEST_F(FrameSourceTest, FolderInNameOrderWithStep) {
  for (int i = 0; i < 5; ++i) WriteImageAtomic(dir_ / ("f" + std::to_string(i) + ".png"), FrameImage(i));
  WriteTextFileAtomic(dir_ / "notes.txt", "not an image");
  FrameSourceOptions options;
  options.step = 2;
  FrameSource source(dir_, options);
  EXPECT_FALSE(source.IsVideo());
  std::vector<std::string> names;
  Frame frame;
  while (source.Next(&frame)) {
    names.push_back(frame.name);
    EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0)[0], 20 * frame.index);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"f0.png", "f2.png", "f4.png"}));
}

TEST_F(FrameSourceTest, VideoFramesNamedByIndex) {
  const fs::path video = dir_ / "row3.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, {64, 48});
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 7; ++i) writer.write(FrameImage(i));
  }
  FrameSourceOptions options;
  options.step = 3;
  FrameSource source(video, options);
  EXPECT_TRUE(source.IsVideo());
  std::vector<std::string> names;
  Frame frame;
  while (source.Next(&frame)) {
    names.push_back(frame.name);
    EXPECT_EQ(frame.image.size(), cv::Size(64, 48));
    EXPECT_NEAR(frame.image.at<cv::Vec3b>(20, 20)[1], 20 * frame.index, 6);  // MJPG is lossy
  }
  EXPECT_EQ(names, (std::vector<std::string>{"row3_000000.png", "row3_000003.png", "row3_000006.png"}));
  options.step = 1;
  options.max_frames = 2;
  FrameSource limited(video, options);
  int n = 0;
  while (limited.Next(&frame)) ++n;
  EXPECT_EQ(n, 2);
}

TEST_F(FrameSourceTest, ClearErrors) {
  EXPECT_THROW(FrameSource{dir_ / "missing"}, Error);
  EXPECT_THROW(FrameSource{dir_}, Error);  // empty folder
  WriteTextFileAtomic(dir_ / "fake.mp4", "this is not a video");
  EXPECT_THROW(FrameSource{dir_ / "fake.mp4"}, Error);
  const fs::path sub = dir_ / "broken";
  WriteTextFileAtomic(sub / "a.png", "not a png");
  FrameSource source(sub);
  Frame frame;
  EXPECT_THROW(source.Next(&frame), Error);
  FrameSourceOptions bad;
  bad.step = 0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(VideoFrameName, SixDigits) { EXPECT_EQ(VideoFrameName("/a/b/row.mp4", 42), "row_000042.png"); }

}  // namespace
}  // namespace orchard
