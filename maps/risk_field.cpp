#include "maps/risk_field.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "maps/in_two_halves.h"
#include "maps/seabed_map.h"

namespace sage::maps {
namespace {

// From this many components a field's coefficients and their blocked water are computed on two
// threads (the generated 10,000-vehicle field's 35,000 valves at K = 64: seconds of its set-up),
// each component's column by itself, so the field is the same to the bit either way.
constexpr std::size_t kTwoThreadsFrom = 2000;

// Closed forms for a symmetric 2x2 covariance [[a, b], [b, d]]: its largest eigenvalue
// (a + d)/2 + sqrt(((a - d)/2)^2 + b^2), determinant and inverse. Eigen's general EigenSolver
// cost seven seconds of compile time for this one number.
double LargestEigenvalue(const Eigen::Matrix2d& m) {
  const double b = 0.5 * (m(0, 1) + m(1, 0));
  return 0.5 * (m(0, 0) + m(1, 1)) + std::hypot(0.5 * (m(0, 0) - m(1, 1)), b);
}
double Determinant(const Eigen::Matrix2d& m) { return m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0); }
Eigen::Matrix2d Inverse(const Eigen::Matrix2d& m) {
  Eigen::Matrix2d inverse;
  inverse << m(1, 1), -m(0, 1), -m(1, 0), m(0, 0);
  return inverse / Determinant(m);
}

}  // namespace

GaussianComponent NarrowedTo(const GaussianComponent& valve, double max_sigma_m) {
  const double widest = LargestEigenvalue(valve.covariance_m2);
  if (!(widest > max_sigma_m * max_sigma_m)) return valve;
  return {valve.mean_m, valve.covariance_m2 * (max_sigma_m * max_sigma_m / widest)};
}

RiskField::RiskField(const SpectralBasis& basis, std::vector<GaussianComponent> components)
    : components_(std::move(components)) {
  if (components_.empty()) throw std::invalid_argument("RiskField: needs at least one component");
  per_component_.resize(basis.size(), component_count());
  InTwoHalves(components_.size(), kTwoThreadsFrom, [&](std::size_t begin, std::size_t end) {
    for (auto i = static_cast<int>(begin); i < static_cast<int>(end); ++i) {
      per_component_.col(i) = GaussianCoefficients(basis, components_[i]);
    }
  });
  raw_weights_ = Eigen::VectorXd::Ones(component_count());
  blocked_mass_ = Eigen::VectorXd::Zero(component_count());
  Recompute();
}

RiskField RiskField::ForScenario(const Scenario& scenario, const SpectralBasis& basis) {
  return ForScenario(scenario, basis, SeabedMap::OperatingSlice(scenario));
}

RiskField RiskField::ForScenario(const Scenario& scenario, const SpectralBasis& basis, const OccupancyGrid& obstacles) {
  return ForValves(scenario, basis, obstacles.Inflated(kVehicleClearance_m));
}

RiskField RiskField::ForValves(const Scenario& scenario, const SpectralBasis& basis, const OccupancyGrid& blocked) {
  std::vector<GaussianComponent> components;
  for (const Valve& valve : scenario.AllValves()) components.push_back({valve.position_m, valve.covariance_m2});
  RiskField field(basis, std::move(components));
  field.ExcludeBlocked(basis, blocked);
  return field;
}

void RiskField::ExcludeBlocked(const SpectralBasis& basis, const OccupancyGrid& blocked, const Eigen::Vector2d& origin_m) {
  const double r = blocked.resolution_m();
  const double area = r * r;
  InTwoHalves(components_.size(), kTwoThreadsFrom, [&](std::size_t begin, std::size_t end) {
    ExcludeBlocked(basis, blocked, origin_m, static_cast<int>(begin), static_cast<int>(end), area);
  });
  Recompute();
}

void RiskField::ExcludeBlocked(const SpectralBasis& basis, const OccupancyGrid& blocked, const Eigen::Vector2d& origin_m,
                               int begin, int end, double cell_area_m2) {
  const double area = cell_area_m2;
  Eigen::VectorXd f;
  for (int i = begin; i < end; ++i) {
    const GaussianComponent& g = components_[i];
    const Eigen::Matrix2d inverse = Inverse(g.covariance_m2);
    const double norm = 1.0 / (2.0 * std::numbers::pi * std::sqrt(Determinant(g.covariance_m2)));
    const double reach = 5.0 * std::sqrt(LargestEigenvalue(g.covariance_m2));
    // The components and the basis are in the box's frame; the grid is in the workspace's.
    const Eigen::Vector2i lo = blocked.CellOf(origin_m + g.mean_m - Eigen::Vector2d::Constant(reach));
    const Eigen::Vector2i hi = blocked.CellOf(origin_m + g.mean_m + Eigen::Vector2d::Constant(reach));
    double mass = 0.0;
    Eigen::VectorXd removed = Eigen::VectorXd::Zero(basis.size());
    for (int a = lo.x(); a <= hi.x(); ++a) {
      for (int b = lo.y(); b <= hi.y(); ++b) {
        if (!blocked.Occupied(a, b)) continue;
        const Eigen::Vector2d x = blocked.CenterOf({a, b}) - origin_m;
        const Eigen::Vector2d d = x - g.mean_m;
        const double p = norm * std::exp(-0.5 * d.dot(inverse * d)) * area;
        if (p == 0.0) continue;
        basis.Evaluate(x, f);
        removed += p * f;
        mass += p;
      }
    }
    mass = std::min(mass, 0.99);  // a valve inside a structure is rejected on load; stay finite anyway
    per_component_.col(i) = (per_component_.col(i) - removed) / (1.0 - mass);
    blocked_mass_[i] = mass;
  }
}

Eigen::VectorXd RiskField::GaussianCoefficients(const SpectralBasis& basis, const GaussianComponent& g) {
  // The characteristic function of N(mu, Sigma) at q is exp(i q.mu - q^T Sigma q / 2); the
  // product of cosines splits into the two sign patterns (kappa1, +-kappa2):
  //   phi_k = (1/h_k) (1/2) sum_{s=+-1} cos(kappa1 mu1 + s kappa2 mu2) exp(-q_s^T Sigma q_s / 2).
  // This integrates over the whole plane, i.e. it is exact for the Gaussian mirrored into the box.
  // With cos(A +- B) = cos A cos B -+ sin A sin B the cosines come from 2K per-axis values
  // rather than 2K^2 calls, and exp(-q^T Sigma q / 2) = e_x(kappa1) e_y(kappa2) exp(-+kappa1
  // kappa2 sigma12); without correlation (every valve's covariance is diagonal) the two patterns
  // add to e_x e_y cos A cos B, which is separable: O(K) transcendental calls, not O(K^2). A
  // 10,000-vehicle field's 35,000 valves at K = 64 took ~3 s of cosines before the first cycle.
  const int order = basis.order();
  Eigen::VectorXd phi(basis.size());
  const double s11 = g.covariance_m2(0, 0);
  const double s12 = 0.5 * (g.covariance_m2(0, 1) + g.covariance_m2(1, 0));
  const double s22 = g.covariance_m2(1, 1);
  Eigen::ArrayXd cos_x(order), sin_x(order), exp_x(order), cos_y(order), sin_y(order), exp_y(order);
  for (int k = 0; k < order; ++k) {
    const double a = basis.kappa_x()[k], b = basis.kappa_y()[k];
    cos_x[k] = std::cos(a * g.mean_m.x()), sin_x[k] = std::sin(a * g.mean_m.x());
    cos_y[k] = std::cos(b * g.mean_m.y()), sin_y[k] = std::sin(b * g.mean_m.y());
    exp_x[k] = std::exp(-0.5 * a * a * s11), exp_y[k] = std::exp(-0.5 * b * b * s22);
  }
  for (int k1 = 0; k1 < order; ++k1) {
    const double a = basis.kappa_x()[k1];
    for (int k2 = 0; k2 < order; ++k2) {
      const int i = SpectralBasis::Index(k1, k2, order);
      const double cc = cos_x[k1] * cos_y[k2];
      if (s12 == 0.0) {
        phi[i] = exp_x[k1] * exp_y[k2] * cc / basis.Normalizer(k1, k2);
        continue;
      }
      // Correlated: each pattern's exponent whole (a product of factors could overflow where
      // the exponent cannot: |kappa1 kappa2 sigma12| <= q^T Sigma q / 2).
      const double b = basis.kappa_y()[k2], ss = sin_x[k1] * sin_y[k2];
      const double quad_diag = a * a * s11 + b * b * s22;
      const double plus = (cc - ss) * std::exp(-0.5 * (quad_diag + 2 * a * b * s12));
      const double minus = (cc + ss) * std::exp(-0.5 * (quad_diag - 2 * a * b * s12));
      phi[i] = 0.5 * (plus + minus) / basis.Normalizer(k1, k2);
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

Eigen::VectorXd RiskField::CoefficientsFor(const Eigen::VectorXd& weights) const {
  if (weights.size() != component_count() || !(weights.sum() > 0.0)) {
    throw std::invalid_argument("RiskField::CoefficientsFor: wrong size or all-zero weights");
  }
  return per_component_ * (weights / weights.sum());
}

void RiskField::Recompute() {
  weights_ = raw_weights_ / raw_weights_.sum();
  coefficients_stale_ = true;
}

const Eigen::VectorXd& RiskField::coefficients() const {
  if (coefficients_stale_) {
    coefficients_.noalias() = per_component_ * weights_;  // phi_k is linear in the weights: O(M K^2)
    coefficients_stale_ = false;
  }
  return coefficients_;
}

double RiskField::Density(const Eigen::Vector2d& x) const {
  double density = 0.0;
  for (int i = 0; i < component_count(); ++i) {
    const Eigen::Matrix2d& cov = components_[i].covariance_m2;
    const Eigen::Vector2d d = x - components_[i].mean_m;
    const double det = Determinant(cov);
    const double mahalanobis = d.dot(Inverse(cov) * d);
    density += weights_[i] * std::exp(-0.5 * mahalanobis) / (2.0 * std::numbers::pi * std::sqrt(det));
  }
  return density;
}

}  // namespace sage::maps
