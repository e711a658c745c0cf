// COLMAP sparse models in the text format (cameras.txt, images.txt,
// points3D.txt): read, write, and the pose helpers the pipeline needs.
// Conventions follow COLMAP: images store the world-to-camera rotation as a
// quaternion (qw qx qy qz) and translation t, so x_cam = R * X_world + t and
// the projection centre is -R^T t; pixel centres are at +0.5.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace orchard {

namespace fs = std::filesystem;

struct ColmapCamera {
  int camera_id = 0;
  std::string model;  // "PINHOLE", "SIMPLE_RADIAL", ...
  int width = 0;
  int height = 0;
  std::vector<double> params;  // in COLMAP's order for the model (PINHOLE: fx fy cx cy)
};

struct ColmapPoint2D {
  double x = 0, y = 0;
  std::int64_t point3D_id = -1;  // -1 when the observation has no 3D point
};

struct ColmapImage {
  int image_id = 0;
  Eigen::Quaterniond qvec = Eigen::Quaterniond::Identity();  // world-to-camera
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();
  int camera_id = 0;
  std::string name;
  std::vector<ColmapPoint2D> points2D;

  Eigen::Matrix3d Rotation() const { return qvec.normalized().toRotationMatrix(); }
  // Camera centre in world coordinates.
  Eigen::Vector3d ProjectionCenter() const { return -Rotation().transpose() * tvec; }
};

struct ColmapTrackElement {
  int image_id = 0;
  int point2D_idx = 0;
};

struct ColmapPoint3D {
  std::int64_t point3D_id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  int r = 0, g = 0, b = 0;
  double error = 0;
  std::vector<ColmapTrackElement> track;
};

struct ColmapModel {
  std::map<int, ColmapCamera> cameras;
  std::map<int, ColmapImage> images;
  std::map<std::int64_t, ColmapPoint3D> points3D;

  // The image with this file name, or nullptr.
  const ColmapImage* FindImage(const std::string& name) const;
};

// Number of parameters of a COLMAP camera model; throws orchard::Error for an
// unknown model name.
int ColmapCameraModelNumParams(const std::string& model);

// Readers throw orchard::Error naming the file and line on malformed input.
std::map<int, ColmapCamera> ReadColmapCamerasText(const fs::path& path);
std::map<int, ColmapImage> ReadColmapImagesText(const fs::path& path);
std::map<std::int64_t, ColmapPoint3D> ReadColmapPoints3DText(const fs::path& path);
// Reads dir/cameras.txt, dir/images.txt and dir/points3D.txt (all three must
// exist) and checks that every image's camera exists.
ColmapModel ReadColmapTextModel(const fs::path& dir);

// Text of each file, in COLMAP's own layout (header comments, 17 digits).
std::string ColmapCamerasText(const std::map<int, ColmapCamera>& cameras);
std::string ColmapImagesText(const std::map<int, ColmapImage>& images);
std::string ColmapPoints3DText(const std::map<std::int64_t, ColmapPoint3D>& points3D);
// Writes the three files into `dir` (created if missing), each atomically.
void WriteColmapTextModel(const ColmapModel& model, const fs::path& dir);

}  // namespace orchard
