#include "orchard/synth/synth.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <mutex>
#include <numeric>
#include <thread>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/sfm/colmap_model.h"
#include "orchard/synth/random.h"

namespace orchard::synth {
namespace {

constexpr double kDeg = M_PI / 180.0;
const char* kSideNames[2] = {"front", "back"};

std::string Format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, v);
  return buf;
}

std::string FrameName(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "frame_%04d", frame);
  return buf;
}

// The camera of `side` (0 front at y < 0, 1 back at y > 0) at frame `frame`.
CameraPose FramePose(const Scene& scene, const SynthOptions& options, int side, int frame) {
  const CameraPathOptions& c = options.camera;
  const double x = scene.row_x_min + frame * c.FrameStep();
  const double sign = side == 0 ? -1.0 : 1.0;
  Eigen::Vector3d center(x, sign * c.distance, c.height);
  const double pitch = c.pitch_deg * kDeg;
  const Eigen::Vector3d forward(0, -sign * std::cos(pitch), std::sin(pitch));
  Random rng(SubSeed(options.seed, 40 + side, frame));
  center += Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal()) * c.jitter_m;
  CameraPose pose = CameraPose::LookAlong(center, forward);
  const double sd = c.jitter_deg * kDeg;
  const Eigen::Matrix3d shake = (Eigen::AngleAxisd(rng.Normal(0, sd), Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(rng.Normal(0, sd), Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(rng.Normal(0, sd), Eigen::Vector3d::UnitZ()))
                                    .toRotationMatrix();
  pose.R = shake * pose.R;
  pose.t = -pose.R * center;
  return pose;
}

struct PatchRecord {
  std::string name;
  int count = 0;
};

struct FrameResult {
  std::vector<std::pair<int, int>> pixels;  // (apple id, unoccluded pixels), all apples in the frame
  std::vector<PatchRecord> patches;
};

// Union-find over connected-component labels.
int FindRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

// Counting patches: each connected group of labelled apples (touching, or
// split only by a thin occluder; one apple in several pieces joins them),
// cut with a margin; groups of more than six apples are left out; plus
// background patches without any apple pixel.
std::vector<PatchRecord> CutPatches(const SynthOptions& options, const cv::Mat& image, const cv::Mat& labelled_ids,
                                    const cv::Mat& raw_ids, const std::string& prefix, const fs::path& dir,
                                    std::uint64_t seed) {
  std::vector<PatchRecord> records;
  cv::Mat binary = labelled_ids > 0;
  cv::morphologyEx(binary, binary, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(binary, labels, stats, centroids, 8, CV_32S);
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::map<int, int> first_component;  // apple id -> a component holding it
  for (int y = 0; y < labelled_ids.rows; ++y) {
    const auto* id = labelled_ids.ptr<std::uint16_t>(y);
    const auto* lab = labels.ptr<int>(y);
    for (int x = 0; x < labelled_ids.cols; ++x) {
      if (!id[x]) continue;
      const auto [it, inserted] = first_component.emplace(id[x], lab[x]);
      if (!inserted) {
        const int a = FindRoot(parent, it->second), b = FindRoot(parent, lab[x]);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
  }
  std::map<int, std::vector<int>> group_ids;  // root -> apple ids
  for (const auto& [id, comp] : first_component) group_ids[FindRoot(parent, comp)].push_back(id);
  std::map<int, cv::Rect> group_box;
  for (int l = 1; l < n; ++l) {
    const cv::Rect r(stats.at<int>(l, cv::CC_STAT_LEFT), stats.at<int>(l, cv::CC_STAT_TOP),
                     stats.at<int>(l, cv::CC_STAT_WIDTH), stats.at<int>(l, cv::CC_STAT_HEIGHT));
    const int root = FindRoot(parent, l);
    auto it = group_box.find(root);
    if (it == group_box.end()) group_box.emplace(root, r);
    else it->second |= r;
  }
  const cv::Rect frame_rect(0, 0, image.cols, image.rows);
  int k = 0;
  std::vector<int> sizes;
  for (const auto& [root, ids] : group_ids) {
    const int count = static_cast<int>(ids.size());
    const cv::Rect box = group_box.at(root);
    if (count > 6) continue;
    const int margin = std::max(4, static_cast<int>(std::lround(options.patch_margin * std::max(box.width, box.height))));
    const cv::Rect crop = cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
                          frame_rect;
    char name[96];
    std::snprintf(name, sizeof(name), "%s_g%02d.png", prefix.c_str(), k++);
    WriteImageAtomic(dir / name, image(crop));
    records.push_back({name, count});
    sizes.push_back(std::max(crop.width, crop.height));
  }
  Random rng(seed);
  for (int b = 0, attempts = 0; b < options.background_patches && attempts < 40; ++attempts) {
    const int size = sizes.empty() ? rng.UniformInt(32, 96) : sizes[rng.UniformInt(0, static_cast<int>(sizes.size()) - 1)];
    if (size >= image.cols || size >= image.rows) continue;
    const cv::Rect crop(rng.UniformInt(0, image.cols - size), rng.UniformInt(0, image.rows - size), size, size);
    if (cv::countNonZero(raw_ids(crop)) > 0) continue;
    char name[96];
    std::snprintf(name, sizeof(name), "%s_b%02d.png", prefix.c_str(), b++);
    WriteImageAtomic(dir / name, image(crop));
    records.push_back({name, 0});
  }
  return records;
}

FrameResult RenderAndWriteFrame(const Scene& scene, const SynthOptions& options, const PinholeCamera& camera,
                                int side, int frame, const fs::path& out_dir) {
  const CameraPose pose = FramePose(scene, options, side, frame);
  const RenderedFrame rendered =
      RenderFrame(scene, camera, pose, options.render, SubSeed(options.seed, 10 + side, frame));
  FrameResult result;
  std::map<int, int> pixels;
  std::map<int, cv::Rect> bounds;
  for (int y = 0; y < rendered.ids.rows; ++y) {
    const auto* id = rendered.ids.ptr<std::uint16_t>(y);
    for (int x = 0; x < rendered.ids.cols; ++x) {
      if (!id[x]) continue;
      ++pixels[id[x] - 1];
      auto it = bounds.find(id[x] - 1);
      if (it == bounds.end()) bounds.emplace(id[x] - 1, cv::Rect(x, y, 1, 1));
      else it->second |= cv::Rect(x, y, 1, 1);
    }
  }
  // Mask and labels hold the apples seen in this frame (enough pixels).
  cv::Mat labelled = rendered.ids.clone();
  for (int y = 0; y < labelled.rows; ++y) {
    auto* id = labelled.ptr<std::uint16_t>(y);
    for (int x = 0; x < labelled.cols; ++x) {
      if (id[x] && pixels[id[x] - 1] < options.min_visible_pixels) id[x] = 0;
    }
  }
  std::string labels;
  for (const auto& [id, count] : pixels) {
    result.pixels.emplace_back(id, count);
    if (count < options.min_visible_pixels) continue;
    const cv::Rect& r = bounds.at(id);
    char line[128];
    std::snprintf(line, sizeof(line), "0 %.6f %.6f %.6f %.6f\n", (r.x + 0.5 * r.width) / camera.width,
                  (r.y + 0.5 * r.height) / camera.height, static_cast<double>(r.width) / camera.width,
                  static_cast<double>(r.height) / camera.height);
    labels += line;
  }
  const fs::path side_dir = out_dir / kSideNames[side];
  const std::string name = FrameName(frame);
  WriteImageAtomic(side_dir / "images" / (name + ".png"), rendered.image);
  WriteImageAtomic(side_dir / "masks" / (name + ".png"), labelled);
  WriteTextFileAtomic(side_dir / "labels" / (name + ".txt"), labels);
  if (options.patch_every > 0 && frame % options.patch_every == 0) {
    result.patches = CutPatches(options, rendered.image, labelled, rendered.ids,
                                std::string(kSideNames[side]) + "_" + name, out_dir / "patches" / "images",
                                SubSeed(options.seed, 20 + side, frame));
  }
  return result;
}

nlohmann::json OptionsJson(const SynthOptions& o) {
  const SceneOptions& s = o.scene;
  const CameraPathOptions& c = o.camera;
  nlohmann::json j;
  j["seed"] = o.seed;
  j["scene"] = {{"trees", s.num_trees},
                {"tree_spacing", s.tree_spacing},
                {"canopy", s.canopy_shape},
                {"canopy_base", s.canopy_base},
                {"canopy_top", s.canopy_top},
                {"canopy_thickness", s.canopy_thickness},
                {"apples_per_tree", s.apples_per_tree},
                {"deep_fraction", s.deep_fraction},
                {"apple_radius_min", s.apple_radius_min},
                {"apple_radius_max", s.apple_radius_max},
                {"variety", s.variety},
                {"fallen_fraction", s.fallen_fraction},
                {"leaf_density", s.leaf_density},
                {"leaf_length", s.leaf_length},
                {"yellow_leaves", s.yellow_leaf_fraction},
                {"row_spacing", s.row_spacing},
                {"background_rows", s.background_rows},
                {"sun_elevation_deg", s.sun_elevation_deg},
                {"sun_azimuth_deg", s.sun_azimuth_deg}};
  j["camera"] = {{"distance", c.distance}, {"height", c.height},   {"pitch_deg", c.pitch_deg},
                 {"hfov_deg", c.hfov_deg}, {"width", c.width},     {"height_px", c.height_px},
                 {"speed", c.speed},       {"fps", c.fps},         {"frame_step", c.FrameStep()},
                 {"jitter_m", c.jitter_m}, {"jitter_deg", c.jitter_deg}, {"sides", c.sides}};
  j["render"] = {{"noise", o.render.noise_sigma},
                 {"motion_blur_px", o.render.motion_blur_px},
                 {"lens_blur_sigma", o.render.lens_blur_sigma},
                 {"exposure", o.render.exposure}};
  j["min_visible_pixels"] = o.min_visible_pixels;
  j["patch_every"] = o.patch_every;
  j["patch_margin"] = o.patch_margin;
  j["background_patches"] = o.background_patches;
  return j;
}

}  // namespace

void CameraPathOptions::Check() const {
  ORCHARD_CHECK_OPTION(distance >= 0.5 && distance <= 20, "--distance must be in 0.5..20 m, got ", distance);
  ORCHARD_CHECK_OPTION(height >= 0.1 && height <= 10, "--camera-height must be in 0.1..10 m, got ", height);
  ORCHARD_CHECK_OPTION(pitch_deg >= -60 && pitch_deg <= 60, "--pitch must be in -60..60 degrees, got ", pitch_deg);
  ORCHARD_CHECK_OPTION(hfov_deg >= 10 && hfov_deg <= 150, "--fov must be in 10..150 degrees, got ", hfov_deg);
  ORCHARD_CHECK_OPTION(width >= 16 && width <= 8192 && height_px >= 16 && height_px <= 8192,
                       "--width and --height must be in 16..8192 pixels, got ", width, "x", height_px);
  ORCHARD_CHECK_OPTION(speed > 0 && speed <= 20, "--speed must be in (0, 20] m/s, got ", speed);
  ORCHARD_CHECK_OPTION(fps > 0 && fps <= 240, "--fps must be in (0, 240], got ", fps);
  ORCHARD_CHECK_OPTION(FrameStep() >= 0.002, "frame step speed/fps must be at least 2 mm, got ", FrameStep());
  ORCHARD_CHECK_OPTION(jitter_m >= 0 && jitter_m <= 0.5, "--jitter must be in 0..0.5 m, got ", jitter_m);
  ORCHARD_CHECK_OPTION(jitter_deg >= 0 && jitter_deg <= 10, "--jitter-deg must be in 0..10, got ", jitter_deg);
  ORCHARD_CHECK_OPTION(sides == "both" || sides == "front" || sides == "back",
                       "--sides must be both, front or back, got '", sides, "'");
}

void SynthOptions::Check() const {
  scene.Check();
  camera.Check();
  render.Check();
  ORCHARD_CHECK_OPTION(camera.distance > 0.5 * scene.canopy_thickness * (scene.canopy_shape == "round" ? 1.5 : 1.0) + 0.3,
                       "--distance ", camera.distance, " m puts the camera inside the canopy");
  // The neighbouring row behind the camera must not reach into the view.
  const double neighbour_half = scene.canopy_shape == "round" ? 0.75 * 1.15 * scene.canopy_thickness
                                                              : 0.5 * 1.25 * scene.canopy_thickness;
  ORCHARD_CHECK_OPTION(!scene.background_rows || camera.distance + neighbour_half + 0.1 <= scene.row_spacing,
                       "--distance ", camera.distance, " m puts the camera inside the neighbouring row's canopy (",
                       "--row-spacing ", scene.row_spacing, " m); increase --row-spacing or reduce --distance");
  ORCHARD_CHECK_OPTION(min_visible_pixels >= 1, "--min-visible-pixels must be at least 1, got ", min_visible_pixels);
  ORCHARD_CHECK_OPTION(patch_every >= 0, "--patch-every must be >= 0, got ", patch_every);
  ORCHARD_CHECK_OPTION(patch_margin >= 0 && patch_margin <= 2, "--patch-margin must be in 0..2, got ", patch_margin);
  ORCHARD_CHECK_OPTION(background_patches >= 0 && background_patches <= 100,
                       "--background-patches must be in 0..100, got ", background_patches);
  ORCHARD_CHECK_OPTION(threads >= 0 && threads <= 256, "--threads must be in 0..256, got ", threads);
}

SynthSummary RunSynth(const SynthOptions& options, const fs::path& out_dir) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  auto log = [&](const std::string& line) {
    if (options.progress) std::fprintf(stderr, "synth: %s\n", line.c_str());
  };
  const Scene scene = GenerateScene(options.scene, options.seed);
  log("scene: " + std::to_string(scene.apples.size()) + " apples, " + std::to_string(scene.leaves.size()) +
      " leaves, " + std::to_string(scene.cylinders.size()) + " branches and posts");

  const PinholeCamera camera = PinholeCamera::FromFov(options.camera.width, options.camera.height_px,
                                                      options.camera.hfov_deg);
  const double length = scene.row_x_max - scene.row_x_min;
  const int num_frames = static_cast<int>(std::floor(length / options.camera.FrameStep() + 1e-9)) + 1;
  std::vector<int> sides;
  if (options.camera.sides != "back") sides.push_back(0);
  if (options.camera.sides != "front") sides.push_back(1);

  // Frames of both sides rendered in parallel; each job writes its own files.
  struct Job {
    int side, frame;
  };
  std::vector<Job> jobs;
  for (int side : sides) {
    for (int f = 0; f < num_frames; ++f) jobs.push_back({side, f});
  }
  std::vector<FrameResult> results(jobs.size());
  std::atomic<size_t> next{0}, done{0};
  std::mutex mutex;
  std::exception_ptr failure;
  const int num_threads = ThreadsOrAvailableCores(options.threads);
  auto worker = [&]() {
    for (;;) {
      const size_t k = next++;
      if (k >= jobs.size()) return;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (failure) return;
      }
      try {
        results[k] = RenderAndWriteFrame(scene, options, camera, jobs[k].side, jobs[k].frame, out_dir);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
        return;
      }
      const size_t d = ++done;
      if (options.progress && (d % 10 == 0 || d == jobs.size())) {
        std::lock_guard<std::mutex> lock(mutex);
        std::fprintf(stderr, "synth: rendered %zu/%zu frames\n", d, jobs.size());
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::min<int>(num_threads, static_cast<int>(jobs.size())); ++t) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);

  // Visibility per apple and side: the largest unoccluded area over the side's frames.
  const size_t num_apples = scene.apples.size();
  std::vector<int> max_pixels[2] = {std::vector<int>(num_apples, 0), std::vector<int>(num_apples, 0)};
  std::vector<PatchRecord> patches;
  for (size_t k = 0; k < jobs.size(); ++k) {
    for (const auto& [id, count] : results[k].pixels) {
      max_pixels[jobs[k].side][id] = std::max(max_pixels[jobs[k].side][id], count);
    }
    patches.insert(patches.end(), results[k].patches.begin(), results[k].patches.end());
  }
  auto visible = [&](int side, size_t id) { return max_pixels[side][id] >= options.min_visible_pixels; };

  SynthSummary summary;
  summary.frames_per_side = num_frames;
  summary.patches = static_cast<int>(patches.size());
  std::string csv =
      "id,tree,row,x,y,z,radius,colour,cluster,visible_front,visible_back,on_ground,front_max_pixels,"
      "back_max_pixels\n";
  struct TreeCounts {
    int harvested = 0, front = 0, back = 0, any = 0, both = 0, fallen = 0;
  };
  std::vector<TreeCounts> trees(options.scene.num_trees);
  int background_apples = 0;
  for (const Apple& a : scene.apples) {
    const bool vf = visible(0, a.id), vb = visible(1, a.id);
    csv += std::to_string(a.id) + "," + std::to_string(a.tree) + "," + std::to_string(a.row) + "," +
           Format("%.5f", a.center.x()) + "," + Format("%.5f", a.center.y()) + "," + Format("%.5f", a.center.z()) +
           "," + Format("%.5f", a.radius) + "," + VarietyName(a.variety) + "," + std::to_string(a.cluster) + "," +
           (vf ? "1" : "0") + "," + (vb ? "1" : "0") + "," + (a.on_ground ? "1" : "0") + "," +
           std::to_string(max_pixels[0][a.id]) + "," + std::to_string(max_pixels[1][a.id]) + "\n";
    if (a.row != 0) {
      ++background_apples;
      continue;
    }
    TreeCounts& t = trees[a.tree];
    if (a.on_ground) {
      ++t.fallen;
      continue;
    }
    ++t.harvested;
    t.front += vf;
    t.back += vb;
    t.any += vf || vb;
    t.both += vf && vb;
  }
  nlohmann::json per_tree = nlohmann::json::array();
  for (int i = 0; i < options.scene.num_trees; ++i) {
    const TreeCounts& t = trees[i];
    per_tree.push_back({{"tree", i}, {"x", scene.tree_x[i]}, {"harvested", t.harvested}, {"visible_front", t.front},
                        {"visible_back", t.back}, {"visible_any", t.any}, {"visible_both", t.both},
                        {"fallen", t.fallen}});
    summary.harvested += t.harvested;
    summary.visible_front += t.front;
    summary.visible_back += t.back;
    summary.visible_any += t.any;
    summary.visible_both += t.both;
    summary.fallen += t.fallen;
  }
  nlohmann::json truth;
  truth["harvested"] = summary.harvested;
  truth["visible_front"] = summary.visible_front;
  truth["visible_back"] = summary.visible_back;
  truth["visible_any"] = summary.visible_any;
  truth["visible_both"] = summary.visible_both;
  truth["fallen"] = summary.fallen;
  truth["background_apples"] = background_apples;
  truth["per_tree"] = per_tree;
  truth["frames_per_side"] = num_frames;
  truth["sides"] = options.camera.sides;
  truth["seed"] = options.seed;
  truth["parameters"] = OptionsJson(options);
  truth["definitions"] = {
      {"harvested", "apples on the trees of the filmed row (row 0), fallen apples excluded"},
      {"visible_front", "harvested apples with at least min_visible_pixels unoccluded pixels in some front frame"},
      {"fallen", "apples on the ground under the filmed row"}};
  WriteTextFileAtomic(out_dir / "truth.json", truth.dump(2) + "\n");
  WriteTextFileAtomic(out_dir / "apples.csv", csv);

  // Counting patches.
  if (options.patch_every > 0) {
    std::string counts;
    for (const PatchRecord& p : patches) counts += p.name + "," + std::to_string(p.count) + "\n";
    WriteTextFileAtomic(out_dir / "patches" / "counts.csv", counts);
  }

  // True poses as COLMAP text models, and the row geometry, per side.
  for (int side : sides) {
    ColmapModel model;
    ColmapCamera cam;
    cam.camera_id = 1;
    cam.model = "PINHOLE";
    cam.width = camera.width;
    cam.height = camera.height;
    cam.params = {camera.fx, camera.fy, camera.cx, camera.cy};
    model.cameras.emplace(1, cam);
    nlohmann::json path = nlohmann::json::array();
    for (int f = 0; f < num_frames; ++f) {
      const CameraPose pose = FramePose(scene, options, side, f);
      ColmapImage image;
      image.image_id = f + 1;
      image.qvec = Eigen::Quaterniond(pose.R).normalized();
      if (image.qvec.w() < 0) image.qvec.coeffs() *= -1;
      image.tvec = pose.t;
      image.camera_id = 1;
      image.name = FrameName(f) + ".png";
      model.images.emplace(image.image_id, image);
      const Eigen::Vector3d c = pose.Center();
      path.push_back({c.x(), c.y(), c.z()});
    }
    const fs::path side_dir = out_dir / kSideNames[side];
    WriteColmapTextModel(model, side_dir / "sparse");
    const SceneOptions& s = options.scene;
    nlohmann::json geometry;
    geometry["side"] = kSideNames[side];
    geometry["frame"] = "world: x along the row, y across (front camera at y < 0), z up; metres";
    geometry["ground_plane"] = {{"normal", {0, 0, 1}}, {"d", 0.0}, {"equation", "n . X + d = 0"}};
    geometry["row"] = {{"origin", {0, 0, 0}},
                       {"direction", {1, 0, 0}},
                       {"center_y", 0.0},
                       {"x_min", scene.row_x_min},
                       {"x_max", scene.row_x_max},
                       {"tree_x", scene.tree_x},
                       {"tree_spacing", s.tree_spacing},
                       {"canopy", s.canopy_shape},
                       {"canopy_base", s.canopy_base},
                       {"canopy_top", s.canopy_top},
                       {"canopy_thickness", s.canopy_thickness},
                       {"row_spacing", s.row_spacing},
                       {"neighbour_rows_y", s.background_rows ? nlohmann::json({-s.row_spacing, s.row_spacing})
                                                              : nlohmann::json::array()}};
    geometry["camera"] = {{"distance", options.camera.distance},
                          {"height", options.camera.height},
                          {"look_direction", {0, side == 0 ? 1 : -1, 0}},
                          {"frame_step", options.camera.FrameStep()},
                          {"centers", path}};
    const Eigen::Vector3d sun = scene.sun_direction;
    geometry["sun_direction"] = {sun.x(), sun.y(), sun.z()};
    WriteTextFileAtomic(side_dir / "scene.json", geometry.dump(2) + "\n");
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  log("harvested " + std::to_string(summary.harvested) + ", visible front " + std::to_string(summary.visible_front) +
      ", back " + std::to_string(summary.visible_back) + ", both " + std::to_string(summary.visible_both) +
      ", fallen " + std::to_string(summary.fallen) + "; " + std::to_string(jobs.size()) + " frames, " +
      std::to_string(patches.size()) + " patches in " + Format("%.1f", seconds) + " s");
  return summary;
}

}  // namespace orchard::synth
