#include "maps/risk_field.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/LU>

namespace sage::maps {

RiskField::RiskField(const SpectralBasis& basis, std::vector<GaussianComponent> components)
    : components_(std::move(components)) {
  if (components_.empty()) throw std::invalid_argument("RiskField: needs at least one component");
  per_component_.resize(basis.size(), component_count());
  for (int i = 0; i < component_count(); ++i) per_component_.col(i) = GaussianCoefficients(basis, components_[i]);
  raw_weights_ = Eigen::VectorXd::Ones(component_count());
  Recompute();
}

Eigen::VectorXd RiskField::GaussianCoefficients(const SpectralBasis& basis, const GaussianComponent& g) {
  // The characteristic function of N(mu, Sigma) at q is exp(i q.mu - q^T Sigma q / 2); the
  // product of cosines splits into the two sign patterns (kappa1, +-kappa2):
  //   phi_k = (1/h_k) (1/2) sum_{s=+-1} cos(kappa1 mu1 + s kappa2 mu2) exp(-q_s^T Sigma q_s / 2).
  // This integrates over the whole plane, i.e. it is exact for the Gaussian mirrored into the box.
  const int order = basis.order();
  Eigen::VectorXd phi(basis.size());
  const double s11 = g.covariance_m2(0, 0);
  const double s12 = 0.5 * (g.covariance_m2(0, 1) + g.covariance_m2(1, 0));
  const double s22 = g.covariance_m2(1, 1);
  for (int k1 = 0; k1 < order; ++k1) {
    const double a = basis.kappa_x()[k1];
    for (int k2 = 0; k2 < order; ++k2) {
      const double b = basis.kappa_y()[k2];
      const double quad_diag = a * a * s11 + b * b * s22;
      const double plus = std::cos(a * g.mean_m.x() + b * g.mean_m.y()) * std::exp(-0.5 * (quad_diag + 2 * a * b * s12));
      const double minus = std::cos(a * g.mean_m.x() - b * g.mean_m.y()) * std::exp(-0.5 * (quad_diag - 2 * a * b * s12));
      const int i = SpectralBasis::Index(k1, k2, order);
      phi[i] = 0.5 * (plus + minus) / basis.normalizers()[i];
    }
  }
  return phi;
}

void RiskField::SetWeights(const Eigen::VectorXd& weights) {
  if (weights.size() != component_count()) throw std::invalid_argument("RiskField::SetWeights: wrong size");
  if ((weights.array() < 0.0).any() || !(weights.sum() > 0.0) || !weights.allFinite()) {
    throw std::invalid_argument("RiskField::SetWeights: weights must be finite, >= 0 and not all zero");
  }
  raw_weights_ = weights;
  Recompute();
}

void RiskField::SetWeight(int component, double weight) {
  if (component < 0 || component >= component_count()) throw std::out_of_range("RiskField::SetWeight: no such component");
  Eigen::VectorXd w = raw_weights_;
  w[component] = weight;
  SetWeights(w);
}

void RiskField::Recompute() {
  weights_ = raw_weights_ / raw_weights_.sum();
  coefficients_.noalias() = per_component_ * weights_;  // phi_k is linear in the weights: O(M K^2)
}

double RiskField::Density(const Eigen::Vector2d& x) const {
  double density = 0.0;
  for (int i = 0; i < component_count(); ++i) {
    const Eigen::Matrix2d& cov = components_[i].covariance_m2;
    const Eigen::Vector2d d = x - components_[i].mean_m;
    const double det = cov.determinant();
    const double mahalanobis = d.dot(cov.inverse() * d);
    density += weights_[i] * std::exp(-0.5 * mahalanobis) / (2.0 * std::numbers::pi * std::sqrt(det));
  }
  return density;
}

}  // namespace sage::maps
