// One side's kept fruit clusters and, with COLMAP poses, its sparse scene
// points, in its row frame (x along the camera path, y across towards the
// row, z up from the ground, metres), read back from an `orchard side` output
// folder: the merge's only input from the side stage.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace orchard {

namespace fs = std::filesystem;

struct SideCluster {
  int id = 0;      // the id in the side's clusters.csv
  int count = 0;   // apples (median of the best views)
  // Its count when no cluster of the other side links to it (-1: count);
  // LoadSideCloud's unlinked_count_column.
  int count_unlinked = -1;
  std::vector<Eigen::Vector3d> points;  // fruit points, row frame
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
  // Seen only as slivers at the frames' top edge (clusters.csv `edge`) or as
  // pieces through the leaves (`glimpsed`): its place along the slivers' or
  // pieces' rays is a guess, so the merge links it along them (edge_rays.csv:
  // each ray's ends, consecutive pairs here, moved with the points), and
  // registrations leave it out.
  bool edge = false;
  bool glimpsed = false;  // of the two, glimpsed: its rays pass through the apple's centre
  std::vector<Eigen::Vector3d> ray_ends;
  // Camera centres of the frames its count came from (clusters.csv `frames`,
  // cameras.csv; empty for sides written before cameras.csv), moved with the
  // points: the merge follows its lines of sight through its centre.
  std::vector<Eigen::Vector3d> view_centres;
};

struct SideCloud {
  std::string name;  // "front" / "back"
  // Poses' frame -> row frame.
  Eigen::Isometry3d to_row = Eigen::Isometry3d::Identity();
  std::vector<SideCluster> clusters;  // kept clusters only
  // Clusters the side removed as fallen (on the ground): never counted, but
  // both sides see the apples lying under the row, so they are landmarks for
  // the registration (WithFallenLandmarks).
  std::vector<SideCluster> fallen;
  int count = 0;                      // the side's count (sum over kept clusters)
  // COLMAP's sparse points (sparse/points3D.txt, scaled like the poses):
  // leaves, branches, trunks and ground of the row; for given poses the
  // points COLMAP triangulated with them held (empty when it did not).
  std::vector<Eigen::Vector3d> sparse;
  std::vector<Eigen::Vector3d> cameras;  // camera centres (sparse/images.txt), with the sparse points
  double row_distance = 0;  // side.json: the filmed row's fruit distance from the camera path (m)
  std::vector<std::string> warnings;  // side.json's warnings
};

// Fills centre, min and max from the points.
void UpdateClusterExtent(SideCluster* cluster);

// Moves all of a cluster's geometry (points, edge rays, view centres) by
// `move` (point -> point) and updates its extent: every transform of a side
// goes through here, so no part of a cluster is left in the old frame.
template <typename Move>
void MoveCluster(SideCluster* cluster, const Move& move) {
  for (auto* points : {&cluster->points, &cluster->ray_ends, &cluster->view_centres})
    for (auto& p : *points) p = move(p);
  UpdateClusterExtent(cluster);
}

// Scales the side's clusters (kept and fallen), sparse points and cameras
// about its row frame's origin (on the ground under the camera path).
void ScaleSideCloud(SideCloud* side, double scale);

// A copy whose clusters are the kept and the fallen ones, for the
// registration (fallen emptied).
SideCloud WithFallenLandmarks(const SideCloud& side);

// A copy without the edge apples (SideCluster::edge), for registrations.
SideCloud WithoutEdgeApples(const SideCloud& side);

// The row frame as a transform from origin and axes (columns of the rotation
// are along, across, up).
Eigen::Isometry3d RowFrameTransform(const Eigen::Vector3d& origin, const Eigen::Vector3d& along,
                                    const Eigen::Vector3d& across, const Eigen::Vector3d& up);

// Reads side.json (row_frame, count), clusters.csv (kept and fallen clusters,
// their counts; count_unlinked from the column `unlinked_count_column`, e.g.
// "count_by_count"), fruit.ply (points with cluster ids) and, when present,
// edge_rays.csv (an edge apple's rays), cameras.csv (the view centres),
// sparse/points3D.txt and images.txt of `side_dir`. Throws orchard::Error naming the file
// when one is missing or malformed.
SideCloud LoadSideCloud(const fs::path& side_dir, const std::string& name,
                        const std::string& unlinked_count_column = "count");

}  // namespace orchard
