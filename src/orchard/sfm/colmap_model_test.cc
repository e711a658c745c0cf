#include "orchard/sfm/colmap_model.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/test_util.h"
#include "orchard/sfm/camera_view.h"

namespace orchard {
namespace {

fs::path TempDir(const std::string& name) { return test::FreshTempDir("colmap_test_" + name); }

// A model as COLMAP writes it (values from a COLMAP 3.8 model_converter output layout).
const char* kCameras =
    "# Camera list with one line of data per camera:\n"
    "1 PINHOLE 960 540 572.5 572.5 480 270\n"
    "2 SIMPLE_RADIAL 640 480 500 320 240 0.01\n";
const char* kImages =
    "# Image list with two lines of data per image:\n"
    "1 1 0 0 0 -1 2 3 1 a.png\n"
    "10.5 20.25 7 30 40 -1\n"
    "2 0.70710678118654757 0 0.70710678118654757 0 0 0 1 2 b.png\n"
    "\n";
const char* kPoints = "7 1.5 -2 3 255 0 10 0.25 1 0 1 1\n";

TEST(ColmapModel, ReadsKnownValues) {
  const fs::path dir = TempDir("known");
  WriteTextFileAtomic(dir / "cameras.txt", kCameras);
  WriteTextFileAtomic(dir / "images.txt", kImages);
  WriteTextFileAtomic(dir / "points3D.txt", kPoints);
  const ColmapModel model = ReadColmapTextModel(dir);
  ASSERT_EQ(model.cameras.size(), 2u);
  EXPECT_EQ(model.cameras.at(1).model, "PINHOLE");
  EXPECT_EQ(model.cameras.at(1).params, (std::vector<double>{572.5, 572.5, 480, 270}));
  ASSERT_EQ(model.images.size(), 2u);
  const ColmapImage& a = model.images.at(1);
  EXPECT_EQ(a.name, "a.png");
  ASSERT_EQ(a.points2D.size(), 2u);
  EXPECT_EQ(a.points2D[0].point3D_id, 7);
  EXPECT_EQ(a.points2D[1].point3D_id, -1);
  EXPECT_DOUBLE_EQ(a.points2D[0].y, 20.25);
  // Identity rotation: the centre is -t.
  EXPECT_TRUE(a.ProjectionCenter().isApprox(Eigen::Vector3d(1, -2, -3)));
  // 90 degrees about y, t = (0, 0, 1): x_cam = R X + t; centre C = -R^T t.
  const ColmapImage& b = model.images.at(2);
  EXPECT_TRUE(b.points2D.empty());
  const Eigen::Vector3d c = b.ProjectionCenter();
  EXPECT_NEAR(c.x(), 1.0, 1e-12);
  EXPECT_NEAR(c.y(), 0.0, 1e-12);
  EXPECT_NEAR(c.z(), 0.0, 1e-12);
  EXPECT_NEAR((b.Rotation() * c + b.tvec).norm(), 0.0, 1e-12);
  ASSERT_EQ(model.points3D.size(), 1u);
  EXPECT_EQ(model.points3D.at(7).track.size(), 2u);
  EXPECT_EQ(model.points3D.at(7).r, 255);
  EXPECT_EQ(model.FindImage("b.png"), &model.images.at(2));
  EXPECT_EQ(model.FindImage("c.png"), nullptr);
}

TEST(ColmapModel, ViewsInFrameOrderEvenWithoutLeadingZeros) {
  ColmapModel model;
  model.cameras[1] = ColmapCamera{1, "PINHOLE", 960, 540, {572.5, 572.5, 480, 270}};
  int id = 1;
  for (const char* name : {"frame_10.png", "frame_9.png", "frame_1.png", "frame_100.png"}) {
    ColmapImage image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = name;
    image.tvec = Eigen::Vector3d(id, 0, 0);
    model.images[id++] = image;
  }
  std::vector<std::string> names;
  for (const auto& v : ViewsFromColmapModel(model)) names.push_back(v.name);
  EXPECT_EQ(names, (std::vector<std::string>{"frame_1.png", "frame_9.png", "frame_10.png", "frame_100.png"}));
}

TEST(ColmapModel, RoundTripIsExact) {
  const fs::path dir = TempDir("roundtrip");
  WriteTextFileAtomic(dir / "cameras.txt", kCameras);
  WriteTextFileAtomic(dir / "images.txt", kImages);
  WriteTextFileAtomic(dir / "points3D.txt", kPoints);
  ColmapModel model = ReadColmapTextModel(dir);
  model.images.at(1).qvec = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  model.images.at(1).tvec = Eigen::Vector3d(0.1, 1.0 / 3.0, -7.25);
  const fs::path out = dir / "out";
  WriteColmapTextModel(model, out);
  const ColmapModel again = ReadColmapTextModel(out);
  ASSERT_EQ(again.images.size(), model.images.size());
  for (const auto& [id, image] : model.images) {
    const ColmapImage& other = again.images.at(id);
    EXPECT_EQ(other.name, image.name);
    EXPECT_EQ(other.qvec.coeffs(), image.qvec.coeffs());
    EXPECT_EQ(other.tvec, image.tvec);
    EXPECT_EQ(other.points2D.size(), image.points2D.size());
  }
  EXPECT_EQ(again.cameras.at(2).params, model.cameras.at(2).params);
  EXPECT_EQ(again.points3D.at(7).xyz, model.points3D.at(7).xyz);
  // Writing again gives the same bytes.
  EXPECT_EQ(ReadTextFile(out / "images.txt"), ColmapImagesText(again.images));
}

using test::ExpectErrorContains;

TEST(ColmapModel, MalformedInputGivesClearErrors) {
  const fs::path dir = TempDir("bad");
  WriteTextFileAtomic(dir / "c1.txt", "1 PINHOLE 960 540 572.5 572.5 480\n");
  ExpectErrorContains([&] { ReadColmapCamerasText(dir / "c1.txt"); }, "c1.txt:1: model PINHOLE needs 4");
  WriteTextFileAtomic(dir / "c2.txt", "# x\n1 PINHOLE 960 540 572.5 abc 480 270\n");
  ExpectErrorContains([&] { ReadColmapCamerasText(dir / "c2.txt"); }, "c2.txt:2: parameter is not a number");
  WriteTextFileAtomic(dir / "c3.txt", "1 WEIRD 960 540 1 2 3\n");
  ExpectErrorContains([&] { ReadColmapCamerasText(dir / "c3.txt"); }, "unknown COLMAP camera model");
  WriteTextFileAtomic(dir / "i1.txt", "1 1 0 0 0 0 0 0 1\n\n");
  ExpectErrorContains([&] { ReadColmapImagesText(dir / "i1.txt"); }, "i1.txt:1: expected IMAGE_ID");
  WriteTextFileAtomic(dir / "i2.txt", "1 1 0 0 0 0 0 0 1 a.png\n1 2\n");
  ExpectErrorContains([&] { ReadColmapImagesText(dir / "i2.txt"); }, "i2.txt:2: 2D points line");
  WriteTextFileAtomic(dir / "p1.txt", "1 0 0 0 1 2 3\n");
  ExpectErrorContains([&] { ReadColmapPoints3DText(dir / "p1.txt"); }, "p1.txt:1: expected POINT3D_ID");
  ExpectErrorContains([&] { ReadColmapTextModel(dir / "nowhere"); }, "folder not found");
  ExpectErrorContains([&] { ReadColmapTextModel(dir); }, "has no cameras.txt");
  // An image whose camera is missing.
  WriteTextFileAtomic(dir / "m/cameras.txt", "");
  WriteTextFileAtomic(dir / "m/images.txt", "1 1 0 0 0 0 0 0 3 a.png\n\n");
  WriteTextFileAtomic(dir / "m/points3D.txt", "");
  ExpectErrorContains([&] { ReadColmapTextModel(dir / "m"); }, "uses camera 3");
}

}  // namespace
}  // namespace orchard
