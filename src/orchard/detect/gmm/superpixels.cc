#include "orchard/detect/gmm/superpixels.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core/utility.hpp>
#include <opencv2/ximgproc/slic.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace {

struct Centre {
  float l, a, b, x, y;
};

// Relabels 4-connected regions of `labels` so each label is one region; regions
// smaller than `min_size` are merged into the neighbouring region met first
// (left or above), as in Achanta et al.'s EnforceLabelConnectivity.
int EnforceConnectivity(cv::Mat1i& labels, int min_size) {
  const int w = labels.cols, h = labels.rows, n = w * h;
  cv::Mat1i out(h, w, -1);
  const int* in = labels.ptr<int>(0);
  int* o = out.ptr<int>(0);
  std::vector<int> region;
  region.reserve(4096);
  int next_label = 0;
  for (int start = 0; start < n; ++start) {
    if (o[start] >= 0) continue;
    const int original = in[start];
    // Adjacent final label for small-region merging.
    int adjacent = -1;
    const int sx = start % w, sy = start / w;
    if (sx > 0 && o[start - 1] >= 0) adjacent = o[start - 1];
    else if (sy > 0 && o[start - w] >= 0) adjacent = o[start - w];
    region.clear();
    region.push_back(start);
    o[start] = next_label;
    for (size_t i = 0; i < region.size(); ++i) {
      const int p = region[i];
      const int px = p % w, py = p / w;
      const int nbr[4] = {px > 0 ? p - 1 : -1, px + 1 < w ? p + 1 : -1, py > 0 ? p - w : -1,
                          py + 1 < h ? p + w : -1};
      for (int q : nbr) {
        if (q >= 0 && o[q] < 0 && in[q] == original) {
          o[q] = next_label;
          region.push_back(q);
        }
      }
    }
    if (static_cast<int>(region.size()) < min_size && adjacent >= 0) {
      for (int p : region) o[p] = adjacent;
    } else {
      ++next_label;
    }
  }
  labels = out;
  return next_label;
}

// One of the 9 neighbouring centres of every pixel of a row, spread out per
// pixel (the centre of the pixel's cell offset by one grid step, clamped at
// the border: a repeated centre never wins twice).
struct SpreadCentres {
  std::vector<float> l, a, b, x, y;
  std::vector<int> id;
  void Resize(int w) {
    for (auto* v : {&l, &a, &b, &x, &y}) v->resize(w);
    id.resize(w);
  }
};

// A whole row against one spread neighbour: keeps the nearest centre per
// pixel. The hot loop of the fast path, contiguous over the row so it
// vectorises; compiled for AVX2 as well as the baseline, the CPU picks at load
// time (GCC function multi-versioning).
__attribute__((target_clones("avx2", "default"))) void AssignRow(
    const float* __restrict pl, const float* __restrict pa, const float* __restrict pb,
    const float* __restrict xs, int w, float fy, float spatial_weight, const float* __restrict kl,
    const float* __restrict ka, const float* __restrict kb, const float* __restrict kx,
    const float* __restrict ky, const int* __restrict kid, float* __restrict bd, int* __restrict bc) {
  for (int x = 0; x < w; ++x) {
    const float dl = pl[x] - kl[x], da = pa[x] - ka[x], db = pb[x] - kb[x];
    const float dx = xs[x] - kx[x], dy = fy - ky[x];
    const float d = dl * dl + da * da + db * db + (dx * dx + dy * dy) * spatial_weight;
    const bool better = d < bd[x];
    bd[x] = better ? d : bd[x];
    bc[x] = better ? kid[x] : bc[x];
  }
}

Superpixels FastSlic(const cv::Mat& lab8, const SuperpixelOptions& opt) {
  const int w = lab8.cols, h = lab8.rows;
  const int s = opt.region_size;
  const int nx = std::max(1, (w + s / 2) / s), ny = std::max(1, (h + s / 2) / s);
  const float cw = static_cast<float>(w) / nx, ch = static_cast<float>(h) / ny;
  const float spatial_weight = static_cast<float>((opt.compactness / s) * (opt.compactness / s));

  // Separate float planes once per image: the row loops below then read
  // contiguous floats and vectorise (interleaved LAB did not).
  cv::Mat1b planes8[3];
  cv::split(lab8, planes8);
  cv::Mat1f planes[3];
  for (int i = 0; i < 3; ++i) planes8[i].convertTo(planes[i], CV_32F);
  std::vector<Centre> centres(nx * ny);
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const int x = std::min(w - 1, static_cast<int>((cx + 0.5f) * cw));
      const int y = std::min(h - 1, static_cast<int>((cy + 0.5f) * ch));
      centres[cy * nx + cx] = {planes[0](y, x), planes[1](y, x), planes[2](y, x), static_cast<float>(x),
                               static_cast<float>(y)};
    }
  }
  // Column of the grid cell each pixel column lies in, and cell column spans.
  std::vector<int> cell_x0(nx + 1);
  for (int cx = 0; cx <= nx; ++cx) cell_x0[cx] = std::min(w, static_cast<int>(std::lround(cx * cw)));
  std::vector<int> cell_of_x(w);
  for (int cx = 0; cx < nx; ++cx)
    for (int x = cell_x0[cx]; x < cell_x0[cx + 1]; ++x) cell_of_x[x] = cx;

  Superpixels result;
  result.labels.create(h, w);
  const int bands = std::max(1, std::min(opt.num_threads, h));
  struct Sums {
    std::vector<double> v;  // 6 per centre: l a b x y count
  };
  std::vector<Sums> sums(bands);

  for (int iter = 0; iter < opt.iterations; ++iter) {
    const bool last = iter + 1 == opt.iterations;
    cv::parallel_for_(cv::Range(0, bands), [&](const cv::Range& range) {
      std::vector<float> best_d(w), xs(w);
      std::vector<int> best_c(w);
      for (int x = 0; x < w; ++x) xs[x] = static_cast<float>(x);
      SpreadCentres spread[9];
      for (SpreadCentres& sc : spread) sc.Resize(w);
      int spread_row = -1;  // cell row the spread centres were built for
      for (int band = range.start; band < range.end; ++band) {
        std::vector<double>& acc = sums[band].v;
        acc.assign(centres.size() * 6, 0.0);
        const int y0 = h * band / bands, y1 = h * (band + 1) / bands;
        for (int y = y0; y < y1; ++y) {
          const float* pl = planes[0].ptr<float>(y);
          const float* pa = planes[1].ptr<float>(y);
          const float* pb = planes[2].ptr<float>(y);
          const float fy = static_cast<float>(y);
          const int cy = std::min(ny - 1, static_cast<int>(y / ch));
          std::fill(best_d.begin(), best_d.end(), std::numeric_limits<float>::max());
          if (cy != spread_row) {
            // Neighbours in the order the per-cell search visited them
            // (row-major), so ties resolve the same way.
            for (int o = 0; o < 9; ++o) {
              const int ny_ = std::clamp(cy + o / 3 - 1, 0, ny - 1);
              SpreadCentres& sc = spread[o];
              for (int x = 0; x < w; ++x) {
                const int nx_ = std::clamp(cell_of_x[x] + o % 3 - 1, 0, nx - 1);
                const int c = ny_ * nx + nx_;
                const Centre& k = centres[c];
                sc.l[x] = k.l, sc.a[x] = k.a, sc.b[x] = k.b, sc.x[x] = k.x, sc.y[x] = k.y, sc.id[x] = c;
              }
            }
            spread_row = cy;
          }
          for (const SpreadCentres& sc : spread)
            AssignRow(pl, pa, pb, xs.data(), w, fy, spatial_weight, sc.l.data(), sc.a.data(), sc.b.data(),
                      sc.x.data(), sc.y.data(), sc.id.data(), best_d.data(), best_c.data());
          if (last) {
            std::copy(best_c.begin(), best_c.end(), result.labels.ptr<int>(y));
          } else {
            for (int x = 0; x < w; ++x) {
              double* a = &acc[6 * best_c[x]];
              a[0] += pl[x];
              a[1] += pa[x];
              a[2] += pb[x];
              a[3] += x;
              a[4] += y;
              a[5] += 1;
            }
          }
        }
      }
    }, bands);
    if (last) break;
    for (size_t c = 0; c < centres.size(); ++c) {
      double t[6] = {0, 0, 0, 0, 0, 0};
      for (int b = 0; b < bands; ++b)
        for (int i = 0; i < 6; ++i) t[i] += sums[b].v[6 * c + i];
      if (t[5] > 0) {
        centres[c] = {static_cast<float>(t[0] / t[5]), static_cast<float>(t[1] / t[5]),
                      static_cast<float>(t[2] / t[5]), static_cast<float>(t[3] / t[5]),
                      static_cast<float>(t[4] / t[5])};
      }
    }
  }
  const int min_size = static_cast<int>(opt.min_size_fraction * s * s);
  result.num_labels = EnforceConnectivity(result.labels, min_size);
  return result;
}

Superpixels OpenCvSlic(const cv::Mat& lab8, const SuperpixelOptions& opt) {
  cv::Ptr<cv::ximgproc::SuperpixelSLIC> slic = cv::ximgproc::createSuperpixelSLIC(
      lab8, cv::ximgproc::SLIC, opt.region_size, static_cast<float>(opt.compactness));
  slic->iterate(10);
  slic->enforceLabelConnectivity(static_cast<int>(std::lround(opt.min_size_fraction * 100)));
  Superpixels result;
  slic->getLabels(result.labels);
  // OpenCV may leave label numbers unused; compact them and make each region
  // connected (OpenCV's merging already did; this keeps the contract exact).
  result.num_labels = EnforceConnectivity(result.labels, 0);
  return result;
}

}  // namespace

void SuperpixelOptions::Check() const {
  ORCHARD_CHECK_OPTION(region_size >= 2, "superpixel region_size must be >= 2 pixels, got ", region_size);
  ORCHARD_CHECK_OPTION(compactness > 0, "superpixel compactness must be > 0, got ", compactness);
  ORCHARD_CHECK_OPTION(iterations >= 1, "superpixel iterations must be >= 1, got ", iterations);
  ORCHARD_CHECK_OPTION(min_size_fraction >= 0 && min_size_fraction <= 1,
                       "superpixel min_size_fraction must be in [0, 1], got ", min_size_fraction);
  ORCHARD_CHECK_OPTION(num_threads >= 1, "num_threads must be >= 1, got ", num_threads);
}

Superpixels ComputeSuperpixels(const cv::Mat& lab8, const SuperpixelOptions& options) {
  options.Check();
  if (lab8.empty()) Fail("cannot compute superpixels of an empty image");
  if (lab8.type() != CV_8UC3) Fail("superpixels need an 8-bit 3-channel LAB image");
  return options.use_opencv ? OpenCvSlic(lab8, options) : FastSlic(lab8, options);
}

SuperpixelColours ComputeSuperpixelColours(const cv::Mat& lab8, const Superpixels& sp, int num_threads) {
  const int n = sp.num_labels;
  const int bands = std::max(1, std::min(num_threads, lab8.rows));
  // Per label: sums of l a b, ll la lb aa ab bb, count (10 values).
  std::vector<std::vector<double>> sums(bands);
  cv::parallel_for_(cv::Range(0, bands), [&](const cv::Range& range) {
    for (int band = range.start; band < range.end; ++band) {
      std::vector<double>& s = sums[band];
      s.assign(static_cast<size_t>(n) * 10, 0.0);
      const int y0 = lab8.rows * band / bands, y1 = lab8.rows * (band + 1) / bands;
      for (int y = y0; y < y1; ++y) {
        const uchar* p = lab8.ptr<uchar>(y);
        const int* lab = sp.labels.ptr<int>(y);
        for (int x = 0; x < lab8.cols; ++x) {
          const double l = p[3 * x], a = p[3 * x + 1], b = p[3 * x + 2];
          double* t = &s[10 * static_cast<size_t>(lab[x])];
          t[0] += l; t[1] += a; t[2] += b;
          t[3] += l * l; t[4] += l * a; t[5] += l * b;
          t[6] += a * a; t[7] += a * b; t[8] += b * b;
          t[9] += 1;
        }
      }
    }
  }, bands);
  SuperpixelColours out;
  out.mean.resize(n);
  out.covariance.resize(n);
  out.pixels.resize(n);
  const double sl = 100.0 / 255.0;
  const Eigen::Vector3d scale(sl, 1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    double t[10] = {};
    for (int b = 0; b < bands; ++b)
      for (int j = 0; j < 10; ++j) t[j] += sums[b][10 * static_cast<size_t>(i) + j];
    const double c = std::max(1.0, t[9]);
    const Eigen::Vector3d m8(t[0] / c, t[1] / c, t[2] / c);
    Eigen::Matrix3d cov;
    cov << t[3] / c - m8[0] * m8[0], t[4] / c - m8[0] * m8[1], t[5] / c - m8[0] * m8[2],
        0, t[6] / c - m8[1] * m8[1], t[7] / c - m8[1] * m8[2],
        0, 0, t[8] / c - m8[2] * m8[2];
    cov(1, 0) = cov(0, 1);
    cov(2, 0) = cov(0, 2);
    cov(2, 1) = cov(1, 2);
    out.mean[i] = LabFrom8Bit(m8[0], m8[1], m8[2]);
    out.covariance[i] = scale.asDiagonal() * cov * scale.asDiagonal();
    out.pixels[i] = static_cast<int>(t[9]);
  }
  return out;
}

}  // namespace orchard
