#include "agents/ergodic_controller.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "maps/prefetch.h"
#include "maps/simd_clones.h"

namespace sage::agents {

Eigen::Vector2d TurnToward(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double max_angle_rad) {
  const double angle = std::atan2(from.x() * to.y() - from.y() * to.x(), from.dot(to));
  if (std::abs(angle) <= max_angle_rad) return to;
  const bool reversal = std::abs(angle) > M_PI - 1e-9;
  const double step = angle < 0.0 && !reversal ? -max_angle_rad : max_angle_rad;
  const double c = std::cos(step), s = std::sin(step);
  return {c * from.x() - s * from.y(), s * from.x() + c * from.y()};
}

ErgodicController::ErgodicController(const maps::SpectralBasis& basis, double speed_mps, double forgetting_time_s,
                                     double min_turn_radius_m)
    : basis_(basis),
      speed_mps_(speed_mps),
      max_turn_rate_radps_(min_turn_radius_m > 0.0 ? speed_mps / min_turn_radius_m
                                                   : std::numeric_limits<double>::infinity()),
      coverage_(basis.size(), forgetting_time_s),
      target_(Eigen::VectorXd::Zero(basis.size())),
      lambda_(basis.weights().data()) {
  if (!(speed_mps > 0.0)) throw std::invalid_argument("ErgodicController: speed must be > 0");
  if (!(min_turn_radius_m >= 0.0) || !std::isfinite(min_turn_radius_m)) {
    throw std::invalid_argument("ErgodicController: minimum turning radius must be finite and >= 0");
  }
}

void ErgodicController::SetTarget(const Eigen::VectorXd& phi_k) {
  if (phi_k.size() != basis_.size()) throw std::invalid_argument("ErgodicController::SetTarget: wrong size");
  target_ = phi_k;
}

void ErgodicController::SetFleetCoverage(const Eigen::VectorXd& sums, double time_s) {
  if (sums.size() != basis_.size()) throw std::invalid_argument("ErgodicController::SetFleetCoverage: wrong size");
  fleet_sums_ = sums;
  fleet_time_s_ = time_s;
  fleet_zero_ = (sums.array() == 0.0).all();
}

void ErgodicController::ClearFleetCoverage() {
  if (!fleet_zero_) fleet_sums_.setZero();
  fleet_time_s_ = 0.0;
  fleet_zero_ = true;
}

Eigen::VectorXd ErgodicController::CoverageError() const {
  const double total_time = coverage_.time_s() + fleet_time_s_;
  if (total_time <= 0.0) return -target_;
  if (fleet_zero_) return coverage_.sums() / total_time - target_;
  return (coverage_.sums() + fleet_sums_) / total_time - target_;
}

void ErgodicController::Prefetch() const {
  const std::size_t bytes = sizeof(double) * static_cast<std::size_t>(basis_.size());
  maps::PrefetchBytes(coverage_.sums().data(), bytes);
  maps::PrefetchBytes(target_.data(), bytes);
  if (!fleet_zero_) maps::PrefetchBytes(fleet_sums_.data(), bytes);
  basis_.Prefetch();
}

double ErgodicController::Metric() const { return basis_.Metric(CoverageError()); }

double ErgodicController::TargetDensity(const Eigen::Vector2d& x_m) const {
  if (target_.size() != basis_.size()) return 0.0;
  // Asked for every valve in a looking vehicle's reach every cycle: no allocation per call.
  thread_local Eigen::VectorXd f;
  basis_.Evaluate(x_m, f);
  return target_.dot(f);
}

ErgodicController::Densities ErgodicController::DensitiesAt(const Eigen::Vector2d& x_m) const {
  if (target_.size() != basis_.size()) return {};
  thread_local Eigen::VectorXd f;
  basis_.Evaluate(x_m, f);
  Densities d;
  d.target = target_.dot(f);
  const double total_time = coverage_.time_s() + fleet_time_s_;
  if (total_time > 0.0) {
    d.covered = coverage_.sums().dot(f);
    if (!fleet_zero_) d.covered += fleet_sums_.dot(f);
    d.covered /= total_time;
  }
  return d;
}

SAGE_AVX2_CLONES Eigen::Vector2d ErgodicController::DeficitGradient(const maps::SpectralBasis::Trigonometry& t) const {
  // With b_k = Lambda_k / h_k (c_k - phi_k) and grad F_k = -(1/h_k) (kx_k1 sin_x[k1] cos_y[k2],
  // ky_k2 cos_x[k1] sin_y[k2]) (kx, ky: the wave numbers kappa),
  //   B_x = -sum_k2 cos_y[k2] col_x[k2],            col_x[k2] = sum_k1 kx_k1 sin_x[k1] b_k,
  //   B_y = -sum_k2 ky_k2 sin_y[k2] col_y[k2],      col_y[k2] = sum_k1 cos_x[k1] b_k.
  // The column sums run along k1, so the inner loop over k2 carries no reduction and the compiler
  // vectorises it without reassociating (no -ffast-math), four lanes in the AVX2 clone with the
  // same bits (maps/simd_clones.h); b_k is formed where it is used.
  const int order = basis_.order();
  std::array<double, maps::SpectralBasis::kMaxOrder> col_x, col_y;
  std::fill_n(col_x.begin(), order, 0.0);
  std::fill_n(col_y.begin(), order, 0.0);
  const double* kappa_x = basis_.kappa_x().data();
  const double* lambda = lambda_;
  const double* phi = target_.data();
  auto accumulate = [&](auto deficit) {  // deficit(k) = c_k - phi_k
    for (int k1 = 0; k1 < order; ++k1) {
      const int row = k1 * order;
      const double dsin_x = kappa_x[k1] * t.sin_x[k1];
      const double cos_x = t.cos_x[k1];
      // Lambda_k / h_k as the product the basis' tables would hold: the same bits.
      const double b0 = (lambda[row] * basis_.InverseNormalizer(k1, 0)) * deficit(row);
      col_x[0] += dsin_x * b0;
      col_y[0] += cos_x * b0;
      const double inv_h = basis_.InverseNormalizer(k1, 1);
      for (int k2 = 1; k2 < order; ++k2) {
        const double b = (lambda[row + k2] * inv_h) * deficit(row + k2);
        col_x[k2] += dsin_x * b;
        col_y[k2] += cos_x * b;
      }
    }
  };
  const double total_time = coverage_.time_s() + fleet_time_s_;
  if (total_time > 0.0) {
    // c_k = (own S_k + fleet S_k) / (own W + fleet W).
    const double inv_time = 1.0 / total_time;
    const double* own = coverage_.sums().data();
    const double* fleet = fleet_sums_.data();
    if (fleet_zero_) {
      accumulate([&](int k) { return own[k] * inv_time - phi[k]; });
    } else {
      accumulate([&](int k) { return (own[k] + fleet[k]) * inv_time - phi[k]; });
    }
  } else {
    accumulate([&](int k) { return -phi[k]; });  // no coverage yet: c = 0
  }
  const double* kappa_y = basis_.kappa_y().data();
  double bx = 0.0, by = 0.0;
  for (int k2 = 0; k2 < order; ++k2) {
    bx -= t.cos_y[k2] * col_x[k2];
    by -= kappa_y[k2] * t.sin_y[k2] * col_y[k2];
  }
  return {bx, by};
}

Eigen::Vector2d ErgodicController::Command(const VehicleState& state, double time_s) {
  // Rectangle rule over the control period: the position at this cycle stands for the interval
  // since the last one. At 10 Hz and 0.7 m/s that is a 7 cm stride, far below the finest
  // wavelength resolved at K = 10 on a 7 m box (1.4 m).
  const bool integrates = !std::isnan(last_time_s_);
  const double dt = integrates ? std::max(0.0, time_s - last_time_s_) : 0.0;
  last_time_s_ = time_s;
  // One set of cos/sin tables serves F_k (the coverage update) and grad F_k (the law).
  maps::SpectralBasis::Trigonometry t;
  basis_.EvaluateTrigonometry(state.position_m, t);
  if (integrates) {
    // F_k(x) = (cos_x[k1] / h_x[k1]) (cos_y[k2] / h_y[k2]): the coverage update is an outer product.
    const int order = basis_.order();
    std::array<double, maps::SpectralBasis::kMaxOrder> f_x, f_y;
    for (int k = 0; k < order; ++k) {
      f_x[k] = t.cos_x[k] * basis_.inverse_normalizers_x()[k];
      f_y[k] = t.cos_y[k] * basis_.inverse_normalizers_y()[k];
    }
    const auto n = static_cast<std::size_t>(order);
    coverage_.AddOuterProduct({f_x.data(), n}, {f_y.data(), n}, dt);
  }
  // B = sum_k Lambda_k (c_k - phi_k) grad F_k(x);  u = -u_max B / |B|.
  const Eigen::Vector2d b = DeficitGradient(t);
  const double norm = b.norm();
  if (norm > 1e-12) {  // at a stationary point keep the last heading
    const Eigen::Vector2d wanted = -b / norm;
    const bool limited = has_direction_ && std::isfinite(max_turn_rate_radps_);
    last_direction_ = limited ? TurnToward(last_direction_, wanted, max_turn_rate_radps_ * dt) : wanted;
  }
  has_direction_ = true;  // whatever was commanded (even the initial heading) is where turns start from
  return speed_mps_ * last_direction_;
}

}  // namespace sage::agents
