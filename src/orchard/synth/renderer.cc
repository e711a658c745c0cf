#include "orchard/synth/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/synth/random.h"

namespace orchard::synth {
namespace {

using V3 = Eigen::Vector3f;
constexpr float kNear = 0.05f;
constexpr float kInf = std::numeric_limits<float>::infinity();

// Light (linear RGB irradiance): direct sun and sky.
const V3 kSunLight(2.5f, 2.3f, 2.0f);
const V3 kSkyLight(0.45f, 0.52f, 0.65f);

inline float Clamp01(float v) { return v < 0 ? 0 : (v > 1 ? 1 : v); }
inline float SmoothStep(float a, float b, float x) {
  const float t = Clamp01((x - a) / (b - a));
  return t * t * (3 - 2 * t);
}
inline V3 Mix(const V3& a, const V3& b, float t) { return a + (b - a) * t; }

// Sum of value-noise octaves whose wavelength is above ~2 pixels (`footprint`
// is the pixel size in the noise's units), faded in smoothly: a cheap mip-map.
float FilteredFbm2(float x, float y, float footprint, int octaves, std::uint32_t seed) {
  float sum = 0, norm = 0, amp = 1, freq = 1;
  for (int o = 0; o < octaves; ++o) {
    const float w = SmoothStep(4.0f, 1.5f, footprint * freq);  // 1 when the octave is resolved
    const float n = ValueNoise2(x * freq, y * freq, seed + o * 131);
    sum += amp * (w * n + (1 - w) * 0.5f);
    norm += amp;
    amp *= 0.55f;
    freq *= 2.03f;
  }
  return sum / norm;
}

struct Buffers {
  int w, h;
  std::vector<V3> color;
  std::vector<float> depth;
  std::vector<std::uint16_t> ids;
};

struct View {
  V3 origin;             // camera centre
  V3 d00, dx, dy;        // ray direction of pixel (i, j) = d00 + i dx + j dy (camera z = 1)
  Eigen::Matrix3f R;
  V3 t;
  float fx, fy, cx, cy;

  V3 Ray(int i, int j) const { return d00 + dx * static_cast<float>(i) + dy * static_cast<float>(j); }
  // Projects; returns camera depth (<= 0 behind).
  float ProjectPoint(const V3& X, float* u, float* v) const {
    const V3 p = R * X + t;
    *u = *v = 0;
    if (p.z() <= 1e-6f) return p.z();
    *u = fx * p.x() / p.z() + cx;
    *v = fy * p.y() / p.z() + cy;
    return p.z();
  }
};

// Pixel rectangle [x0, x1) x [y0, y1) covering a projected disc; false when off screen.
bool ScreenRect(const View& view, int w, int h, const V3& center, float radius, int* x0, int* y0, int* x1, int* y1) {
  float u, v;
  const float z = view.ProjectPoint(center, &u, &v);
  if (z - radius < kNear) return false;
  const float pr = radius * view.fx / (z - radius) * 1.05f + 1.0f;
  *x0 = std::max(0, static_cast<int>(std::floor(u - pr)));
  *y0 = std::max(0, static_cast<int>(std::floor(v - pr)));
  *x1 = std::min(w, static_cast<int>(std::ceil(u + pr)) + 1);
  *y1 = std::min(h, static_cast<int>(std::ceil(v + pr)) + 1);
  return *x0 < *x1 && *y0 < *y1;
}

// ----- Sky and ground ---------------------------------------------------------

V3 SkyColor(const V3& dir, const V3& sun, std::uint32_t seed) {
  const V3 d = dir.normalized();
  const float up = std::max(0.0f, d.z());
  V3 c = Mix(V3(0.62f, 0.72f, 0.86f), V3(0.16f, 0.33f, 0.72f), std::sqrt(up));
  const float glow = std::pow(std::max(0.0f, d.dot(sun)), 8.0f);
  c += V3(0.5f, 0.45f, 0.35f) * glow;
  if (up > 0.02f) {
    const float px = d.x() / up * 0.6f, py = d.y() / up * 0.6f;
    const float n = FilteredFbm2(px, py, 0.0f, 5, seed);
    const float cloud = SmoothStep(0.52f, 0.72f, n) * SmoothStep(0.02f, 0.15f, up);
    c = Mix(c, V3(0.95f, 0.95f, 0.97f), cloud * 0.85f);
  }
  return c;
}

V3 GroundColor(const Scene& scene, float x, float y, float footprint, std::uint32_t seed) {
  const SceneOptions& o = scene.options;
  // Bare soil strip under each row (herbicide strip), grass in the alleys.
  const float row_y = static_cast<float>(o.row_spacing * std::round(y / o.row_spacing));
  const float edge = 0.55f + 0.25f * (ValueNoise2(x * 1.3f, y * 1.3f, seed + 7) - 0.5f);
  const float grass_patch = FilteredFbm2(x * 3.0f, y * 3.0f, footprint * 3.0f, 4, seed + 11);
  float soil = SmoothStep(edge + 0.1f, edge - 0.1f, std::abs(y - row_y));
  soil *= SmoothStep(0.35f, 0.6f, grass_patch + 0.15f);
  // Grass: colour varies at metre scale, blades and clumps at centimetre scale.
  const float meadow = FilteredFbm2(x * 0.7f, y * 0.7f, footprint * 0.7f, 3, seed + 13);
  const float clumps = FilteredFbm2(x * 9.0f, y * 9.0f, footprint * 9.0f, 4, seed + 17);
  const float blades = FilteredFbm2(x * 45.0f, y * 25.0f, footprint * 45.0f, 3, seed + 19);
  V3 grass = Mix(V3(0.035f, 0.075f, 0.015f), V3(0.11f, 0.15f, 0.035f), meadow);
  grass *= 0.55f + 0.9f * clumps * (0.6f + 0.8f * blades);
  // Soil: brown with pebbles, crumbs and dry leaves.
  const float crumbs = FilteredFbm2(x * 20.0f, y * 20.0f, footprint * 20.0f, 4, seed + 23);
  const float pebbles = FilteredFbm2(x * 70.0f, y * 70.0f, footprint * 70.0f, 2, seed + 29);
  V3 dirt = Mix(V3(0.075f, 0.05f, 0.032f), V3(0.16f, 0.12f, 0.08f), crumbs);
  dirt = Mix(dirt, V3(0.2f, 0.18f, 0.15f), SmoothStep(0.62f, 0.75f, pebbles));
  return Mix(grass, dirt, soil);
}

void RenderBackground(const Scene& scene, const View& view, Buffers& b) {
  const V3 sun = scene.sun_direction.cast<float>();
  const std::uint32_t seed = static_cast<std::uint32_t>(scene.seed * 2654435761u);
  const float pixel_angle = 1.0f / view.fx;
  for (int j = 0; j < b.h; ++j) {
    for (int i = 0; i < b.w; ++i) {
      const size_t k = static_cast<size_t>(j) * b.w + i;
      const V3 d = view.Ray(i, j);
      if (d.z() < -1e-5f) {
        const float t = -view.origin.z() / d.z();
        const V3 g = view.origin + d * t;
        const float len = d.norm();
        const float sin_grazing = -d.z() / len;
        const float footprint = t * len * pixel_angle / std::max(sin_grazing, 0.08f);
        V3 albedo = GroundColor(scene, g.x(), g.y(), footprint, seed);
        // Dappled shadow of the canopies.
        const float transmission = scene.GroundSun(g.x(), g.y());
        const float dapple = FilteredFbm2(g.x() * 7.0f, g.y() * 7.0f, footprint * 7.0f, 3, seed + 31);
        const float lit = SmoothStep(0.45f, 0.6f, dapple + transmission - 0.5f);
        V3 c = albedo.cwiseProduct(kSunLight * (sun.z() * lit) + kSkyLight * 0.9f);
        // Aerial haze far away.
        const float haze = 1.0f - std::exp(-t * len / 90.0f);
        c = Mix(c, V3(0.6f, 0.68f, 0.8f), haze);
        b.color[k] = c;
        b.depth[k] = t;
      } else {
        b.color[k] = SkyColor(d, sun, seed + 101);
        b.depth[k] = kInf;
      }
      b.ids[k] = 0;
    }
  }
}

// ----- Cylinders (wood, posts) -----------------------------------------------

void RenderCylinders(const Scene& scene, const View& view, Buffers& b) {
  const V3 sun = scene.sun_direction.cast<float>();
  for (const Cylinder& c : scene.cylinders) {
    const V3 p0 = c.p0.cast<float>(), a = c.axis.cast<float>();
    const float L = static_cast<float>(c.length), r = static_cast<float>(c.radius);
    // Bounding rectangle of the two end discs; both ends must be in front.
    float ua, va, ub, vb;
    const float za = view.ProjectPoint(p0, &ua, &va), zb = view.ProjectPoint(p0 + a * L, &ub, &vb);
    if (za - r < kNear || zb - r < kNear) continue;
    const float pra = r * view.fx / (za - r) + 1.0f, prb = r * view.fx / (zb - r) + 1.0f;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(ua - pra, ub - prb))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(va - pra, vb - prb))));
    const int x1 = std::min(b.w, static_cast<int>(std::ceil(std::max(ua + pra, ub + prb))) + 1);
    const int y1 = std::min(b.h, static_cast<int>(std::ceil(std::max(va + pra, vb + prb))) + 1);
    if (x0 >= x1 || y0 >= y1) continue;
    const V3 e1 = (std::abs(a.x()) < 0.9f ? a.cross(V3::UnitX()) : a.cross(V3::UnitY())).normalized();
    const V3 e2 = a.cross(e1);
    const V3 m = view.origin - p0;
    const float ma = m.dot(a);
    const V3 mm = m - a * ma;
    const float C = mm.dot(mm) - r * r;
    const std::uint32_t seed = c.texture_seed;
    for (int j = y0; j < y1; ++j) {
      for (int i = x0; i < x1; ++i) {
        const V3 d = view.Ray(i, j);
        const float da = d.dot(a);
        const V3 dd = d - a * da;
        const float A = dd.dot(dd);
        if (A < 1e-12f) continue;
        const float B = 2 * dd.dot(mm);
        const float disc = B * B - 4 * A * C;
        if (disc < 0) continue;
        const float t = (-B - std::sqrt(disc)) / (2 * A);
        const size_t k = static_cast<size_t>(j) * b.w + i;
        if (t <= kNear || t >= b.depth[k]) continue;
        const float s = ma + t * da;
        if (s < 0 || s > L) continue;
        const V3 n = (m + d * t - a * s) / r;
        const float theta = std::atan2(n.dot(e2), n.dot(e1));
        const float arc = theta * r;
        V3 albedo = c.color;
        if (c.material == Material::kBark) {
          // Bark: fissures along the axis and scaly patches.
          const float fissure = ValueNoise2(s * 12.0f, arc * 90.0f, seed);
          const float scales = ValueNoise2(s * 45.0f, arc * 45.0f, seed + 1);
          const float lichen = SmoothStep(0.7f, 0.8f, ValueNoise2(s * 6.0f, arc * 20.0f, seed + 2));
          albedo = albedo * (0.45f + 0.9f * fissure) * (0.75f + 0.5f * scales);
          albedo = Mix(albedo, V3(0.12f, 0.14f, 0.09f), lichen * 0.6f);
        } else {
          const float grain = ValueNoise2(s * 30.0f, arc * 30.0f, seed);
          albedo = albedo * (0.8f + 0.4f * grain);
          // Painted height marks every 50 cm help matching along the post.
          if (std::fmod(s + 0.05f, 0.5f) < 0.04f) albedo = V3(0.5f, 0.5f, 0.48f);
        }
        const float ndl = std::max(0.0f, n.dot(sun));
        V3 col = albedo.cwiseProduct(kSunLight * (ndl * c.sun) + kSkyLight * (c.ambient * (0.6f + 0.4f * n.z())));
        if (c.material == Material::kPost) {
          const V3 h = (sun - d.normalized()).normalized();
          col += kSunLight * (0.3f * c.sun * std::pow(std::max(0.0f, n.dot(h)), 30.0f));
        }
        b.color[k] = col;
        b.depth[k] = t;
        b.ids[k] = 0;
      }
    }
  }
}

// ----- Leaves ----------------------------------------------------------------

void RenderLeaves(const Scene& scene, const View& view, Buffers& b) {
  const V3 sun = scene.sun_direction.cast<float>();
  for (const Leaf& leaf : scene.leaves) {
    int x0, y0, x1, y1;
    if (!ScreenRect(view, b.w, b.h, leaf.center, leaf.a, &x0, &y0, &x1, &y1)) continue;
    const V3 c = leaf.center, u = leaf.u, v = leaf.v, n = leaf.normal;
    const float inv_a = 1.0f / leaf.a, inv_b = 1.0f / leaf.b;
    const float nc = n.dot(c - view.origin);
    const V3 oc = view.origin - c;
    const float ou = oc.dot(u), ov = oc.dot(v);
    const std::uint32_t seed = leaf.texture_seed;
    const float mottle_x = static_cast<float>(seed & 1023) * 0.37f;
    for (int j = y0; j < y1; ++j) {
      for (int i = x0; i < x1; ++i) {
        const V3 d = view.Ray(i, j);
        const float denom = n.dot(d);
        if (std::abs(denom) < 1e-7f) continue;
        const float t = nc / denom;
        const size_t k = static_cast<size_t>(j) * b.w + i;
        if (t <= kNear || t >= b.depth[k]) continue;
        const float s = (ou + t * d.dot(u)) * inv_a;   // -1 petiole .. +1 tip
        if (s <= -1 || s >= 1) continue;
        const float w = (ov + t * d.dot(v)) * inv_b;
        // Ovate blade, widest below the middle, pointed tip.
        const float profile = std::pow(1 - s * s, 0.65f) * (1.0f - 0.3f * s) * 0.95f;
        if (std::abs(w) >= profile) continue;
        const bool top = denom < 0;  // the camera sees the upper side
        V3 nf = top ? n : V3(-n);
        // The two halves tilt about the midrib, the tip droops.
        V3 ns = (nf + v * ((w > 0 ? 1.0f : -1.0f) * leaf.fold) + u * (0.25f * s)).normalized();
        V3 albedo = leaf.color;
        if (!top) albedo = albedo.cwiseProduct(V3(1.5f, 1.45f, 1.6f)) + V3(0.02f, 0.025f, 0.02f);  // pale underside
        const float aw = std::abs(w) / std::max(profile, 1e-3f);
        const float midrib = SmoothStep(0.09f, 0.03f, aw);
        const float vein_phase = s * 5.5f - aw * 1.8f;
        const float vein = SmoothStep(0.1f, 0.0f, std::abs(vein_phase - std::round(vein_phase))) * (1 - aw);
        const float mottle = ValueNoise2(s * 2.5f + mottle_x, w * 2.0f, seed);
        albedo *= (0.8f + 0.4f * mottle) * (1.0f + 0.5f * midrib + 0.2f * vein) * (0.85f + 0.15f * aw);
        const float ndl = ns.dot(sun);
        V3 light = kSkyLight * (leaf.ambient * (0.55f + 0.45f * ns.z()));
        if (ndl > 0) {
          light += kSunLight * (leaf.sun * ndl);
        } else {
          // Sun through the blade: leaves glow yellow-green on the shady side.
          light += kSunLight.cwiseProduct(V3(0.9f, 1.2f, 0.35f)) * (leaf.sun * -ndl * 0.3f);
        }
        V3 col = albedo.cwiseProduct(light);
        if (top && ndl > 0) {
          const V3 h = (sun - d.normalized()).normalized();
          col += kSunLight * (0.06f * leaf.sun * std::pow(std::max(0.0f, ns.dot(h)), 25.0f));
        }
        b.color[k] = col;
        b.depth[k] = t;
        b.ids[k] = 0;
      }
    }
  }
}

// ----- Apples ----------------------------------------------------------------

void RenderApples(const Scene& scene, const View& view, Buffers& b) {
  const V3 sun = scene.sun_direction.cast<float>();
  for (const Apple& apple : scene.apples) {
    const V3 c = apple.center.cast<float>();
    const float r = static_cast<float>(apple.radius);
    int x0, y0, x1, y1;
    if (!ScreenRect(view, b.w, b.h, c, r, &x0, &y0, &x1, &y1)) continue;
    const V3 up = apple.up.cast<float>();
    const V3 e1 = (std::abs(up.x()) < 0.9f ? up.cross(V3::UnitX()) : up.cross(V3::UnitY())).normalized();
    const V3 e2 = up.cross(e1);
    const V3 oc = view.origin - c;
    const float C = oc.dot(oc) - r * r;
    const std::uint32_t seed = apple.texture_seed;
    float sun_vis = apple.sun;
    if (apple.on_ground) sun_vis = scene.GroundSun(c.x(), c.y());
    const float blush_threshold = 1.0f - apple.blush;
    for (int j = y0; j < y1; ++j) {
      for (int i = x0; i < x1; ++i) {
        const V3 d = view.Ray(i, j);
        const float A = d.dot(d), B = 2 * oc.dot(d);
        const float disc = B * B - 4 * A * C;
        if (disc < 0) continue;
        const float t = (-B - std::sqrt(disc)) / (2 * A);
        const size_t k = static_cast<size_t>(j) * b.w + i;
        if (t <= kNear || t >= b.depth[k]) continue;
        const V3 n = (oc + d * t) / r;
        const float cu = n.dot(up);
        const float phi = std::atan2(n.dot(e2), n.dot(e1));
        // Blush: patches plus streaks running from stem to calyx.
        const float patch = ValueNoise3(n.x() * 1.8f + 5, n.y() * 1.8f, n.z() * 1.8f, seed);
        const float streak = ValueNoise2(phi * 7.0f, cu * 1.5f, seed + 1);
        const float blush = SmoothStep(blush_threshold - 0.12f, blush_threshold + 0.12f,
                                       0.7f * patch + 0.3f * streak + 0.15f * (1 - apple.blush));
        V3 albedo = Mix(apple.base_color, apple.blush_color, apple.blush > 0 ? blush : 0.0f);
        // Lenticels: small pale dots.
        const float dots = ValueNoise3(n.x() * 40.0f, n.y() * 40.0f, n.z() * 40.0f, seed + 2);
        albedo = Mix(albedo, V3(0.5f, 0.45f, 0.25f), SmoothStep(0.88f, 0.95f, dots) * 0.4f);
        // Stem cavity and calyx: darker, brownish.
        const float cavity = SmoothStep(0.86f, 0.97f, cu) + SmoothStep(-0.9f, -0.98f, cu) * 0.7f;
        albedo = Mix(albedo, V3(0.08f, 0.07f, 0.02f), cavity * 0.7f);
        const float ndl = std::max(0.0f, n.dot(sun));
        V3 col = albedo.cwiseProduct(kSunLight * (sun_vis * ndl) +
                                     kSkyLight * (apple.ambient * (0.55f + 0.45f * n.z())));
        // Waxy skin: a soft specular highlight.
        const V3 h = (sun - d.normalized()).normalized();
        col += kSunLight * (0.22f * sun_vis * std::pow(std::max(0.0f, n.dot(h)), 40.0f));
        col += kSkyLight * (0.05f * apple.ambient * std::pow(std::max(0.0f, n.z()), 4.0f));
        b.color[k] = col;
        b.depth[k] = t;
        b.ids[k] = static_cast<std::uint16_t>(apple.id + 1);
      }
    }
  }
}

// Linear radiance to 8-bit sRGB-like values with a soft shoulder.
std::vector<std::uint8_t> ToneLut(int size, float exposure) {
  std::vector<std::uint8_t> lut(size);
  for (int i = 0; i < size; ++i) {
    float x = exposure * 4.0f * i / (size - 1);
    x = x < 0.7f ? x : 0.7f + 0.3f * (1 - std::exp(-(x - 0.7f) / 0.3f));
    lut[i] = static_cast<std::uint8_t>(std::lround(255.0 * std::pow(Clamp01(x), 1.0 / 2.2)));
  }
  return lut;
}

}  // namespace

PinholeCamera PinholeCamera::FromFov(int width, int height, double hfov_deg) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  return c;
}

CameraPose CameraPose::LookAlong(const Eigen::Vector3d& center, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  CameraPose pose;
  pose.R.row(0) = x.transpose();
  pose.R.row(1) = y.transpose();
  pose.R.row(2) = z.transpose();
  pose.t = -pose.R * center;
  return pose;
}

bool Project(const PinholeCamera& camera, const CameraPose& pose, const Eigen::Vector3d& X, Eigen::Vector2d* uv,
             double* depth) {
  const Eigen::Vector3d p = pose.R * X + pose.t;
  if (depth) *depth = p.z();
  if (p.z() <= 0) return false;
  *uv = Eigen::Vector2d(camera.fx * p.x() / p.z() + camera.cx, camera.fy * p.y() / p.z() + camera.cy);
  return true;
}

void RenderOptions::Check() const {
  ORCHARD_CHECK_OPTION(noise_sigma >= 0 && noise_sigma <= 50, "--noise must be in 0..50, got ", noise_sigma);
  ORCHARD_CHECK_OPTION(motion_blur_px >= 0 && motion_blur_px <= 100, "--motion-blur must be in 0..100 pixels, got ",
                       motion_blur_px);
  ORCHARD_CHECK_OPTION(lens_blur_sigma >= 0 && lens_blur_sigma <= 10, "--lens-blur must be in 0..10, got ",
                       lens_blur_sigma);
  ORCHARD_CHECK_OPTION(exposure > 0 && exposure <= 20, "--exposure must be in (0, 20], got ", exposure);
}

RenderedFrame RenderFrame(const Scene& scene, const PinholeCamera& camera, const CameraPose& pose,
                          const RenderOptions& options, std::uint64_t noise_seed) {
  Buffers b;
  b.w = camera.width;
  b.h = camera.height;
  const size_t n = static_cast<size_t>(b.w) * b.h;
  b.color.resize(n);
  b.depth.resize(n);
  b.ids.resize(n);
  View view;
  view.R = pose.R.cast<float>();
  view.t = pose.t.cast<float>();
  view.origin = pose.Center().cast<float>();
  view.fx = static_cast<float>(camera.fx);
  view.fy = static_cast<float>(camera.fy);
  view.cx = static_cast<float>(camera.cx);
  view.cy = static_cast<float>(camera.cy);
  const Eigen::Matrix3d Rt = pose.R.transpose();
  view.d00 = (Rt * Eigen::Vector3d((0.5 - camera.cx) / camera.fx, (0.5 - camera.cy) / camera.fy, 1.0)).cast<float>();
  view.dx = (Rt * Eigen::Vector3d(1.0 / camera.fx, 0, 0)).cast<float>();
  view.dy = (Rt * Eigen::Vector3d(0, 1.0 / camera.fy, 0)).cast<float>();

  RenderBackground(scene, view, b);
  RenderCylinders(scene, view, b);
  RenderLeaves(scene, view, b);
  RenderApples(scene, view, b);

  RenderedFrame frame;
  constexpr int kLut = 4096;
  const std::vector<std::uint8_t> lut = ToneLut(kLut, static_cast<float>(options.exposure));
  frame.image.create(b.h, b.w, CV_8UC3);
  frame.ids.create(b.h, b.w, CV_16UC1);
  frame.depth.create(b.h, b.w, CV_32FC1);
  for (int j = 0; j < b.h; ++j) {
    auto* img = frame.image.ptr<cv::Vec3b>(j);
    auto* ids = frame.ids.ptr<std::uint16_t>(j);
    auto* depth = frame.depth.ptr<float>(j);
    for (int i = 0; i < b.w; ++i) {
      const size_t k = static_cast<size_t>(j) * b.w + i;
      const V3& c = b.color[k];
      auto index = [&](float v) { return std::min(kLut - 1, std::max(0, static_cast<int>(v * (kLut - 1) / 4.0f))); };
      img[i] = cv::Vec3b(lut[index(c.z())], lut[index(c.y())], lut[index(c.x())]);
      ids[i] = b.ids[k];
      depth[i] = b.depth[k];
    }
  }
  if (options.lens_blur_sigma > 0) cv::GaussianBlur(frame.image, frame.image, cv::Size(0, 0), options.lens_blur_sigma);
  if (options.motion_blur_px > 1) cv::blur(frame.image, frame.image, cv::Size(options.motion_blur_px, 1));
  if (options.noise_sigma > 0) {
    Random rng(noise_seed);
    for (int j = 0; j < b.h; ++j) {
      auto* img = frame.image.ptr<std::uint8_t>(j);
      for (int i = 0; i < 3 * b.w; ++i) {
        const double v = img[i] + options.noise_sigma * rng.Normal();
        img[i] = static_cast<std::uint8_t>(std::min(255.0, std::max(0.0, std::round(v))));
      }
    }
  }
  return frame;
}

}  // namespace orchard::synth
