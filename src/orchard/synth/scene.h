// A procedural apple-tree row in world coordinates: x along the row, y across
// it (the front camera path is at y < 0, the back one at y > 0), z up, ground
// plane z = 0, metres. Trees stand at y = 0; neighbouring rows at
// y = +-row_spacing give the background seen behind the filmed row.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace orchard::synth {

using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;

struct SceneOptions {
  // Trees in the filmed row (the ones counted in the ground truth).
  int num_trees = 4;
  // Distance between trunks along the row (m); high-density rows use 1-1.5 m.
  double tree_spacing = 1.25;
  // "planar" (fruit wall / hedge, apples often visible from both sides) or
  // "round" (spindle-like ellipsoid per tree, thicker, rarely both sides).
  std::string canopy_shape = "planar";
  // Lowest and highest foliage above the ground (m).
  double canopy_base = 0.6;
  double canopy_top = 3.0;
  // Canopy thickness across the row at its base (m); planar canopies taper
  // to half of it at the top.
  double canopy_thickness = 1.2;
  // Mean apples per tree (actual counts vary +-20%).
  double apples_per_tree = 70;
  // Fraction of apples growing deep inside the canopy (rarely visible).
  double deep_fraction = 0.15;
  // Apple radius range (m).
  double apple_radius_min = 0.03;
  double apple_radius_max = 0.05;
  // "red", "green", "yellow", "blush" or "mixed" (one variety per tree).
  std::string variety = "mixed";
  // Fallen apples on the ground, as a fraction of the apples on the trees.
  double fallen_fraction = 0.15;
  // Multiplier on the number of leaves (1 = dense summer canopy).
  double leaf_density = 1.0;
  // Leaf length (m); width is about half of it.
  double leaf_length = 0.08;
  // Fraction of yellowing leaves (late season).
  double yellow_leaf_fraction = 0.0;
  // Distance between rows (m) and whether the neighbouring rows are drawn.
  double row_spacing = 3.5;
  bool background_rows = true;
  // Sun elevation above the horizon and azimuth from the -y axis towards +x
  // (degrees): azimuth 0 puts the sun on the front side (y < 0).
  double sun_elevation_deg = 40;
  double sun_azimuth_deg = 30;

  void Check() const;
};

enum class Variety { kRed = 0, kGreen = 1, kYellow = 2, kBlush = 3 };
const char* VarietyName(Variety variety);

struct Apple {
  int id = 0;             // 0-based; masks store id + 1
  int tree = -1;          // index in the filmed row, -1 for background rows
  int row = 0;            // 0 = filmed row, -1 / +1 = neighbouring rows
  int cluster = -1;       // cluster id (unique over the scene); -1 for fallen apples
  bool on_ground = false;
  Vec3 center = Vec3::Zero();
  double radius = 0.04;
  Variety variety = Variety::kRed;
  // Appearance.
  Vec3 up = Vec3::UnitZ();  // stem direction
  Vec3f base_color = Vec3f::Zero();
  Vec3f blush_color = Vec3f::Zero();
  float blush = 0;          // fraction of the surface covered by blush
  float sun = 1;            // direct sunlight reaching it (0..1)
  float ambient = 1;        // sky light reaching it (0..1)
  std::uint32_t texture_seed = 0;
};

// A flat leaf: an ovate blade in the plane spanned by `u` (midrib, half
// length a) and `v` (half width b) around `center`.
struct Leaf {
  Eigen::Vector3f center, u, v, normal;
  float a = 0.04f, b = 0.02f;
  Vec3f color;
  float sun = 1, ambient = 1;
  float fold = 0.3f;  // shading tilt of the two halves about the midrib
  std::uint32_t texture_seed = 0;
};

enum class Material { kBark = 0, kPost = 1 };

// A finite open cylinder from p0 along unit `axis` over `length`.
struct Cylinder {
  Vec3 p0 = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double length = 1;
  double radius = 0.05;
  Material material = Material::kBark;
  Vec3f color;
  float sun = 1, ambient = 1;  // light reaching the cylinder's middle
  std::uint32_t texture_seed = 0;
};

struct Scene {
  SceneOptions options;
  std::uint64_t seed = 0;
  Vec3 sun_direction = Vec3::UnitZ();   // unit vector towards the sun
  std::vector<double> tree_x;           // trunk positions of the filmed row
  double row_x_min = 0, row_x_max = 0;  // extent of the filmed row's canopy
  std::vector<Apple> apples;            // id == index
  std::vector<Leaf> leaves;
  std::vector<Cylinder> cylinders;

  // Ground shadow: fraction of direct sun reaching ground point (x, y), from
  // a precomputed grid (1 outside it).
  float GroundSun(double x, double y) const;
  // Inside the canopy volume of row `row` (0 = filmed row).
  bool InsideCanopy(const Vec3& p, int row) const;
  // Depth of p below the canopy surface (m); negative outside.
  double CanopyDepth(const Vec3& p, int row) const;

  // Ground shadow grid (row-major, cells of shadow_cell metres from
  // (shadow_x0, shadow_y0)).
  std::vector<float> shadow;
  int shadow_nx = 0, shadow_ny = 0;
  double shadow_x0 = 0, shadow_y0 = 0, shadow_cell = 0.05;
};

// Builds the scene; the same options and seed give the same scene.
Scene GenerateScene(const SceneOptions& options, std::uint64_t seed);

}  // namespace orchard::synth
