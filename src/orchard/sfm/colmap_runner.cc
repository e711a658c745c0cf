#include "orchard/sfm/colmap_runner.h"

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <set>
#include <sstream>

#include <spdlog/spdlog.h>

#include "orchard/core/cpu.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/sfm/colmap_binary.h"

namespace orchard {
namespace {

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void RunStep(const std::string& what, const std::string& command, const fs::path& log) {
  spdlog::info("colmap {}", what);
  const std::string full = command + " >> " + Quote(log.string()) + " 2>&1";
  if (std::system(full.c_str()) != 0) Fail("colmap ", what, " failed (see ", log.string(), ")");
}

}  // namespace

void ColmapRunnerOptions::Check() const {
  ORCHARD_CHECK_OPTION(!colmap.empty(), "colmap executable must be named");
  ORCHARD_CHECK_OPTION(camera_model == "PINHOLE" || camera_model == "SIMPLE_PINHOLE" ||
                           camera_model == "SIMPLE_RADIAL" || camera_model == "RADIAL",
                       "camera model must be SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL, got ", camera_model);
  ORCHARD_CHECK_OPTION(max_num_features > 0, "max_num_features must be positive, got ", max_num_features);
  ORCHARD_CHECK_OPTION(overlap >= 1, "matching overlap must be at least 1, got ", overlap);
  ORCHARD_CHECK_OPTION(triangulation_overlap >= 1, "triangulation matching overlap must be at least 1, got ",
                       triangulation_overlap);
  ORCHARD_CHECK_OPTION(mapper_attempts >= 1, "mapper attempts must be at least 1, got ", mapper_attempts);
  ORCHARD_CHECK_OPTION(retry_unregistered_fraction >= 0 && retry_unregistered_fraction <= 1,
                       "retry unregistered fraction must be in [0, 1], got ", retry_unregistered_fraction);
  ORCHARD_CHECK_OPTION(min_registered >= 2, "min registered frames must be at least 2, got ", min_registered);
  ORCHARD_CHECK_OPTION(num_threads >= 0, "COLMAP threads must be 0 (all cores) or more, got ", num_threads);
}

bool ColmapAvailable(const std::string& colmap) {
  return std::system((Quote(colmap) + " help > /dev/null 2>&1").c_str()) == 0;
}

void MatchColmapFeatures(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options,
                         const std::vector<std::string>& only, const ColmapCamera* known_camera) {
  options.Check();
  const size_t num_images = only.empty() ? ListImages(image_dir).size() : only.size();
  if (static_cast<int>(num_images) < options.min_registered)
    Fail("only ", num_images, " frames in ", image_dir.string(), ", structure from motion needs at least ",
         options.min_registered, " (too few frames)");
  if (!ColmapAvailable(options.colmap))
    Fail("the colmap program '", options.colmap, "' cannot be run (install colmap, or give poses with --poses)");
  // A fresh workspace: a database from an earlier, different run would be reused.
  fs::remove_all(workspace);
  fs::create_directories(workspace);
  const fs::path log = workspace / "colmap.log";
  const std::string db = Quote((workspace / "database.db").string());
  const std::string exe = Quote(options.colmap);
  const std::string threads = std::to_string(ThreadsOrAvailableCores(options.num_threads));
  std::string reader = " --ImageReader.camera_model " + options.camera_model;
  if (known_camera) {
    std::ostringstream params;
    params.precision(17);
    for (size_t i = 0; i < known_camera->params.size(); ++i) params << (i ? "," : "") << known_camera->params[i];
    reader = " --ImageReader.camera_model " + known_camera->model + " --ImageReader.camera_params " +
             Quote(params.str());
  }
  if (!only.empty()) {
    std::string list;
    for (const auto& name : only) list += name + "\n";
    WriteTextFileAtomic(workspace / "image_list.txt", list);
    reader += " --image_list_path " + Quote((workspace / "image_list.txt").string());
  }
  RunStep("feature_extractor",
          exe + " feature_extractor --database_path " + db + " --image_path " + Quote(image_dir.string()) + reader +
              " --ImageReader.single_camera 1 --SiftExtraction.use_gpu 0 --SiftExtraction.max_num_features " +
              std::to_string(options.max_num_features) +
              " --SiftExtraction.first_octave " + std::to_string(options.first_octave) +
              " --SiftExtraction.num_threads " + threads,
          log);
  RunStep("sequential_matcher",
          exe + " sequential_matcher --database_path " + db +
              " --SiftMatching.use_gpu 0 --SequentialMatching.overlap " + std::to_string(options.overlap) +
              " --SequentialMatching.quadratic_overlap " + (options.quadratic_overlap ? "1" : "0") +
              " --SiftMatching.num_threads " + threads,
          log);
}

ColmapModel TriangulateColmapPoints(const fs::path& image_dir, const ColmapModel& posed, const fs::path& workspace,
                                    const ColmapRunnerOptions& options) {
  if (posed.cameras.size() != 1)
    Fail("triangulating points for given poses needs one camera; the pose model has ", posed.cameras.size());
  const ColmapCamera& camera = posed.cameras.begin()->second;
  std::vector<std::string> names;
  for (const auto& [id, image] : posed.images) names.push_back(image.name);
  std::sort(names.begin(), names.end());
  ColmapRunnerOptions matching = options;
  matching.overlap = options.triangulation_overlap;
  matching.quadratic_overlap = false;
  MatchColmapFeatures(image_dir, workspace, matching, names, &camera);
  // The given poses without points: COLMAP matches frames to the database by
  // name (--clear_points 1 takes the database's image ids and keypoints); a
  // fresh database with one camera gives it id 1.
  ColmapModel input;
  ColmapCamera one = camera;
  one.camera_id = 1;
  input.cameras[1] = one;
  for (const auto& [id, image] : posed.images) {
    ColmapImage i = image;
    i.camera_id = 1;
    i.points2D.clear();
    input.images[id] = std::move(i);
  }
  WriteColmapTextModel(input, workspace / "posed");
  const fs::path log = workspace / "colmap.log";
  const std::string exe = Quote(options.colmap);
  fs::create_directories(workspace / "triangulated");
  RunStep("point_triangulator",
          exe + " point_triangulator --database_path " + Quote((workspace / "database.db").string()) +
              " --image_path " + Quote(image_dir.string()) + " --input_path " +
              Quote((workspace / "posed").string()) + " --output_path " +
              Quote((workspace / "triangulated").string()) +
              " --clear_points 1 --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0"
              " --Mapper.ba_refine_extra_params 0 --Mapper.num_threads " +
              std::to_string(ThreadsOrAvailableCores(options.num_threads)),
          log);
  const ColmapModel triangulated = ReadColmapModel(workspace / "triangulated");
  // Back to the given ids, poses and camera; the keypoints and tracks are COLMAP's.
  std::map<int, int> to_given;
  ColmapModel out;
  out.cameras = posed.cameras;
  out.images = posed.images;
  for (auto& [id, image] : out.images) image.points2D.clear();
  double moved = 0;
  for (const auto& [id, image] : triangulated.images) {
    const ColmapImage* posed_image = posed.FindImage(image.name);
    if (!posed_image) Fail("COLMAP's point_triangulator returned frame ", image.name, ", which has no given pose");
    to_given[id] = posed_image->image_id;
    ColmapImage& given = out.images.at(posed_image->image_id);
    given.points2D = image.points2D;
    moved = std::max(moved, (image.ProjectionCenter() - given.ProjectionCenter()).norm());
  }
  // The poses are held; a camera that moved means the model does not match.
  if (moved > 1e-6 * (1 + posed.images.begin()->second.ProjectionCenter().norm()))
    spdlog::warn("COLMAP's point_triangulator moved a given camera by {:.3g} (its points are kept)", moved);
  out.points3D = triangulated.points3D;
  for (auto& [pid, point] : out.points3D)
    for (auto& el : point.track) el.image_id = to_given.at(el.image_id);
  spdlog::info("COLMAP triangulated {} points for the {} given poses", out.points3D.size(), out.images.size());
  return out;
}

ColmapRunResult RunColmap(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options) {
  MatchColmapFeatures(image_dir, workspace, options);
  return MapColmap(image_dir, workspace, options);
}

ColmapRunResult MapColmap(const fs::path& image_dir, const fs::path& workspace, const ColmapRunnerOptions& options) {
  options.Check();
  const std::vector<fs::path> images = ListImages(image_dir);
  const fs::path log = workspace / "colmap.log";
  const std::string exe = Quote(options.colmap);
  if (!fs::exists(workspace / "database.db")) Fail("no COLMAP database in ", workspace.string());
  // The models of an earlier mapper run would be read as this one's.
  for (const auto& entry : fs::directory_iterator(workspace))
    if (entry.is_directory()) fs::remove_all(entry.path());
  fs::create_directories(workspace / "sparse");
  RunStep("mapper",
          exe + " mapper --database_path " + Quote((workspace / "database.db").string()) + " --image_path " +
              Quote(image_dir.string()) + " --output_path " + Quote((workspace / "sparse").string()) +
              " --random_seed " + std::to_string(options.random_seed) +
              " --Mapper.num_threads " + std::to_string(ThreadsOrAvailableCores(options.num_threads)),
          log);
  ColmapRunResult result;
  result.num_input_images = static_cast<int>(images.size());
  std::vector<fs::path> models;
  for (const auto& entry : fs::directory_iterator(workspace / "sparse"))
    if (entry.is_directory()) models.push_back(entry.path());
  std::sort(models.begin(), models.end());
  result.num_models = static_cast<int>(models.size());
  if (models.empty())
    Fail("COLMAP registered no frames of ", image_dir.string(),
         " (too little texture or too little motion between frames; see ", log.string(), ")");
  for (const fs::path& m : models) {
    const fs::path txt = workspace / ("text_" + m.filename().string());
    fs::create_directories(txt);
    RunStep("model_converter",
            exe + " model_converter --input_path " + Quote(m.string()) + " --output_path " + Quote(txt.string()) +
                " --output_type TXT",
            log);
    ColmapModel model = ReadColmapTextModel(txt);
    if (model.images.size() > result.model.images.size()) result.model = std::move(model), result.model_dir = txt;
  }
  std::set<std::string> registered;
  for (const auto& [id, image] : result.model.images) registered.insert(image.name);
  for (const fs::path& p : images)
    if (!registered.count(p.filename().string())) result.unregistered.push_back(p.filename().string());
  const int n = static_cast<int>(registered.size());
  if (n < options.min_registered)
    Fail("COLMAP registered only ", n, " of ", images.size(), " frames (need ", options.min_registered,
         "): too little texture or too little motion between frames");
  if (!result.unregistered.empty())
    spdlog::warn("COLMAP left {} of {} frames out of the largest of {} model(s)", result.unregistered.size(),
                 images.size(), result.num_models);
  return result;
}

int BestAttempt(const std::function<int(int)>& attempt, int max_attempts) {
  int best = -1, best_problems = 0;
  std::optional<Error> first_error;
  for (int k = 0; k < max_attempts && (best < 0 || best_problems > 0); ++k) {
    try {
      const int problems = attempt(k);
      if (best < 0 || problems < best_problems) best = k, best_problems = problems;
    } catch (const Error& e) {
      if (!first_error) first_error = e;
    }
  }
  if (best < 0) {
    if (first_error) throw *first_error;
    Fail("no attempt was made");
  }
  return best;
}

}  // namespace orchard
