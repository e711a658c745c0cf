// The structure-from-motion check on a synthetic row: runs the COLMAP
// program (CPU, sequential matching) on one side's frames, aligns the
// reconstructed camera centres to the true ones with a similarity (Umeyama)
// and reports the registered fraction and the path error relative to the
// path length. Goal: >= 95% registered, error within 1% of the length.
// usage: bench_synth_colmap_check SYNTH_DIR [SIDE=front] [WORKSPACE]
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "orchard/sfm/colmap_model.h"

namespace fs = std::filesystem;

static void Run(const std::string& cmd) {
  std::fprintf(stderr, "+ %s\n", cmd.c_str());
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "command failed: %s\n", cmd.c_str());
    std::exit(1);
  }
}

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SYNTH_DIR [SIDE] [WORKSPACE]\n", argv[0]);
    return 2;
  }
  const fs::path synth = argv[1];
  const std::string side = argc > 2 ? argv[2] : "front";
  const fs::path ws = argc > 3 ? fs::path(argv[3]) : fs::temp_directory_path() / ("orchard_colmap_" + side);
  const fs::path images = synth / side / "images";
  fs::remove_all(ws);
  fs::create_directories(ws / "sparse");
  const std::string q = "'";
  const std::string log = " >> " + (ws / "colmap.log").string() + " 2>&1";
  Run("colmap feature_extractor --database_path " + q + (ws / "db.db").string() + q + " --image_path " + q +
      images.string() + q +
      " --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1 --SiftExtraction.use_gpu 0"
      " --SiftExtraction.max_num_features 2048 --SiftExtraction.first_octave 0" + log);
  Run("colmap sequential_matcher --database_path " + q + (ws / "db.db").string() + q +
      " --SiftMatching.use_gpu 0 --SequentialMatching.overlap 5" + log);
  Run("colmap mapper --database_path " + q + (ws / "db.db").string() + q + " --image_path " + q + images.string() +
      q + " --output_path " + q + (ws / "sparse").string() + q + log);
  // The largest model (COLMAP numbers them 0, 1, ...).
  fs::path best;
  size_t best_images = 0;
  for (const auto& entry : fs::directory_iterator(ws / "sparse")) {
    if (!entry.is_directory()) continue;
    const fs::path txt = ws / ("txt_" + entry.path().filename().string());
    fs::create_directories(txt);
    Run("colmap model_converter --input_path " + q + entry.path().string() + q + " --output_path " + q +
        txt.string() + q + " --output_type TXT" + log);
    const auto model = orchard::ReadColmapTextModel(txt);
    if (model.images.size() > best_images) best_images = model.images.size(), best = txt;
  }
  const auto truth = orchard::ReadColmapTextModel(synth / side / "sparse");
  if (best.empty()) {
    std::printf("registered 0/%zu frames: FAIL\n", truth.images.size());
    return 1;
  }
  const auto model = orchard::ReadColmapTextModel(best);
  std::vector<Eigen::Vector3d> est, ref;
  for (const auto& [id, image] : truth.images) {
    const auto* found = model.FindImage(image.name);
    if (!found) continue;
    est.push_back(found->ProjectionCenter());
    ref.push_back(image.ProjectionCenter());
  }
  double length = 0;
  for (auto it = std::next(truth.images.begin()); it != truth.images.end(); ++it) {
    length += (it->second.ProjectionCenter() - std::prev(it)->second.ProjectionCenter()).norm();
  }
  const int n = static_cast<int>(est.size());
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (int i = 0; i < n; ++i) src.col(i) = est[i], dst.col(i) = ref[i];
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  double max_err = 0, sum_sq = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = sim.topLeftCorner<3, 3>() * src.col(i) + sim.topRightCorner<3, 1>();
    const double e = (p - dst.col(i)).norm();
    max_err = std::max(max_err, e);
    sum_sq += e * e;
  }
  const double fraction = static_cast<double>(n) / truth.images.size();
  const double rms = std::sqrt(sum_sq / std::max(1, n));
  const bool pass = fraction >= 0.95 && max_err <= 0.01 * length;
  std::printf("side %s: registered %d/%zu frames (%.1f%%), %zu 3D points\n", side.c_str(), n, truth.images.size(),
              100 * fraction, model.points3D.size());
  std::printf("camera path %.3f m; after similarity alignment: max error %.4f m (%.3f%% of length), rms %.4f m: %s\n",
              length, max_err, 100 * max_err / length, rms, pass ? "PASS" : "FAIL");
  return pass ? 0 : 1;
}
