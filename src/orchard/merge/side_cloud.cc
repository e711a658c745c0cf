#include "orchard/merge/side_cloud.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {

void UpdateClusterExtent(SideCluster* c) {
  if (c->points.empty()) return;
  c->centre.setZero();
  c->min = c->max = c->points[0];
  for (const auto& p : c->points) {
    c->centre += p;
    c->min = c->min.cwiseMin(p), c->max = c->max.cwiseMax(p);
  }
  c->centre /= static_cast<double>(c->points.size());
}

void ScaleSideCloud(SideCloud* side, double scale) {
  for (auto& p : side->sparse) p *= scale;
  for (auto& p : side->cameras) p *= scale;
  for (auto* clusters : {&side->clusters, &side->fallen})
    for (auto& c : *clusters) MoveCluster(&c, [scale](const Eigen::Vector3d& p) -> Eigen::Vector3d { return p * scale; });
}

SideCloud WithFallenLandmarks(const SideCloud& side) {
  SideCloud with = side;
  with.clusters.insert(with.clusters.end(), side.fallen.begin(), side.fallen.end());
  with.fallen.clear();
  return with;
}

SideCloud WithoutEdgeApples(const SideCloud& side) {
  SideCloud without = side;
  without.clusters.erase(std::remove_if(without.clusters.begin(), without.clusters.end(),
                                        [](const SideCluster& c) { return c.edge; }),
                         without.clusters.end());
  return without;
}

Eigen::Isometry3d RowFrameTransform(const Eigen::Vector3d& origin, const Eigen::Vector3d& along,
                                    const Eigen::Vector3d& across, const Eigen::Vector3d& up) {
  Eigen::Matrix3d axes;
  axes.col(0) = along.normalized(), axes.col(1) = across.normalized(), axes.col(2) = up.normalized();
  if (std::abs(axes.determinant() - 1) > 1e-3) Fail("row frame axes are not a right-handed orthonormal basis");
  Eigen::Isometry3d to_row = Eigen::Isometry3d::Identity();
  to_row.linear() = axes.transpose();
  to_row.translation() = -axes.transpose() * origin;
  return to_row;
}

namespace {

// Calls row_fn(fields, line number) for each line after the header of a CSV
// file; false (and no call) when there is no such file.
template <typename RowFn>
bool ForEachCsvRow(const fs::path& path, RowFn&& row_fn) {
  if (!fs::is_regular_file(path)) return false;
  std::istringstream csv(ReadTextFile(path));
  std::string line;
  std::getline(csv, line);
  int row = 1;
  while (std::getline(csv, line)) row_fn(SplitCsvLine(line), ++row);
  return true;
}

Eigen::Vector3d Vec3(const nlohmann::json& j) {
  const auto v = j.get<std::vector<double>>();
  if (v.size() != 3) Fail("expected three numbers, got ", v.size());
  return {v[0], v[1], v[2]};
}

}  // namespace

SideCloud LoadSideCloud(const fs::path& dir, const std::string& name, const std::string& unlinked_count_column) {
  SideCloud cloud;
  cloud.name = name;
  double scale = 1;  // COLMAP's model -> metres (the poses were scaled by it before the row frame was made)
  const fs::path json_path = dir / "side.json", csv_path = dir / "clusters.csv", ply_path = dir / "fruit.ply";
  for (const auto& p : {json_path, csv_path, ply_path})
    if (!fs::is_regular_file(p)) Fail(name, " side: ", p.string(), " is missing (run `orchard side` first)");
  try {
    const nlohmann::json j = nlohmann::json::parse(ReadTextFile(json_path));
    const auto& f = j.at("row_frame");
    cloud.to_row = RowFrameTransform(Vec3(f.at("origin")), Vec3(f.at("along")), Vec3(f.at("across")), Vec3(f.at("up")));
    cloud.count = j.at("count").get<int>();
    cloud.row_distance = j.value("row_distance", 0.0);
    scale = j.value("scale", 1.0);
    if (j.contains("warnings")) cloud.warnings = j.at("warnings").get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    Fail(name, " side: ", json_path.string(), " has no usable row_frame/count (made by an older version?): ", e.what());
  }
  // Kept and fallen clusters and their counts.
  std::map<int, SideCluster*> index;  // cluster id -> its place in cloud.clusters or cloud.fallen
  std::map<int, std::string> count_frames;  // cluster id -> its `frames` (names separated by ';')
  {
    std::istringstream csv(ReadTextFile(csv_path));
    std::string line;
    std::getline(csv, line);
    if (line.rfind("id,x,y,z,", 0) != 0) Fail(name, " side: ", csv_path.string(), " is not a side clusters.csv");
    const std::vector<std::string> header = SplitCsvLine(line);
    const auto unlinked_it = std::find(header.begin(), header.end(), unlinked_count_column);
    if (unlinked_it == header.end())
      Fail(name, " side: ", csv_path.string(), " has no column ", unlinked_count_column,
           " (made by an older version? run the side again)");
    const size_t unlinked_col = static_cast<size_t>(unlinked_it - header.begin());
    // Sides written before edge apples have no `edge` column, before glimpsed
    // apples no `glimpsed` column.
    const auto column = [&header](const char* name) {
      const auto it = std::find(header.begin(), header.end(), name);
      return it == header.end() ? size_t{0} : static_cast<size_t>(it - header.begin());
    };
    const size_t edge_col = column("edge"), glimpsed_col = column("glimpsed");
    const auto flag = [](const std::vector<std::string>& f, size_t col) { return col > 0 && col < f.size() && f[col] == "1"; };
    int row = 1;
    while (std::getline(csv, line)) {
      ++row;
      const std::vector<std::string> f = SplitCsvLine(line);
      if (f.size() < std::max<size_t>(10, unlinked_col + 1))
        Fail(name, " side: ", csv_path.string(), " line ", row, " has ", f.size(), " fields");
      if (f[9] != "kept" && f[9] != "fallen") continue;
      SideCluster c;
      try {
        c.id = std::stoi(f[0]);
        c.count = std::stoi(f[8]);
        c.count_unlinked = std::stoi(f[unlinked_col]);
        c.glimpsed = flag(f, glimpsed_col);
        c.edge = flag(f, edge_col) || c.glimpsed;
        if (f.size() > 12) count_frames[c.id] = f[12];
      } catch (const std::exception&) {
        Fail(name, " side: ", csv_path.string(), " line ", row, ": bad id or count");
      }
      (f[9] == "kept" ? cloud.clusters : cloud.fallen).push_back(c);
    }
  }
  // Pointers once the vectors stop growing.
  for (auto* clusters : {&cloud.clusters, &cloud.fallen})
    for (auto& c : *clusters) index[c.id] = &c;
  // Fruit points (ascii PLY written by RunSide: x y z r g b cluster).
  {
    std::ifstream ply(ply_path);
    std::string line;
    bool header = true;
    int line_no = 0;
    while (std::getline(ply, line)) {
      ++line_no;
      if (header) {
        if (line == "end_header") header = false;
        continue;
      }
      std::istringstream ls(line);
      Eigen::Vector3d p;
      int r, g, b, id;
      if (!(ls >> p.x() >> p.y() >> p.z() >> r >> g >> b >> id))
        Fail(name, " side: ", ply_path.string(), " line ", line_no, " is not 'x y z r g b cluster'");
      const auto it = index.find(id);
      if (it != index.end()) it->second->points.push_back(cloud.to_row * p);
    }
    if (header) Fail(name, " side: ", ply_path.string(), " has no PLY header");
  }
  // Edge apples' rays.
  const fs::path rays_path = dir / "edge_rays.csv";
  ForEachCsvRow(rays_path, [&](const std::vector<std::string>& f, int row) {
    Eigen::Vector3d a, b;
    int id = 0;
    try {
      if (f.size() != 10) throw std::invalid_argument("fields");
      id = std::stoi(f[0]);
      a = {std::stod(f[4]), std::stod(f[5]), std::stod(f[6])};
      b = {std::stod(f[7]), std::stod(f[8]), std::stod(f[9])};
    } catch (const std::exception&) {
      Fail(name, " side: ", rays_path.string(), " line ", row,
           " is not 'cluster,frame,column,pixels,near x,y,z,far x,y,z'");
    }
    const auto it = index.find(id);
    if (it == index.end() || !it->second->edge) return;
    it->second->ray_ends.push_back(cloud.to_row * a);
    it->second->ray_ends.push_back(cloud.to_row * b);
  });
  // The count frames' camera centres.
  const fs::path cameras_path = dir / "cameras.csv";
  std::map<std::string, Eigen::Vector3d> centre_of;
  ForEachCsvRow(cameras_path, [&](const std::vector<std::string>& f, int row) {
    try {
      if (f.size() != 4) throw std::invalid_argument("fields");
      centre_of[f[0]] = cloud.to_row * Eigen::Vector3d(std::stod(f[1]), std::stod(f[2]), std::stod(f[3]));
    } catch (const std::exception&) {
      Fail(name, " side: ", cameras_path.string(), " line ", row, " is not 'frame,x,y,z'");
    }
  });
  for (const auto& [id, names] : count_frames) {
    std::istringstream list(names);
    std::string frame;
    while (std::getline(list, frame, ';')) {
      const auto it = centre_of.find(frame);
      if (it != centre_of.end()) index.at(id)->view_centres.push_back(it->second);
    }
  }
  // Sparse points (COLMAP text: "id x y z r g b error track..."); the side
  // writes sparse/ for the poses it solved and for given poses it
  // triangulated points for (WithSparsePoints), never for given poses alone.
  const fs::path points_path = dir / "sparse" / "points3D.txt";
  if (fs::is_regular_file(points_path)) {
    std::ifstream in(points_path);
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ls(line);
      long long id;
      Eigen::Vector3d p;
      if (!(ls >> id >> p.x() >> p.y() >> p.z()))
        Fail(name, " side: ", points_path.string(), " has a line that is not 'id x y z ...'");
      cloud.sparse.push_back(cloud.to_row * (scale * p));
    }
    // Camera centres: "id qw qx qy qz tx ty tz camera name", then a line of
    // 2D points.
    std::ifstream images(dir / "sparse" / "images.txt");
    bool pose_line = true;
    while (std::getline(images, line)) {
      if (!line.empty() && line[0] == '#') continue;
      if (pose_line) {
        std::istringstream ls(line);
        long long id;
        double qw, qx, qy, qz;
        Eigen::Vector3d t;
        if (!(ls >> id >> qw >> qx >> qy >> qz >> t.x() >> t.y() >> t.z()))
          Fail(name, " side: ", (dir / "sparse" / "images.txt").string(), " has a pose line that is not 'id qw qx qy qz tx ty tz ...'");
        const Eigen::Vector3d centre = -(Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix().transpose() * t);
        cloud.cameras.push_back(cloud.to_row * (scale * centre));
      }
      pose_line = !pose_line;
    }
  }
  for (auto& c : cloud.clusters) {
    if (c.points.empty()) Fail(name, " side: cluster ", c.id, " of ", csv_path.string(), " has no points in ", ply_path.string());
    UpdateClusterExtent(&c);
  }
  // Landmarks only: one without points is left out.
  cloud.fallen.erase(std::remove_if(cloud.fallen.begin(), cloud.fallen.end(),
                                    [](const SideCluster& c) { return c.points.empty(); }),
                     cloud.fallen.end());
  for (auto& c : cloud.fallen) UpdateClusterExtent(&c);
  return cloud;
}

}  // namespace orchard
