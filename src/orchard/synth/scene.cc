#include "orchard/synth/scene.h"

#include <algorithm>
#include <cmath>

#include "orchard/core/error.h"
#include "orchard/synth/random.h"

namespace orchard::synth {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Light extinction per metre of canopy at leaf_density 1 (leaf area density
// times a projection factor ~0.4).
constexpr double kExtinction = 2.0;
// Leaf area per canopy volume (m^2/m^3) at leaf_density 1: dense enough that
// most of the far side is hidden, with gaps between shoots.
constexpr double kLeafAreaDensity = 5.0;

double Clamp(double v, double lo, double hi) { return std::min(hi, std::max(lo, v)); }

Vec3 RandomUnit(Random& rng) {
  for (;;) {
    const Vec3 v(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
    const double n = v.squaredNorm();
    if (n > 1e-4 && n <= 1.0) return v / std::sqrt(n);
  }
}

// Any unit vector perpendicular to n.
Vec3 Perpendicular(const Vec3& n) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return n.cross(a).normalized();
}

Vec3f Jitter(Random& rng, const Vec3f& color, double amount) {
  const double k = 1.0 + amount * rng.Normal();
  Vec3f c = color * static_cast<float>(Clamp(k, 0.5, 1.6));
  for (int i = 0; i < 3; ++i) c[i] *= static_cast<float>(1.0 + 0.4 * amount * rng.Normal());
  return c.cwiseMax(0.0f);
}

}  // namespace

const char* VarietyName(Variety variety) {
  switch (variety) {
    case Variety::kRed: return "red";
    case Variety::kGreen: return "green";
    case Variety::kYellow: return "yellow";
    case Variety::kBlush: return "blush";
  }
  return "?";
}

void SceneOptions::Check() const {
  ORCHARD_CHECK_OPTION(num_trees >= 1 && num_trees <= 200, "--trees must be in 1..200, got ", num_trees);
  ORCHARD_CHECK_OPTION(tree_spacing >= 0.3 && tree_spacing <= 10, "--tree-spacing must be in 0.3..10 m, got ",
                       tree_spacing);
  ORCHARD_CHECK_OPTION(canopy_shape == "planar" || canopy_shape == "round",
                       "--canopy must be planar or round, got '", canopy_shape, "'");
  ORCHARD_CHECK_OPTION(canopy_base >= 0.1 && canopy_top > canopy_base + 0.5 && canopy_top <= 8,
                       "canopy must span at least 0.5 m between --canopy-base (>= 0.1) and --canopy-top (<= 8), got ",
                       canopy_base, "..", canopy_top);
  ORCHARD_CHECK_OPTION(canopy_thickness >= 0.3 && canopy_thickness <= 4,
                       "--canopy-thickness must be in 0.3..4 m, got ", canopy_thickness);
  ORCHARD_CHECK_OPTION(apples_per_tree >= 0 && apples_per_tree <= 1000,
                       "--apples-per-tree must be in 0..1000, got ", apples_per_tree);
  ORCHARD_CHECK_OPTION(deep_fraction >= 0 && deep_fraction <= 1, "--deep-fraction must be in 0..1, got ",
                       deep_fraction);
  ORCHARD_CHECK_OPTION(apple_radius_min >= 0.01 && apple_radius_max >= apple_radius_min && apple_radius_max <= 0.1,
                       "apple radius range must satisfy 0.01 <= min <= max <= 0.1 m, got ", apple_radius_min,
                       "..", apple_radius_max);
  ORCHARD_CHECK_OPTION(variety == "red" || variety == "green" || variety == "yellow" || variety == "blush" ||
                           variety == "mixed",
                       "--variety must be red, green, yellow, blush or mixed, got '", variety, "'");
  ORCHARD_CHECK_OPTION(fallen_fraction >= 0 && fallen_fraction <= 2, "--fallen-fraction must be in 0..2, got ",
                       fallen_fraction);
  ORCHARD_CHECK_OPTION(leaf_density >= 0 && leaf_density <= 4, "--leaf-density must be in 0..4, got ",
                       leaf_density);
  ORCHARD_CHECK_OPTION(leaf_length >= 0.02 && leaf_length <= 0.3, "--leaf-length must be in 0.02..0.3 m, got ",
                       leaf_length);
  ORCHARD_CHECK_OPTION(yellow_leaf_fraction >= 0 && yellow_leaf_fraction <= 1,
                       "--yellow-leaves must be in 0..1, got ", yellow_leaf_fraction);
  ORCHARD_CHECK_OPTION(row_spacing >= canopy_thickness * (canopy_shape == "round" ? 1.5 : 1.0) + 0.5 &&
                           row_spacing <= 20,
                       "--row-spacing must leave an alley of at least 0.5 m beside the canopy and be <= 20 m, got ",
                       row_spacing);
  ORCHARD_CHECK_OPTION(sun_elevation_deg >= 5 && sun_elevation_deg <= 90,
                       "--sun-elevation must be in 5..90 degrees, got ", sun_elevation_deg);
  ORCHARD_CHECK_OPTION(std::isfinite(sun_azimuth_deg), "--sun-azimuth must be a number");
}

// ----- Canopy envelope -------------------------------------------------------

namespace {

// Half thickness of a planar canopy at height z, with a lumpy surface.
double PlanarHalfThickness(const SceneOptions& o, double x, double z, std::uint32_t seed) {
  const double h = Clamp((z - o.canopy_base) / (o.canopy_top - o.canopy_base), 0, 1);
  const double lump = 0.75 + 0.5 * ValueNoise2(static_cast<float>(x * 2.2), static_cast<float>(z * 2.2), seed);
  return 0.5 * o.canopy_thickness * (1.0 - 0.5 * h) * lump;
}

struct RowGeometry {
  double y = 0;
  double x_min = 0, x_max = 0;
  double tree_x0 = 0;  // trunk positions tree_x0 + k * spacing
  std::uint32_t seed = 0;
};

}  // namespace

// Rows -1, 0, +1; the filmed row's extent is the trees' extent, the
// neighbouring rows reach further so they fill the background.
static RowGeometry GetRow(const Scene& scene, int row) {
  const SceneOptions& o = scene.options;
  RowGeometry g;
  g.y = row * o.row_spacing;
  g.seed = static_cast<std::uint32_t>(scene.seed * 7 + 101 * (row + 2));
  if (row == 0) {
    g.x_min = scene.row_x_min;
    g.x_max = scene.row_x_max;
    g.tree_x0 = scene.tree_x.front();
  } else {
    g.x_min = scene.row_x_min - 7.0;
    g.x_max = scene.row_x_max + 7.0;
    g.tree_x0 = g.x_min + 0.5 * o.tree_spacing + 0.37 * o.tree_spacing * row;
  }
  return g;
}

static double CanopyDepthInRow(const Scene& scene, const Vec3& p, const RowGeometry& g) {
  const SceneOptions& o = scene.options;
  if (o.canopy_shape == "planar") {
    const double ht = PlanarHalfThickness(o, p.x(), p.z(), g.seed);
    double d = ht - std::abs(p.y() - g.y);
    d = std::min(d, o.canopy_top - p.z());
    d = std::min(d, p.z() - o.canopy_base);
    d = std::min(d, p.x() - g.x_min);
    d = std::min(d, g.x_max - p.x());
    return d;
  }
  // Round: one ellipsoid per tree; depth approximated in the smallest semi-axis.
  const double rx = 0.62 * o.tree_spacing, ry = 0.75 * o.canopy_thickness;
  const double rz = 0.5 * (o.canopy_top - o.canopy_base), zc = 0.5 * (o.canopy_top + o.canopy_base);
  const double k = std::round((p.x() - g.tree_x0) / o.tree_spacing);
  double best = -1e9;
  for (double kk = k - 1; kk <= k + 1; ++kk) {
    const double cx = g.tree_x0 + kk * o.tree_spacing;
    if (cx < g.x_min || cx > g.x_max) continue;
    const double lump =
        0.85 + 0.3 * ValueNoise2(static_cast<float>(p.x() * 2.5), static_cast<float>(p.z() * 2.5 + p.y()), g.seed);
    const double rho = std::sqrt(std::pow((p.x() - cx) / rx, 2) + std::pow((p.y() - g.y) / ry, 2) +
                                 std::pow((p.z() - zc) / rz, 2)) / lump;
    best = std::max(best, (1.0 - rho) * std::min({rx, ry, rz}));
  }
  return best;
}

double Scene::CanopyDepth(const Vec3& p, int row) const { return CanopyDepthInRow(*this, p, GetRow(*this, row)); }
bool Scene::InsideCanopy(const Vec3& p, int row) const { return CanopyDepth(p, row) >= 0; }

float Scene::GroundSun(double x, double y) const {
  if (shadow.empty()) return 1.0f;
  const double fx = (x - shadow_x0) / shadow_cell - 0.5, fy = (y - shadow_y0) / shadow_cell - 0.5;
  if (fx < 0 || fy < 0 || fx >= shadow_nx - 1 || fy >= shadow_ny - 1) return 1.0f;
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const float tx = static_cast<float>(fx - ix), ty = static_cast<float>(fy - iy);
  const float* s = &shadow[static_cast<size_t>(iy) * shadow_nx + ix];
  const float a = s[0] + (s[1] - s[0]) * tx;
  const float b = s[shadow_nx] + (s[shadow_nx + 1] - s[shadow_nx]) * tx;
  return a + (b - a) * ty;
}

namespace {

// Fraction of direct sun reaching p through the canopies (Beer-Lambert along
// the sun ray, marched in steps).
double SunTransmission(const Scene& scene, const Vec3& p, double step) {
  const SceneOptions& o = scene.options;
  const Vec3& s = scene.sun_direction;
  double length = 0;
  for (double t = step * 0.5; t < 8.0; t += step) {
    const Vec3 q = p + t * s;
    if (q.z() > o.canopy_top) break;
    const int row = static_cast<int>(std::lround(q.y() / o.row_spacing));
    if (row < -1 || row > 1) continue;
    if (row != 0 && !o.background_rows) continue;
    if (scene.CanopyDepth(q, row) >= 0) length += step;
  }
  return std::exp(-kExtinction * o.leaf_density * length);
}

// Sun (dappled: a leaf is either in a sunfleck or in shade) and sky light.
void Lighting(const Scene& scene, const Vec3& p, int row, Random& rng, double step, float* sun, float* ambient) {
  const double transmission = SunTransmission(scene, p, step);
  *sun = rng.Bernoulli(transmission) ? static_cast<float>(rng.Uniform(0.75, 1.0))
                                     : static_cast<float>(rng.Uniform(0.0, 0.08));
  const double depth = std::max(0.0, scene.CanopyDepth(p, row));
  *ambient = static_cast<float>(0.25 + 0.75 * std::exp(-depth / (0.25 / std::max(0.2, scene.options.leaf_density))));
}

Variety PickVariety(const std::string& name, Random& rng) {
  if (name == "red") return Variety::kRed;
  if (name == "green") return Variety::kGreen;
  if (name == "yellow") return Variety::kYellow;
  if (name == "blush") return Variety::kBlush;
  return static_cast<Variety>(rng.UniformInt(0, 3));
}

// Linear-RGB albedos of the apple varieties: ground colour, blush colour and
// blush coverage.
void VarietyColors(Variety v, Random& rng, Apple* a) {
  switch (v) {
    case Variety::kRed:
      a->base_color = {0.42f, 0.28f, 0.05f}, a->blush_color = {0.30f, 0.015f, 0.02f};
      a->blush = static_cast<float>(rng.Uniform(0.7, 0.95));
      break;
    case Variety::kGreen:
      a->base_color = {0.22f, 0.42f, 0.05f}, a->blush_color = {0.35f, 0.22f, 0.04f};
      a->blush = static_cast<float>(rng.Uniform(0.0, 0.15));
      break;
    case Variety::kYellow:
      a->base_color = {0.62f, 0.48f, 0.08f}, a->blush_color = {0.55f, 0.22f, 0.04f};
      a->blush = static_cast<float>(rng.Uniform(0.0, 0.25));
      break;
    case Variety::kBlush:
      a->base_color = {0.50f, 0.45f, 0.09f}, a->blush_color = {0.42f, 0.04f, 0.03f};
      a->blush = static_cast<float>(rng.Uniform(0.3, 0.6));
      break;
  }
  a->base_color = Jitter(rng, a->base_color, 0.08);
  a->blush_color = Jitter(rng, a->blush_color, 0.1);
}

// Cluster size: skewed to one apple, up to six, occasionally more.
int DrawClusterSize(Random& rng) {
  static const double kCumulative[] = {0.42, 0.66, 0.80, 0.89, 0.94, 0.98};
  const double u = rng.Uniform();
  for (int k = 0; k < 6; ++k) {
    if (u < kCumulative[k]) return k + 1;
  }
  return rng.UniformInt(7, 9);
}

bool Overlaps(const std::vector<Apple>& apples, size_t first, const Vec3& c, double r) {
  for (size_t i = first; i < apples.size(); ++i) {
    if ((apples[i].center - c).norm() < apples[i].radius + r + 0.002) return true;
  }
  return false;
}

// Point inside the canopy of tree column [x0, x1] of `row` with canopy depth in [dmin, dmax].
bool SampleCanopyPoint(const Scene& scene, const RowGeometry& g, int row, double x0, double x1, double dmin,
                       double dmax, Random& rng, Vec3* out) {
  const SceneOptions& o = scene.options;
  const double half = (o.canopy_shape == "round" ? 0.75 : 0.6) * o.canopy_thickness;
  for (int attempt = 0; attempt < 400; ++attempt) {
    const Vec3 p(rng.Uniform(x0, x1), g.y + rng.Uniform(-half, half), rng.Uniform(o.canopy_base, o.canopy_top));
    const double d = CanopyDepthInRow(scene, p, g);
    if (d >= dmin && d <= dmax) {
      *out = p;
      (void)row;
      return true;
    }
  }
  return false;
}

void AddApplesForTree(Scene& scene, const RowGeometry& g, int row, int tree, double tree_x, double per_tree,
                      double deep_fraction, Variety variety, Random& rng, int* next_cluster) {
  const SceneOptions& o = scene.options;
  const int target = static_cast<int>(std::lround(per_tree * rng.Uniform(0.8, 1.2)));
  const size_t first = scene.apples.size();
  const double x0 = tree_x - 0.5 * o.tree_spacing, x1 = tree_x + 0.5 * o.tree_spacing;
  int placed = 0, failures = 0;
  while (placed < target && failures < 50) {
    int size = std::min(DrawClusterSize(rng), target - placed);
    const bool deep = rng.Bernoulli(deep_fraction);
    Vec3 c;
    const double max_depth = o.canopy_shape == "round" ? 0.75 * o.canopy_thickness : 0.5 * o.canopy_thickness;
    const bool ok = deep ? SampleCanopyPoint(scene, g, row, x0, x1, 0.45 * max_depth, 10, rng, &c)
                         : SampleCanopyPoint(scene, g, row, x0, x1, 0.0, 0.22, rng, &c);
    if (!ok) {
      ++failures;
      continue;
    }
    const int cluster = (*next_cluster)++;
    std::vector<size_t> members;
    for (int k = 0; k < size; ++k) {
      const double r = Clamp(rng.Normal(0.5 * (o.apple_radius_min + o.apple_radius_max),
                                        0.25 * (o.apple_radius_max - o.apple_radius_min)),
                             o.apple_radius_min, o.apple_radius_max);
      bool done = false;
      for (int attempt = 0; attempt < 40 && !done; ++attempt) {
        Vec3 p = c;
        if (!members.empty()) {
          const Apple& other = scene.apples[members[rng.UniformInt(0, static_cast<int>(members.size()) - 1)]];
          Vec3 dir = RandomUnit(rng);
          dir.z() -= 0.4;  // clusters hang
          p = other.center + dir.normalized() * (other.radius + r + rng.Uniform(0.003, 0.012));
        }
        if (p.z() < o.canopy_base - 0.1 || Overlaps(scene.apples, first, p, r)) continue;
        Apple a;
        a.id = static_cast<int>(scene.apples.size());
        a.tree = tree;
        a.row = row;
        a.cluster = cluster;
        a.center = p;
        a.radius = r;
        a.variety = variety;
        a.up = (Vec3::UnitZ() + 0.35 * RandomUnit(rng)).normalized();
        VarietyColors(variety, rng, &a);
        a.texture_seed = static_cast<std::uint32_t>(rng.Bits());
        Lighting(scene, p, row, rng, 0.05, &a.sun, &a.ambient);
        members.push_back(scene.apples.size());
        scene.apples.push_back(a);
        ++placed;
        done = true;
      }
    }
    if (members.empty()) ++failures;
  }
}

void AddCylinder(Scene& scene, const Vec3& p0, const Vec3& p1, double radius, Material material,
                 const Vec3f& color, Random& rng) {
  Cylinder c;
  c.p0 = p0;
  c.length = (p1 - p0).norm();
  if (c.length < 1e-6) return;
  c.axis = (p1 - p0) / c.length;
  c.radius = radius;
  c.material = material;
  c.color = Jitter(rng, color, 0.1);
  c.texture_seed = static_cast<std::uint32_t>(rng.Bits());
  const Vec3 mid = 0.5 * (p0 + p1);
  const int row = static_cast<int>(std::lround(mid.y() / scene.options.row_spacing));
  c.sun = static_cast<float>(SunTransmission(scene, mid, 0.1));
  c.ambient = static_cast<float>(0.3 + 0.7 * std::exp(-std::max(0.0, scene.CanopyDepth(mid, row)) / 0.3));
  scene.cylinders.push_back(c);
}

void AddTreeWood(Scene& scene, const RowGeometry& g, double tree_x, bool filmed, Random& rng) {
  const SceneOptions& o = scene.options;
  const Vec3f bark(0.075f, 0.058f, 0.045f);
  // Trunk / central leader, tapering in segments, leaning slightly.
  const Vec3 lean(rng.Normal(0, 0.03), rng.Normal(0, 0.03), 1.0);
  const double top = o.canopy_top * 0.96;
  const int segments = 5;
  Vec3 p(tree_x, g.y, 0.0);
  for (int s = 0; s < segments; ++s) {
    const double h = top / segments;
    const Vec3 q = p + lean.normalized() * h + Vec3(rng.Normal(0, 0.015), rng.Normal(0, 0.015), 0);
    const double r = 0.045 - 0.032 * s / (segments - 1.0);
    AddCylinder(scene, p, q, r, Material::kBark, bark, rng);
    p = q;
  }
  // Scaffold branches.
  const bool planar = o.canopy_shape == "planar";
  double z = o.canopy_base + rng.Uniform(0.0, 0.15);
  int side = rng.Bernoulli(0.5) ? 1 : -1;
  while (z < o.canopy_top - 0.35) {
    const double h = (z - o.canopy_base) / (o.canopy_top - o.canopy_base);
    const double azimuth = planar ? (side > 0 ? 0.0 : M_PI) + rng.Normal(0, 0.3) : rng.Uniform(0, 2 * M_PI);
    const double elevation = rng.Uniform(10, 40) * kDeg;
    const Vec3 dir(std::cos(azimuth) * std::cos(elevation), std::sin(azimuth) * std::cos(elevation),
                   std::sin(elevation));
    const double reach = planar ? 0.55 * o.tree_spacing : 0.6 * std::max(o.tree_spacing, o.canopy_thickness);
    const double length = reach * (1.0 - 0.5 * h) * rng.Uniform(0.6, 1.0);
    const Vec3 start(tree_x + lean.x() * z, g.y + lean.y() * z, z);
    const Vec3 mid = start + dir * (0.55 * length);
    Vec3 dir2 = (dir + Vec3(0, 0, 0.35) + 0.2 * RandomUnit(rng)).normalized();
    const Vec3 end = mid + dir2 * (0.45 * length);
    const double r = (0.028 - 0.012 * h) * (filmed ? 1.0 : 0.8);
    AddCylinder(scene, start, mid, r, Material::kBark, bark, rng);
    AddCylinder(scene, mid, end, 0.65 * r, Material::kBark, bark, rng);
    z += rng.Uniform(0.18, 0.32);
    side = -side;
  }
  // A support stake beside the trunk (galvanised steel), as in modern rows.
  AddCylinder(scene, Vec3(tree_x + 0.07, g.y + 0.03, 0.0), Vec3(tree_x + 0.07, g.y + 0.03, o.canopy_top + 0.2),
              0.016, Material::kPost, Vec3f(0.30f, 0.31f, 0.33f), rng);
}

void AddLeaves(Scene& scene, const RowGeometry& g, int row, double x0, double x1, double scale, Random& rng) {
  const SceneOptions& o = scene.options;
  // Canopy volume by Monte Carlo, then leaves by leaf area density.
  const double half = (o.canopy_shape == "round" ? 0.75 : 0.6) * o.canopy_thickness;
  const double box = (x1 - x0) * 2 * half * (o.canopy_top - o.canopy_base);
  int inside = 0;
  const int probes = 2000;
  for (int i = 0; i < probes; ++i) {
    const Vec3 p(rng.Uniform(x0, x1), g.y + rng.Uniform(-half, half), rng.Uniform(o.canopy_base, o.canopy_top));
    if (CanopyDepthInRow(scene, p, g) >= 0) ++inside;
  }
  const double volume = box * inside / probes;
  const double leaf_len = o.leaf_length * scale;
  const double leaf_area = M_PI * 0.5 * leaf_len * 0.25 * leaf_len;
  const int num_leaves = static_cast<int>(kLeafAreaDensity * o.leaf_density * volume / leaf_area);
  const double light_step = row == 0 ? 0.05 : 0.1;
  int made = 0;
  while (made < num_leaves) {
    // A shoot: 4-9 leaves along a short twig.
    Vec3 base;
    if (!SampleCanopyPoint(scene, g, row, x0, x1, 0.0, 10.0, rng, &base)) break;
    Vec3 outward(0, base.y() - g.y, 0.3);
    Vec3 shoot = (outward.normalized() + 0.9 * RandomUnit(rng) + Vec3(0, 0, 0.3)).normalized();
    const int n = rng.UniformInt(4, 9);
    // Lighting varies little along one shoot: compute it once.
    float sun = 1, ambient = 1;
    Lighting(scene, base, row, rng, light_step, &sun, &ambient);
    for (int k = 0; k < n && made < num_leaves; ++k, ++made) {
      Leaf leaf;
      const double along = 0.025 * scale * k;
      const Vec3 node = base + shoot * along;
      const double side = (k % 2 ? 1.0 : -1.0);
      Vec3 perp = Perpendicular(shoot);
      perp = (Eigen::AngleAxisd(rng.Uniform(0, 2 * M_PI), shoot) * perp);
      Vec3 midrib = (shoot * rng.Uniform(0.3, 0.8) + side * perp).normalized();
      // Leaf blades face up and out, towards the light.
      Vec3 normal = (RandomUnit(rng) + Vec3(0, 0, 0.9) + 0.5 * outward.normalized()).normalized();
      Vec3 u = (midrib - midrib.dot(normal) * normal);
      if (u.norm() < 1e-3) u = Perpendicular(normal);
      u.normalize();
      const Vec3 v = normal.cross(u);
      const double len = leaf_len * Clamp(rng.Normal(1.0, 0.15), 0.6, 1.4);
      leaf.a = static_cast<float>(0.5 * len);
      leaf.b = static_cast<float>(0.5 * len * rng.Uniform(0.42, 0.55));
      const Vec3 center = node + u * (0.5 * len + 0.01 * scale);
      leaf.center = center.cast<float>();
      leaf.u = u.cast<float>();
      leaf.v = v.cast<float>();
      leaf.normal = normal.cast<float>();
      const bool yellow = rng.Bernoulli(o.yellow_leaf_fraction);
      const Vec3f green(0.045f, 0.105f, 0.018f);
      const Vec3f yellowing(0.30f, 0.26f, 0.04f);
      leaf.color = Jitter(rng, yellow ? yellowing : green, 0.18);
      leaf.sun = std::min(1.0f, std::max(0.0f, sun + static_cast<float>(rng.Normal(0, 0.05))));
      leaf.ambient = ambient;
      leaf.fold = static_cast<float>(rng.Uniform(0.1, 0.5));
      leaf.texture_seed = static_cast<std::uint32_t>(rng.Bits());
      scene.leaves.push_back(leaf);
    }
  }
}

void ComputeGroundShadow(Scene& scene) {
  const SceneOptions& o = scene.options;
  scene.shadow_cell = 0.08;
  scene.shadow_x0 = scene.row_x_min - 7.5;
  scene.shadow_y0 = -(o.background_rows ? o.row_spacing + 2.5 : 3.0);
  const double x1 = scene.row_x_max + 7.5, y1 = -scene.shadow_y0;
  scene.shadow_nx = static_cast<int>(std::ceil((x1 - scene.shadow_x0) / scene.shadow_cell));
  scene.shadow_ny = static_cast<int>(std::ceil((y1 - scene.shadow_y0) / scene.shadow_cell));
  scene.shadow.assign(static_cast<size_t>(scene.shadow_nx) * scene.shadow_ny, 1.0f);
  for (int iy = 0; iy < scene.shadow_ny; ++iy) {
    for (int ix = 0; ix < scene.shadow_nx; ++ix) {
      const Vec3 p(scene.shadow_x0 + (ix + 0.5) * scene.shadow_cell, scene.shadow_y0 + (iy + 0.5) * scene.shadow_cell,
                   0.0);
      scene.shadow[static_cast<size_t>(iy) * scene.shadow_nx + ix] =
          static_cast<float>(SunTransmission(scene, p, 0.08));
    }
  }
}

}  // namespace

Scene GenerateScene(const SceneOptions& options, std::uint64_t seed) {
  options.Check();
  Scene scene;
  scene.options = options;
  scene.seed = seed;
  const double el = options.sun_elevation_deg * kDeg, az = options.sun_azimuth_deg * kDeg;
  scene.sun_direction = Vec3(std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), std::sin(el)).normalized();
  for (int i = 0; i < options.num_trees; ++i) scene.tree_x.push_back(i * options.tree_spacing);
  scene.row_x_min = -0.5 * options.tree_spacing;
  scene.row_x_max = (options.num_trees - 0.5) * options.tree_spacing;

  Random rng(SubSeed(seed, 1));
  int next_cluster = 0;
  // Filmed row: wood, apples (before leaves, so leaves can avoid them), leaves.
  const RowGeometry g0 = GetRow(scene, 0);
  std::vector<Variety> varieties;
  for (int t = 0; t < options.num_trees; ++t) varieties.push_back(PickVariety(options.variety, rng));
  for (int t = 0; t < options.num_trees; ++t) AddTreeWood(scene, g0, scene.tree_x[t], true, rng);
  for (int t = 0; t < options.num_trees; ++t) {
    AddApplesForTree(scene, g0, 0, t, scene.tree_x[t], options.apples_per_tree, options.deep_fraction, varieties[t],
                     rng, &next_cluster);
  }
  const int harvested = static_cast<int>(scene.apples.size());
  // Fallen apples under the filmed row.
  const int fallen = static_cast<int>(std::lround(options.fallen_fraction * harvested));
  const size_t fallen_first = scene.apples.size();
  for (int k = 0, attempts = 0; k < fallen && attempts < 100 * (fallen + 1); ++attempts) {
    const double r = rng.Uniform(options.apple_radius_min, options.apple_radius_max);
    const Vec3 c(rng.Uniform(scene.row_x_min, scene.row_x_max), Clamp(rng.Normal(0, 0.45), -1.2, 1.2), r);
    if (Overlaps(scene.apples, fallen_first, c, r)) continue;
    Apple a;
    a.id = static_cast<int>(scene.apples.size());
    a.on_ground = true;
    a.center = c;
    a.radius = r;
    const int nearest = static_cast<int>(Clamp(std::lround(c.x() / options.tree_spacing), 0, options.num_trees - 1));
    a.tree = nearest;
    a.variety = varieties[nearest];
    a.up = RandomUnit(rng);
    VarietyColors(a.variety, rng, &a);
    // Fallen fruit browns.
    a.base_color = a.base_color * 0.75f + Vec3f(0.10f, 0.06f, 0.02f) * 0.25f;
    a.blush_color *= 0.8f;
    a.texture_seed = static_cast<std::uint32_t>(rng.Bits());
    a.sun = 1;  // ground shadow applies at render time
    a.ambient = 0.8f;
    scene.apples.push_back(a);
    ++k;
  }
  // Neighbouring rows (background): wood, fewer and larger leaves, apples.
  if (options.background_rows) {
    for (int row : {-1, 1}) {
      const RowGeometry g = GetRow(scene, row);
      Random row_rng(SubSeed(seed, 2, static_cast<std::uint64_t>(row + 5)));
      for (double x = g.tree_x0; x <= g.x_max; x += options.tree_spacing) {
        AddTreeWood(scene, g, x, false, row_rng);
        AddApplesForTree(scene, g, row, -1, x, 0.8 * options.apples_per_tree, 0.0,
                         PickVariety(options.variety, row_rng), row_rng, &next_cluster);
      }
    }
  }
  // Leaves.
  AddLeaves(scene, g0, 0, g0.x_min, g0.x_max, 1.0, rng);
  if (options.background_rows) {
    for (int row : {-1, 1}) {
      Random row_rng(SubSeed(seed, 3, static_cast<std::uint64_t>(row + 5)));
      const RowGeometry g = GetRow(scene, row);
      AddLeaves(scene, g, row, g.x_min, g.x_max, 1.8, row_rng);
    }
  }
  ComputeGroundShadow(scene);
  return scene;
}

}  // namespace orchard::synth
