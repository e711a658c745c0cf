#include "orchard/detect/gmm/gaussian_mixture.h"

#include <cmath>
#include <random>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "orchard/core/error.h"

namespace orchard {
namespace {

Gaussian MakeGaussian(std::vector<double> mean, std::vector<double> cov_row_major) {
  const int d = static_cast<int>(mean.size());
  Gaussian g;
  g.mean = Eigen::Map<Eigen::VectorXd>(mean.data(), d);
  g.covariance = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      cov_row_major.data(), d, d);
  return g;
}

// Samples from a known mixture.
Eigen::MatrixXd Sample(const GaussianMixture& m, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::discrete_distribution<int> pick(m.weights.begin(), m.weights.end());
  std::normal_distribution<double> normal;
  Eigen::MatrixXd x(n, m.Dim());
  for (int i = 0; i < n; ++i) {
    const Gaussian& g = m.components[pick(rng)];
    Eigen::VectorXd z(m.Dim());
    for (int k = 0; k < m.Dim(); ++k) z[k] = normal(rng);
    x.row(i) = (g.mean + Eigen::MatrixXd(g.covariance.llt().matrixL()) * z).transpose();
  }
  return x;
}

GaussianMixture ThreeBlobs() {
  GaussianMixture m;
  m.weights = {0.5, 0.3, 0.2};
  m.components = {MakeGaussian({0, 0}, {1, 0.3, 0.3, 1}), MakeGaussian({10, 0}, {2, 0, 0, 0.5}),
                  MakeGaussian({0, 12}, {0.5, 0, 0, 0.5})};
  return m;
}

TEST(GaussianMixture, EmRecoversKnownMixture) {
  const GaussianMixture truth = ThreeBlobs();
  const Eigen::MatrixXd x = Sample(truth, 6000, 7);
  GaussianMixtureOptions options;
  options.num_components = 3;
  const GaussianMixtureFit fit = FitGaussianMixture(x, options);
  EXPECT_TRUE(fit.converged);
  for (int t = 0; t < 3; ++t) {
    // The fitted component nearest to each true mean.
    int best = 0;
    for (int j = 1; j < 3; ++j)
      if ((fit.mixture.components[j].mean - truth.components[t].mean).norm() <
          (fit.mixture.components[best].mean - truth.components[t].mean).norm())
        best = j;
    EXPECT_LT((fit.mixture.components[best].mean - truth.components[t].mean).norm(), 0.1) << t;
    EXPECT_NEAR(fit.mixture.weights[best], truth.weights[t], 0.02) << t;
    EXPECT_LT((fit.mixture.components[best].covariance - truth.components[t].covariance).norm(), 0.2) << t;
  }
  fit.mixture.Validate();
}

TEST(GaussianMixture, SameSeedSameFit) {
  const Eigen::MatrixXd x = Sample(ThreeBlobs(), 500, 3);
  GaussianMixtureOptions options;
  options.num_components = 4;
  options.seed = 11;
  const GaussianMixtureFit a = FitGaussianMixture(x, options), b = FitGaussianMixture(x, options);
  EXPECT_EQ(a.log_likelihood, b.log_likelihood);
}

TEST(GaussianMixture, BicPicksTrueNumberOfComponents) {
  const Eigen::MatrixXd x = Sample(ThreeBlobs(), 1500, 5);
  int best_k = 0;
  double best_bic = 1e300;
  for (int k = 1; k <= 6; ++k) {
    GaussianMixtureOptions options;
    options.num_components = k;
    const double bic = FitGaussianMixture(x, options).Bic();
    if (bic < best_bic) best_bic = bic, best_k = k;
  }
  EXPECT_EQ(best_k, 3);
}

TEST(GaussianMixture, PosteriorsSumToOneAndLogDensityMatchesOneGaussian) {
  GaussianMixture one;
  one.weights = {1.0};
  one.components = {MakeGaussian({0}, {4})};
  Eigen::MatrixXd x(1, 1);
  x << 2.0;
  // log N(2 | 0, 4) = -0.5 (ln(2 pi 4) + 1)
  EXPECT_NEAR(one.LogDensity(x)[0], -0.5 * (std::log(2 * M_PI * 4) + 1.0), 1e-12);
  const GaussianMixture m = ThreeBlobs();
  const Eigen::MatrixXd p = m.Posteriors(Sample(m, 20, 1));
  for (int i = 0; i < p.rows(); ++i) EXPECT_NEAR(p.row(i).sum(), 1.0, 1e-12);
}

TEST(GaussianMixture, RejectsBadInput) {
  GaussianMixtureOptions options;
  options.num_components = 5;
  EXPECT_THROW(FitGaussianMixture(Eigen::MatrixXd::Zero(3, 2), options), Error);
  Eigen::MatrixXd nan = Eigen::MatrixXd::Zero(10, 2);
  nan(3, 1) = std::nan("");
  EXPECT_THROW(FitGaussianMixture(nan, options), Error);
  options.num_components = 0;
  EXPECT_THROW(options.Check(), Error);
  GaussianMixture bad = ThreeBlobs();
  bad.components[1].covariance(0, 0) = -1;
  EXPECT_THROW(bad.Validate(), Error);
}

TEST(KLDivergence, KnownValues) {
  // 1-D: KL(N(0,1) || N(1,1)) = 0.5; KL(N(0,1) || N(0,4)) = 0.5 (1/4 - 1 + ln 4).
  EXPECT_NEAR(KLDivergence(MakeGaussian({0}, {1}), MakeGaussian({1}, {1})), 0.5, 1e-12);
  EXPECT_NEAR(KLDivergence(MakeGaussian({0}, {1}), MakeGaussian({0}, {4})), 0.5 * (0.25 - 1 + std::log(4.0)), 1e-12);
  // 2-D diagonal: sum of the 1-D terms. f = N((0,0), diag(1,2)), g = N((1,2), diag(2,1)):
  // 0.5 [(1/2 + 2) + (1/2 + 4) - 2 + ln(2/2)] = 2.5.
  EXPECT_NEAR(KLDivergence(MakeGaussian({0, 0}, {1, 0, 0, 2}), MakeGaussian({1, 2}, {2, 0, 0, 1})), 2.5, 1e-12);
  EXPECT_NEAR(KLDivergence(MakeGaussian({3, 1}, {1, 0.5, 0.5, 2}), MakeGaussian({3, 1}, {1, 0.5, 0.5, 2})), 0, 1e-12);
}

TEST(KLDivergence, GoldbergerOnSingleGaussiansIsTheGaussianKL) {
  GaussianMixture f, g;
  f.weights = {1.0};
  g.weights = {1.0};
  f.components = {MakeGaussian({0, 1}, {2, 0.3, 0.3, 1})};
  g.components = {MakeGaussian({1, -1}, {1, -0.2, -0.2, 3})};
  EXPECT_NEAR(GoldbergerKL(f, g), KLDivergence(f.components[0], g.components[0]), 1e-12);
  // A mixture of well-separated components against itself: 0.
  EXPECT_NEAR(GoldbergerKL(ThreeBlobs(), ThreeBlobs()), 0.0, 1e-9);
  // Matching picks the nearest component: a Gaussian against a two-component mixture that contains it
  // with weight w costs ln(1/w).
  GaussianMixture h;
  h.weights = {0.25, 0.75};
  h.components = {f.components[0], MakeGaussian({100, 100}, {1, 0, 0, 1})};
  EXPECT_NEAR(GoldbergerKL(f, h), std::log(4.0), 1e-12);
}

}  // namespace
}  // namespace orchard
