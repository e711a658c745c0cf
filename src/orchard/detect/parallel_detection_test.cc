#include "orchard/detect/parallel_detection.h"

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "orchard/core/error.h"

namespace orchard {
namespace {

// Reports the frame's grey level as its one blob's score; takes longer on
// some frames so that threads finish out of order; fails on `fail_at`.
class GreyLevelDetector : public Detector {
 public:
  explicit GreyLevelDetector(int fail_at = -1) : fail_at_(fail_at) {}
  FrameDetection Detect(const cv::Mat& bgr) override {
    if (busy_.exchange(true)) shared_ = true;  // another thread is inside this detector
    const int level = bgr.at<cv::Vec3b>(0, 0)[0];
    std::this_thread::sleep_for(std::chrono::milliseconds(level % 3 == 0 ? 6 : 1));
    busy_ = false;
    if (level == fail_at_) Fail("cannot detect in frame ", level);
    FrameDetection d;
    Blob b;
    b.id = 1;
    b.score = level;
    d.blobs.push_back(b);
    return d;
  }
  bool WasShared() const { return shared_; }

 private:
  int fail_at_;
  std::atomic<bool> busy_{false}, shared_{false};
};

FrameReader CountingReader(int num_frames, int fail_at = -1) {
  auto next = std::make_shared<int>(0);
  return [=](Frame* frame) {
    if (*next == num_frames) return false;
    if (*next == fail_at) Fail("cannot read frame ", *next);
    frame->index = (*next)++;
    frame->name = std::to_string(frame->index);
    frame->image = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(frame->index));
    return true;
  };
}

std::vector<std::unique_ptr<Detector>> GreyLevelDetectors(int n, int fail_at = -1) {
  std::vector<std::unique_ptr<Detector>> detectors;
  for (int i = 0; i < n; ++i) detectors.push_back(std::make_unique<GreyLevelDetector>(fail_at));
  return detectors;
}

TEST(DetectFrames, EveryFrameInOrderWithItsOwnDetection) {
  for (int workers : {1, 2, 3}) {
    const auto detectors = GreyLevelDetectors(workers);
    std::vector<int> order;
    DetectFrames(detectors, CountingReader(40), [&](Frame& frame, FrameDetection& d) {
      ASSERT_EQ(d.blobs.size(), 1u);
      EXPECT_EQ(d.blobs[0].score, frame.index);  // the detection belongs to this frame
      order.push_back(frame.index);
    });
    ASSERT_EQ(order.size(), 40u) << workers << " workers";
    for (int i = 0; i < 40; ++i) EXPECT_EQ(order[i], i);
    for (const auto& d : detectors) EXPECT_FALSE(static_cast<GreyLevelDetector&>(*d).WasShared());
  }
}

TEST(DetectFrames, DetectorErrorStopsTheRunAndKeepsEarlierFramesInOrder) {
  const auto detectors = GreyLevelDetectors(2, /*fail_at=*/7);
  std::vector<int> order;
  try {
    DetectFrames(detectors, CountingReader(40), [&](Frame& frame, FrameDetection&) { order.push_back(frame.index); });
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "cannot detect in frame 7");
  }
  ASSERT_EQ(order.size(), 7u);  // frames 0..6, none after the failed one
  for (int i = 0; i < 7; ++i) EXPECT_EQ(order[i], i);
}

TEST(DetectFrames, ReaderAndSinkErrorsReachTheCaller) {
  const auto detectors = GreyLevelDetectors(2);
  int sunk = 0;
  EXPECT_THROW(DetectFrames(detectors, CountingReader(40, /*fail_at=*/5), [&](Frame&, FrameDetection&) { ++sunk; }),
               Error);
  EXPECT_EQ(sunk, 5);  // every frame read before the failed one
  sunk = 0;
  EXPECT_THROW(DetectFrames(detectors, CountingReader(40),
                            [&](Frame& frame, FrameDetection&) {
                              if (frame.index == 3) Fail("disk full");
                              ++sunk;
                            }),
               Error);
  EXPECT_EQ(sunk, 3);
  EXPECT_THROW(DetectFrames({}, CountingReader(1), [](Frame&, FrameDetection&) {}), Error);
}

}  // namespace
}  // namespace orchard
