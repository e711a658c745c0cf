// The structure-from-motion check on a synthetic row: runs the COLMAP
// program (CPU, sequential matching, through orchard's COLMAP runner) on one
// side's frames, aligns the reconstructed camera centres to the true ones
// with a similarity (Umeyama) and reports the registered fraction and the
// path error relative to the path length. Goal: >= 95% registered, error
// within 1% of the length.
// usage: bench_synth_colmap_check SYNTH_DIR [SIDE=front] [WORKSPACE]
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "orchard/core/error.h"
#include "orchard/sfm/colmap_model.h"
#include "orchard/sfm/colmap_runner.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SYNTH_DIR [SIDE] [WORKSPACE]\n", argv[0]);
    return 2;
  }
  const fs::path synth = argv[1];
  const std::string side = argc > 2 ? argv[2] : "front";
  const fs::path ws = argc > 3 ? fs::path(argv[3]) : fs::temp_directory_path() / ("orchard_colmap_" + side);
  const auto truth = orchard::ReadColmapTextModel(synth / side / "sparse");
  orchard::ColmapRunnerOptions options;
  options.camera_model = "PINHOLE";  // the generator renders undistorted frames
  orchard::ColmapModel model;
  try {
    model = orchard::RunColmap(synth / side / "images", ws, options).model;
  } catch (const orchard::Error& e) {
    std::printf("%s: FAIL\n", e.what());
    return 1;
  }
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
