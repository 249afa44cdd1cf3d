#include "agents/ergodic_controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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
      fleet_sums_(Eigen::VectorXd::Zero(basis.size())),
      f_(basis.size()),
      weighted_(Eigen::VectorXd::Zero(basis.size())) {
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
}

Eigen::VectorXd ErgodicController::CoverageError() const {
  const double total_time = coverage_.time_s() + fleet_time_s_;
  if (total_time <= 0.0) return -target_;
  return (coverage_.sums() + fleet_sums_) / total_time - target_;
}

double ErgodicController::Metric() const { return basis_.Metric(CoverageError()); }

Eigen::Vector2d ErgodicController::Command(const VehicleState& state, double time_s) {
  // Rectangle rule over the control period: the position at this cycle stands for the interval
  // since the last one. At 10 Hz and 0.7 m/s that is a 7 cm stride, far below the finest
  // wavelength resolved at K = 10 on a 7 m box (1.4 m).
  const double dt = std::isnan(last_time_s_) ? 0.0 : std::max(0.0, time_s - last_time_s_);
  if (!std::isnan(last_time_s_)) {
    basis_.Evaluate(state.position_m, f_);
    coverage_.Add(f_, dt);
  }
  last_time_s_ = time_s;

  const double total_time = coverage_.time_s() + fleet_time_s_;
  if (total_time > 0.0) {
    weighted_ = basis_.weights().cwiseProduct((coverage_.sums() + fleet_sums_) / total_time - target_);
  } else {
    weighted_ = -basis_.weights().cwiseProduct(target_);
  }
  // B = sum_k Lambda_k (c_k - phi_k) grad F_k(x);  u = -u_max B / |B|.
  const Eigen::Vector2d b = basis_.GradientOfSum(state.position_m, weighted_);
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
