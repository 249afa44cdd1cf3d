#include "maps/coverage.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "maps/simd_clones.h"

namespace sage::maps {

double ForgettingDecay(double age_s, double forgetting_time_s) {
  return std::isfinite(forgetting_time_s) ? std::exp(-std::max(0.0, age_s) / forgetting_time_s) : 1.0;
}

CoverageAccumulator::CoverageAccumulator(int size, double forgetting_time_s)
    : forgetting_time_s_(forgetting_time_s), sums_(Eigen::VectorXd::Zero(size)) {
  if (!(forgetting_time_s > 0.0)) throw std::invalid_argument("CoverageAccumulator: forgetting time must be > 0");
}

void CoverageAccumulator::Add(const Eigen::VectorXd& f, double dt_s) {
  if (dt_s <= 0.0) return;
  if (std::isfinite(forgetting_time_s_)) {
    // Exponential kernel g(s) = exp(-s/T): the history decays by exp(-dt/T) each step, so after
    // a risk change the old coverage stops dominating within a few T.
    const double decay = std::exp(-dt_s / forgetting_time_s_);
    sums_ *= decay;
    time_s_ *= decay;
  }
  sums_.noalias() += dt_s * f;
  time_s_ += dt_s;
}

SAGE_AVX2_CLONES void CoverageAccumulator::AddOuterProduct(std::span<const double> x, std::span<const double> y, double dt_s) {
  const auto rows = static_cast<Eigen::Index>(x.size()), cols = static_cast<Eigen::Index>(y.size());
  if (rows * cols != sums_.size()) throw std::invalid_argument("CoverageAccumulator::AddOuterProduct: wrong size");
  if (dt_s <= 0.0) return;
  // S_{ij} <- decay S_{ij} + (dt x_i) y_j; the decay multiply is skipped without forgetting, as
  // in Add. Plain loops over contiguous rows: the compiler vectorises them (each element its own:
  // the AVX2 clone gives the same bits, maps/simd_clones.h).
  const bool forgets = std::isfinite(forgetting_time_s_);
  const double decay = forgets ? std::exp(-dt_s / forgetting_time_s_) : 1.0;
  double* s = sums_.data();
  for (Eigen::Index i = 0; i < rows; ++i) {
    const double dt_x = dt_s * x[i];
    double* row = s + i * cols;
    if (forgets) {
      for (Eigen::Index j = 0; j < cols; ++j) row[j] = decay * row[j] + dt_x * y[j];
    } else {
      for (Eigen::Index j = 0; j < cols; ++j) row[j] += dt_x * y[j];
    }
  }
  time_s_ = time_s_ * decay + dt_s;
}

void CoverageAccumulator::Reset() {
  sums_.setZero();
  time_s_ = 0.0;
}

void CoverageAccumulator::Restore(const Eigen::VectorXd& sums, double time_s) {
  if (sums.size() != sums_.size() || !sums.allFinite() || !(time_s >= 0.0)) {
    throw std::invalid_argument("CoverageAccumulator::Restore: wrong size or non-finite coverage");
  }
  sums_ = sums;
  time_s_ = time_s;
}

FleetCoverage SumFleetCoverage(const std::map<int, const CoverageReport*>& reports, double time_s, int size,
                               double forgetting_time_s) {
  FleetCoverage fleet;
  fleet.time_s = time_s;
  fleet.sums = Eigen::VectorXd::Zero(size);
  for (const auto& [id, report] : reports) {
    const double decay = ForgettingDecay(time_s - report->stamp_s, forgetting_time_s);
    fleet.sums.noalias() += decay * report->sums;
    fleet.kernel_time_s += decay * report->kernel_time_s;
    fleet.accounted_seq[id] = report->seq;
  }
  return fleet;
}

Coverage OthersCoverage(const FleetCoverage& fleet, const CoverageReport* own, double at_s, double forgetting_time_s) {
  Coverage others{fleet.sums, fleet.kernel_time_s};
  if (own != nullptr) {
    // The report as the sum holds it: aged from its stamp to the sum's time.
    const double decay = ForgettingDecay(fleet.time_s - own->stamp_s, forgetting_time_s);
    others.sums.noalias() -= decay * own->sums;
    others.kernel_time_s -= decay * own->kernel_time_s;
  }
  const double age = ForgettingDecay(at_s - fleet.time_s, forgetting_time_s);
  others.sums *= age;
  others.kernel_time_s = std::max(0.0, others.kernel_time_s * age);
  return others;
}

}  // namespace sage::maps
