// Gaussian mixtures with full covariances: expectation-maximisation in Eigen
// (deterministic k-means++ initialisation from a seed), model-selection
// criteria (BIC, AIC), and KL divergences between Gaussians (closed form) and
// between mixtures (Goldberger's matched-bound approximation). Used for the
// colour classes of the GMM detector and by the GMM counter.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace orchard {

struct Gaussian {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

struct GaussianMixture {
  std::vector<double> weights;  // sum to 1
  std::vector<Gaussian> components;

  int NumComponents() const { return static_cast<int>(components.size()); }
  int Dim() const { return components.empty() ? 0 : static_cast<int>(components[0].mean.size()); }
  // Number of free parameters: (K-1) weights + K*D means + K*D(D+1)/2 covariances.
  int NumParameters() const;
  // Per-sample log densities log p(x_i) of the rows of `samples` (N x D).
  Eigen::VectorXd LogDensity(const Eigen::MatrixXd& samples) const;
  // Posteriors (N x K) of the components for the rows of `samples`.
  Eigen::MatrixXd Posteriors(const Eigen::MatrixXd& samples) const;
  // Throws orchard::Error when weights/shapes are inconsistent or a covariance
  // is not positive definite (e.g. a corrupt model file).
  void Validate() const;
};

struct GaussianMixtureOptions {
  // Number of mixture components K.
  int num_components = 25;
  // EM stops after this many iterations...
  int max_iterations = 300;
  // ... or when the mean per-sample log-likelihood improves by less than this.
  double tolerance = 1e-6;
  // Added to every covariance diagonal (in squared data units) so that a
  // component collapsing on a few identical samples stays invertible.
  double regularization = 1e-3;
  // Seed of the k-means++ initialisation: same data + same seed = same fit.
  std::uint64_t seed = 0;

  void Check() const;
};

struct GaussianMixtureFit {
  GaussianMixture mixture;
  double log_likelihood = 0;  // total over samples
  int num_samples = 0;
  int iterations = 0;
  bool converged = false;

  // Bayesian information criterion -2 LL + p ln N (lower is better).
  double Bic() const;
  // Akaike information criterion -2 LL + 2 p (lower is better).
  double Aic() const;
};

// Fits a mixture to the rows of `samples` (N x D). Throws orchard::Error when
// there are fewer samples than components or the data are not finite.
GaussianMixtureFit FitGaussianMixture(const Eigen::MatrixXd& samples,
                                      const GaussianMixtureOptions& options);

// KL(f || g) between two Gaussians, closed form:
// 0.5 [tr(Sg^-1 Sf) + (mg-mf)' Sg^-1 (mg-mf) - D + ln(det Sg / det Sf)].
double KLDivergence(const Gaussian& f, const Gaussian& g);

// Goldberger et al. (2003) matched-bound approximation of KL(f || g) between
// mixtures: sum_a pi_a [KL(f_a || g_m(a)) + ln(pi_a / w_m(a))] where
// m(a) = argmin_b KL(f_a || g_b) - ln w_b. Exact for single Gaussians.
double GoldbergerKL(const GaussianMixture& f, const GaussianMixture& g);

}  // namespace orchard
