// A small software renderer for synthetic orchard scenes: pinhole camera,
// z-buffer, exact ray intersection for apples (spheres), wood (cylinders),
// leaves (planar blades) and the ground plane; procedural textures anchored
// in world coordinates so that structure from motion finds stable features.
#pragma once

#include <cstdint>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "orchard/synth/scene.h"

namespace orchard::synth {

// Intrinsics in COLMAP's PINHOLE convention (pixel centres at +0.5).
struct PinholeCamera {
  int width = 960;
  int height = 540;
  double fx = 0, fy = 0, cx = 0, cy = 0;

  // Square pixels, principal point at the image centre, horizontal field of view.
  static PinholeCamera FromFov(int width, int height, double hfov_deg);
};

// World-to-camera pose: x_cam = R * X + t (camera x right, y down, z forward).
struct CameraPose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  // Camera at `center` looking along `forward`, with world +z as up.
  static CameraPose LookAlong(const Eigen::Vector3d& center, const Eigen::Vector3d& forward);
};

// Pixel coordinates (continuous, COLMAP convention) of a world point; false
// when it is behind the camera.
bool Project(const PinholeCamera& camera, const CameraPose& pose, const Eigen::Vector3d& X, Eigen::Vector2d* uv,
             double* depth = nullptr);

struct RenderOptions {
  // Standard deviation of Gaussian sensor noise in 8-bit levels (0 = none).
  double noise_sigma = 1.5;
  // Horizontal motion blur length in pixels (0 = none), as from camera motion
  // along the row during the exposure.
  int motion_blur_px = 0;
  // Optical softness (Gaussian sigma in pixels) that also hides the
  // renderer's aliasing; 0 = none.
  double lens_blur_sigma = 0.6;
  // Exposure multiplier before the tone curve.
  double exposure = 1.0;

  void Check() const;
};

struct RenderedFrame {
  cv::Mat image;  // CV_8UC3, BGR
  cv::Mat ids;    // CV_16UC1, apple id + 1, 0 elsewhere
  cv::Mat depth;  // CV_32FC1, camera z in metres; +inf for sky
};

// Renders one frame; `noise_seed` drives the sensor noise only.
RenderedFrame RenderFrame(const Scene& scene, const PinholeCamera& camera, const CameraPose& pose,
                          const RenderOptions& options, std::uint64_t noise_seed);

}  // namespace orchard::synth
