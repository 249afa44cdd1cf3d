#include "server/metrics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "maps/prefetch.h"

namespace sage::server {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

// True if the values are equal up to rounding: time-averaged equal weights (0.2 each) can differ
// in the last bit, and a correlation of rounding noise would be a made-up number.
bool IsConstant(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double scale = std::max({1.0, std::abs(*lo), std::abs(*hi)});
  return *hi - *lo <= 1e-12 * scale;
}

// Each schedule entry's weights, checked and normalised to sum 1 (a raw schedule is accepted).
Eigen::VectorXd Normalised(const WeightChange& change, int valves) {
  const Eigen::VectorXd& w = change.weights;
  if (w.size() != valves || (w.array() < 0.0).any() || !w.allFinite() || !(w.sum() > 0.0)) {
    throw std::invalid_argument("ComputeMetrics: weights at t = " + std::to_string(change.time_s) + " must be " +
                                std::to_string(valves) + " finite values >= 0, not all zero");
  }
  return w / w.sum();
}

// Index of the schedule entry in force at t, by WeightsAt's own rule.
std::size_t ScheduleIndex(const std::vector<WeightChange>& schedule, double time_s) {
  const Eigen::VectorXd* in_force = &WeightsAt(schedule, time_s);
  std::size_t i = 0;
  while (&schedule[i].weights != in_force) ++i;
  return i;
}

// (1/T) integral_0^T w(t) dt of the piecewise-constant (normalised) schedule.
Eigen::VectorXd TimeAveragedWeights(const std::vector<WeightChange>& schedule, double duration_s) {
  std::vector<double> breaks = {0.0, duration_s};
  for (const WeightChange& change : schedule) {
    if (change.time_s > 0.0 && change.time_s < duration_s) breaks.push_back(change.time_s);
  }
  std::sort(breaks.begin(), breaks.end());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(schedule.front().weights.size());
  for (std::size_t j = 0; j + 1 < breaks.size(); ++j) {
    sum += (breaks[j + 1] - breaks[j]) * schedule[ScheduleIndex(schedule, breaks[j])].weights;
  }
  return sum / duration_s;
}

}  // namespace

VisitTracker::VisitTracker(std::vector<Eigen::Vector2d> valves, double visit_radius_m,
                           double rearm_radius_m)
    : valves_(std::move(valves)),
      visit_radius_m_(visit_radius_m),
      rearm_radius_m_(rearm_radius_m),
      nearby_(valves_, visit_radius_m > 0.0 && std::isfinite(visit_radius_m) ? visit_radius_m : 1.0),
      visits_(valves_.size()),
      last_visit_s_(valves_.size(), -std::numeric_limits<double>::infinity()),
      watches_of_(valves_.size()) {
  if (!(visit_radius_m_ > 0.0) || !(rearm_radius_m_ >= visit_radius_m_)) {
    throw std::invalid_argument("VisitTracker: need 0 < visit_radius <= rearm_radius");
  }
}

void VisitTracker::ValveVisits::Add(double time_s) {
  ++count;
  const double none = -std::numeric_limits<double>::infinity();
  if (folded_last_s != none && time_s < folded_last_s) {
    // Older than every visit kept (a vehicle far behind the others): only a new first visit's gap
    // is known; one between two folded visits splits a gap that is no longer known.
    if (time_s < first_s) folded_max_gap_s = std::max(folded_max_gap_s, first_s - time_s);
    first_s = std::min(first_s, time_s);
    return;
  }
  first_s = std::min(first_s, time_s);
  // Vehicles' samples may interleave out of time order (a late host over DDS): kept sorted.
  recent.insert(std::upper_bound(recent.begin(), recent.end(), time_s), time_s);
  if (recent.size() > kRecentVisits) {
    const double oldest = recent.front();
    if (folded_last_s != none) folded_max_gap_s = std::max(folded_max_gap_s, oldest - folded_last_s);
    folded_last_s = oldest;
    recent.erase(recent.begin());
  }
}

void VisitTracker::EventWatch::Count(double visit_s) {
  if (visit_s < time_s) {
    ++before;
    last_before_s = std::max(last_before_s, visit_s);
  } else {
    ++after;
    first_after_s = std::min(first_after_s, visit_s);
    last_after_s = std::max(last_after_s, visit_s);
  }
}

void VisitTracker::Record(int valve, double time_s) {
  visits_[valve].Add(time_s);
  last_visit_s_[valve] = visits_[valve].last_s();
  for (const std::size_t i : watches_of_[valve]) watches_[i].Count(time_s);
}

// The valves this vehicle had disarmed are re-armed once it is past rearm_radius of them; the
// armed valves within visit_radius are visited (and disarmed). The two sets are apart (a valve
// re-armed here is beyond rearm_radius >= visit_radius), so the order of the two steps is moot.
std::vector<int> VisitTracker::Update(int vehicle, const Eigen::Vector2d& position_m, double time_s) {
  if (vehicle < 0) throw std::invalid_argument("VisitTracker: vehicle id must be >= 0");
  if (static_cast<std::size_t>(vehicle) >= disarmed_.size()) disarmed_.resize(vehicle + 1);
  std::vector<int>& disarmed = disarmed_[vehicle];
  std::erase_if(disarmed, [&](int i) { return (position_m - valves_[i]).norm() > rearm_radius_m_; });
  nearby_.Within(position_m, visit_radius_m_, near_scratch_);
  std::vector<int> visited;
  for (int i : near_scratch_) {
    const auto at = std::lower_bound(disarmed.begin(), disarmed.end(), i);
    if (at != disarmed.end() && *at == i) continue;  // still disarmed
    disarmed.insert(at, i);
    Record(i, time_s);
    visited.push_back(i);
  }
  return visited;
}

void VisitTracker::WatchAround(int valve, double time_s) {
  EventWatch w;
  w.valve = valve;
  w.time_s = time_s;
  const ValveVisits& v = visits_.at(static_cast<std::size_t>(valve));
  // The visits no longer kept are older than every kept one: before the event (a mission watches
  // an event when it happens, long before 64 later visits).
  w.before = v.count - v.recent.size();
  w.last_before_s = v.folded_last_s;
  for (const double t : v.recent) w.Count(t);
  watches_of_[static_cast<std::size_t>(valve)].push_back(watches_.size());
  watches_.push_back(w);
}

void VisitTracker::Restore(std::vector<std::vector<int>> disarmed, std::vector<ValveVisits> visits,
                           std::vector<EventWatch> watches) {
  if (visits.size() != valves_.size()) throw std::invalid_argument("VisitTracker::Restore: wrong valve count");
  for (const auto& d : disarmed) {
    for (std::size_t k = 0; k < d.size(); ++k) {
      if (d[k] < 0 || static_cast<std::size_t>(d[k]) >= valves_.size() || (k > 0 && d[k] <= d[k - 1])) {
        throw std::invalid_argument("VisitTracker::Restore: disarmed valves out of range or not ascending");
      }
    }
  }
  for (const ValveVisits& v : visits) {
    if (v.recent.size() > kRecentVisits || v.recent.size() > v.count || !std::is_sorted(v.recent.begin(), v.recent.end())) {
      throw std::invalid_argument("VisitTracker::Restore: a valve's visits are not a record of visits");
    }
  }
  std::vector<std::vector<std::size_t>> of(valves_.size());
  for (std::size_t i = 0; i < watches.size(); ++i) {
    if (watches[i].valve < 0 || static_cast<std::size_t>(watches[i].valve) >= valves_.size()) {
      throw std::invalid_argument("VisitTracker::Restore: a watch of no valve");
    }
    of[static_cast<std::size_t>(watches[i].valve)].push_back(i);
  }
  disarmed_ = std::move(disarmed);
  visits_ = std::move(visits);
  last_visit_s_.resize(visits_.size());
  for (std::size_t i = 0; i < visits_.size(); ++i) last_visit_s_[i] = visits_[i].last_s();
  watches_ = std::move(watches);
  watches_of_ = std::move(of);
}

void VisitTracker::Forget(int vehicle) {
  if (vehicle >= 0 && static_cast<std::size_t>(vehicle) < disarmed_.size()) disarmed_[vehicle].clear();
}

double VisitTracker::LastVisit(int valve) const { return last_visit_s_.at(static_cast<std::size_t>(valve)); }

void VisitTracker::PrefetchArming(int vehicle) const {
  if (vehicle >= 0 && static_cast<std::size_t>(vehicle) < disarmed_.size()) {
    const std::vector<int>& disarmed = disarmed_[static_cast<std::size_t>(vehicle)];
    maps::PrefetchBytes(disarmed.data(), sizeof(int) * disarmed.size());
  }
}

void VisitTracker::PrefetchLastVisit(int valve) const {
  if (valve >= 0 && static_cast<std::size_t>(valve) < last_visit_s_.size()) {
    maps::PrefetchObject(&last_visit_s_[static_cast<std::size_t>(valve)]);
  }
}

void FillEventResponses(const VisitTracker& visits, MissionMetrics& metrics) {
  const std::size_t n = std::min(metrics.events.size(), visits.watches().size());
  for (std::size_t i = 0; i < n; ++i) {
    const VisitTracker::EventWatch& w = visits.watches()[i];
    const double first = visits.visits()[static_cast<std::size_t>(w.valve)].first_s;
    EventResponse& r = metrics.events[i];
    // The mean of consecutive differences telescopes to (last - first) / (n - 1).
    r.time_to_next_visit_s = w.after > 0 ? w.first_after_s - w.time_s : kNaN;
    r.interval_before_s = w.before >= 2 ? (w.last_before_s - first) / static_cast<double>(w.before - 1) : kNaN;
    r.interval_after_s = w.after >= 2 ? (w.last_after_s - w.first_after_s) / static_cast<double>(w.after - 1) : kNaN;
  }
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

MetricsAccumulator::MetricsAccumulator(const maps::Scenario& scenario, const maps::SpectralBasis& basis,
                                       const maps::RiskField& risk, const MetricsOptions& options)
    : scenario_(scenario),
      basis_(basis),
      risk_(risk),
      options_(options),
      valves_(scenario.ValvePositions()),
      visits_(valves_, scenario.visit_radius_m, scenario.rearm_radius_m) {
  if (valves_.empty()) throw std::invalid_argument("MetricsAccumulator: the scenario has no valves");
  if (!(options.metric_sample_period_s > 0.0)) throw std::invalid_argument("MetricsAccumulator: period must be > 0");
  state_.time_near_s.assign(valves_.size(), 0.0);
  state_.watched_until_s.assign(valves_.size(), 0.0);
  state_.longest_unwatched_s.assign(valves_.size(), 0.0);
  state_.unwatched_squares_s2.assign(valves_.size(), 0.0);
  state_.sum_f = Eigen::VectorXd::Zero(basis.size());
}

void MetricsAccumulator::OnWeights(double time_s, const Eigen::VectorXd& weights) {
  holds_.Wait();
  WeightChange change{time_s, Normalised({time_s, weights}, static_cast<int>(valves_.size()))};
  phi_.push_back(risk_.CoefficientsFor(change.weights));
  state_.schedule.push_back(std::move(change));
}

std::vector<int> MetricsAccumulator::Add(const TrajectorySample& sample) {
  holds_.Wait();
  if (!Accept(sample)) return {};
  HoldNext(sample);
  return visits_.Update(sample.vehicle, sample.position_m, sample.time_s);
}

void MetricsAccumulator::AddCycle(const std::vector<TrajectorySample>& samples) {
  holds_.Wait();
  if (state_.schedule.empty()) throw std::logic_error("MetricsAccumulator: OnWeights before the first sample");
  std::vector<TrajectorySample> accepted;
  accepted.reserve(samples.size());
  // Each vehicle's list of disarmed valves is a heap block of its own: asked for a few samples
  // ahead (at 10,000 vehicles each was a cache miss).
  constexpr std::size_t kArmingAhead = 4;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (i + kArmingAhead < samples.size()) visits_.PrefetchArming(samples[i + kArmingAhead].vehicle);
    const TrajectorySample& sample = samples[i];
    if (!Accept(sample)) continue;
    visits_.Update(sample.vehicle, sample.position_m, sample.time_s);
    accepted.push_back(sample);
  }
  const auto hold = [this, batch = std::move(accepted)] {
    for (const TrajectorySample& sample : batch) HoldNext(sample);
    LaunchQueuedCoverage();
  };
  if (samples.size() >= kHoldBatch) {
    holds_.Launch(hold);
  } else {
    hold();  // a small fleet's cycle: a thread would cost more than it saves
  }
}

bool MetricsAccumulator::Accept(const TrajectorySample& sample) {
  if (sample.vehicle < 0) throw std::invalid_argument("MetricsAccumulator: vehicle id must be >= 0");
  const auto vehicle = static_cast<std::size_t>(sample.vehicle);
  if (vehicle >= accepted_until_s_.size()) accepted_until_s_.resize(vehicle + 1, -kInfinity);
  // Refused (counted, no effect): before 0, not finite, or not after its vehicle's previous one.
  if (!(sample.time_s >= 0.0) || !sample.position_m.allFinite() || !(sample.time_s > accepted_until_s_[vehicle])) {
    ++state_.refused;
    return false;
  }
  accepted_until_s_[vehicle] = sample.time_s;
  return true;
}

void MetricsAccumulator::HoldNext(const TrajectorySample& sample) {
  const auto pending = pending_at_.Find(state_.pending, sample.vehicle);
  if (pending != state_.pending.end()) {
    const double dt = sample.time_s - pending->second.time_s;  // > 0: Accept saw to it
    ++state_.spacings[dt];
    TakeCheckpointsBefore(pending->second.time_s);
    Hold(pending->second, dt);
    pending->second = sample;
  } else {
    state_.pending[sample.vehicle] = sample;
  }
}

void MetricsAccumulator::Retire(int vehicle) {
  holds_.Wait();
  // Its last sample holds for the median spacing, as checkpoints since have counted it; should
  // the vehicle come back (a host that stalled), its next sample starts afresh.
  auto it = state_.pending.find(vehicle);
  if (it != state_.pending.end()) {
    TakeCheckpointsBefore(it->second.time_s);
    Hold(it->second, MedianSpacing());
    pending_at_.Forget();
    state_.pending.erase(it);
  }
  if (vehicle >= 0 && static_cast<std::size_t>(vehicle) < accepted_until_s_.size()) {
    accepted_until_s_[static_cast<std::size_t>(vehicle)] = -kInfinity;
  }
  visits_.Forget(vehicle);
}

void MetricsAccumulator::Advance(double time_s) {
  holds_.Wait();
  TakeCheckpointsBefore(time_s);
}

void MetricsAccumulator::LaunchCoverage() {
  holds_.Wait();
  LaunchQueuedCoverage();
}

void MetricsAccumulator::LaunchQueuedCoverage() {
  if (coverage_.queued() >= kCoverageBatch) coverage_.Launch(basis_, state_.sum_f);
}

// Logically const: the sums become what they are with every held sample in; an accumulator is
// never defined const, so writing its sums here is defined.
void MetricsAccumulator::SettleCoverage() const {
  coverage_.Settle(basis_, const_cast<Eigen::VectorXd&>(state_.sum_f));
}

void MetricsAccumulator::CoverageBacklog::Launch(const maps::SpectralBasis& basis, Eigen::VectorXd& sums) {
  Wait();
  job_ = std::async(std::launch::async, [batch = std::move(queued_), &basis, &sums] {
           basis.AddScaledAll(batch, sums);
         }).share();
  queued_.clear();  // moved from: empty it for certain
}

void MetricsAccumulator::CoverageBacklog::Settle(const maps::SpectralBasis& basis, Eigen::VectorXd& sums) const {
  Wait();
  basis.AddScaledAll(queued_, sums);
  queued_.clear();
}

void MetricsAccumulator::Restore(State state, VisitTracker visits) {
  holds_.Wait();
  if (state.time_near_s.size() != valves_.size() || state.sum_f.size() != basis_.size() || state.schedule.empty()) {
    throw std::invalid_argument("MetricsAccumulator::Restore: state of another mission");
  }
  std::vector<double> accepted_until;  // the pending samples' times: what Accept screens against
  for (const auto& [vehicle, sample] : state.pending) {
    if (vehicle < 0) throw std::invalid_argument("MetricsAccumulator::Restore: a pending sample of vehicle < 0");
    const auto v = static_cast<std::size_t>(vehicle);
    if (v >= accepted_until.size()) accepted_until.resize(v + 1, -kInfinity);
    accepted_until[v] = sample.time_s;
  }
  accepted_until_s_ = std::move(accepted_until);
  phi_.clear();
  for (const WeightChange& change : state.schedule) phi_.push_back(risk_.CoefficientsFor(change.weights));
  pending_at_.Forget();
  held_at_.Forget();
  coverage_.Drop();
  state_ = std::move(state);
  visits_ = std::move(visits);
}

// A sample held for dt: time near each valve, at the boundary, and its share of the coverage.
void MetricsAccumulator::Hold(const TrajectorySample& sample, double dt_s) {
  const Eigen::Vector2d& p = sample.position_m;
  visits_.ValvesWithinVisitRadius(p, near_scratch_);
  for (const int v : near_scratch_) {
    state_.time_near_s[v] += dt_s;
    // Watched over [t, t + dt): the stretch since it was last watched closes here.
    const double unwatched = sample.time_s - state_.watched_until_s[v];
    if (unwatched > 0.0) {
      state_.longest_unwatched_s[v] = std::max(state_.longest_unwatched_s[v], unwatched);
      state_.unwatched_squares_s2[v] += unwatched * unwatched;
    }
    state_.watched_until_s[v] = std::max(state_.watched_until_s[v], sample.time_s + dt_s);
  }
  const double to_edge =
      std::min({p.x(), scenario_.workspace.width_m - p.x(), p.y(), scenario_.workspace.height_m - p.y()});
  if (to_edge < 0.0) {
    state_.time_outside_s += dt_s;
  } else if (to_edge <= options_.boundary_margin_m) {
    state_.time_pinned_s += dt_s;
  }
  coverage_.Queue(p, dt_s);
  // A reader of recorded samples that never launches: the queue stays within a few batches.
  if (coverage_.queued() >= 64 * kCoverageBatch) coverage_.Settle(basis_, state_.sum_f);
  state_.sum_dt += dt_s;
  const LastHeld held{sample.time_s, sample.time_s + dt_s, p};
  const auto at = held_at_.Find(state_.last_held, sample.vehicle);
  if (at != state_.last_held.end()) {
    at->second = held;
  } else {
    state_.last_held.emplace(sample.vehicle, held);
  }
}

double MetricsAccumulator::MedianSpacing() const {
  if (state_.spacings.empty()) return 1.0 / scenario_.control_rate_hz;
  std::size_t total = 0;
  for (const auto& [dt, count] : state_.spacings) total += count;
  // The middle element (odd count) or the mean of the two middle ones, as a sorted list gives.
  const std::size_t upper = total / 2, lower = total % 2 == 0 ? upper - 1 : upper;
  double lower_value = 0.0, upper_value = 0.0;
  std::size_t seen = 0;
  for (const auto& [dt, count] : state_.spacings) {
    if (seen <= lower && lower < seen + count) lower_value = dt;
    if (seen <= upper && upper < seen + count) {
      upper_value = dt;
      break;
    }
    seen += count;
  }
  return 0.5 * (lower_value + upper_value);
}

// The fleet's time-averaged coverage of the samples before `time_s` against phi_k(time_s): a
// held sample running past it counts only up to it; a sample whose hold is not known yet counts
// for the median spacing, also only up to time_s.
double MetricsAccumulator::MetricAt(double time_s) const {
  SettleCoverage();
  Eigen::VectorXd covered = state_.sum_f;
  double covered_dt = state_.sum_dt;
  for (const auto& [vehicle, held] : state_.last_held) {
    const double beyond = held.end_s - std::max(time_s, held.time_s);
    if (beyond > 0.0 && held.time_s < time_s) {
      basis_.Evaluate(held.position_m, f_);
      covered.noalias() -= beyond * f_;
      covered_dt -= beyond;
    }
  }
  const double median = MedianSpacing();
  for (const auto& [vehicle, pending] : state_.pending) {
    if (!(pending.time_s < time_s)) continue;
    const double dt = std::min(median, time_s - pending.time_s);
    basis_.Evaluate(pending.position_m, f_);
    covered.noalias() += dt * f_;
    covered_dt += dt;
  }
  if (!(covered_dt > 0.0)) return kNaN;  // nothing observed yet
  return basis_.Metric(covered / covered_dt - phi_[ScheduleIndex(state_.schedule, time_s)]);
}

// Checkpoints k * period at or before time_s, each before any sample at or after it is held.
void MetricsAccumulator::TakeCheckpointsBefore(double time_s) {
  if (state_.schedule.empty()) throw std::logic_error("MetricsAccumulator: OnWeights before the first sample");
  const double period = options_.metric_sample_period_s;
  for (; state_.next_checkpoint * period <= time_s; ++state_.next_checkpoint) TakeCheckpoint(state_.next_checkpoint);
}

void MetricsAccumulator::TakeCheckpoint(int k) {
  const double period = options_.metric_sample_period_s;
  const double value = MetricAt(k * period);
  if (std::isnan(value)) return;
  state_.latest_metric = value;
  if (k % state_.metric_stride != 0) return;
  std::vector<MetricSample>& kept = state_.metric_over_time;
  kept.push_back({k * period, value});
  if (kept.size() <= kMetricSamplesKept) return;
  // Every other one goes: the spacing doubles (the samples kept are on the new stride already).
  state_.metric_stride *= 2;
  std::erase_if(kept, [&](const MetricSample& m) { return std::llround(m.time_s / period) % state_.metric_stride != 0; });
}

MissionMetrics MetricsAccumulator::Result(double end_s) const {
  if (!(end_s > 0.0) || !std::isfinite(end_s)) {
    throw maps::ScenarioError(fmt::format("metrics: mission length = {}: must be finite and > 0", end_s));
  }
  holds_.Wait();
  if (state_.schedule.empty()) throw std::logic_error("MetricsAccumulator: no weights");
  SettleCoverage();
  // Finish a copy: each vehicle's last sample holds for the median spacing, clipped to the end.
  MetricsAccumulator done = *this;
  const double median = done.MedianSpacing();
  // Checkpoints strictly before the end (within rounding), then the end itself.
  const double period = options_.metric_sample_period_s;
  for (; done.state_.next_checkpoint * period < end_s * (1.0 - 1e-12); ++done.state_.next_checkpoint) {
    done.TakeCheckpoint(done.state_.next_checkpoint);
  }
  for (const auto& [vehicle, pending] : state_.pending) {
    if (pending.time_s <= end_s) done.Hold(pending, std::clamp(median, 0.0, end_s - pending.time_s));
  }
  done.state_.pending.clear();
  MissionMetrics out;
  out.controller = options_.controller;
  out.profile = options_.profile;
  out.duration_s = end_s;
  out.boundary_margin_m = options_.boundary_margin_m;
  out.vehicle_count = static_cast<int>(done.state_.last_held.size());
  out.time_outside_s = done.state_.time_outside_s;
  out.time_pinned_s = done.state_.time_pinned_s;
  out.metric_over_time = done.state_.metric_over_time;
  // Checkpoints strictly before the end (an online one taken at the end itself is the end's).
  while (!out.metric_over_time.empty() && out.metric_over_time.back().time_s >= end_s * (1.0 - 1e-12)) {
    out.metric_over_time.pop_back();
  }
  out.ergodic_metric = done.MetricAt(end_s);
  if (!std::isnan(out.ergodic_metric)) out.metric_over_time.push_back({end_s, out.ergodic_metric});

  const std::vector<maps::Valve> valves = scenario_.AllValves();
  const Eigen::VectorXd average_weights = TimeAveragedWeights(state_.schedule, end_s);
  std::vector<double> visit_counts, weight_values;
  for (std::size_t v = 0; v < valves.size(); ++v) {
    ValveMetrics m;
    m.name = valves[v].name;
    m.weight = average_weights[v];
    const VisitTracker::ValveVisits& record = visits_.visits()[v];
    // Visits after the end (a record read past it) are left out; those are among the kept ones.
    for (double t : record.recent)
      if (t <= end_s) m.visit_times_s.push_back(t);
    const std::size_t later = record.recent.size() - m.visit_times_s.size();
    m.visits = static_cast<int>(record.count - later);
    m.time_near_s = done.state_.time_near_s[v];
    const double open = std::max(0.0, end_s - std::min(end_s, done.state_.watched_until_s[v]));  // to the end
    m.longest_unwatched_s = std::max(done.state_.longest_unwatched_s[v], open);
    m.unwatched_squares_s2 = done.state_.unwatched_squares_s2[v] + open * open;
    m.max_gap_s = end_s;
    if (m.visits > 0) {
      const double last = m.visit_times_s.empty() ? record.folded_last_s : m.visit_times_s.back();
      // start -> first, last -> end, the gaps folded away, the one into the kept visits, and theirs.
      m.max_gap_s = std::max({record.first_s, end_s - last, record.folded_max_gap_s});
      if (!m.visit_times_s.empty() && record.count > record.recent.size()) {
        m.max_gap_s = std::max(m.max_gap_s, m.visit_times_s.front() - record.folded_last_s);
      }
      for (std::size_t j = 1; j < m.visit_times_s.size(); ++j) {
        m.max_gap_s = std::max(m.max_gap_s, m.visit_times_s[j] - m.visit_times_s[j - 1]);
      }
      // The mean of consecutive differences telescopes to (last - first) / (n - 1): the paper's
      // A* row, 37 visits one lap apart, gives its 8.1 s.
      if (m.visits >= 2) m.mean_interval_s = (last - record.first_s) / (m.visits - 1);
    }
    visit_counts.push_back(m.visits);
    weight_values.push_back(m.weight);
    out.valves.push_back(std::move(m));
  }
  out.visit_weight_correlation = PearsonCorrelation(visit_counts, weight_values);
  SummariseGaps(out);
  return out;
}

double NearestRankPercentile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double rank = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size()) - 1e-9);
  const std::size_t index = static_cast<std::size_t>(std::clamp(rank, 1.0, static_cast<double>(values.size()))) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  return values[index];
}

void SummariseGaps(MissionMetrics& m) {
  const double T = m.duration_s;
  std::vector<double> longest;
  double weight_sum = 0.0;
  m.expected_detection_delay_s = m.risk_weighted_interval_s = 0.0;
  m.unvisited_valves = 0;
  const ValveMetrics* dominant = nullptr;
  for (const ValveMetrics& v : m.valves) {
    m.expected_detection_delay_s += v.weight * v.unwatched_squares_s2 / (2.0 * T);
    m.risk_weighted_interval_s += v.weight * T / std::max(v.visits, 1);
    weight_sum += v.weight;
    m.unvisited_valves += v.visits == 0 ? 1 : 0;
    longest.push_back(v.longest_unwatched_s);
    if (dominant == nullptr || v.weight > dominant->weight) dominant = &v;
  }
  if (weight_sum > 0.0) {
    m.expected_detection_delay_s /= weight_sum;
    m.risk_weighted_interval_s /= weight_sum;
  }
  m.dominant_interval_s = dominant != nullptr ? T / std::max(dominant->visits, 1) : 0.0;
  std::sort(longest.begin(), longest.end());
  const auto at = [&](double q) {
    return longest.empty() ? 0.0 : longest[std::min(longest.size() - 1, static_cast<std::size_t>(q * longest.size()))];
  };
  m.longest_gap_median_s = at(0.5);
  m.longest_gap_p90_s = at(0.9);
  m.longest_gap_max_s = longest.empty() ? 0.0 : longest.back();
}

MissionMetrics ComputeMetrics(const Trajectory& trajectory, const maps::Scenario& scenario,
                              const std::vector<WeightChange>& weights, double duration_s,
                              const MetricsOptions& options) {
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) {
    throw maps::ScenarioError(fmt::format("mission length = {} s: must be finite and > 0", duration_s));
  }
  // Bounded so a typo (1e-9 s) cannot ask for billions of metric evaluations.
  if (!(options.metric_sample_period_s > 0.0) || duration_s / options.metric_sample_period_s > 1e6) {
    throw maps::ScenarioError(fmt::format("mission length = {} s: at most 1e6 metric checkpoints of {} s", duration_s,
                                          options.metric_sample_period_s));
  }
  if (weights.empty()) throw std::invalid_argument("ComputeMetrics: empty weight schedule");
  const maps::SpectralBasis basis(scenario.workspace.width_m, scenario.workspace.height_m,
                                  scenario.ergodic.basis_order);
  // The same target the server steers on: the valves' risk where a vehicle can be.
  const maps::RiskField field = maps::RiskField::ForScenario(scenario, basis);
  MetricsAccumulator metrics(scenario, basis, field, options);
  for (const WeightChange& change : weights) metrics.OnWeights(change.time_s, change.weights);
  std::vector<const TrajectorySample*> samples;
  samples.reserve(trajectory.samples.size());
  for (const TrajectorySample& s : trajectory.samples) {
    if (s.time_s >= 0.0 && s.time_s <= duration_s) samples.push_back(&s);
  }
  std::stable_sort(samples.begin(), samples.end(), [](const auto* a, const auto* b) {
    return a->time_s != b->time_s ? a->time_s < b->time_s : a->vehicle < b->vehicle;
  });
  for (const TrajectorySample* s : samples) metrics.Add(*s);
  return metrics.Result(duration_s);
}

}  // namespace sage::server
