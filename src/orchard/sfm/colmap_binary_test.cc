#include <cstdlib>

#include <gtest/gtest.h>
#include <unistd.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/sfm/colmap_binary.h"

namespace orchard {
namespace {

ColmapModel SmallModel() {
  ColmapModel m;
  m.cameras[1] = {1, "SIMPLE_RADIAL", 960, 540, {700.5, 480, 270, -0.03}};
  m.cameras[2] = {2, "PINHOLE", 640, 480, {500, 501, 320, 240}};
  ColmapImage a;
  a.image_id = 3, a.camera_id = 1, a.name = "frame_0001.png";
  a.qvec = Eigen::Quaterniond(0.9, 0.1, -0.2, 0.3).normalized();
  a.tvec = {0.5, -1.25, 2};
  a.points2D = {{10.5, 20.25, 7}, {30, 40, -1}};
  ColmapImage b = a;
  b.image_id = 4, b.camera_id = 2, b.name = "frame_0002.png", b.points2D.clear();
  m.images[3] = a, m.images[4] = b;
  ColmapPoint3D p;
  p.point3D_id = 7, p.xyz = {1, 2, 3}, p.r = 200, p.g = 10, p.b = 0, p.error = 0.75;
  p.track = {{3, 0}};
  m.points3D[7] = p;
  return m;
}

TEST(ColmapBinary, RoundTripMatchesTheTextModel) {
  const fs::path dir = fs::temp_directory_path() / ("orchard_colmap_bin_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const ColmapModel m = SmallModel();
  WriteColmapBinaryModel(m, dir / "bin");
  WriteColmapTextModel(m, dir / "txt");
  const ColmapModel b = ReadColmapModel(dir / "bin");
  // Same text as the original once written back: every field survived.
  EXPECT_EQ(ColmapCamerasText(b.cameras), ColmapCamerasText(m.cameras));
  EXPECT_EQ(ColmapImagesText(b.images), ColmapImagesText(m.images));
  EXPECT_EQ(ColmapPoints3DText(b.points3D), ColmapPoints3DText(m.points3D));
  EXPECT_EQ(ColmapImagesText(ReadColmapModel(dir / "txt").images), ColmapImagesText(m.images));
  // Truncated and missing files are errors naming the file.
  const std::string images = ReadTextFile(dir / "bin/images.bin");
  WriteTextFileAtomic(dir / "bin/images.bin", images.substr(0, images.size() - 5));
  try {
    ReadColmapBinaryModel(dir / "bin");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("images.bin"), std::string::npos) << e.what();
  }
  fs::remove(dir / "bin/points3D.bin");
  EXPECT_THROW(ReadColmapBinaryModel(dir / "bin"), Error);
  EXPECT_THROW(ReadColmapModel(dir / "nowhere"), Error);
  fs::create_directories(dir / "empty");
  EXPECT_THROW(ReadColmapModel(dir / "empty"), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
