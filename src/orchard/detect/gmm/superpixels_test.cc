#include "orchard/detect/gmm/superpixels.h"

#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace {

// A noisy LAB-like test image: coloured discs and a stripe on a textured background.
cv::Mat TestImage(int w, int h) {
  cv::Mat bgr(h, w, CV_8UC3, cv::Scalar(40, 120, 50));
  cv::circle(bgr, {w / 3, h / 2}, h / 5, cv::Scalar(30, 30, 200), cv::FILLED);
  cv::circle(bgr, {2 * w / 3, h / 3}, h / 6, cv::Scalar(40, 200, 220), cv::FILLED);
  cv::rectangle(bgr, {0, 4 * h / 5}, {w, h}, cv::Scalar(60, 70, 90), cv::FILLED);
  cv::Mat noise(h, w, CV_8UC3);
  cv::randn(noise, cv::Scalar::all(0), cv::Scalar::all(12));
  bgr += noise;
  cv::Mat lab;
  cv::cvtColor(bgr, lab, cv::COLOR_BGR2Lab);
  return lab;
}

void CheckSuperpixels(const cv::Mat& lab, const SuperpixelOptions& options) {
  const Superpixels sp = ComputeSuperpixels(lab, options);
  ASSERT_EQ(sp.labels.size(), lab.size());
  ASSERT_GT(sp.num_labels, 1);
  std::vector<int> size(sp.num_labels, 0);
  for (int y = 0; y < lab.rows; ++y)
    for (int x = 0; x < lab.cols; ++x) {
      const int l = sp.labels(y, x);
      ASSERT_GE(l, 0);
      ASSERT_LT(l, sp.num_labels);
      ++size[l];
    }
  // Every label used, and each label one 4-connected region.
  for (int l = 0; l < sp.num_labels; ++l) {
    ASSERT_GT(size[l], 0) << l;
    cv::Mat1b m = sp.labels == l;
    cv::Mat cc;
    EXPECT_EQ(cv::connectedComponents(m, cc, 4), 2) << "label " << l << " is not connected";
  }
  // Mean size near the requested region_size^2.
  const double mean_size = static_cast<double>(lab.total()) / sp.num_labels;
  const double want = options.region_size * options.region_size;
  EXPECT_GT(mean_size, 0.6 * want);
  EXPECT_LT(mean_size, 1.6 * want);
}

TEST(Superpixels, FastSlicLabelsEveryPixelConnectedNearRequestedSize) {
  SuperpixelOptions options;
  options.region_size = 10;
  CheckSuperpixels(TestImage(203, 151), options);
  options.num_threads = 1;
  CheckSuperpixels(TestImage(64, 48), options);
}

TEST(Superpixels, OpenCvReferencePathMeetsTheSameContract) {
  SuperpixelOptions options;
  options.region_size = 10;
  options.use_opencv = true;
  CheckSuperpixels(TestImage(203, 151), options);
}

TEST(Superpixels, ThreadCountDoesNotChangeTheResult) {
  const cv::Mat lab = TestImage(160, 120);
  SuperpixelOptions options;
  options.region_size = 8;
  options.num_threads = 1;
  const Superpixels a = ComputeSuperpixels(lab, options);
  options.num_threads = 2;
  const Superpixels b = ComputeSuperpixels(lab, options);
  EXPECT_EQ(a.num_labels, b.num_labels);
  EXPECT_EQ(cv::countNonZero(a.labels != b.labels), 0);
}

TEST(Superpixels, AdhereToColourEdges) {
  // Two flat halves: no superpixel may straddle the edge.
  cv::Mat lab(60, 80, CV_8UC3, cv::Scalar(100, 100, 100));
  lab(cv::Rect(37, 0, 43, 60)).setTo(cv::Scalar(200, 160, 160));
  SuperpixelOptions options;
  options.region_size = 10;
  const Superpixels sp = ComputeSuperpixels(lab, options);
  const SuperpixelColours colours = ComputeSuperpixelColours(lab, sp);
  for (int l = 0; l < sp.num_labels; ++l) {
    EXPECT_LT(colours.covariance[l].trace(), 1e-9) << "superpixel " << l << " mixes both halves";
  }
  // Colour statistics in CIELAB units: 8-bit (100,100,100) -> (39.2, -28, -28).
  const int left = sp.labels(30, 5);
  EXPECT_NEAR(colours.mean[left][0], 100 * 100.0 / 255, 1e-9);
  EXPECT_NEAR(colours.mean[left][1], -28, 1e-9);
}

TEST(Superpixels, RejectsBadInput) {
  SuperpixelOptions options;
  EXPECT_THROW(ComputeSuperpixels(cv::Mat(), options), Error);
  EXPECT_THROW(ComputeSuperpixels(cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)), options), Error);
  options.region_size = 1;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace orchard
