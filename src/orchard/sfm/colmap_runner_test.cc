#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/sfm/colmap_runner.h"
#include "orchard/sfm/frame_selection.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

fs::path TempDir(const std::string& name) { return test::FreshTempDir("sfm_" + name); }

TEST(ColmapRunner, TooFewFramesAndMissingProgram) {
  const fs::path dir = TempDir("few");
  for (int i = 0; i < 3; ++i)
    cv::imwrite((dir / ("f" + std::to_string(i) + ".png")).string(), cv::Mat3b(32, 32, cv::Vec3b(i, i, i)));
  ColmapRunnerOptions o;
  EXPECT_NE(Message([&] { RunColmap(dir, dir / "ws", o); }).find("too few frames"), std::string::npos);
  o.min_registered = 2;
  o.colmap = "/nonexistent/colmap";
  EXPECT_NE(Message([&] { RunColmap(dir, dir / "ws", o); }).find("cannot be run"), std::string::npos);
  o.camera_model = "FISHEYE";
  EXPECT_NE(Message([&] { RunColmap(dir, dir / "ws", o); }).find("camera model"), std::string::npos);
  fs::remove_all(dir);
}

// `frames` small frames f0.png, f1.png, ... in `dir` and a stand-in for the
// colmap program that records its arguments in dir/args.txt and makes the
// database the mapper looks for; returns options that run it.
ColmapRunnerOptions FakeColmap(const fs::path& dir, int frames) {
  for (int i = 0; i < frames; ++i)
    cv::imwrite((dir / ("f" + std::to_string(i) + ".png")).string(), cv::Mat3b(32, 32, cv::Vec3b(i, i, i)));
  const fs::path fake = dir / "colmap.sh";
  WriteTextFileAtomic(fake, "#!/bin/sh\necho \"$@\" >> '" + (dir / "args.txt").string() +
                                "'\nfor a in \"$@\"; do case $a in *database.db) touch \"$a\";; esac; done\n");
  fs::permissions(fake, fs::perms::owner_all);
  ColmapRunnerOptions o;
  o.colmap = fake.string();
  return o;
}

// COLMAP's own default thread count is every CPU of the machine; the runner
// passes the count it is given, or the cores this process may use.
TEST(ColmapRunner, PassesItsThreadCountToEveryStep) {
  const fs::path dir = TempDir("threads"), args = dir / "args.txt";
  ColmapRunnerOptions o = FakeColmap(dir, 5);
  o.num_threads = 3;
  MatchColmapFeatures(dir, dir / "ws", o);
  EXPECT_THROW(MapColmap(dir, dir / "ws", o), Error);  // the stand-in writes no model
  const std::string three = ReadTextFile(args);
  EXPECT_NE(three.find("feature_extractor") , std::string::npos);
  EXPECT_NE(three.find("--SiftExtraction.num_threads 3"), std::string::npos);
  EXPECT_NE(three.find("--SiftMatching.num_threads 3"), std::string::npos);
  EXPECT_NE(three.find("--Mapper.num_threads 3"), std::string::npos);
  // The mapper's matching: 5 following frames and the quadratic pairs.
  EXPECT_NE(three.find("--SequentialMatching.overlap 5 --SequentialMatching.quadratic_overlap 1"), std::string::npos);
  fs::remove(args);
  o.num_threads = 0;
  MatchColmapFeatures(dir, dir / "ws", o);
  EXPECT_NE(ReadTextFile(args).find("--SiftExtraction.num_threads " + std::to_string(AvailableCores())),
            std::string::npos);
  o.num_threads = -1;
  EXPECT_NE(Message([&] { MatchColmapFeatures(dir, dir / "ws", o); }).find("COLMAP threads"), std::string::npos);
  fs::remove_all(dir);
}

// Points for given poses: only the posed frames' features, with the given
// camera, and the triangulator holding poses and camera (the real program
// runs in fruitmap's SideTest.TriangulatesPointsForGivenPosesAndFitsTheGround).
TEST(ColmapRunner, TriangulationHoldsTheGivenPosesAndCamera) {
  const fs::path dir = TempDir("triangulate"), args = dir / "args.txt";
  ColmapRunnerOptions o = FakeColmap(dir, 6);
  o.num_threads = 1;
  ColmapModel posed;
  posed.cameras[3] = ColmapCamera{3, "PINHOLE", 32, 32, {40, 41, 16, 16}};
  for (int i = 1; i <= 5; ++i) {  // f5.png has no pose
    ColmapImage image;
    image.image_id = 10 + i, image.camera_id = 3, image.name = "f" + std::to_string(i - 1) + ".png";
    image.tvec = Eigen::Vector3d(-0.1 * i, 0, 0);
    posed.images[image.image_id] = image;
  }
  EXPECT_THROW(TriangulateColmapPoints(dir, posed, dir / "ws", o), Error);  // the stand-in writes no model
  const std::string a = ReadTextFile(args);
  EXPECT_NE(a.find("--ImageReader.camera_model PINHOLE --ImageReader.camera_params 40,41,16,16"), std::string::npos)
      << a;
  EXPECT_EQ(ReadTextFile(dir / "ws/image_list.txt"), "f0.png\nf1.png\nf2.png\nf3.png\nf4.png\n");
  EXPECT_NE(a.find("point_triangulator"), std::string::npos);
  // Poses held: the near frames only.
  EXPECT_NE(a.find("--SequentialMatching.overlap 3 --SequentialMatching.quadratic_overlap 0"), std::string::npos);
  for (const char* held : {"--clear_points 1", "--Mapper.ba_refine_focal_length 0",
                           "--Mapper.ba_refine_principal_point 0", "--Mapper.ba_refine_extra_params 0"})
    EXPECT_NE(a.find(held), std::string::npos) << held;
  // The triangulator's input: the given poses under camera 1, the fresh
  // database's only camera, and no points.
  const ColmapModel input = ReadColmapTextModel(dir / "ws/posed");
  ASSERT_EQ(input.cameras.size(), 1u);
  EXPECT_EQ(input.cameras.begin()->first, 1);
  EXPECT_EQ(input.images.size(), 5u);
  EXPECT_EQ(input.images.at(12).camera_id, 1);
  EXPECT_EQ(input.images.at(12).tvec, posed.images.at(12).tvec);
  EXPECT_TRUE(input.points3D.empty());
  posed.cameras[4] = posed.cameras[3];
  EXPECT_NE(Message([&] { TriangulateColmapPoints(dir, posed, dir / "ws", o); }).find("one camera"),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(ColmapRunner, BestAttemptStopsAtTheFirstWithoutProblems) {
  // Problems per attempt; -1 throws.
  const auto run = [](std::vector<int> problems, int max_attempts, std::vector<int>* ran) {
    return BestAttempt(
        [&](int k) {
          ran->push_back(k);
          if (problems.at(k) < 0) Fail("attempt ", k, " failed");
          return problems.at(k);
        },
        max_attempts);
  };
  std::vector<int> ran;
  EXPECT_EQ(run({0, 5, 5}, 3, &ran), 0);
  EXPECT_EQ(ran, (std::vector<int>{0}));  // no problems: no second run
  ran.clear();
  EXPECT_EQ(run({3, 0, 5}, 3, &ran), 1);
  EXPECT_EQ(ran, (std::vector<int>{0, 1}));
  ran.clear();
  EXPECT_EQ(run({3, 1, 2}, 3, &ran), 1);  // all have problems: the fewest
  EXPECT_EQ(ran, (std::vector<int>{0, 1, 2}));
  ran.clear();
  EXPECT_EQ(run({2, 2, 2}, 3, &ran), 0);  // ties: the earliest
  ran.clear();
  EXPECT_EQ(run({-1, 4, -1}, 3, &ran), 1);  // an attempt that throws is never the best
  ran.clear();
  EXPECT_EQ(run({3, 0}, 1, &ran), 0);  // one attempt allowed
  EXPECT_EQ(ran, (std::vector<int>{0}));
  ran.clear();
  const std::string m = Message([&] { run({-1, -1}, 2, &ran); });
  EXPECT_EQ(m, "attempt 0 failed");  // every attempt threw: the first error
  EXPECT_EQ(ran, (std::vector<int>{0, 1}));
  ColmapRunnerOptions o;
  o.mapper_attempts = 0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(ColmapModel, MissingFilesNameThePath) {
  const fs::path dir = TempDir("model");
  const std::string m = Message([&] { ReadColmapTextModel(dir); });
  EXPECT_NE(m.find("cameras.txt"), std::string::npos) << m;
  fs::remove_all(dir);
}

TEST(FrameSelection, StepMotionAndTooFewFrames) {
  // A textured image shifted right by 4 px per frame.
  const fs::path dir = TempDir("frames");
  cv::Mat3b texture(120, 400);
  cv::randu(texture, 0, 255);
  cv::Mat3b smooth;
  cv::GaussianBlur(texture, smooth, cv::Size(5, 5), 1.5);
  for (int i = 0; i < 10; ++i)
    cv::imwrite((dir / cv::format("f%02d.png", i)).string(), smooth(cv::Rect(100 - 4 * i, 0, 160, 120)));
  EXPECT_NEAR(MedianFlowDisplacement(cv::imread((dir / "f00.png").string()), cv::imread((dir / "f01.png").string())),
              4, 0.5);
  FrameSelectionOptions o;
  o.step = 3;
  EXPECT_EQ(SelectFrames(dir, o, dir / "step").size(), 4u);  // 0 3 6 9
  o.method = "motion";
  o.motion_fraction = 0.06;  // 9.6 px: every 3rd frame (12 px; 8 px is too little)
  const auto kept = SelectFrames(dir, o, dir / "motion");
  EXPECT_EQ(kept, (std::vector<std::string>{"f00.png", "f03.png", "f06.png", "f09.png"}));
  o.motion_fraction = 0.5;  // never enough motion
  EXPECT_NE(Message([&] { SelectFrames(dir, o, dir / "none"); }).find("too little motion"), std::string::npos);
  fs::remove_all(dir);
}

TEST(FrameSelection, FramesWithoutLeadingZerosKeepTheirOrder) {
  // ffmpeg's frame_%d.png: 1, 2, ..., 12. Plain string order would take
  // frame_10 after frame_1; the frames are read in natural order and written
  // with padded numbers, the order COLMAP's sequential matcher takes.
  const fs::path dir = TempDir("unpadded");
  for (int i = 1; i <= 12; ++i)
    cv::imwrite((dir / ("frame_" + std::to_string(i) + ".png")).string(), cv::Mat3b(8, 8, cv::Vec3b(i, i, i)));
  FrameSelectionOptions o;
  o.step = 5;
  const auto kept = SelectFrames(dir, o, dir / "out");
  EXPECT_EQ(kept, (std::vector<std::string>{"frame_000001.png", "frame_000006.png", "frame_000011.png"}));
  EXPECT_EQ(cv::imread((dir / "out" / "frame_000011.png").string()).at<cv::Vec3b>(0, 0)[0], 11);
  // Padded names are written as they are.
  EXPECT_EQ(SelectFrames(dir / "out", FrameSelectionOptions{}, dir / "again"), kept);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
