// SLIC superpixels (Achanta et al. 2012) on 8-bit CIELAB images: a fast
// implementation of the project's own (grid seeds, each pixel compared with the
// 3x3 neighbouring seeds only, float arithmetic in vectorisable row loops, rows
// split over threads, connectivity enforced) and OpenCV's
// cv::ximgproc::createSuperpixelSLIC as the reference path. Also the
// per-superpixel colour statistics the colour model works on.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace orchard {

struct SuperpixelOptions {
  // Desired superpixel side in pixels of the image given to ComputeSuperpixels.
  int region_size = 16;
  // SLIC compactness m: colour distance (8-bit LAB units) worth one region_size
  // of spatial distance. Larger = more regular, less colour-adherent. OpenCV's "ruler".
  double compactness = 10.0;
  // Assignment/update rounds (fast path; SLIC converges in a few). The
  // reference path always runs OpenCV's recommended 10.
  int iterations = 4;
  // Segments smaller than this fraction of region_size^2 are merged into a
  // neighbour when connectivity is enforced (OpenCV's min_element_size = 25 %).
  double min_size_fraction = 0.25;
  // Threads for the fast path (rows are split into this many bands).
  int num_threads = 2;
  // Use OpenCV's SLIC instead of the fast implementation.
  bool use_opencv = false;

  void Check() const;
};

struct Superpixels {
  cv::Mat1i labels;    // 0 .. num_labels-1 for every pixel
  int num_labels = 0;
};

// Superpixels of an 8-bit LAB image (cv::cvtColor(..., COLOR_BGR2Lab)). Every
// pixel gets a label, labels are 0..num_labels-1 and each label is one
// 4-connected region.
Superpixels ComputeSuperpixels(const cv::Mat& lab8, const SuperpixelOptions& options);

// Mean and covariance of the CIELAB colours (L in 0..100, a and b in -128..127,
// converted from OpenCV's 8-bit encoding) of each superpixel, and its size.
struct SuperpixelColours {
  std::vector<Eigen::Vector3d> mean;
  std::vector<Eigen::Matrix3d> covariance;
  std::vector<int> pixels;
};
SuperpixelColours ComputeSuperpixelColours(const cv::Mat& lab8, const Superpixels& superpixels,
                                           int num_threads = 2);

// OpenCV 8-bit LAB value -> CIELAB units.
inline Eigen::Vector3d LabFrom8Bit(double l8, double a8, double b8) {
  return {l8 * (100.0 / 255.0), a8 - 128.0, b8 - 128.0};
}
// CIELAB units -> OpenCV 8-bit LAB value (not rounded or clamped).
inline Eigen::Vector3d Lab8BitFrom(const Eigen::Vector3d& lab) {
  return {lab[0] * (255.0 / 100.0), lab[1] + 128.0, lab[2] + 128.0};
}

}  // namespace orchard
