#include "orchard/synth/synth.h"

#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/sfm/colmap_model.h"
#include "orchard/core/test_util.h"

namespace orchard::synth {
namespace {

// A one-tree row at low resolution: a few frames per side, seconds to make.
SynthOptions SmallOptions() {
  SynthOptions o;
  o.scene.num_trees = 1;
  o.scene.apples_per_tree = 40;
  o.scene.background_rows = false;
  o.scene.leaf_density = 0.7;
  o.camera.width = 240;
  o.camera.height_px = 136;
  o.camera.speed = 0.3;
  o.camera.fps = 1;  // 0.3 m per frame: 5 frames per side
  o.min_visible_pixels = 6;
  o.patch_every = 2;
  o.threads = 2;
  o.progress = false;
  o.seed = 7;
  return o;
}

struct AppleRow {
  int id, tree, row;
  double x, y, z, radius;
  bool front, back, ground;
};

std::vector<AppleRow> ReadApples(const fs::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("id,tree,row,x,y,z,radius,colour,cluster,visible_front,visible_back,on_ground", 0), 0u);
  std::vector<AppleRow> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    EXPECT_EQ(f.size(), 14u) << line;
    if (f.size() != 14) continue;
    rows.push_back({std::stoi(f[0]), std::stoi(f[1]), std::stoi(f[2]), std::stod(f[3]), std::stod(f[4]),
                    std::stod(f[5]), std::stod(f[6]), f[9] == "1", f[10] == "1", f[11] == "1"});
  }
  return rows;
}

class SynthOutput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // Per process: ctest runs the tests of this suite in parallel processes.
    dir_ = test::FreshTempDir("synth_test");
    summary_ = RunSynth(SmallOptions(), dir_);
  }
  static fs::path dir_;
  static SynthSummary summary_;
};
fs::path SynthOutput::dir_;
SynthSummary SynthOutput::summary_;

TEST_F(SynthOutput, WritesTheDocumentedLayout) {
  for (const char* side : {"front", "back"}) {
    const fs::path s = dir_ / side;
    EXPECT_EQ(ListImages(s / "images").size(), 5u);
    EXPECT_EQ(ListImages(s / "masks").size(), 5u);
    EXPECT_TRUE(fs::exists(s / "labels" / "frame_0000.txt"));
    EXPECT_TRUE(fs::exists(s / "scene.json"));
    const ColmapModel model = ReadColmapTextModel(s / "sparse");
    EXPECT_EQ(model.images.size(), 5u);
    EXPECT_TRUE(model.points3D.empty());
    const cv::Mat mask = cv::imread((s / "masks" / "frame_0000.png").string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(mask.type(), CV_16UC1);
  }
  EXPECT_TRUE(fs::exists(dir_ / "patches" / "counts.csv"));
  EXPECT_EQ(summary_.frames_per_side, 5);
}

TEST_F(SynthOutput, GroundTruthIsSelfConsistent) {
  const auto apples = ReadApples(dir_ / "apples.csv");
  ASSERT_FALSE(apples.empty());
  std::map<int, AppleRow> by_id;
  for (const auto& a : apples) by_id[a.id] = a;
  const int min_pixels = SmallOptions().min_visible_pixels;
  for (const char* side : {"front", "back"}) {
    std::map<int, int> max_pixels;  // from the masks
    for (const fs::path& mask_path : ListImages(dir_ / side / "masks")) {
      const cv::Mat mask = cv::imread(mask_path.string(), cv::IMREAD_UNCHANGED);
      std::map<int, int> pixels;
      std::map<int, cv::Rect> bounds;
      for (int y = 0; y < mask.rows; ++y) {
        for (int x = 0; x < mask.cols; ++x) {
          const int v = mask.at<std::uint16_t>(y, x);
          if (!v) continue;
          ++pixels[v - 1];
          auto it = bounds.find(v - 1);
          if (it == bounds.end()) bounds[v - 1] = cv::Rect(x, y, 1, 1);
          else it->second |= cv::Rect(x, y, 1, 1);
        }
      }
      for (const auto& [id, n] : pixels) {
        ASSERT_TRUE(by_id.count(id)) << "mask id " << id + 1 << " not in apples.csv";
        EXPECT_GE(n, min_pixels);  // smaller fragments are left out of the mask
        max_pixels[id] = std::max(max_pixels[id], n);
      }
      // YOLO boxes: one per apple in the mask, equal to the mask bounds.
      std::istringstream labels(ReadTextFile(dir_ / side / "labels" / (mask_path.stem().string() + ".txt")));
      std::vector<cv::Rect> boxes;
      std::string line;
      while (std::getline(labels, line)) {
        int cls;
        double cx, cy, w, h;
        ASSERT_EQ(std::sscanf(line.c_str(), "%d %lf %lf %lf %lf", &cls, &cx, &cy, &w, &h), 5) << line;
        EXPECT_EQ(cls, 0);
        boxes.emplace_back(static_cast<int>(std::lround((cx - w / 2) * mask.cols)),
                           static_cast<int>(std::lround((cy - h / 2) * mask.rows)),
                           static_cast<int>(std::lround(w * mask.cols)), static_cast<int>(std::lround(h * mask.rows)));
      }
      ASSERT_EQ(boxes.size(), bounds.size()) << mask_path;
      for (const auto& [id, r] : bounds) {
        EXPECT_NE(std::find(boxes.begin(), boxes.end(), r), boxes.end()) << "no YOLO box equals the mask bounds of "
                                                                           << id << " in " << mask_path;
      }
    }
    // Visible from this side <=> seen in some frame of it.
    const bool front = std::string(side) == "front";
    for (const auto& a : apples) {
      const bool visible = front ? a.front : a.back;
      EXPECT_EQ(visible, max_pixels.count(a.id) > 0) << side << " apple " << a.id;
    }
  }
  // truth.json counts recomputed from apples.csv.
  const auto truth = nlohmann::json::parse(ReadTextFile(dir_ / "truth.json"));
  int harvested = 0, vf = 0, vb = 0, any = 0, both = 0, fallen = 0;
  for (const auto& a : apples) {
    if (a.row != 0) continue;
    if (a.ground) {
      ++fallen;
      continue;
    }
    ++harvested;
    vf += a.front;
    vb += a.back;
    any += a.front || a.back;
    both += a.front && a.back;
  }
  EXPECT_EQ(truth["harvested"].get<int>(), harvested);
  EXPECT_EQ(truth["visible_front"].get<int>(), vf);
  EXPECT_EQ(truth["visible_back"].get<int>(), vb);
  EXPECT_EQ(truth["visible_any"].get<int>(), any);
  EXPECT_EQ(truth["visible_both"].get<int>(), both);
  EXPECT_EQ(truth["fallen"].get<int>(), fallen);
  EXPECT_EQ(truth["seed"].get<int>(), 7);
  EXPECT_GT(harvested, 20);
  EXPECT_GT(vf, 0);
  EXPECT_LT(any, harvested + 1);
  int per_tree_total = 0;
  for (const auto& t : truth["per_tree"]) per_tree_total += t["harvested"].get<int>();
  EXPECT_EQ(per_tree_total, harvested);
}

TEST_F(SynthOutput, TruePosesProjectApplesOntoTheirMasks) {
  const auto apples = ReadApples(dir_ / "apples.csv");
  int checked = 0;
  for (const char* side : {"front", "back"}) {
    const ColmapModel model = ReadColmapTextModel(dir_ / side / "sparse");
    const ColmapCamera& cam = model.cameras.at(1);
    ASSERT_EQ(cam.model, "PINHOLE");
    for (const auto& [id, image] : model.images) {
      const cv::Mat mask =
          cv::imread((dir_ / side / "masks" / image.name).string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(mask.empty());
      for (const auto& a : apples) {
        // An apple whose pixels surround its projected centre must own that pixel.
        const Eigen::Vector3d p = image.Rotation() * Eigen::Vector3d(a.x, a.y, a.z) + image.tvec;
        if (p.z() <= 0) continue;
        const double u = cam.params[0] * p.x() / p.z() + cam.params[2];
        const double v = cam.params[1] * p.y() / p.z() + cam.params[3];
        const int x = static_cast<int>(std::floor(u)), y = static_cast<int>(std::floor(v));
        if (x < 1 || y < 1 || x + 1 >= mask.cols || y + 1 >= mask.rows) continue;
        bool all = true, any = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const bool own = mask.at<std::uint16_t>(y + dy, x + dx) == a.id + 1;
            all &= own;
            any |= own;
          }
        }
        if (all) ++checked;
        // Where the centre's 3x3 neighbourhood is this apple's, the centre pixel is too.
        if (any && mask.at<std::uint16_t>(y, x) != 0) {
          const int owner = mask.at<std::uint16_t>(y, x) - 1;
          const auto& o = apples[owner];
          // The owner is this apple or one in front of it along the ray.
          if (owner != a.id) {
            const Eigen::Vector3d q = image.Rotation() * Eigen::Vector3d(o.x, o.y, o.z) + image.tvec;
            EXPECT_LT(q.z() - o.radius, p.z()) << "apple " << a.id << " centre pixel owned by a farther apple";
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 10);
}

TEST(Renderer, SingleAppleProjectsWhereTheMaskSays) {
  Scene scene;
  scene.options.background_rows = false;
  scene.sun_direction = Vec3(0, -1, 1).normalized();
  Apple a;
  a.center = Vec3(0.3, 0.1, 1.6);
  a.radius = 0.04;
  a.base_color = {0.4f, 0.1f, 0.1f};
  scene.apples.push_back(a);
  const PinholeCamera camera = PinholeCamera::FromFov(320, 200, 60);
  const CameraPose pose = CameraPose::LookAlong(Vec3(0, -2, 1.5), Vec3(0, 1, 0));
  RenderOptions options;
  options.noise_sigma = 0;
  const RenderedFrame frame = RenderFrame(scene, camera, pose, options, 1);
  Eigen::Vector2d uv;
  double depth = 0;
  ASSERT_TRUE(Project(camera, pose, a.center, &uv, &depth));
  // Camera looks along +y from y = -2: depth 2.1, x right, z up = image up.
  EXPECT_NEAR(depth, 2.1, 1e-12);
  EXPECT_NEAR(uv.x(), camera.cx + camera.fx * 0.3 / 2.1, 1e-9);
  EXPECT_NEAR(uv.y(), camera.cy - camera.fy * 0.1 / 2.1, 1e-9);
  EXPECT_EQ(frame.ids.at<std::uint16_t>(static_cast<int>(uv.y()), static_cast<int>(uv.x())), 1);
  // Area of the silhouette: a circle of radius f r / sqrt(d^2 - r^2) (to a pixel's rim).
  const double r_px = camera.fx * a.radius / std::sqrt(depth * depth - a.radius * a.radius);
  const double area = cv::countNonZero(frame.ids);
  EXPECT_NEAR(area, M_PI * r_px * r_px, 2 * M_PI * r_px);
  EXPECT_NEAR(frame.depth.at<float>(static_cast<int>(uv.y()), static_cast<int>(uv.x())), depth - a.radius, 0.01);
}

TEST(Synth, SameSeedGivesByteIdenticalOutput) {
  SynthOptions o = SmallOptions();
  o.camera.sides = "front";
  o.camera.width = 120;
  o.camera.height_px = 68;
  const fs::path a = test::FreshTempDir("synth_det_a");
  const fs::path b = test::FreshTempDir("synth_det_b");
  fs::remove_all(a);
  fs::remove_all(b);
  RunSynth(o, a);
  o.threads = 1;  // thread count must not matter
  RunSynth(o, b);
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a)) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), a);
    ASSERT_TRUE(fs::exists(b / rel)) << rel;
    EXPECT_EQ(ReadTextFile(entry.path()), ReadTextFile(b / rel)) << rel;
    ++files;
  }
  EXPECT_GT(files, 15);
  // A different seed gives a different row.
  o.seed = 8;
  const fs::path c = test::FreshTempDir("synth_det_c");
  fs::remove_all(c);
  RunSynth(o, c);
  EXPECT_NE(ReadTextFile(a / "apples.csv"), ReadTextFile(c / "apples.csv"));
}

void ExpectOptionError(const std::function<void(SynthOptions&)>& change, const std::string& needle) {
  SynthOptions o = SmallOptions();
  change(o);
  try {
    RunSynth(o, test::FreshTempDir("synth_bad") / "out");
    ADD_FAILURE() << "no error for " << needle;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Synth, BadOptionsGiveClearErrors) {
  ExpectOptionError([](SynthOptions& o) { o.scene.num_trees = -1; }, "--trees must be in 1..200, got -1");
  ExpectOptionError([](SynthOptions& o) { o.camera.width = 0; }, "--width and --height");
  ExpectOptionError([](SynthOptions& o) { o.camera.fps = 0; }, "--fps");
  ExpectOptionError([](SynthOptions& o) { o.scene.canopy_shape = "cube"; }, "--canopy must be planar or round");
  ExpectOptionError([](SynthOptions& o) { o.scene.variety = "pear"; }, "--variety");
  ExpectOptionError([](SynthOptions& o) { o.camera.distance = 0.6; }, "inside the canopy");
  ExpectOptionError([](SynthOptions& o) { o.scene.apple_radius_min = 0.06; }, "apple radius range");
  ExpectOptionError([](SynthOptions& o) { o.render.noise_sigma = -1; }, "--noise");
  ExpectOptionError(
      [](SynthOptions& o) {
        o.scene.background_rows = true;
        o.scene.canopy_shape = "round";
        o.scene.canopy_thickness = 1.6;
      },
      "inside the neighbouring row's canopy");
}

TEST(Synth, CommandLineReportsBadValues) {
  const char* bin = std::getenv("ORCHARD_BIN");
  if (!bin || !fs::exists(bin)) GTEST_SKIP() << "ORCHARD_BIN not built";
  const fs::path cli_dir = test::FreshTempDir("synth_cli");
  const fs::path log = cli_dir / "log.txt";
  const std::string cmd = std::string(bin) + " synth --out " +
                          (cli_dir / "out").string() + " --trees 0 > " +
                          log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  EXPECT_NE(rc, 0);
  EXPECT_NE(ReadTextFile(log).find("orchard: error: invalid option: --trees must be in 1..200, got 0"),
            std::string::npos)
      << ReadTextFile(log);
}

}  // namespace
}  // namespace orchard::synth
