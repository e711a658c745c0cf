#include "orchard/merge/registration.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "orchard/core/error.h"

namespace orchard {

void RegistrationOptions::Check() const {
  ORCHARD_CHECK_OPTION(match_distance > 0, "match distance must be positive, got ", match_distance);
  ORCHARD_CHECK_OPTION(max_heading_deg >= 0 && max_heading_deg < 90, "max heading must be in [0, 90), got ",
                       max_heading_deg);
  ORCHARD_CHECK_OPTION(heading_step_deg > 0, "heading step must be positive, got ", heading_step_deg);
  ORCHARD_CHECK_OPTION(cell > 0, "Hough cell must be positive, got ", cell);
  ORCHARD_CHECK_OPTION(min_path_distance >= 0 && max_path_distance > min_path_distance,
                       "path distance range must be 0 <= min < max, got ", min_path_distance, "..", max_path_distance);
  ORCHARD_CHECK_OPTION(min_matched >= 3, "min matched must be at least 3, got ", min_matched);
  ORCHARD_CHECK_OPTION(min_matched_fraction >= 0 && min_matched_fraction <= 1,
                       "min matched fraction must be in [0, 1], got ", min_matched_fraction);
  ORCHARD_CHECK_OPTION(min_distinctness >= 1, "min distinctness must be >= 1, got ", min_distinctness);
  ORCHARD_CHECK_OPTION(max_scale_change >= 0 && max_scale_change < 0.5, "max scale change must be in [0, 0.5), got ",
                       max_scale_change);
  ORCHARD_CHECK_OPTION(scale_step > 0, "scale step must be positive, got ", scale_step);
  ORCHARD_CHECK_OPTION(min_overlap >= 0 && min_overlap <= 1, "min overlap must be in [0, 1], got ", min_overlap);
  ORCHARD_CHECK_OPTION(refine_iterations >= 1, "refine iterations must be >= 1, got ", refine_iterations);
}

Eigen::Isometry3d BackToFrontTransform(double heading_deg, double along, double across) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(M_PI + heading_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(along, across, 0);
  return t;
}

namespace {

struct Candidate {
  double heading_deg = 0;
  double scale = 1;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  int votes = 0;
};

struct Fit {
  double heading_deg = 0;
  double scale = 1;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  std::vector<std::pair<int, int>> pairs;
  double residual = 0;
};

// Mutual nearest neighbours within `distance` of the transformed back centres.
std::vector<std::pair<int, int>> MatchCentres(const std::vector<Eigen::Vector3d>& front,
                                              const std::vector<Eigen::Vector3d>& back_in_front, double distance) {
  const int nf = static_cast<int>(front.size()), nb = static_cast<int>(back_in_front.size());
  std::vector<int> best_f(nb, -1), best_b(nf, -1);
  std::vector<double> dist_f(nb, distance), dist_b(nf, distance);
  for (int b = 0; b < nb; ++b)
    for (int f = 0; f < nf; ++f) {
      const double d = (front[f] - back_in_front[b]).norm();
      if (d < dist_f[b]) dist_f[b] = d, best_f[b] = f;
      if (d < dist_b[f]) dist_b[f] = d, best_b[f] = b;
    }
  std::vector<std::pair<int, int>> pairs;
  for (int b = 0; b < nb; ++b)
    if (best_f[b] >= 0 && best_b[best_f[b]] == b) pairs.emplace_back(best_f[b], b);
  return pairs;
}

std::vector<Eigen::Vector3d> Transformed(const Eigen::Isometry3d& t, const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> moved;
  moved.reserve(points.size());
  for (const auto& p : points) moved.push_back(t * p);
  return moved;
}

// A back point placed in the front row frame: scaled about the back's
// origin, then turned and shifted.
Eigen::Vector3d Place(double heading_deg, double scale, const Eigen::Vector2d& offset, const Eigen::Vector3d& p) {
  return BackToFrontTransform(heading_deg, offset.x(), offset.y()) * Eigen::Vector3d(scale * p);
}

std::vector<Eigen::Vector3d> Placed(const Fit& f, const std::vector<Eigen::Vector3d>& back) {
  const Eigen::Isometry3d t = BackToFrontTransform(f.heading_deg, f.offset.x(), f.offset.y());
  std::vector<Eigen::Vector3d> moved;
  moved.reserve(back.size());
  for (const auto& p : back) moved.push_back(t * Eigen::Vector3d(f.scale * p));
  return moved;
}

// RMS distance between corresponding points.
double RmsDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).squaredNorm();
  return a.empty() ? 0 : std::sqrt(sum / static_cast<double>(a.size()));
}

// RMS distance between matched centres.
double RmsDistance(const std::vector<Eigen::Vector3d>& front, const std::vector<Eigen::Vector3d>& back_in_front,
                   const std::vector<std::pair<int, int>>& pairs) {
  double sum = 0;
  for (const auto& [f, b] : pairs) sum += (front[f] - back_in_front[b]).squaredNorm();
  return pairs.empty() ? 0 : std::sqrt(sum / static_cast<double>(pairs.size()));
}

// Closest points and a rigid fit in the ground plane, repeated.
Fit Refine(const std::vector<Eigen::Vector3d>& front, const std::vector<Eigen::Vector3d>& back, const Candidate& start,
           const RegistrationOptions& o) {
  Fit fit;
  fit.heading_deg = start.heading_deg;
  fit.scale = start.scale;
  fit.offset = start.offset;
  for (int it = 0; it < o.refine_iterations; ++it) {
    auto pairs = MatchCentres(front, Placed(fit, back), o.match_distance);
    if (pairs.size() < 3) {
      fit.pairs = pairs;
      break;
    }
    // 2D Procrustes: rotation about z and translation in x, y.
    Eigen::Vector2d mf = Eigen::Vector2d::Zero(), mb = Eigen::Vector2d::Zero();
    for (const auto& [f, b] : pairs) mf += front[f].head<2>(), mb += back[b].head<2>();
    mf /= static_cast<double>(pairs.size()), mb /= static_cast<double>(pairs.size());
    double s_dot = 0, s_cross = 0;
    for (const auto& [f, b] : pairs) {
      const Eigen::Vector2d p = back[b].head<2>() - mb, q = front[f].head<2>() - mf;
      s_dot += p.dot(q), s_cross += p.x() * q.y() - p.y() * q.x();
    }
    double angle = std::atan2(s_cross, s_dot);  // full rotation, about pi
    double heading = std::remainder(angle - M_PI, 2 * M_PI) * 180 / M_PI;
    heading = std::clamp(heading, -o.max_heading_deg, o.max_heading_deg);
    const Eigen::Rotation2Dd rot(M_PI + heading * M_PI / 180);
    // Least-squares scale at that rotation (2D similarity), within bounds.
    double scale = 1;
    if (o.max_scale_change > 0) {
      double s_pp = 0, s_qrp = 0;
      for (const auto& [f, b] : pairs) {
        const Eigen::Vector2d p = back[b].head<2>() - mb, q = front[f].head<2>() - mf;
        s_pp += p.squaredNorm(), s_qrp += q.dot(rot * p);
      }
      if (s_pp > 0) scale = std::clamp(s_qrp / s_pp, 1 - o.max_scale_change, 1 + o.max_scale_change);
    }
    const Eigen::Vector2d offset = mf - scale * (rot * mb);
    const bool converged = std::abs(heading - fit.heading_deg) < 1e-4 && std::abs(scale - fit.scale) < 1e-6 &&
                           (offset - fit.offset).norm() < 1e-5 && pairs == fit.pairs;
    fit.heading_deg = heading, fit.scale = scale, fit.offset = offset, fit.pairs = std::move(pairs);
    if (converged) break;
  }
  const auto moved = Placed(fit, back);
  fit.pairs = MatchCentres(front, moved, o.match_distance);
  fit.residual = RmsDistance(front, moved, fit.pairs);
  return fit;
}

std::vector<Eigen::Vector3d> Centres(const SideCloud& side) {
  std::vector<Eigen::Vector3d> centres;
  for (const auto& c : side.clusters) centres.push_back(c.centre);
  return centres;
}

// Along-row extent (min, max x) of centres.
std::pair<double, double> AlongExtent(const std::vector<Eigen::Vector3d>& centres) {
  double lo = centres[0].x(), hi = lo;
  for (const auto& c : centres) lo = std::min(lo, c.x()), hi = std::max(hi, c.x());
  return {lo, hi};
}

}  // namespace

Registration EvaluateAlignment(const SideCloud& front, const SideCloud& back, const Eigen::Isometry3d& t,
                               const RegistrationOptions& o) {
  Registration r;
  r.back_to_front = t;
  const Eigen::Matrix3d rot = t.linear();
  r.heading_deg = std::remainder(std::atan2(rot(1, 0), rot(0, 0)) - M_PI, 2 * M_PI) * 180 / M_PI;
  r.along = t.translation().x(), r.across = t.translation().y();
  const std::vector<Eigen::Vector3d> fc = Centres(front), moved = Transformed(t, Centres(back));
  if (fc.empty() || moved.empty()) return r;
  r.pairs = MatchCentres(fc, moved, o.match_distance);
  r.matched = static_cast<int>(r.pairs.size());
  r.residual = RmsDistance(fc, moved, r.pairs);
  const auto [f0, f1] = AlongExtent(fc);
  const auto [b0, b1] = AlongExtent(moved);
  r.front_length = f1 - f0, r.back_length = b1 - b0;
  r.overlap = std::max(0.0, std::min(f1, b1) - std::max(f0, b0));
  return r;
}

Registration RegisterSides(const SideCloud& front, const SideCloud& back, const RegistrationOptions& o,
                           const Eigen::Isometry3d* given) {
  o.Check();
  for (const SideCloud* s : {&front, &back})
    if (static_cast<int>(s->clusters.size()) < o.min_matched)
      Fail("the ", s->name, " side has ", s->clusters.size(), " fruit clusters, too few to register the two sides (need ",
           o.min_matched, ")");
  const std::vector<Eigen::Vector3d> fc = Centres(front), bc = Centres(back);

  // Hough vote: every pair of clusters at a similar height proposes the
  // offset that would put them on top of each other, for each heading and
  // scale of the back side.
  std::vector<Candidate> peaks;  // the best cells of each heading (over the scales)
  const int steps = static_cast<int>(std::floor(o.max_heading_deg / o.heading_step_deg + 1e-9));
  const int scale_steps = static_cast<int>(std::floor(o.max_scale_change / o.scale_step + 1e-9));
  auto key = [](long long ix, long long iy) {
    return static_cast<long long>((static_cast<unsigned long long>(ix) << 32) | static_cast<std::uint32_t>(iy));
  };
  for (int h = -steps; h <= steps; ++h) {
    const double heading = h * o.heading_step_deg;
    const Eigen::Rotation2Dd rot(M_PI + heading * M_PI / 180);
    std::vector<Candidate> cells;
    for (int si = -scale_steps; si <= scale_steps; ++si) {
      const double scale = 1 + si * o.scale_step;
      std::unordered_map<long long, int> votes;
      for (const auto& b : bc) {
        const Eigen::Vector2d rb = scale * (rot * b.head<2>());
        for (const auto& f : fc) {
          if (std::abs(f.z() - scale * b.z()) > o.match_distance) continue;
          const Eigen::Vector2d t = f.head<2>() - rb;
          if (t.y() < o.min_path_distance || t.y() > o.max_path_distance) continue;
          ++votes[key(static_cast<long long>(std::floor(t.x() / o.cell)),
                      static_cast<long long>(std::floor(t.y() / o.cell)))];
        }
      }
      // Score of a cell: votes in it and its 8 neighbours (a match straddles cells).
      for (const auto& [k, v] : votes) {
        (void)v;
        const long long ix = k >> 32, iy = static_cast<std::int32_t>(static_cast<std::uint32_t>(k & 0xffffffffLL));
        int sum = 0;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy) {
            const auto it = votes.find(key(ix + dx, iy + dy));
            if (it != votes.end()) sum += it->second;
          }
        cells.push_back({heading, scale, Eigen::Vector2d((ix + 0.5) * o.cell, (iy + 0.5) * o.cell), sum});
      }
    }
    std::sort(cells.begin(), cells.end(), [](const Candidate& a, const Candidate& b) { return a.votes > b.votes; });
    // Keep a few well-separated peaks per heading, whatever their scale.
    std::vector<Candidate> kept;
    for (const auto& c : cells) {
      bool near = false;
      for (const auto& k : kept) near |= (k.offset - c.offset).norm() < 0.5;
      if (!near) kept.push_back(c);
      if (kept.size() >= 3) break;
    }
    peaks.insert(peaks.end(), kept.begin(), kept.end());
  }
  std::sort(peaks.begin(), peaks.end(), [](const Candidate& a, const Candidate& b) { return a.votes > b.votes; });
  // The 24 best peaks to refine, at most 4 of them at one place (where they
  // put the back side's centre, within 0.5 m): neighbouring headings and
  // scales all peak at the true alignment, and the best alignment elsewhere
  // must be refined too for the distinctness check.
  Eigen::Vector3d back_centre = Eigen::Vector3d::Zero();
  for (const auto& b : bc) back_centre += b / static_cast<double>(bc.size());
  std::vector<Candidate> selected;
  std::vector<Eigen::Vector2d> selected_at;
  for (const auto& p : peaks) {
    const Eigen::Vector2d at = Place(p.heading_deg, p.scale, p.offset, back_centre).head<2>();
    int near = 0;
    for (const auto& q : selected_at) near += (q - at).norm() < 0.5;
    if (near >= 4) continue;
    selected.push_back(p), selected_at.push_back(at);
    if (selected.size() >= 24) break;
  }
  peaks.swap(selected);

  std::vector<Fit> fits;
  for (const auto& p : peaks) fits.push_back(Refine(fc, bc, p, o));
  auto better = [](const Fit& a, const Fit& b) {
    return a.pairs.size() != b.pairs.size() ? a.pairs.size() > b.pairs.size() : a.residual < b.residual;
  };
  if (fits.empty())
    Fail("no pair of fruit clusters from the two sides could be the same fruit: the sides do not show the same row");
  const Fit best = *std::min_element(fits.begin(), fits.end(), better);
  // Another alignment moves the back side's clusters by more than 0.5 m
  // (RMS) from where the best puts them: fits at neighbouring headings and
  // scales that agree about the middle of the row are the same alignment.
  const std::vector<Eigen::Vector3d> best_placed = Placed(best, bc);
  int chance = 0;
  for (const auto& f : fits)
    if (RmsDistance(best_placed, Placed(f, bc)) > 0.5) chance = std::max(chance, static_cast<int>(f.pairs.size()));

  // The matches and extents need the back's clusters only, not its sparse points.
  SideCloud scaled_back;
  scaled_back.name = back.name, scaled_back.clusters = back.clusters;
  ScaleSideCloud(&scaled_back, best.scale);
  Registration r =
      EvaluateAlignment(front, scaled_back, BackToFrontTransform(best.heading_deg, best.offset.x(), best.offset.y()), o);
  r.back_scale = best.scale;
  r.chance_matched = chance;
  if (r.matched < o.min_matched)
    Fail("the two sides share no consistent fruit clusters (the best alignment matches ", r.matched, ", need ",
         o.min_matched, "): they do not show the same row, or the reconstructions are broken");
  const size_t fewer = std::min(front.clusters.size(), back.clusters.size());
  if (r.matched < o.min_matched_fraction * static_cast<double>(fewer))
    Fail("the two sides share too few fruit clusters (", r.matched, " of the ", fewer,
         " on the side with fewer): they do not show the same row, or the detections are too sparse to register "
         "them (give poses in one frame with --poses-registered)");
  // The given poses imply the same alignment by the measure above.
  if (r.matched < o.min_distinctness * std::max(chance, 1) && given != nullptr &&
      RmsDistance(best_placed, Transformed(*given, bc)) <= 0.5)
    r.settled_by_given_poses = true;
  if (!r.settled_by_given_poses && r.matched < o.min_distinctness * std::max(chance, 1))
    Fail("the two sides' alignment is ambiguous (", r.matched, " clusters matched at the best alignment, ", chance,
         " at another): they may not show the same row");
  const double shorter = std::min(r.front_length, r.back_length);
  if (shorter <= 0 || r.overlap < o.min_overlap * shorter)
    Fail("the two sides cover different stretches of the row: they overlap by ", r.overlap, " m along the row (front ",
         r.front_length, " m, back ", r.back_length, " m)");
  return r;
}

}  // namespace orchard
