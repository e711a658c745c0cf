#include "orchard/detect/gmm/gaussian_mixture.h"

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Cholesky>

#include "orchard/core/error.h"

namespace orchard {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

// Per-component log N(x_i | mu, S) for all rows, via the Cholesky factor.
Eigen::MatrixXd ComponentLogDensities(const GaussianMixture& mixture, const Eigen::MatrixXd& x) {
  const int n = static_cast<int>(x.rows());
  const int d = static_cast<int>(x.cols());
  const int k = mixture.NumComponents();
  Eigen::MatrixXd out(n, k);
  for (int j = 0; j < k; ++j) {
    const Gaussian& g = mixture.components[j];
    Eigen::LLT<Eigen::MatrixXd> llt(g.covariance);
    if (llt.info() != Eigen::Success) Fail("covariance of component ", j, " is not positive definite");
    const Eigen::MatrixXd& l = llt.matrixL();
    const double log_det = 2.0 * l.diagonal().array().log().sum();
    Eigen::MatrixXd diff = (x.rowwise() - g.mean.transpose()).transpose();  // d x n
    l.triangularView<Eigen::Lower>().solveInPlace(diff);
    out.col(j) = -0.5 * (diff.colwise().squaredNorm().transpose().array() + d * kLog2Pi + log_det);
  }
  return out;
}

// log sum_j exp(a_ij) per row; also returns normalised posteriors in `post`.
Eigen::VectorXd LogSumExpRows(const Eigen::MatrixXd& a, Eigen::MatrixXd* post) {
  const Eigen::VectorXd row_max = a.rowwise().maxCoeff();
  Eigen::MatrixXd e = (a.colwise() - row_max).array().exp();
  const Eigen::VectorXd sums = e.rowwise().sum();
  if (post) *post = e.array().colwise() / sums.array();
  return row_max.array() + sums.array().log();
}

Eigen::MatrixXd WeightedLogDensities(const GaussianMixture& m, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd a = ComponentLogDensities(m, x);
  for (int j = 0; j < m.NumComponents(); ++j) a.col(j).array() += std::log(std::max(m.weights[j], 1e-300));
  return a;
}

Eigen::MatrixXd Covariance(const Eigen::MatrixXd& x) {
  const Eigen::RowVectorXd mean = x.colwise().mean();
  const Eigen::MatrixXd c = x.rowwise() - mean;
  return (c.transpose() * c) / std::max<double>(1, x.rows());
}

// M step from responsibilities r (n x k).
void MaximizationStep(const Eigen::MatrixXd& x, const Eigen::MatrixXd& r, const Eigen::MatrixXd& fallback_cov,
                      double regularization, GaussianMixture* m) {
  const int d = static_cast<int>(x.cols());
  const int k = static_cast<int>(r.cols());
  const Eigen::VectorXd nk = r.colwise().sum().transpose();
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(d, d);
  m->weights.assign(k, 0.0);
  m->components.resize(k);
  for (int j = 0; j < k; ++j) {
    Gaussian& g = m->components[j];
    m->weights[j] = nk[j] / x.rows();
    if (nk[j] < 1e-8) {
      // An empty component keeps its mean and gets the data's spread, so it may recapture samples.
      if (g.mean.size() != d) g.mean = x.colwise().mean().transpose();
      g.covariance = fallback_cov + regularization * identity;
      m->weights[j] = 1e-12;
      continue;
    }
    g.mean = (x.transpose() * r.col(j)) / nk[j];
    const Eigen::MatrixXd c = x.rowwise() - g.mean.transpose();
    g.covariance = (c.transpose() * (c.array().colwise() * r.col(j).array()).matrix()) / nk[j];
    g.covariance += regularization * identity;
  }
  double total = 0;
  for (double w : m->weights) total += w;
  for (double& w : m->weights) w /= total;
}

}  // namespace

int GaussianMixture::NumParameters() const {
  const int k = NumComponents();
  const int d = Dim();
  return (k - 1) + k * d + k * d * (d + 1) / 2;
}

Eigen::VectorXd GaussianMixture::LogDensity(const Eigen::MatrixXd& samples) const {
  return LogSumExpRows(WeightedLogDensities(*this, samples), nullptr);
}

Eigen::MatrixXd GaussianMixture::Posteriors(const Eigen::MatrixXd& samples) const {
  Eigen::MatrixXd post;
  LogSumExpRows(WeightedLogDensities(*this, samples), &post);
  return post;
}

void GaussianMixture::Validate() const {
  if (components.empty()) Fail("mixture has no components");
  if (weights.size() != components.size()) Fail("mixture has ", weights.size(), " weights for ", components.size(), " components");
  const int d = Dim();
  if (d <= 0) Fail("mixture components have no dimensions");
  double total = 0;
  for (size_t j = 0; j < components.size(); ++j) {
    const Gaussian& g = components[j];
    if (!(weights[j] >= 0) || !std::isfinite(weights[j])) Fail("mixture weight ", j, " is not a non-negative number");
    total += weights[j];
    if (g.mean.size() != d || g.covariance.rows() != d || g.covariance.cols() != d)
      Fail("mixture component ", j, " has inconsistent dimensions");
    if (!g.mean.allFinite() || !g.covariance.allFinite()) Fail("mixture component ", j, " is not finite");
    Eigen::LLT<Eigen::MatrixXd> llt(g.covariance);
    if (llt.info() != Eigen::Success) Fail("covariance of mixture component ", j, " is not positive definite");
  }
  if (std::abs(total - 1.0) > 1e-3) Fail("mixture weights sum to ", total, ", not 1");
}

void GaussianMixtureOptions::Check() const {
  ORCHARD_CHECK_OPTION(num_components >= 1, "num_components must be >= 1, got ", num_components);
  ORCHARD_CHECK_OPTION(max_iterations >= 1, "max_iterations must be >= 1, got ", max_iterations);
  ORCHARD_CHECK_OPTION(tolerance >= 0, "tolerance must be >= 0, got ", tolerance);
  ORCHARD_CHECK_OPTION(regularization > 0, "regularization must be > 0, got ", regularization);
}

double GaussianMixtureFit::Bic() const {
  return -2.0 * log_likelihood + mixture.NumParameters() * std::log(std::max(1, num_samples));
}

double GaussianMixtureFit::Aic() const { return -2.0 * log_likelihood + 2.0 * mixture.NumParameters(); }

GaussianMixtureFit FitGaussianMixture(const Eigen::MatrixXd& x, const GaussianMixtureOptions& options) {
  options.Check();
  const int n = static_cast<int>(x.rows());
  const int k = options.num_components;
  if (x.cols() < 1) Fail("cannot fit a mixture to samples with no dimensions");
  if (n < k) Fail("cannot fit ", k, " mixture components to ", n, " samples");
  if (!x.allFinite()) Fail("cannot fit a mixture: samples contain NaN or infinity");

  // k-means++ seeding: first centre uniform, the others with probability ~ squared distance.
  std::mt19937_64 rng(options.seed);
  std::vector<int> centres;
  centres.push_back(static_cast<int>(std::uniform_int_distribution<int>(0, n - 1)(rng)));
  Eigen::VectorXd d2 = (x.rowwise() - x.row(centres[0])).rowwise().squaredNorm();
  while (static_cast<int>(centres.size()) < k) {
    const double total = d2.sum();
    int next = 0;
    if (total <= 0) {
      next = std::uniform_int_distribution<int>(0, n - 1)(rng);
    } else {
      double u = std::uniform_real_distribution<double>(0, total)(rng);
      for (next = 0; next < n - 1; ++next) {
        u -= d2[next];
        if (u <= 0) break;
      }
    }
    centres.push_back(next);
    d2 = d2.cwiseMin((x.rowwise() - x.row(next)).rowwise().squaredNorm());
  }
  // Hard assignment to the nearest centre gives the first responsibilities.
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(n, k);
  for (int i = 0; i < n; ++i) {
    int best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (int j = 0; j < k; ++j) {
      const double d = (x.row(i) - x.row(centres[j])).squaredNorm();
      if (d < best_d) best_d = d, best = j;
    }
    r(i, best) = 1.0;
  }
  const Eigen::MatrixXd global_cov = Covariance(x);
  GaussianMixtureFit fit;
  fit.num_samples = n;
  for (int j = 0; j < k; ++j) fit.mixture.components.push_back({x.row(centres[j]).transpose(), global_cov});
  MaximizationStep(x, r, global_cov, options.regularization, &fit.mixture);

  double previous = -std::numeric_limits<double>::infinity();
  for (int it = 1; it <= options.max_iterations; ++it) {
    const Eigen::VectorXd ll = LogSumExpRows(WeightedLogDensities(fit.mixture, x), &r);
    fit.log_likelihood = ll.sum();
    fit.iterations = it;
    const double mean_ll = fit.log_likelihood / n;
    if (mean_ll - previous < options.tolerance) {
      fit.converged = true;
      break;
    }
    previous = mean_ll;
    MaximizationStep(x, r, global_cov, options.regularization, &fit.mixture);
  }
  if (!fit.converged) fit.log_likelihood = fit.mixture.LogDensity(x).sum();
  return fit;
}

double KLDivergence(const Gaussian& f, const Gaussian& g) {
  const int d = static_cast<int>(f.mean.size());
  if (g.mean.size() != d) Fail("KL divergence between Gaussians of dimensions ", d, " and ", g.mean.size());
  Eigen::LLT<Eigen::MatrixXd> lg(g.covariance), lf(f.covariance);
  if (lg.info() != Eigen::Success || lf.info() != Eigen::Success) Fail("KL divergence: covariance is not positive definite");
  const double log_det_g = 2.0 * Eigen::MatrixXd(lg.matrixL()).diagonal().array().log().sum();
  const double log_det_f = 2.0 * Eigen::MatrixXd(lf.matrixL()).diagonal().array().log().sum();
  const Eigen::VectorXd diff = g.mean - f.mean;
  const double trace = lg.solve(f.covariance).trace();
  const double maha = diff.dot(lg.solve(diff));
  return 0.5 * (trace + maha - d + log_det_g - log_det_f);
}

double GoldbergerKL(const GaussianMixture& f, const GaussianMixture& g) {
  double kl = 0;
  for (int a = 0; a < f.NumComponents(); ++a) {
    const double pa = f.weights[a];
    if (pa <= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    double best_kl = 0, best_w = 1;
    for (int b = 0; b < g.NumComponents(); ++b) {
      const double kab = KLDivergence(f.components[a], g.components[b]);
      const double cost = kab - std::log(std::max(g.weights[b], 1e-300));
      if (cost < best) best = cost, best_kl = kab, best_w = g.weights[b];
    }
    kl += pa * (best_kl + std::log(pa / std::max(best_w, 1e-300)));
  }
  return kl;
}

}  // namespace orchard
