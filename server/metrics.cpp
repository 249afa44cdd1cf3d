#include "server/metrics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "maps/risk_field.h"
#include "maps/spectral_basis.h"

namespace sage::server {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// True if the values are equal up to rounding: time-averaged equal weights (0.2 each) can differ
// in the last bit, and a correlation of rounding noise would be a made-up number.
bool IsConstant(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double scale = std::max({1.0, std::abs(*lo), std::abs(*hi)});
  return *hi - *lo <= 1e-12 * scale;
}

// The samples of the mission window [0, duration], sorted by time then vehicle.
std::vector<TrajectorySample> MissionSamples(const Trajectory& trajectory, double duration_s) {
  std::vector<TrajectorySample> samples;
  samples.reserve(trajectory.samples.size());
  for (const TrajectorySample& s : trajectory.samples) {
    if (s.time_s >= 0.0 && s.time_s <= duration_s) samples.push_back(s);
  }
  std::stable_sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.vehicle < b.vehicle;
  });
  return samples;
}

// How long each sample stands for (s): the time to the same vehicle's next sample. A vehicle's
// last sample has no successor, so it gets the median spacing (a log's typical period), or the
// control period if no vehicle has two samples. Clipped so no sample outlasts the mission.
std::vector<double> HoldTimes(const std::vector<TrajectorySample>& samples, double duration_s,
                              double fallback_period_s, int* vehicle_count) {
  std::vector<double> dt(samples.size(), kNaN);
  std::map<int, std::size_t> last_of_vehicle;
  std::vector<double> spacings;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    auto [it, first] = last_of_vehicle.try_emplace(samples[i].vehicle, i);
    if (!first) {
      dt[it->second] = samples[i].time_s - samples[it->second].time_s;
      if (dt[it->second] > 0.0) spacings.push_back(dt[it->second]);
      it->second = i;
    }
  }
  double median = fallback_period_s;
  if (!spacings.empty()) {
    const std::size_t mid = spacings.size() / 2;
    std::nth_element(spacings.begin(), spacings.begin() + mid, spacings.end());
    median = spacings[mid];
    if (spacings.size() % 2 == 0) {
      median = 0.5 * (median + *std::max_element(spacings.begin(), spacings.begin() + mid));
    }
  }
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (std::isnan(dt[i])) dt[i] = median;
    dt[i] = std::clamp(dt[i], 0.0, duration_s - samples[i].time_s);
  }
  *vehicle_count = static_cast<int>(last_of_vehicle.size());
  return dt;
}

// Each schedule entry's weights, checked and normalised to sum 1 (a raw schedule is accepted).
std::vector<Eigen::VectorXd> NormalisedSchedule(const std::vector<WeightChange>& schedule, int valves) {
  if (schedule.empty()) throw std::invalid_argument("ComputeMetrics: empty weight schedule");
  std::vector<Eigen::VectorXd> out;
  for (const WeightChange& change : schedule) {
    const Eigen::VectorXd& w = change.weights;
    if (w.size() != valves || (w.array() < 0.0).any() || !w.allFinite() || !(w.sum() > 0.0)) {
      throw std::invalid_argument("ComputeMetrics: weights at t = " + std::to_string(change.time_s) +
                                  " must be " + std::to_string(valves) +
                                  " finite values >= 0, not all zero");
    }
    out.push_back(w / w.sum());
  }
  return out;
}

// Index of the schedule entry in force at t, by WeightsAt's own rule.
std::size_t ScheduleIndex(const std::vector<WeightChange>& schedule, double time_s) {
  const Eigen::VectorXd* in_force = &WeightsAt(schedule, time_s);
  std::size_t i = 0;
  while (&schedule[i].weights != in_force) ++i;
  return i;
}

// (1/T) integral_0^T w(t) dt of the piecewise-constant schedule.
Eigen::VectorXd TimeAveragedWeights(const std::vector<WeightChange>& schedule,
                                    const std::vector<Eigen::VectorXd>& normalised, double duration_s) {
  std::vector<double> breaks = {0.0, duration_s};
  for (const WeightChange& change : schedule) {
    if (change.time_s > 0.0 && change.time_s < duration_s) breaks.push_back(change.time_s);
  }
  std::sort(breaks.begin(), breaks.end());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(normalised.front().size());
  for (std::size_t j = 0; j + 1 < breaks.size(); ++j) {
    sum += (breaks[j + 1] - breaks[j]) * normalised[ScheduleIndex(schedule, breaks[j])];
  }
  return sum / duration_s;
}

// The fleet's time-averaged coverage c_k(t) = sum_samples F_k(x) dt / sum dt against phi_k(t),
// every period and at the end. A sample still "running" at a checkpoint counts only up to it,
// so the curve does not depend on where the samples fall relative to the checkpoints.
void ErgodicMetrics(const std::vector<TrajectorySample>& samples, const std::vector<double>& dt,
                    const maps::Scenario& scenario, const std::vector<WeightChange>& schedule,
                    const std::vector<Eigen::VectorXd>& normalised, double duration_s,
                    double period_s, MissionMetrics& out) {
  const maps::SpectralBasis basis(scenario.workspace.width_m, scenario.workspace.height_m,
                                  scenario.ergodic.basis_order);
  // The same target the server steers on: the valves' risk where a vehicle can be.
  maps::RiskField field = maps::RiskField::ForScenario(scenario, basis);
  std::vector<Eigen::VectorXd> phi;
  for (const Eigen::VectorXd& w : normalised) {
    field.SetWeights(w);
    phi.push_back(field.coefficients());
  }

  struct Running {
    double end_s;
    Eigen::VectorXd f;
  };
  std::map<int, Running> last_sample;  // per vehicle, the latest sample added to the sums
  Eigen::VectorXd sum_f = Eigen::VectorXd::Zero(basis.size());
  double sum_dt = 0.0;
  Eigen::VectorXd f;
  std::size_t next = 0;
  const auto metric_at = [&](double t) {
    while (next < samples.size() && samples[next].time_s < t) {
      basis.Evaluate(samples[next].position_m, f);
      sum_f += dt[next] * f;
      sum_dt += dt[next];
      Running& running = last_sample[samples[next].vehicle];
      running.end_s = samples[next].time_s + dt[next];
      running.f = f;  // reuses the vector's storage after the first sample
      ++next;
    }
    Eigen::VectorXd covered = sum_f;
    double covered_dt = sum_dt;
    for (const auto& [vehicle, running] : last_sample) {
      const double beyond = running.end_s - t;
      if (beyond > 0.0) {
        covered -= beyond * running.f;
        covered_dt -= beyond;
      }
    }
    if (!(covered_dt > 0.0)) return kNaN;  // nothing observed yet
    return basis.Metric(covered / covered_dt - phi[ScheduleIndex(schedule, t)]);
  };

  // Checkpoints k * period strictly before the end (within rounding), then the end itself.
  for (int k = 1; k * period_s < duration_s * (1.0 - 1e-12); ++k) {
    const double value = metric_at(k * period_s);
    if (!std::isnan(value)) out.metric_over_time.push_back({k * period_s, value});
  }
  out.ergodic_metric = metric_at(duration_s);
  if (!std::isnan(out.ergodic_metric)) out.metric_over_time.push_back({duration_s, out.ergodic_metric});
}

}  // namespace

VisitTracker::VisitTracker(std::vector<Eigen::Vector2d> valves, double visit_radius_m,
                           double rearm_radius_m)
    : valves_(std::move(valves)),
      visit_radius_m_(visit_radius_m),
      rearm_radius_m_(rearm_radius_m),
      visit_times_(valves_.size()) {
  if (!(visit_radius_m_ > 0.0) || !(rearm_radius_m_ >= visit_radius_m_)) {
    throw std::invalid_argument("VisitTracker: need 0 < visit_radius <= rearm_radius");
  }
}

std::vector<int> VisitTracker::Update(int vehicle, const Eigen::Vector2d& position_m, double time_s) {
  if (vehicle < 0) throw std::invalid_argument("VisitTracker: vehicle id must be >= 0");
  if (static_cast<std::size_t>(vehicle) >= armed_.size()) {
    armed_.resize(vehicle + 1, std::vector<unsigned char>(valves_.size(), 1));
  }
  std::vector<int> visited;
  std::vector<unsigned char>& armed = armed_[vehicle];
  for (std::size_t i = 0; i < valves_.size(); ++i) {
    const double distance = (position_m - valves_[i]).norm();
    if (armed[i] && distance <= visit_radius_m_) {
      armed[i] = 0;
      visit_times_[i].push_back(time_s);
      visited.push_back(static_cast<int>(i));
    } else if (!armed[i] && distance > rearm_radius_m_) {
      armed[i] = 1;
    }
  }
  return visited;
}

void VisitTracker::Forget(int vehicle) {
  if (vehicle >= 0 && static_cast<std::size_t>(vehicle) < armed_.size()) {
    std::fill(armed_[vehicle].begin(), armed_[vehicle].end(), 1);
  }
}

double VisitTracker::LastVisit(int valve) const {
  const std::vector<double>& times = visit_times_.at(valve);
  return times.empty() ? -std::numeric_limits<double>::infinity() : times.back();
}

double PearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("PearsonCorrelation: sizes differ");
  if (a.size() < 2 || IsConstant(a) || IsConstant(b)) return kNaN;
  const double n = static_cast<double>(a.size());
  double mean_a = 0.0, mean_b = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    mean_a += a[i] / n;
    mean_b += b[i] / n;
  }
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ab += (a[i] - mean_a) * (b[i] - mean_b);
    aa += (a[i] - mean_a) * (a[i] - mean_a);
    bb += (b[i] - mean_b) * (b[i] - mean_b);
  }
  return std::clamp(ab / std::sqrt(aa * bb), -1.0, 1.0);
}

MissionMetrics ComputeMetrics(const Trajectory& trajectory, const maps::Scenario& scenario,
                              const std::vector<WeightChange>& weights, double duration_s,
                              const MetricsOptions& options) {
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) {
    throw std::invalid_argument("ComputeMetrics: duration_s must be finite and > 0");
  }
  // Bounded so a typo (1e-9 s) cannot ask for billions of metric evaluations.
  if (!(options.metric_sample_period_s > 0.0) || duration_s / options.metric_sample_period_s > 1e6) {
    throw std::invalid_argument("ComputeMetrics: metric_sample_period_s must be > 0 and >= duration / 1e6");
  }
  const std::vector<maps::Valve> valves = scenario.AllValves();
  if (valves.empty()) throw std::invalid_argument("ComputeMetrics: the scenario has no valves");
  const std::vector<Eigen::VectorXd> normalised =
      NormalisedSchedule(weights, static_cast<int>(valves.size()));

  MissionMetrics out;
  out.controller = options.controller;
  out.profile = options.profile;
  out.duration_s = duration_s;
  out.boundary_margin_m = options.boundary_margin_m;

  const std::vector<TrajectorySample> samples = MissionSamples(trajectory, duration_s);
  const double control_period_s = scenario.control_rate_hz > 0.0 ? 1.0 / scenario.control_rate_hz : 0.1;
  const std::vector<double> dt = HoldTimes(samples, duration_s, control_period_s, &out.vehicle_count);

  std::vector<Eigen::Vector2d> positions;
  for (const maps::Valve& valve : valves) positions.push_back(valve.position_m);
  VisitTracker tracker(positions, scenario.visit_radius_m, scenario.rearm_radius_m);
  std::vector<double> time_near(valves.size(), 0.0);
  const double width = scenario.workspace.width_m, height = scenario.workspace.height_m;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Eigen::Vector2d& p = samples[i].position_m;
    tracker.Update(samples[i].vehicle, p, samples[i].time_s);
    for (std::size_t v = 0; v < valves.size(); ++v) {
      if ((p - positions[v]).norm() <= scenario.visit_radius_m) time_near[v] += dt[i];
    }
    const double to_edge = std::min({p.x(), width - p.x(), p.y(), height - p.y()});
    if (to_edge < 0.0) {
      out.time_outside_s += dt[i];
    } else if (to_edge <= options.boundary_margin_m) {
      out.time_pinned_s += dt[i];
    }
  }

  const Eigen::VectorXd average_weights = TimeAveragedWeights(weights, normalised, duration_s);
  std::vector<double> visit_counts, weight_values;
  for (std::size_t v = 0; v < valves.size(); ++v) {
    ValveMetrics m;
    m.name = valves[v].name;
    m.weight = average_weights[v];
    m.visit_times_s = tracker.visit_times()[v];
    m.visits = static_cast<int>(m.visit_times_s.size());
    m.time_near_s = time_near[v];
    m.max_gap_s = duration_s;
    if (!m.visit_times_s.empty()) {
      m.max_gap_s = std::max(m.visit_times_s.front(), duration_s - m.visit_times_s.back());
      for (std::size_t j = 1; j < m.visit_times_s.size(); ++j) {
        m.max_gap_s = std::max(m.max_gap_s, m.visit_times_s[j] - m.visit_times_s[j - 1]);
      }
    }
    // The mean of consecutive differences telescopes to (last - first) / (n - 1): the paper's
    // A* row, 37 visits one lap apart, gives its 8.1 s.
    if (m.visits >= 2) {
      m.mean_interval_s = (m.visit_times_s.back() - m.visit_times_s.front()) / (m.visits - 1);
    }
    visit_counts.push_back(m.visits);
    weight_values.push_back(m.weight);
    out.valves.push_back(std::move(m));
  }
  out.visit_weight_correlation = PearsonCorrelation(visit_counts, weight_values);

  ErgodicMetrics(samples, dt, scenario, weights, normalised, duration_s,
                 options.metric_sample_period_s, out);
  return out;
}

}  // namespace sage::server
