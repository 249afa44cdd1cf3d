#pragma once
// Coverage algebra shared by both sides of a fleet (Mathew & Mezic's multi-agent SMC).
// A vehicle's running coverage is S_k(t) = integral_0^t F_k(x(tau)) g(t - tau) dtau with kernel
// time W(t) = integral_0^t g, g(s) = exp(-s / T) (g = 1 for T = infinity: the paper's average).
// Because both are linear in the path and decay by the same factor, a report of (S, W) stamped at
// time s stands for exp(-(t - s) / T) (S, W) at any later t, and the fleet's coverage is the sum
// of its vehicles' aged reports. The server sums them; each vehicle takes its own report out of
// that sum to get "the rest of the fleet", exactly, by the report's sequence number.
#include <cstdint>
#include <limits>
#include <map>
#include <span>

#include <Eigen/Core>

namespace sage::maps {

/// exp(-max(0, age) / T); 1 for T = infinity (no forgetting).
double ForgettingDecay(double age_s, double forgetting_time_s);

/// Running, optionally forgetting, integral of the basis along a path.
class CoverageAccumulator {
 public:
  /// size: number of coefficients; forgetting_time_s: T (> 0, infinity = none).
  CoverageAccumulator(int size, double forgetting_time_s = std::numeric_limits<double>::infinity());

  /// Decays the history by exp(-dt/T) and adds f * dt (f = F_k at the current position).
  void Add(const Eigen::VectorXd& f, double dt_s);
  /// Add(f, dt) for a separable f, without forming it: f_{i n + j} = x_i y_j with n = y.size()
  /// and x.size() * n = size(). For the cosine basis x_i = cos(k1 pi x / L1) / h_x[k1] and
  /// y_j = cos(k2 pi y / L2) / h_y[k2] (SpectralBasis::inverse_normalizers_x/y). One pass and one
  /// multiply per coefficient; agrees with Add to rounding (dt f_k is formed as (dt x_i) y_j).
  void AddOuterProduct(std::span<const double> x, std::span<const double> y, double dt_s);
  const Eigen::VectorXd& sums() const { return sums_; }
  double time_s() const { return time_s_; }  ///< W(t): integral of the kernel (s)
  double forgetting_time_s() const { return forgetting_time_s_; }
  void Reset();
  /// Starts from given sums and kernel time (a resumed vehicle's last accounted coverage).
  void Restore(const Eigen::VectorXd& sums, double time_s);

 private:
  double forgetting_time_s_;
  Eigen::VectorXd sums_;
  double time_s_ = 0.0;
};

/// One vehicle's coverage as it reported it: running sums and kernel time as of mission time
/// stamp_s, numbered by seq (1, 2, ... per vehicle) so late and duplicated reports are known.
struct CoverageReport {
  std::uint64_t seq = 0;
  double stamp_s = 0.0;
  double kernel_time_s = 0.0;
  Eigen::VectorXd sums;
};

/// Coverage sums and kernel time, as one value.
struct Coverage {
  Eigen::VectorXd sums;
  double kernel_time_s = 0.0;
};

/// The fleet's coverage as the server accounts it at time_s: the sum of every vehicle's latest
/// report aged to time_s (lost vehicles' too: what they covered stays covered, fading with the
/// forgetting window), and which report of each vehicle is inside.
struct FleetCoverage {
  double time_s = 0.0;
  Eigen::VectorXd sums;
  double kernel_time_s = 0.0;
  std::map<int, std::uint64_t> accounted_seq;  ///< vehicle id -> seq of the report included
};

/// Sums the vehicles' latest reports (vehicle id -> report), each aged to `time_s`.
FleetCoverage SumFleetCoverage(const std::map<int, const CoverageReport*>& reports, double time_s, int size,
                               double forgetting_time_s);

/// The report of `seq` among a vehicle's recent ones, or nullptr.
template <typename Reports>
const CoverageReport* FindReport(const Reports& reports, std::uint64_t seq) {
  for (const CoverageReport& r : reports)
    if (r.seq == seq) return &r;
  return nullptr;
}

/// The rest of the fleet's coverage as one vehicle sees it, aged to `at_s`: the fleet's sum less
/// `own`, the vehicle's report that the sum holds (nullptr if it holds none). Kernel time is
/// clamped at 0 against rounding.
Coverage OthersCoverage(const FleetCoverage& fleet, const CoverageReport* own, double at_s, double forgetting_time_s);

}  // namespace sage::maps
