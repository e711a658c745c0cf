#include "orchard/merge/row_registration.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "orchard/core/error.h"
#include "orchard/core/quantile.h"

namespace orchard {

void RowRegistrationOptions::Check() const {
  ORCHARD_CHECK_OPTION(camera_height > 0, "camera height must be positive, got ", camera_height);
  ORCHARD_CHECK_OPTION(min_ground_fraction > 0 && min_ground_fraction < 1, "min ground fraction must be in (0, 1), got ",
                       min_ground_fraction);
  ORCHARD_CHECK_OPTION(ground_layer > 0, "ground layer must be positive, got ", ground_layer);
  ORCHARD_CHECK_OPTION(max_ground_offset >= 0, "max ground offset must be >= 0, got ", max_ground_offset);
  ORCHARD_CHECK_OPTION(max_ground_tilt_deg >= 0, "max ground tilt must be >= 0, got ", max_ground_tilt_deg);
  ORCHARD_CHECK_OPTION(canopy_min_height < canopy_max_height, "canopy heights must be min < max, got ",
                       canopy_min_height, "..", canopy_max_height);
  ORCHARD_CHECK_OPTION(canopy_depth > 0, "canopy depth must be positive, got ", canopy_depth);
  ORCHARD_CHECK_OPTION(min_canopy_points >= 10, "min canopy points must be >= 10, got ", min_canopy_points);
  ORCHARD_CHECK_OPTION(profile_bin > 0, "profile bin must be positive, got ", profile_bin);
  ORCHARD_CHECK_OPTION(profile_smoothing >= 0, "profile smoothing must be >= 0, got ", profile_smoothing);
  ORCHARD_CHECK_OPTION(max_along > 0, "max along must be positive, got ", max_along);
  ORCHARD_CHECK_OPTION(min_correlation > -1 && min_correlation < 1, "min correlation must be in (-1, 1), got ",
                       min_correlation);
  ORCHARD_CHECK_OPTION(min_overlap >= 0 && min_overlap <= 1, "min overlap must be in [0, 1], got ", min_overlap);
  ORCHARD_CHECK_OPTION(match_distance > 0, "match distance must be positive, got ", match_distance);
  ORCHARD_CHECK_OPTION(along_window >= 0, "along window must be >= 0, got ", along_window);
  ORCHARD_CHECK_OPTION(max_thickness > 0, "max thickness must be positive, got ", max_thickness);
  ORCHARD_CHECK_OPTION(grid_step > 0, "grid step must be positive, got ", grid_step);
  ORCHARD_CHECK_OPTION(min_matched >= 1, "min matched must be >= 1, got ", min_matched);
  ORCHARD_CHECK_OPTION(min_distinctness >= 1, "min distinctness must be >= 1, got ", min_distinctness);
  ORCHARD_CHECK_OPTION(centre_quantile > 0 && centre_quantile <= 1, "centre quantile must be in (0, 1], got ",
                       centre_quantile);
  ORCHARD_CHECK_OPTION(trunk_min_height < trunk_max_height, "trunk heights must be min < max, got ", trunk_min_height,
                       "..", trunk_max_height);
  ORCHARD_CHECK_OPTION(trunk_depth > 0, "trunk depth must be positive, got ", trunk_depth);
  ORCHARD_CHECK_OPTION(trunk_bin > 0, "trunk bin must be positive, got ", trunk_bin);
  ORCHARD_CHECK_OPTION(trunk_width >= trunk_bin, "trunk width must be >= the trunk bin, got ", trunk_width);
  ORCHARD_CHECK_OPTION(min_trunk_points >= 3, "min trunk points must be >= 3, got ", min_trunk_points);
  ORCHARD_CHECK_OPTION(trunk_contrast >= 1, "trunk contrast must be >= 1, got ", trunk_contrast);
  ORCHARD_CHECK_OPTION(min_trunk_span >= 0, "min trunk span must be >= 0, got ", min_trunk_span);
  ORCHARD_CHECK_OPTION(min_trunk_spacing > 0, "min trunk spacing must be positive, got ", min_trunk_spacing);
  ORCHARD_CHECK_OPTION(min_trunks >= 1, "min trunks must be >= 1, got ", min_trunks);
  ORCHARD_CHECK_OPTION(max_trunk_disagreement > 0, "max trunk disagreement must be positive, got ",
                       max_trunk_disagreement);
  ORCHARD_CHECK_OPTION(max_heading_deg >= 0 && max_heading_deg < 90, "max heading must be in [0, 90), got ",
                       max_heading_deg);
}

namespace {

// Least-squares plane z = a x + b y + c.
Eigen::Vector3d FitHeightPlane(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::MatrixXd a(pts.size(), 3);
  Eigen::VectorXd z(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    a(k, 0) = pts[i].x(), a(k, 1) = pts[i].y(), a(k, 2) = 1, z(k) = pts[i].z();
  }
  return a.colPivHouseholderQr().solve(z);
}

// The canopy the camera faces: sparse points at canopy height from the
// nearest dense 10 cm layer across the row to canopy_depth beyond it.
std::vector<Eigen::Vector3d> Canopy(const SideCloud& side, const RowRegistrationOptions& o, double* face) {
  std::map<int, int> layers;
  for (const auto& p : side.sparse)
    if (p.z() > o.canopy_min_height && p.z() < o.canopy_max_height && p.y() > 0.3) ++layers[static_cast<int>(p.y() / 0.1)];
  int most = 0;
  for (const auto& [k, n] : layers) most = std::max(most, n);
  *face = 0;
  for (const auto& [k, n] : layers)
    if (n >= 0.25 * most) {
      *face = k * 0.1;
      break;
    }
  std::vector<Eigen::Vector3d> canopy;
  for (const auto& p : side.sparse)
    if (p.z() > o.canopy_min_height && p.z() < o.canopy_max_height && p.y() > *face - 0.1 &&
        p.y() < *face + o.canopy_depth)
      canopy.push_back(p);
  return canopy;
}

// Direction of the canopy in the ground plane (radians from the side's x
// axis): a line through the median distance of each 25 cm slice along it,
// so that dense and sparse stretches weigh alike.
double CanopyDirection(const std::vector<Eigen::Vector3d>& canopy) {
  std::map<int, std::vector<double>> slices;
  for (const auto& p : canopy) slices[static_cast<int>(std::floor(p.x() / 0.25))].push_back(p.y());
  std::vector<Eigen::Vector2d> xy;
  for (const auto& [k, ys] : slices)
    if (ys.size() >= 5) xy.emplace_back((k + 0.5) * 0.25, Quantile(ys, 0.5));
  if (xy.size() < 3) return 0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : xy) mean += p;
  mean /= static_cast<double>(xy.size());
  double sxx = 0, sxy = 0;
  for (const auto& p : xy) sxx += (p.x() - mean.x()) * (p.x() - mean.x()), sxy += (p.x() - mean.x()) * (p.y() - mean.y());
  return std::atan2(sxy, sxx);
}

// Smoothed sqrt-density of x per bin (sqrt: the sides see the canopy with
// very different numbers of points), over bins [lo, hi).
std::vector<double> Profile(const std::vector<double>& xs, int lo, int hi, const RowRegistrationOptions& o) {
  std::vector<double> count(hi - lo, 0), out(hi - lo, 0);
  for (double x : xs) {
    const int k = static_cast<int>(std::floor(x / o.profile_bin)) - lo;
    if (k >= 0 && k < hi - lo) count[k] += 1;
  }
  for (auto& c : count) c = std::sqrt(c);
  const int r = static_cast<int>(std::ceil(2 * o.profile_smoothing / o.profile_bin));
  const double s = o.profile_smoothing / o.profile_bin;
  for (int i = 0; i < hi - lo; ++i) {
    double sum = 0, w = 0;
    for (int j = std::max(0, i - r); j <= std::min(hi - lo - 1, i + r); ++j) {
      const double g = s > 0 ? std::exp(-0.5 * (i - j) * (i - j) / (s * s)) : (i == j);
      sum += g * count[j], w += g;
    }
    out[i] = sum / w;
  }
  return out;
}

// Pearson correlation of a[i] and b[i - lag] over the bins both observe.
double Correlation(const std::vector<double>& a, int a_lo, const std::vector<double>& b, int b_lo, int lag, int from,
                   int to) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int n = 0;
  for (int k = from; k < to; ++k) {
    const int i = k - a_lo, j = k - lag - b_lo;
    if (i < 0 || i >= static_cast<int>(a.size()) || j < 0 || j >= static_cast<int>(b.size())) continue;
    sa += a[i], sb += b[j], saa += a[i] * a[i], sbb += b[j] * b[j], sab += a[i] * b[j], ++n;
  }
  if (n < 3) return -1;
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  if (va <= 1e-12 || vb <= 1e-12) return -1;
  return (sab - sa * sb / n) / std::sqrt(va * vb);
}

std::vector<double> Xs(const std::vector<Eigen::Vector3d>& pts, const Eigen::Isometry3d& t) {
  std::vector<double> xs;
  xs.reserve(pts.size());
  for (const auto& p : pts) xs.push_back((t * p).x());
  return xs;
}

// The two sides' canopy profiles along the row (the back's through
// `back_turn`), each over the bins its sparse points cover (1%..99%).
struct AlongProfiles {
  std::vector<double> front, back;
  int f_lo = 0, f_hi = 0, b_lo = 0, b_hi = 0;
};

AlongProfiles MakeAlongProfiles(const SideCloud& front, const SideCloud& back,
                                const std::vector<Eigen::Vector3d>& canopy_f,
                                const std::vector<Eigen::Vector3d>& canopy_b, const Eigen::Isometry3d& back_turn,
                                const RowRegistrationOptions& o) {
  const std::vector<double> seen_f = Xs(front.sparse, Eigen::Isometry3d::Identity()),
                            seen_b = Xs(back.sparse, back_turn);
  auto bin = [&](double x) { return static_cast<int>(std::floor(x / o.profile_bin)); };
  AlongProfiles a;
  a.f_lo = bin(Quantile(seen_f, 0.01)), a.f_hi = bin(Quantile(seen_f, 0.99)) + 1;
  a.b_lo = bin(Quantile(seen_b, 0.01)), a.b_hi = bin(Quantile(seen_b, 0.99)) + 1;
  a.front = Profile(Xs(canopy_f, Eigen::Isometry3d::Identity()), a.f_lo, a.f_hi, o);
  a.back = Profile(Xs(canopy_b, back_turn), a.b_lo, a.b_hi, o);
  return a;
}

}  // namespace

std::vector<Trunk> FindTrunks(const SideCloud& side, const RowRegistrationOptions& o) {
  o.Check();
  double face = 0;
  if (static_cast<int>(Canopy(side, o, &face).size()) < o.min_canopy_points) return {};
  std::vector<Eigen::Vector3d> band;
  for (const auto& p : side.sparse)
    if (p.z() >= o.trunk_min_height && p.z() <= o.trunk_max_height && p.y() > face - 0.1 &&
        p.y() < face + o.trunk_depth)
      band.push_back(p);
  if (static_cast<int>(band.size()) < o.min_trunk_points) return {};
  double x_min = band.front().x(), x_max = x_min;
  for (const auto& p : band) x_min = std::min(x_min, p.x()), x_max = std::max(x_max, p.x());
  const int bins = static_cast<int>(std::floor((x_max - x_min) / o.trunk_bin)) + 1;
  std::vector<int> count(bins, 0), window(bins, 0);
  auto bin_of = [&](double x) { return std::min(bins - 1, static_cast<int>(std::floor((x - x_min) / o.trunk_bin))); };
  for (const auto& p : band) ++count[bin_of(p.x())];
  const int w = static_cast<int>(std::round(o.trunk_width / o.trunk_bin));
  for (int i = 0; i < bins; ++i)
    for (int j = std::max(0, i - w); j <= std::min(bins - 1, i + w); ++j) window[i] += count[j];
  // The band's background (grass, low leaves): the median window, which the
  // few trunks do not move.
  std::vector<double> windows(window.begin(), window.end());
  const double background = Quantile(windows, 0.5);
  std::vector<int> order(bins);
  for (int i = 0; i < bins; ++i) order[i] = i;
  // A trunk is narrower than the window: the windows around it tie, and
  // the bin holding it goes first.
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return window[a] != window[b] ? window[a] > window[b] : count[a] > count[b]; });
  std::vector<Trunk> trunks;
  // Peaks looked at: a trunk keeps others min_trunk_spacing away, a peak
  // that is no trunk only its own shoulders (a clod beside a trunk).
  std::vector<std::pair<int, double>> taken;  // bin, distance it blocks
  for (int i : order) {
    if (window[i] < o.min_trunk_points || window[i] < o.trunk_contrast * background) break;
    bool near = false;
    for (const auto& [k, d] : taken) near = near || std::abs(i - k) * o.trunk_bin < d;
    if (near) continue;
    // The points within trunk_width of the peak, again about their median.
    double centre = x_min + (i + 0.5) * o.trunk_bin;
    std::vector<double> xs, ys, zs;
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1 && !xs.empty()) centre = Quantile(xs, 0.5);
      xs.clear(), ys.clear(), zs.clear();
      for (const auto& p : band)
        if (std::abs(p.x() - centre) <= o.trunk_width) xs.push_back(p.x()), ys.push_back(p.y()), zs.push_back(p.z());
    }
    const bool column = static_cast<int>(xs.size()) >= o.min_trunk_points &&
                        Quantile(zs, 0.75) - Quantile(zs, 0.25) >= o.min_trunk_span;
    taken.emplace_back(i, column ? o.min_trunk_spacing : o.trunk_width + 0.5 * o.trunk_bin);
    if (column) trunks.push_back({Quantile(xs, 0.5), Quantile(ys, 0.5), static_cast<int>(xs.size())});
  }
  std::sort(trunks.begin(), trunks.end(), [](const Trunk& a, const Trunk& b) { return a.along < b.along; });
  return trunks;
}

TrunkAcross AcrossFromTrunks(const std::vector<Trunk>& tf, const std::vector<Trunk>& tb,
                             const RowRegistrationOptions& o) {
  TrunkAcross t;
  t.front = static_cast<int>(tf.size()), t.back = static_cast<int>(tb.size());
  if (t.front < o.min_trunks || t.back < o.min_trunks) return t;
  auto median_across = [](const std::vector<Trunk>& trunks) {
    std::vector<double> ys;
    for (const auto& k : trunks) ys.push_back(k.across);
    return Quantile(ys, 0.5);
  };
  t.across = median_across(tf) + median_across(tb);
  return t;
}

std::vector<RowTree> TreesFromTrunks(const std::vector<Trunk>& front, const std::vector<Trunk>& back_in_front,
                                     double merge_distance) {
  std::vector<RowTree> trees;
  for (const auto& t : front) trees.push_back({t.along, true, false});
  for (const auto& t : back_in_front) {
    RowTree* nearest = nullptr;
    for (auto& tree : trees)
      if (tree.front && !tree.back && std::abs(tree.along - t.along) <= merge_distance &&
          (!nearest || std::abs(tree.along - t.along) < std::abs(nearest->along - t.along)))
        nearest = &tree;
    if (nearest)
      nearest->along = 0.5 * (nearest->along + t.along), nearest->back = true;
    else
      trees.push_back({t.along, false, true});
  }
  std::sort(trees.begin(), trees.end(), [](const RowTree& a, const RowTree& b) { return a.along < b.along; });
  return trees;
}

int TreeAt(const std::vector<RowTree>& trees, double along, double lone_half_width) {
  const int n = static_cast<int>(trees.size());
  if (n == 0) return -1;
  int k = 0;
  for (int i = 1; i < n; ++i)
    if (std::abs(trees[i].along - along) < std::abs(trees[k].along - along)) k = i;
  const bool before = along < trees[k].along;
  double half = lone_half_width;
  if (n > 1) {
    // The spacing on the position's side, or at the row's ends the inner one.
    const int neighbour = before ? (k > 0 ? k - 1 : k + 1) : (k < n - 1 ? k + 1 : k - 1);
    half = 0.5 * std::abs(trees[k].along - trees[neighbour].along);
  }
  return std::abs(along - trees[k].along) <= half ? k : -1;
}

Levelling LevelOnSparseGround(SideCloud* side, const RowRegistrationOptions& o, bool keep_scale) {
  o.Check();
  Levelling l;
  const double h = o.camera_height;
  std::map<int, std::vector<Eigen::Vector3d>> slabs;  // 5 cm slabs of height
  int below = 0;
  for (const auto& p : side->sparse)
    if (p.z() < h) slabs[static_cast<int>(std::floor(p.z() / 0.05))].push_back(p), ++below;
  if (below < o.min_canopy_points) return l;
  double slab = 0;
  bool found = false;
  for (const auto& [k, pts] : slabs)
    if (pts.size() >= o.min_ground_fraction * below) {
      slab = (k + 0.5) * 0.05, found = true;
      break;
    }
  if (!found) return l;
  std::vector<Eigen::Vector3d> layer;
  for (const auto& p : side->sparse)
    if (std::abs(p.z() - slab) < o.ground_layer) layer.push_back(p);
  Eigen::Vector3d plane = FitHeightPlane(layer);  // z = a x + b y + c
  // Once more without the points far off it (low leaves, stems).
  std::vector<Eigen::Vector3d> kept;
  for (const auto& p : layer)
    if (std::abs(p.z() - plane.dot(Eigen::Vector3d(p.x(), p.y(), 1))) < 0.5 * o.ground_layer) kept.push_back(p);
  if (kept.size() >= 3) plane = FitHeightPlane(kept), layer.swap(kept);
  l.ground_points = static_cast<int>(layer.size());
  Eigen::Vector3d up(-plane.x(), -plane.y(), 1);
  up.normalize();
  // Height of the plane under the cameras (the row frame's origin lies under them).
  l.ground_height = plane.z();
  l.tilt_deg = std::acos(std::min(1.0, up.z())) * 180 / M_PI;
  if (std::abs(l.ground_height) <= o.max_ground_offset && l.tilt_deg <= o.max_ground_tilt_deg) return l;
  // New frame: up the plane's normal, along the old x laid into the plane,
  // origin on the plane under the old origin; then scaled so that the
  // cameras (camera_height above the old ground) stand camera_height above it.
  Eigen::Vector3d along = Eigen::Vector3d::UnitX() - up * up.x();
  along.normalize();
  const Eigen::Vector3d across = up.cross(along);
  const Eigen::Vector3d origin(0, 0, l.ground_height);
  const double camera_above = up.dot(Eigen::Vector3d(0, 0, h) - origin);
  if (!(camera_above > 0.1 * h))
    Fail(side->name, " side: the ground found in its sparse points lies at the cameras' height; cannot level it");
  l.scale = keep_scale ? 1.0 : h / camera_above;
  Eigen::Matrix3d rot;
  rot.row(0) = along.transpose(), rot.row(1) = across.transpose(), rot.row(2) = up.transpose();
  auto move = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(l.scale * (rot * (p - origin))); };
  for (auto& p : side->sparse) p = move(p);
  for (auto& p : side->cameras) p = move(p);
  for (auto* clusters : {&side->clusters, &side->fallen})
    for (auto& c : *clusters) MoveCluster(&c, move);
  l.transform.linear() = l.scale * rot;
  l.transform.translation() = -l.scale * rot * origin;
  l.changed = true;
  return l;
}

double CanopyProfileCorrelation(const SideCloud& front, const SideCloud& back, const Eigen::Isometry3d& back_to_front,
                                const RowRegistrationOptions& o) {
  o.Check();
  double face_f = 0, face_b = 0;
  const std::vector<Eigen::Vector3d> canopy_f = Canopy(front, o, &face_f), canopy_b = Canopy(back, o, &face_b);
  if (static_cast<int>(std::min(canopy_f.size(), canopy_b.size())) < o.min_canopy_points) return std::nan("");
  const AlongProfiles a = MakeAlongProfiles(front, back, canopy_f, canopy_b, back_to_front, o);
  return Correlation(a.front, a.f_lo, a.back, a.b_lo, 0, std::max(a.f_lo, a.b_lo), std::min(a.f_hi, a.b_hi));
}

Registration RegisterSidesOnRow(const SideCloud& front, const SideCloud& back, const RowRegistrationOptions& o) {
  o.Check();
  double face_f = 0, face_b = 0;
  const std::vector<Eigen::Vector3d> canopy_f = Canopy(front, o, &face_f), canopy_b = Canopy(back, o, &face_b);
  for (const auto* c : {&canopy_f, &canopy_b})
    if (static_cast<int>(c->size()) < o.min_canopy_points)
      Fail("the ", c == &canopy_f ? "front" : "back", " side has ", c->size(),
           " sparse canopy points, too few to register the sides on the row (need ", o.min_canopy_points,
           "; given poses have them only when COLMAP triangulated points for them)");

  // Heading: the half turn, or the angle between the canopy lines (the
  // back's, turned by the half turn plus the heading, runs along the front's).
  const double heading_deg =
      o.heading_from_canopy
          ? std::clamp(std::remainder(CanopyDirection(canopy_f) - CanopyDirection(canopy_b), M_PI) * 180 / M_PI,
                       -o.max_heading_deg, o.max_heading_deg)
          : 0.0;

  // Along: correlate the canopy profiles over the stretch both sides
  // observe (all their sparse points: ground, canopy, next row), so that
  // the row's ends and gaps must line up, not just the canopy's texture.
  const Eigen::Isometry3d turn = BackToFrontTransform(heading_deg, 0, 0);
  const std::vector<double> xf = Xs(canopy_f, Eigen::Isometry3d::Identity());
  const AlongProfiles profiles = MakeAlongProfiles(front, back, canopy_f, canopy_b, turn, o);
  const std::vector<double>& pf = profiles.front;
  const std::vector<double>& pb = profiles.back;
  const int f_lo = profiles.f_lo, f_hi = profiles.f_hi, b_lo = profiles.b_lo, b_hi = profiles.b_hi;
  // Only offsets at which the two camera paths overlap by min_overlap of
  // the shorter: both sides are meant to film the same stretch, and a row of
  // evenly spaced trees looks alike one tree further on.
  const std::vector<double> path_f = Xs(front.cameras, Eigen::Isometry3d::Identity()), path_b = Xs(back.cameras, turn);
  const bool have_paths = !path_f.empty() && !path_b.empty();
  double pf0 = 0, pf1 = 0, pb0 = 0, pb1 = 0;
  if (have_paths) {
    pf0 = *std::min_element(path_f.begin(), path_f.end()), pf1 = *std::max_element(path_f.begin(), path_f.end());
    pb0 = *std::min_element(path_b.begin(), path_b.end()), pb1 = *std::max_element(path_b.begin(), path_b.end());
  }
  auto path_overlap = [&](double along) { return std::min(pf1, pb1 + along) - std::max(pf0, pb0 + along); };
  const double shorter_path = std::min(pf1 - pf0, pb1 - pb0);
  const int max_lag = static_cast<int>(std::ceil(o.max_along / o.profile_bin));
  std::vector<double> corr(2 * max_lag + 1, -1);
  int best = 0;
  bool any = false;
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
    if (have_paths && path_overlap(lag * o.profile_bin) < o.min_overlap * shorter_path) continue;
    const int from = std::max(f_lo, b_lo + lag), to = std::min(f_hi, b_hi + lag);
    corr[lag + max_lag] = Correlation(pf, f_lo, pb, b_lo, lag, from, to);
    if (!any || corr[lag + max_lag] > corr[best + max_lag]) best = lag, any = true;
  }
  if (!any)
    Fail("the two sides' camera paths cannot overlap by ", o.min_overlap,
         " of the shorter within ", o.max_along, " m: they cover different stretches of the row");
  const double correlation = corr[best + max_lag];
  double chance_correlation = 0;
  for (int lag = -max_lag; lag <= max_lag; ++lag)
    if (std::abs(lag - best) * o.profile_bin >= 0.5) chance_correlation = std::max(chance_correlation, corr[lag + max_lag]);
  if (correlation < o.min_correlation)
    Fail("the two sides' canopy profiles along the row do not match (best correlation ", correlation, ", need ",
         o.min_correlation, "): they do not show the same row, or not the same stretch of it");
  double along = best * o.profile_bin;
  // Sub-bin offset: a parabola through the peak and its neighbours.
  if (best > -max_lag && best < max_lag && corr[best + max_lag - 1] > -1 && corr[best + max_lag + 1] > -1) {
    const double c0 = corr[best + max_lag - 1], c1 = corr[best + max_lag], c2 = corr[best + max_lag + 1];
    const double den = c0 - 2 * c1 + c2;
    if (den < 0) along += 0.5 * (c0 - c2) / den * o.profile_bin;
  }

  // Across: the fruit both sides see, searched between the two canopy faces
  // touching and max_thickness apart.
  const double lo = std::max(face_f + face_b, 0.0), hi = lo + o.max_thickness;
  RegistrationOptions ro;
  ro.match_distance = o.match_distance;
  Registration best_fit;
  double best_soft = -1;
  std::vector<std::pair<double, int>> by_across;  // across, matches
  const int na = static_cast<int>(std::round(o.along_window / o.grid_step));
  const int nc = static_cast<int>(std::ceil((hi - lo) / o.grid_step));
  for (int j = 0; j <= nc; ++j) {
    const double across = lo + j * o.grid_step;
    int most = 0;
    for (int i = -na; i <= na; ++i) {
      const Registration e =
          EvaluateAlignment(front, back, BackToFrontTransform(heading_deg, along + i * o.grid_step, across), ro);
      most = std::max(most, e.matched);
      // Ties (many cells match the same clusters): the cell closest to the
      // matched centres, then the profile's along.
      const double soft = e.matched - 0.5 * e.residual / o.match_distance - 1e-3 * std::abs(i);
      if (e.matched > 0 && soft > best_soft) best_soft = soft, best_fit = e;
    }
    by_across.emplace_back(across, most);
  }
  int chance = 0;
  for (const auto& [a, m] : by_across)
    if (best_fit.matched > 0 && std::abs(a - best_fit.across) > 0.25) chance = std::max(chance, m);
  double across;
  Registration::Across across_from = Registration::Across::kFruit;
  const TrunkAcross trunks = AcrossFromTrunks(FindTrunks(front, o), FindTrunks(back, o), o);
  if (best_fit.matched >= o.min_matched && best_fit.matched >= o.min_distinctness * std::max(chance, 1)) {
    along = best_fit.along, across = best_fit.across;
  } else {
    // Trunks place the sides across, but like the canopy's shape they look
    // alike in every row of a planting.
    if (!o.assume_same_row)
      Fail("the fruit clusters of the two sides do not place them across the row (", best_fit.matched,
           " matched at best, ", chance, " at another distance; need ", o.min_matched, " and ", o.min_distinctness,
           "x), and the canopy's shape alone (profile correlation ", correlation,
           ") cannot tell this row from another row of the same planting: check that both videos film the same "
           "row; if they do, rerun with --same-row to register the sides on the canopy ",
           std::isnan(trunks.across) ? "alone" : "and the trunks");
    if (!std::isnan(trunks.across)) {
      // Each side's trunk points lie on the trunks' near faces, so their
      // distances add up to the paths' distance less a trunk's diameter (9 cm
      // at the synthetic trunks' foot); on 16 COLMAP rows they came out 0-6 cm
      // beyond the fruit's distance instead (docs/yield.md, "Trunks"), so
      // nothing is added.
      across = trunks.across;
      across_from = Registration::Across::kTrunks;
    } else {
      // Each side is assumed to see into the canopy up to the row's centre plane.
      std::vector<double> yf, yb;
      for (const auto& p : canopy_f) yf.push_back(p.y());
      for (const auto& p : canopy_b) yb.push_back(p.y());
      across = Quantile(yf, o.centre_quantile) + Quantile(yb, o.centre_quantile);
      across_from = Registration::Across::kAssumed;
    }
    // The centre plane lies at most the thickest canopy behind the two
    // sides' fruit: farther, the canopy found is the next row's (one tree
    // filmed: 12.4 m across for row distances of 2.1 m; 4.98-5.10 m on 31
    // rows of two and four trees, at most 0.85 m beyond the row distances).
    if (front.row_distance > 0 && back.row_distance > 0 &&
        across > front.row_distance + back.row_distance + o.max_thickness)
      Fail("the two sides' cameras would stand ", across, " m apart, more than their distances to the row's fruit (",
           front.row_distance, " + ", back.row_distance, " m) plus ", o.max_thickness,
           " m: the canopy each side sees is not its own row's (too short a stretch filmed?)");
  }
  Registration r = EvaluateAlignment(front, back, BackToFrontTransform(heading_deg, along, across), ro);
  // The two sides see opposite faces of the canopy: the back's canopy points
  // lie beyond the front's. The same video given twice puts them together.
  std::vector<double> depth_f, depth_b;
  for (const auto& p : canopy_f) depth_f.push_back(p.y());
  for (const auto& p : canopy_b) depth_b.push_back((r.back_to_front * p).y());
  if (Quantile(depth_b, 0.5) <= Quantile(depth_f, 0.5))
    Fail("the two sides show the same face of the canopy (the back's canopy points lie ",
         Quantile(depth_f, 0.5) - Quantile(depth_b, 0.5),
         " m nearer the front camera than the front's): they do not show the same row from both sides");
  r.on_row = r.has_profile = true, r.correlation = correlation, r.chance_correlation = chance_correlation;
  r.across_from = across_from, r.chance_matched = chance;
  r.across_trunks = trunks.across, r.trunks_front = trunks.front, r.trunks_back = trunks.back;
  // Overlap along the row: of the camera paths, or without them of the
  // canopies.
  std::vector<double> cb;
  for (const auto& p : canopy_b) cb.push_back((r.back_to_front * p).x());
  double f0 = Quantile(xf, 0.02), f1 = Quantile(xf, 0.98), b0 = Quantile(cb, 0.02), b1 = Quantile(cb, 0.98);
  if (have_paths) f0 = pf0, f1 = pf1, b0 = pb0 + r.along, b1 = pb1 + r.along;
  r.front_length = f1 - f0, r.back_length = b1 - b0;
  r.overlap = std::max(0.0, std::min(f1, b1) - std::max(f0, b0));
  if (r.overlap < o.min_overlap * std::min(r.front_length, r.back_length) - 1e-9)
    Fail("the two sides cover different stretches of the row: they overlap by ", r.overlap, " m along the row (front ",
         r.front_length, " m, back ", r.back_length, " m)");
  return r;
}

}  // namespace orchard
