// End to end on a tiny synthetic row: true poses and the generator's masks
// through the library, count checked against truth.json.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/fruitmap/side.h"
#include "orchard/sfm/colmap_model.h"
#include "orchard/synth/synth.h"

namespace orchard {
namespace {

class SideTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("orchard_side_test_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    synth::SynthOptions o;
    o.seed = 5;
    o.scene.num_trees = 2;
    o.camera.sides = "front";
    o.patch_every = 0;
    o.progress = false;
    synth::RunSynth(o, *dir_ / "synth");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  SideInputs Inputs(const std::string& out) const {
    SideInputs in;
    in.input = *dir_ / "synth/front/images";
    in.poses = *dir_ / "synth/front/sparse";
    in.masks = *dir_ / "synth/front/masks";
    in.ground = ParseGroundPlane((*dir_ / "synth/front/scene.json").string());
    in.out = *dir_ / out;
    return in;
  }
  // The given poses as they are: COLMAP's triangulation of points for them
  // (SideOptions::triangulate_given_poses) costs a test tens of seconds and
  // has its own test below.
  static SideOptions Options() {
    SideOptions o;
    o.triangulate_given_poses = false;
    return o;
  }
  static fs::path* dir_;
};
fs::path* SideTest::dir_ = nullptr;

TEST_F(SideTest, CountsTheVisibleApplesOnceFromTruePosesAndMasks) {
  const auto truth = nlohmann::json::parse(ReadTextFile(*dir_ / "synth/truth.json"));
  const int visible = truth.at("visible_front").get<int>();
  SideOptions o = Options();
  const SideSummary s = RunSide(Inputs("out"), o);
  // Loose: the two-tree row has 21 frames (the docs measure the default 4-tree row).
  EXPECT_GT(visible, 20);
  EXPECT_NEAR(s.count, visible, 0.2 * visible) << "visible_front " << visible;
  EXPECT_GT(s.single_frame_sum, 2 * s.count);
  for (const char* f : {"side.json", "clusters.csv", "fruit.ply"}) EXPECT_TRUE(fs::exists(*dir_ / "out" / f)) << f;
  // cameras.csv: every used frame's camera centre, here the generator's
  // path 1.5 m above the ground.
  {
    std::istringstream cameras(ReadTextFile(*dir_ / "out/cameras.csv"));
    std::string line;
    std::getline(cameras, line);
    EXPECT_EQ(line, "frame,x,y,z");
    int rows = 0;
    while (std::getline(cameras, line)) {
      ++rows;
      EXPECT_NEAR(std::stod(line.substr(line.rfind(',') + 1)), 1.5, 0.05) << line;
    }
    EXPECT_EQ(rows, s.frames_used);
  }
  const auto side = nlohmann::json::parse(ReadTextFile(*dir_ / "out/side.json"));
  EXPECT_EQ(side.at("count").get<int>(), s.count);
  EXPECT_EQ(side.at("scale").get<double>(), 1.0);  // true poses are metric
  // The generator's path passes the reconstruction checks: 12.5 cm steps,
  // 1.5 m up, no fruit below the ground.
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  const auto& check = side.at("reconstruction");
  EXPECT_NEAR(check.at("median_step").get<double>(), 0.125, 0.01);
  EXPECT_NEAR(check.at("height_median").get<double>(), 1.5, 0.02);
  EXPECT_EQ(check.at("backward_steps").get<int>(), 0);
  EXPECT_EQ(check.at("reprojection_error_px").get<double>(), -1);  // given poses: no sparse points
  EXPECT_LT(check.at("fruit_below_ground").get<double>(), 0.01);
  // Single apples measure an apple's size (3-5 cm; 4.1-4.6 cm on fresh rows).
  EXPECT_GT(check.at("single_apples").get<int>(), 10);
  EXPECT_NEAR(check.at("apple_radius").get<double>(), 0.043, 0.01);
  // The spacing the 3D stage is tuned to (0.050-0.061 on the 4-tree rows).
  EXPECT_NEAR(check.at("frame_spacing").get<double>(), 0.057, 0.012);
  // The generator's frames (80 degrees across 960x540 px, 1.5 m up, 5 degrees
  // down; 0.5 degrees of shake) end this high at the row's distance.
  const auto reach = side.at("frames_reach");
  const double distance = side.at("row_distance").get<double>(), deg = M_PI / 180;
  EXPECT_EQ(reach.at("at_distance_m").get<double>(), distance);
  EXPECT_EQ(reach.at("views").get<int>(), s.frames_used);
  const double up = std::atan(270 / (480 / std::tan(40 * deg))) - 5 * deg;
  EXPECT_NEAR(reach.at("top_m").get<double>(), 1.5 + distance * std::tan(up), 0.03) << distance;
  const double down = std::atan(270 / (480 / std::tan(40 * deg))) + 5 * deg;
  EXPECT_NEAR(reach.at("bottom_m").get<double>(), std::max(0.0, 1.5 - distance * std::tan(down)), 0.03) << distance;
  // A rerun resumes from the cached detections and gives the same count.
  EXPECT_TRUE(fs::exists(*dir_ / "out/detections/frame_0000.json"));
  // ... and, given the generator's side folder, says where the count comes from.
  SideInputs scored = Inputs("out");
  scored.truth = *dir_ / "synth/front";
  EXPECT_EQ(RunSide(scored, o).count, s.count);
  const auto t = nlohmann::json::parse(ReadTextFile(*dir_ / "out/side.json")).at("truth");
  EXPECT_EQ(t.at("visible").get<int>(), visible);
  EXPECT_EQ(t.at("count").get<int>(), s.count);
  EXPECT_EQ(t.at("found").get<int>() + t.at("missed").get<int>(), visible);
  EXPECT_GT(t.at("found").get<int>(), 0.8 * visible);
  // The visible and missed apples by the views that show them add up.
  const auto by_visible = t.at("visible_by_views_seen").get<std::vector<int>>();
  const auto by_missed = t.at("missed_by_views_seen").get<std::vector<int>>();
  EXPECT_EQ(std::accumulate(by_visible.begin(), by_visible.end(), 0), visible);
  EXPECT_EQ(std::accumulate(by_missed.begin(), by_missed.end(), 0), t.at("missed").get<int>());
  EXPECT_EQ(by_visible[0], 0);  // every frame is a view: a visible apple shows in one at least
  // Each kept cluster's part, one row each, duplicates with the cluster holding their apple.
  std::vector<std::string> rows;
  std::istringstream csv(ReadTextFile(*dir_ / "out/truth_clusters.csv"));
  for (std::string line; std::getline(csv, line);) rows.push_back(line);
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0],
            "id,x,y,z,count,points,views,votes_won,role,credited,top_apple,top_votes,holder,holder_distance,"
            "cover_id,cover_views,cover_distance");
  int found_rows = 0, duplicate_rows = 0;
  for (size_t i = 1; i < rows.size(); ++i) {
    std::vector<std::string> fields;
    std::istringstream row(rows[i]);
    for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
    ASSERT_EQ(fields.size(), 17u) << rows[i];
    found_rows += fields[8] == "found";
    if (fields[8] == "duplicate") {
      ++duplicate_rows;
      EXPECT_FALSE(fields[12].empty() || fields[13].empty()) << rows[i];  // a holder and its distance
    }
  }
  EXPECT_GT(found_rows, 0.8 * visible - 5);
  EXPECT_LE(duplicate_rows, t.at("duplicates").get<int>());
  EXPECT_EQ(s.count - visible, t.at("duplicates").get<int>() + t.at("over_counted").get<int>() +
                                   t.at("not_visible").get<int>() - t.at("missed").get<int>());
  scored.truth = *dir_ / "synth/nowhere";  // not a side of the generator's row
  EXPECT_THROW(RunSide(scored, o), Error);
  // Another counter on the same detections recounts the cached blobs without
  // detecting again (an empty masks folder to detect from) and caches its counts.
  struct TwoPerBlob : Counter {
    BlobCount Count(const cv::Mat&, const cv::Mat1b&) override { return BlobCount{2, {}}; }
  } two;
  SideInputs recounted = Inputs("out");
  recounted.masks = *dir_ / "synth/empty_masks";
  fs::create_directories(recounted.masks);
  recounted.counter = &two;
  recounted.counter_name = "two";
  EXPECT_GT(RunSide(recounted, o).count, s.count);
  const auto cached = nlohmann::json::parse(ReadTextFile(*dir_ / "out/detections/frame_0000.json"));
  EXPECT_EQ(cached.at("counter").get<std::string>(), "two");
  for (int c : cached.at("counts").get<std::vector<int>>()) EXPECT_EQ(c, 2);
  // Another detector detects again: here from masks that are not there.
  recounted.detector_name = "masks2";
  EXPECT_THROW(RunSide(recounted, o), Error);
}

TEST_F(SideTest, WarnsWhenApplesShowTheScaleIsWrong) {
  // The true poses rescaled to a camera height of 0.5 m instead of 1.5: the
  // row shrinks to a third, and so do the apples.
  SideOptions o = Options();
  o.rescale_given_poses = true;
  o.camera_height = 0.5;
  const SideSummary s = RunSide(Inputs("small_scale"), o);
  const auto check = nlohmann::json::parse(ReadTextFile(*dir_ / "small_scale/side.json")).at("reconstruction");
  EXPECT_LT(check.at("apple_radius").get<double>(), 0.018);
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings.back().find("the scale is likely too small"), std::string::npos) << s.warnings.back();
}

TEST_F(SideTest, StepThinsGivenPosesAndSparseFramesScaleTheFrameCountsOrAreWarnedAbout) {
  SideOptions o = Options();
  o.frames.step = 2;  // every other frame: 25 cm apart, twice the tuned spacing
  o.sparse_frames = SparseFrames::kKeep;
  const SideSummary s = RunSide(Inputs("step2"), o);
  const auto side = nlohmann::json::parse(ReadTextFile(*dir_ / "step2/side.json"));
  EXPECT_EQ(side.at("frames").at("input").get<int>(), 11);  // frames 0, 2, ..., 20 of 21
  EXPECT_EQ(s.frames_used, 11);
  EXPECT_TRUE(side.at("frames").at("unregistered").empty());  // the skipped frames are not "left out"
  EXPECT_NEAR(side.at("reconstruction").at("median_step").get<double>(), 0.25, 0.02);
  EXPECT_EQ(side.at("frames").at("frame_scale").get<double>(), 1);
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings.back().find("the count is likely low; keep more frames"), std::string::npos)
      << s.warnings.back();
  // Scaled: the same frames, the 3D stage's frame counts smaller: the tuned
  // 0.057 row distances over 25 cm steps at about 2.1 m would make them 0.48
  // times as large, the floor keeps 0.6 (within the warning's bound), and
  // apples seen in fewer of the sparse frames count.
  o.sparse_frames = SparseFrames::kScale;
  const SideSummary scaled = RunSide(Inputs("step2_scaled"), o);
  const auto scaled_side = nlohmann::json::parse(ReadTextFile(*dir_ / "step2_scaled/side.json"));
  EXPECT_EQ(scaled_side.at("frames").at("frame_scale").get<double>(), o.min_sparse_frame_scale);
  EXPECT_EQ(scaled.frames_used, 11);
  for (const auto& w : scaled.warnings) EXPECT_EQ(w.find("frames "), std::string::npos) << w;
  o.min_sparse_frame_scale = 0.4;
  RunSide(Inputs("step2_scaled_more"), o);
  EXPECT_NEAR(nlohmann::json::parse(ReadTextFile(*dir_ / "step2_scaled_more/side.json"))
                  .at("frames")
                  .at("frame_scale")
                  .get<double>(),
              0.057 * 2.12 / 0.254, 0.02);
  // Nearer the apples visible (127 on this row: 113 as they are, 116 scaled).
  const int visible = nlohmann::json::parse(ReadTextFile(*dir_ / "synth/truth.json")).at("visible_front").get<int>();
  EXPECT_LT(std::abs(scaled.count - visible), std::abs(s.count - visible)) << s.count << " " << scaled.count;
}

TEST(SideDenseFramesTest, FramesTwiceTooDenseAreThinnedOrScaleTheFrameCounts) {
  // 16 frames per second: 6.25 cm steps, half the spacing the 3D stage is tuned to.
  const fs::path dir = fs::temp_directory_path() / ("orchard_side_dense_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  synth::SynthOptions so;
  so.seed = 5;
  so.scene.num_trees = 1;  // the next row holds more of the fruit pixels than the tree (RowFruitDistance)
  so.camera.sides = "front";
  so.camera.fps = 16;
  so.patch_every = 0;
  so.progress = false;
  synth::RunSynth(so, dir / "synth");
  SideInputs in;
  in.input = dir / "synth/front/images";
  in.poses = dir / "synth/front/sparse";
  in.masks = dir / "synth/front/masks";
  in.ground = ParseGroundPlane((dir / "synth/front/scene.json").string());
  SideOptions o;
  o.draw_every = 0;
  o.triangulate_given_poses = false;  // as in SideTest::Options
  // Default: every other frame.
  in.out = dir / "thin";
  const SideSummary s = RunSide(in, o);
  auto side = nlohmann::json::parse(ReadTextFile(dir / "thin/side.json"));
  const int input = side.at("frames").at("input").get<int>();
  EXPECT_EQ(side.at("frames").at("every").get<int>(), 2);
  EXPECT_EQ(side.at("frames").at("frame_scale").get<double>(), 1);
  EXPECT_EQ(s.frames_used, (input + 1) / 2);
  EXPECT_EQ(s.frames_registered, input);
  EXPECT_NEAR(side.at("reconstruction").at("median_step").get<double>(), 0.125, 0.01);  // of the frames used
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();  // the thinned spacing is the tuned one
  // Scaled: all frames, the frame counts twice as large; the spacing is then the tuned one.
  o.dense_frames = DenseFrames::kScale;
  in.out = dir / "scale";
  const SideSummary scaled = RunSide(in, o);
  side = nlohmann::json::parse(ReadTextFile(dir / "scale/side.json"));
  EXPECT_EQ(side.at("frames").at("frame_scale").get<double>(), 2);
  EXPECT_EQ(side.at("frames").at("every").get<int>(), 1);
  EXPECT_EQ(scaled.frames_used, input);
  EXPECT_TRUE(scaled.warnings.empty()) << scaled.warnings.front();
  // All frames as they are: the spacing is warned about.
  o.dense_frames = DenseFrames::kAll;
  in.out = dir / "all";
  const SideSummary all = RunSide(in, o);
  EXPECT_EQ(all.frames_used, input);
  ASSERT_FALSE(all.warnings.empty());
  EXPECT_NE(all.warnings.back().find("the count is likely high"), std::string::npos) << all.warnings.back();
  // The frame counts given twice as large by hand: the same spacing is the tuned one.
  o.clusters.frame_scale = 2;
  in.out = dir / "given";
  const SideSummary given = RunSide(in, o);
  EXPECT_EQ(given.count, scaled.count);
  EXPECT_TRUE(given.warnings.empty()) << given.warnings.front();
  fs::remove_all(dir);
}

TEST(ScaledToFrameDensityTest, SpansGrowKTimesCountsOverTheSameStretch) {
  ClusterOptions o;
  o.min_points = 4;
  o.frame_scale = 3;
  const ClusterOptions s = ScaledToFrameDensity(o);
  EXPECT_EQ(s.frame_scale, 1);
  EXPECT_EQ(s.points.max_partner_offset, 18);  // 6 frames ahead: 18 at 3 times the density
  EXPECT_EQ(s.points.min_partner_offset, 1);   // the nearest partner stays the next frame
  EXPECT_EQ(s.points.support_window, 18);
  EXPECT_EQ(s.edge.window, 39);
  EXPECT_EQ(s.glimpsed.window, 18);
  EXPECT_EQ(s.points.min_support, 7);  // 3 frames span 2 steps: 7 frames at a third of the step
  EXPECT_EQ(s.min_points, 10);
  EXPECT_EQ(s.min_views, 7);
  EXPECT_EQ(s.glimpsed.min_support, 7);
  EXPECT_EQ(s.best_views, 7);  // the median of 3 is the 2nd highest; of 7, the 4th
  EXPECT_EQ(s.points.min_support_ratio, o.points.min_support_ratio);  // fractions stay
  // Sparser frames (k < 1): the same stretch holds fewer frames, rounded, never under one.
  o.frame_scale = 0.6;
  const ClusterOptions sparse = ScaledToFrameDensity(o);
  EXPECT_EQ(sparse.points.max_partner_offset, 4);  // 3.6 frames
  EXPECT_EQ(sparse.points.support_window, 4);
  EXPECT_EQ(sparse.edge.window, 8);  // 7.8
  EXPECT_EQ(sparse.points.min_support, 2);  // 3 frames over 2 steps: 2.2 at 1 / 0.6 times the step
  EXPECT_EQ(sparse.min_points, 3);          // 2.8
  EXPECT_EQ(sparse.min_views, 2);
  EXPECT_EQ(sparse.glimpsed.min_support, 2);
  EXPECT_EQ(sparse.best_views, 3);  // the 2nd highest: 1.6 frames, rounded to 2
  o.frame_scale = 0.2;
  const ClusterOptions sparsest = ScaledToFrameDensity(o);
  EXPECT_EQ(sparsest.points.max_partner_offset, 1);
  EXPECT_EQ(sparsest.points.min_partner_offset, 1);
  EXPECT_EQ(sparsest.points.min_support, 1);
  EXPECT_EQ(sparsest.best_views, 1);
  o.frame_scale = 1;
  o.best_views = 4;  // an even number of views stays as given
  const ClusterOptions same = ScaledToFrameDensity(o);
  EXPECT_EQ(same.best_views, o.best_views);
  EXPECT_EQ(same.points.min_support, o.points.min_support);
  EXPECT_EQ(same.min_points, o.min_points);
}

TEST_F(SideTest, CommandCountsDetectorBlobsWithTheCnnByDefault) {
  // `orchard side` without --counter: instance masks are one apple per blob,
  // a detector's blobs go to the CNN counter (as in `orchard yield`; before,
  // the command counted a U-Net blob of touching apples as one).
  const char* bin = std::getenv("ORCHARD_BIN");
  if (!bin || !fs::exists(bin)) GTEST_SKIP() << "ORCHARD_BIN not built";
  const fs::path row = *dir_ / "synth/front";
  const std::string common = " --in '" + (row / "images").string() + "' --poses '" + (row / "sparse").string() +
                             "' --ground-plane '" + (row / "scene.json").string() +
                             "' --draw-every 0 --no-triangulate-poses";
  for (const auto& [detector, counter] : {std::pair<std::string, std::string>{"masks", "blob"}, {"gmm", "cnn:"}}) {
    const fs::path out = *dir_ / ("cli_" + detector);
    std::string args = common + " --detector " + detector + " --out '" + out.string() + "'";
    if (detector == "masks") args += " --masks '" + (row / "masks").string() + "'";
    ASSERT_EQ(std::system(("'" + std::string(bin) + "' side" + args + " > /dev/null 2>&1").c_str()), 0) << detector;
    const auto side = nlohmann::json::parse(ReadTextFile(out / "side.json"));
    EXPECT_EQ(side.at("counter").get<std::string>().rfind(counter, 0), 0u) << side.at("counter");
  }
}

TEST_F(SideTest, FailsClearly) {
  SideOptions o = Options();
  SideInputs in = Inputs("bad");
  in.masks = *dir_ / "nowhere";
  EXPECT_THROW(RunSide(in, o), Error);
  in = Inputs("bad");
  in.poses = *dir_ / "synth/front";  // no cameras.txt there
  try {
    RunSide(in, o);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.txt"), std::string::npos) << e.what();
  }
  // True poses carry no 3D points: without a given ground plane it must say
  // so, whether no points are to be triangulated or colmap cannot be run.
  in = Inputs("bad");
  in.ground.reset();
  for (const bool triangulate : {false, true}) {
    o.triangulate_given_poses = triangulate;
    o.colmap.colmap = "/nonexistent/colmap";
    try {
      RunSide(in, o);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("ground plane"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(*dir_ / "bad/side.json"));
}

// Given poses without points (GNSS/IMU, the generator's true poses): COLMAP
// triangulates points with the poses held, the ground plane is fitted to them
// as to the mapper's, and a rerun reuses them.
TEST_F(SideTest, TriangulatesPointsForGivenPosesAndFitsTheGround) {
  SideInputs in = Inputs("triangulated");
  in.ground.reset();
  SideOptions o;  // triangulate_given_poses
  o.draw_every = 0;
  const SideSummary s = RunSide(in, o);
  const auto side = nlohmann::json::parse(ReadTextFile(*dir_ / "triangulated/side.json"));
  EXPECT_EQ(side.at("ground_plane").at("source").get<std::string>().rfind("fitted to ", 0), 0u);
  // The generator's ground is z = 0: the fit within 3 cm and half a degree.
  const auto normal = side.at("ground_plane").at("normal").get<std::vector<double>>();
  EXPECT_GT(std::abs(normal.at(2)), std::cos(0.5 * M_PI / 180));
  EXPECT_LT(std::abs(side.at("ground_plane").at("d").get<double>()), 0.03);
  // The true poses and COLMAP's keypoints agree to well under a pixel.
  const double reprojection = side.at("reconstruction").at("reprojection_error_px").get<double>();
  EXPECT_GT(reprojection, 0);
  EXPECT_LT(reprojection, 1.0);
  EXPECT_EQ(side.at("scale").get<double>(), 1.0);
  // The poses are the given ones, under the given ids.
  const ColmapModel given = ReadColmapTextModel(*dir_ / "synth/front/sparse");
  const ColmapModel sparse = ReadColmapTextModel(*dir_ / "triangulated/sparse");
  ASSERT_EQ(sparse.images.size(), given.images.size());
  for (const auto& [id, image] : given.images) {
    EXPECT_EQ(sparse.images.at(id).name, image.name);
    EXPECT_LT((sparse.images.at(id).ProjectionCenter() - image.ProjectionCenter()).norm(), 1e-9) << image.name;
  }
  EXPECT_GT(sparse.points3D.size(), 500u);
  EXPECT_EQ(side.at("sparse_points").at("count").get<size_t>(), sparse.points3D.size());
  EXPECT_EQ(side.at("sparse_points").at("from").get<std::string>(), "triangulated by COLMAP for the given poses");
  for (const auto& [pid, point] : sparse.points3D)
    for (const auto& el : point.track) ASSERT_TRUE(given.images.count(el.image_id)) << el.image_id;
  // Counted as with the true ground plane.
  SideOptions plain = Options();
  plain.draw_every = 0;
  EXPECT_NEAR(s.count, RunSide(Inputs("triangulated_plain"), plain).count, 2);
  // A rerun reuses the points; poses run without triangulation leave no points behind.
  const auto written = fs::last_write_time(*dir_ / "triangulated/sparse/points3D.txt");
  EXPECT_EQ(RunSide(in, o).count, s.count);
  EXPECT_EQ(fs::last_write_time(*dir_ / "triangulated/sparse/points3D.txt"), written);
  in.ground = ParseGroundPlane((*dir_ / "synth/front/scene.json").string());
  RunSide(in, plain);
  EXPECT_FALSE(fs::exists(*dir_ / "triangulated/sparse"));
  EXPECT_EQ(nlohmann::json::parse(ReadTextFile(*dir_ / "triangulated/side.json")).at("sparse_points").at("from"), "none");
}

// A ground refit may mend a plane tilted about the path (0.54x and 0.98x on
// seeds 11 and 12) but not change the scale a hundredfold (a folded model).
TEST(SideOptionsTest, RefitKeepsTheScaleWithinTheBound) {
  SideOptions o;  // max_refit_scale_change 3
  EXPECT_TRUE(RefitScaleIsPlausible(0.754, 0.405, o));
  EXPECT_TRUE(RefitScaleIsPlausible(0.412, 0.403, o));
  EXPECT_FALSE(RefitScaleIsPlausible(0.0758, 13.6, o));
  EXPECT_FALSE(RefitScaleIsPlausible(1.0, 0.25, o));
  EXPECT_FALSE(RefitScaleIsPlausible(1.0, 0.0, o));
  o.max_refit_scale_change = 1;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace orchard
