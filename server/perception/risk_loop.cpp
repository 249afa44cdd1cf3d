#include "server/perception/risk_loop.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

namespace sage::server {
namespace {

constexpr double kNotYet = std::numeric_limits<double>::quiet_NaN();
// A scan's time is its cycle's (cycle / control rate) to within this (s).
constexpr double kScanTimeSlack_s = 1e-6;
// Its pose is its vehicle's state of the same cycle to within this (m, rad): the same numbers,
// carried by two messages.
constexpr double kScanPoseSlack = 1e-6;
// A host may run at most this far ahead of the server's clock (s), as for states.
constexpr double kScanMaxLead_s = 5.0;
// The least time after a detection over which visits to the leaking valve are given as a rate (s):
// a few of the tour's laps, or of the loop's revisits.
constexpr double kLeastRateWindow_s = 30.0;
// Evidence of a leak worth less risk than this (the valves' prior holds 1) is not written to the layer.
constexpr double kNegligibleMass = 1e-5;

}  // namespace

std::size_t RiskLoop::MaxDetectionsPerScan(const maps::Scenario& scenario) {
  double clutter = 0.0;  // the busiest sensor's mean false alarms a scan
  for (const maps::SensorSpec& sensor : scenario.sensors) {
    if (sensor.rate_hz > 0.0) clutter = std::max(clutter, sensor.false_alarms_per_s / sensor.rate_hz);
  }
  const double honest = static_cast<double>(scenario.leaks.size()) + clutter + 10.0 * std::sqrt(clutter) + 10.0;
  return static_cast<std::size_t>(std::clamp(std::ceil(honest), static_cast<double>(kMinDetectionsPerScan),
                                             static_cast<double>(kMostDetectionsPerScan)));
}

RiskLoop::RiskLoop(const maps::Scenario& scenario, const maps::World& world, maps::RiskLayer& layer)
    : scenario_(scenario),
      max_detections_(MaxDetectionsPerScan(scenario)),
      world_(world),
      layer_(layer),
      belief_(scenario, world, layer.resolution_m()),
      // Onsets as --random-leaks draws them (maps::WithRandomLeaks): uniform in [0.1, 0.9] of the mission.
      // (A mission without sensors keeps none: its checkpoint holds no 35,000 empty valves.)
      scan_waits_(scenario.sensors.empty() ? 0 : scenario.ValveCount(), maps::kRandomLeakOnsetFrom * scenario.duration_s,
                  maps::kRandomLeakOnsetTo * scenario.duration_s),
      // The look planner's: a leak may start at any moment of the mission.
      look_waits_(!scenario.sensors.empty() && scenario.astar.order == maps::AstarSettings::Order::kLooks ? scenario.ValveCount() : 0,
                  0.0, scenario.duration_s) {
  if (sensing()) {
    valve_positions_ = scenario.ValvePositions();
    double longest_range_m = 0.25;  // the index's cell: a scan's reach reads a few cells
    for (const maps::SensorModel& model : belief_.sensors()) longest_range_m = std::max(longest_range_m, model.spec().range_m);
    valve_index_.emplace(valve_positions_, longest_range_m);
  }
  // A detection belongs to a leak within three position sigmas of the noisiest sensor (at least
  // half a metre: a few leaves).
  for (const maps::SensorSpec& s : scenario.sensors) association_m_ = std::max(association_m_, 3.0 * s.position_sigma_m);
  const std::vector<maps::Valve> valves = scenario.AllValves();
  for (const maps::LeakSpec& leak : scenario.leaks) {
    truth_.push_back({maps::LeakPosition(scenario, leak), leak.valve.empty() ? -1 : scenario.ValveIndex(leak.valve),
                      leak.start_s});
    leaks_.push_back({kNotYet, kNotYet, 0});
  }
}

const char* RiskLoop::Take(const agents::ScanReport& s, double latest_s) {
  const int sensors = static_cast<int>(belief_.sensors().size());
  bool finite = s.position_m.allFinite() && std::isfinite(s.heading_rad) && std::isfinite(s.time_s);
  for (const Eigen::Vector2d& z : s.detections_m) finite = finite && z.allFinite();
  if (!finite) return "scan not finite";
  if (s.sensor < 0 || s.sensor >= sensors) return "scan of no such sensor";
  if (s.id < 0) return "scan of no vehicle (id < 0)";
  if (s.cycle < 0 || s.time_s < 0.0) return "scan before the mission";
  if (std::abs(s.time_s - static_cast<double>(s.cycle) / scenario_.control_rate_hz) > kScanTimeSlack_s) {
    return "scan time not its cycle's";
  }
  if (s.time_s > latest_s + kScanMaxLead_s) return "scan ahead of the clock";
  const maps::SensorModel& model = belief_.sensors()[static_cast<std::size_t>(s.sensor)];
  if (!model.ScansAt(s.cycle)) return "scan off its sensor's schedule";
  const Eigen::Vector2d workspace(scenario_.workspace.width_m, scenario_.workspace.height_m);
  const auto inside = [&](const Eigen::Vector2d& p) { return (p.array() >= 0.0).all() && (p.array() <= workspace.array()).all(); };
  if (!inside(s.position_m)) return "scan from outside the workspace";
  if (s.detections_m.size() > max_detections_) return "scan with too many detections";
  const double reach = model.spec().range_m + 4.0 * model.spec().position_sigma_m;
  for (const Eigen::Vector2d& z : s.detections_m) {
    if (!inside(z) || (z - s.position_m).norm() > reach) return "detection out of its sensor's reach";
  }
  const auto last = last_fused_.find({s.id, s.sensor});
  if ((last != last_fused_.end() && s.cycle <= last->second) || held_keys_.count({s.id, s.sensor, s.cycle}) != 0) {
    return "scan not after its vehicle's last";
  }
  held_keys_.insert({s.id, s.sensor, s.cycle});
  held_.push_back(s);
  return nullptr;
}

void RiskLoop::Fuse(std::int64_t cycle, double time_s, const Roster& roster, RejectionCounts& rejected) {
  if (!sensing()) return;
  std::vector<agents::ScanReport> due;
  for (auto it = held_.begin(); it != held_.end();) {
    if (it->cycle <= cycle) {
      held_keys_.erase({it->id, it->sensor, it->cycle});
      due.push_back(std::move(*it));
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  std::sort(due.begin(), due.end(), [](const agents::ScanReport& a, const agents::ScanReport& b) {
    return std::tie(a.cycle, a.id, a.sensor) < std::tie(b.cycle, b.id, b.sensor);
  });
  std::vector<agents::ScanReport> fused;
  for (agents::ScanReport& s : due) {
    const Roster::Member* m = roster.Find(s.id);
    const char* refusal = nullptr;
    if (m == nullptr || m->status != Roster::Status::kAlive) {
      refusal = "scan of no live vehicle";
    } else if (m->has_state && m->last.cycle == s.cycle &&
               ((m->last.state.position_m - s.position_m).norm() > kScanPoseSlack ||
                std::abs(m->last.state.heading_rad - s.heading_rad) > kScanPoseSlack)) {
      refusal = "scan pose not its vehicle's state";
    } else if (const auto last = last_fused_.find({s.id, s.sensor}); last != last_fused_.end() && s.cycle <= last->second) {
      refusal = "scan not after its vehicle's last";
    }
    if (refusal != nullptr) {
      rejected.Count(refusal, fmt::format("vehicle {}", s.id));
      continue;
    }
    last_fused_[{s.id, s.sensor}] = s.cycle;
    belief_.Fuse(s.sensor, s.position_m, s.heading_rad, s.detections_m, s.time_s);
    LookAtValves(s);
    ++scans_;
    fused.push_back(std::move(s));
  }
  Score(fused, time_s);
}

void RiskLoop::LookAtValves(const agents::ScanReport& s) {
  // Each valve in this sensor's view would have shown a leak of strength 1 there with the
  // sensor's probability at its distance (what the hosts' sensors draw their detections by).
  const maps::SensorModel& model = belief_.sensors()[static_cast<std::size_t>(s.sensor)];
  thread_local std::vector<int> near;
  valve_index_->Within(s.position_m, model.spec().range_m, near);
  for (const int v : near) {
    const Eigen::Vector2d& valve = valve_positions_[static_cast<std::size_t>(v)];
    if (!model.InView(s.position_m, s.heading_rad, valve)) continue;
    const double p = model.DetectionProbability((valve - s.position_m).norm(), 1.0);
    if (p <= 0.0) continue;
    scan_waits_.Look(v, s.time_s, p);
    if (look_waits_.valves() > 0) look_waits_.Look(v, s.time_s, p);
  }
}

Eigen::VectorXd RiskLoop::ValveFactors(double time_s) const {
  if (!steers()) return {};
  Eigen::VectorXd factors = belief_.ValveFactors(time_s);
  if ((factors.array() == 1.0).all()) return {};
  return factors;
}

Eigen::VectorXd RiskLoop::Undetected(double time_s) const {
  const std::vector<double> u = look_waits_.Undetected(time_s);
  return Eigen::Map<const Eigen::VectorXd>(u.data(), static_cast<Eigen::Index>(u.size()));
}

Eigen::VectorXd RiskLoop::ValveLeakProbabilities(double time_s) const {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(valve_positions_.size()));
  if (!valve_index_) return p;
  std::vector<int> near;
  for (const LeakBelief::Cell& c : belief_.positive()) {
    valve_index_->Within(belief_.CentreOf(c), association_m_, near);
    if (near.empty()) continue;
    const double pc = belief_.Probability(c, time_s);
    for (int v : near) p[v] = std::max(p[v], pc);
  }
  return p;
}

void RiskLoop::UpdateLayer(double time_s) {
  if (!steers()) return;
  belief_.DropRelaxed(time_s);
  const double r = belief_.resolution_m();
  const double p0 = scenario_.fusion.prior_probability;
  if (kernel_.empty()) {
    // The spread's offsets and Gaussian weights, once (leaves within 3 sigma; the leaf alone at sigma 0).
    const double sigma = scenario_.fusion.spread_m;
    const int reach = sigma > 0.0 ? static_cast<int>(std::ceil(3.0 * sigma / r)) : 0;
    for (int di = -reach; di <= reach; ++di) {
      for (int dj = -reach; dj <= reach; ++dj) {
        const double d2 = (di * di + dj * dj) * r * r;
        if (sigma > 0.0 && d2 > 9.0 * sigma * sigma) continue;
        kernel_.push_back({di, dj, sigma > 0.0 ? std::exp(-0.5 * d2 / (sigma * sigma)) : 1.0});
      }
    }
  }
  const maps::OccupancyGrid& blocked = world_.blocked();
  const auto reachable = [&](const LeakBelief::Cell& c) {
    const std::uint64_t key = CellKey(c);
    const auto known = reachable_.find(key);
    if (known != reachable_.end()) return known->second;
    const Eigen::Vector2i in_grid = blocked.CellOf(belief_.CentreOf(c));
    return reachable_[key] = !blocked.Occupied(in_grid.x(), in_grid.y());
  };
  // Each leaf's chance of a leak above the open seabed's as a mass, spread as a Gaussian over the
  // reachable leaves around it (no risk where no hull can be: SMC would push into the structure):
  // the leaves with evidence of a leak, and the flowlines' joints, whose prior is above P0.
  std::unordered_map<std::uint64_t, double> mass;
  std::vector<std::pair<LeakBelief::Cell, double>> spread;
  std::vector<LeakBelief::Cell> raised(belief_.positive().begin(), belief_.positive().end());
  for (const LeakBelief::Cell& c : belief_.joints()) {
    if (belief_.positive().count(c) == 0) raised.push_back(c);
  }
  // At most one leak's mass a suspected leak: leaves with evidence side by side (a blob around a
  // detection) weigh together leak_mass times the sum of their chances above P0 (the expected
  // number of leaks among them), but at most leak_mass (there is one leak there, or none), shared
  // in proportion to each one's chance. A sonar's detection, 0.3 m off, raises some sixty leaves
  // around its leak; their uncapped sum had put ~30 times the valves' whole prior on two leaks of a
  // new user's field and drawn every vehicle of a shared fleet there. A faint blob (a false alarm)
  // weighs what it did. (Weighing a blob by its likeliest leaf alone had let a false alarm's
  // valve keep too much of the fleet's time late in the mission: 1.22x at 210 s after it.)
  const std::size_t n = raised.size();
  std::vector<double> excess(n);
  for (std::size_t k = 0; k < n; ++k) excess[k] = std::max(0.0, belief_.Probability(raised[k], time_s) - p0);
  // The leaves with evidence come first in `raised`; a joint with none is a site of its own (each
  // joint is where a leak may be, whatever its neighbours).
  const std::size_t with_evidence = belief_.positive().size();
  std::unordered_map<std::uint64_t, std::size_t> index_of;
  index_of.reserve(with_evidence);
  for (std::size_t k = 0; k < with_evidence; ++k) index_of.emplace(CellKey(raised[k]), k);
  std::vector<std::size_t> root(n);
  std::iota(root.begin(), root.end(), std::size_t{0});
  const auto find = [&](std::size_t k) {
    while (root[k] != k) k = root[k] = root[root[k]];
    return k;
  };
  for (std::size_t k = 0; k < with_evidence; ++k) {
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        const auto other = index_of.find(CellKey({raised[k].i + di, raised[k].j + dj}));
        if (other == index_of.end()) continue;
        const std::size_t a = find(k), b = find(other->second);
        if (a != b) root[std::max(a, b)] = std::min(a, b);  // the lower index leads: a fixed order
      }
    }
  }
  std::vector<double> cluster_sum(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) cluster_sum[find(k)] += excess[k];
  for (std::size_t k = 0; k < n; ++k) {
    const LeakBelief::Cell& c = raised[k];
    const std::size_t cluster = find(k);
    const double m = cluster_sum[cluster] > 0.0
                         ? scenario_.fusion.leak_mass * std::min(1.0, cluster_sum[cluster]) * excess[k] /
                               cluster_sum[cluster]
                         : 0.0;
    // A leaf a hundred thousandth of the prior's mass above it steers nobody (and a false alarm's
    // leaves take ten relaxation times to fall below the belief's own threshold).
    if (!(m > kNegligibleMass)) continue;
    spread.clear();
    double total = 0.0;
    for (const Offset& k : kernel_) {
      const LeakBelief::Cell n{c.i + k.di, c.j + k.dj};
      if (!belief_.OnGrid(n) || !reachable(n)) continue;
      spread.emplace_back(n, k.weight);
      total += k.weight;
    }
    for (const auto& [n, w] : spread) mass[CellKey(n)] += m * w / total;
  }
  // Into the layer, in a fixed order; a leaf is written again only when its excess moved by
  // more than kRewrite of itself (relaxation moves every raised leaf a little every cycle, and
  // each write costs the layer O(K^2)).
  constexpr double kRewrite = 0.02;
  std::vector<std::pair<std::uint64_t, float>> now;
  now.reserve(mass.size());
  for (const auto& [key, m] : mass) {
    const float stored = static_cast<float>(m / (r * r));  // density (1/m^2); edge leaves are a little smaller
    if (stored != 0.0f) now.emplace_back(key, stored);
  }
  std::sort(now.begin(), now.end());
  std::vector<std::uint64_t> gone;
  for (const auto& [key, value] : written_) {
    if (!std::binary_search(now.begin(), now.end(), std::pair<std::uint64_t, float>(key, -std::numeric_limits<float>::infinity()),
                            [](const auto& a, const auto& b) { return a.first < b.first; })) {
      gone.push_back(key);
    }
  }
  std::sort(gone.begin(), gone.end());
  for (const std::uint64_t key : gone) {
    layer_.SetExcess(belief_.CentreOf(KeyCell(key)), 0.0);
    written_.erase(key);
  }
  for (const auto& [key, value] : now) {
    const auto was = written_.find(key);
    if (was != written_.end() && std::abs(value - was->second) <= kRewrite * std::abs(was->second)) continue;
    layer_.SetExcess(belief_.CentreOf(KeyCell(key)), value);
    written_[key] = value;
  }
}

void RiskLoop::Score(const std::vector<agents::ScanReport>& fused, double time_s) {
  const double a2 = association_m_ * association_m_;
  // The leak a point is of: the nearest one started by t within the association radius that
  // `could` be it (the first listed on a tie); truth_.size() if none. Two leaks may start closer
  // than that radius (scenarios keep 0.5 m between sites; fleet_field_leaks' sonar associates
  // within 0.6 m): counted for every leak in reach, a leak starting 0.58 m from one found long
  // before was detected by the older one's echoes, and confirmed by its belief at its onset.
  const auto nearest_leak = [&](const Eigen::Vector2d& p, double t, const auto& could) {
    std::size_t nearest = truth_.size();
    double nearest_d2 = a2;
    for (std::size_t k = 0; k < truth_.size(); ++k) {
      const double d2 = (p - truth_[k].position_m).squaredNorm();
      if (t + 1e-9 < truth_[k].start_s || d2 > nearest_d2 || (nearest < truth_.size() && d2 == nearest_d2)) continue;
      if (!could(k)) continue;
      nearest = k;
      nearest_d2 = d2;
    }
    return nearest;
  };
  const auto any_leak = [](std::size_t) { return true; };
  for (const agents::ScanReport& s : fused) {
    const maps::SensorModel& model = belief_.sensors()[static_cast<std::size_t>(s.sensor)];
    for (const Eigen::Vector2d& z : s.detections_m) {
      // Only a scan that had the leak in view could have seen it: a false alarm that fell near a
      // leak out of every sensor's reach (5.2 m from the nearest vehicle, the sonar's range 5 m)
      // had counted as its detection.
      const std::size_t k = nearest_leak(z, s.time_s, [&](std::size_t k) {
        return model.InView(s.position_m, s.heading_rad, truth_[k].position_m);
      });
      if (k == truth_.size()) {
        ++false_detections_;
        continue;
      }
      ++leaks_[k].detections;
      if (std::isnan(leaks_[k].detected_s)) leaks_[k].detected_s = s.time_s;
    }
  }
  const maps::FusionSettings& f = scenario_.fusion;
  // The leaves above the prior now, with their posterior: all that can confirm or raise.
  std::vector<std::pair<Eigen::Vector2d, double>> hot;
  for (const LeakBelief::Cell& c : belief_.positive()) {
    const double p = belief_.Probability(c, time_s);
    if (p >= 0.5 * f.alarm_probability) hot.emplace_back(belief_.CentreOf(c), p);
  }
  // A leaf at the confirmation probability confirms the leak it is of, once a scan has seen that
  // leak (the belief is only ever raised by detections, which are of the nearest leak).
  for (const auto& [centre, p] : hot) {
    if (p < f.confirm_probability) continue;
    const std::size_t k = nearest_leak(centre, time_s, any_leak);
    if (k < truth_.size() && std::isnan(leaks_[k].confirmed_s) && !std::isnan(leaks_[k].detected_s)) {
      leaks_[k].confirmed_s = time_s;
    }
  }
  // Alarms: a leaf at the alarm probability far from every open alarm raises one; an open alarm
  // with no leaf near it at half that probability is cleared.
  for (const auto& [centre, p] : hot) {
    if (p < f.alarm_probability) continue;
    Alarm* open = nullptr;
    for (Alarm& alarm : alarms_) {
      if (alarm.cleared_s < 0.0 && (alarm.anchor_m - centre).squaredNorm() <= a2) {
        open = &alarm;
        break;
      }
    }
    if (open == nullptr) {
      Alarm alarm;
      alarm.anchor_m = centre;
      alarm.raised_s = time_s;
      if (const std::size_t k = nearest_leak(centre, time_s, any_leak); k < truth_.size()) alarm.leak = static_cast<int>(k);
      alarms_.push_back(alarm);
      open = &alarms_.back();
    }
    open->confirmed = open->confirmed || p >= f.confirm_probability;
  }
  for (Alarm& alarm : alarms_) {
    if (alarm.cleared_s >= 0.0) continue;
    const bool still = std::any_of(hot.begin(), hot.end(), [&](const auto& h) {
      return (h.first - alarm.anchor_m).squaredNorm() <= a2;
    });
    if (!still) alarm.cleared_s = time_s;
  }
}

void RiskLoop::Fill(MissionMetrics& metrics, double end_s) const {
  metrics.sensing = sensing();
  metrics.steered_on_posterior = steers();
  metrics.scans = scans_;
  if (sensing()) {
    // Weighted as a random leak's valve is drawn: by the run's profile's risk (maps::WithRandomLeaks).
    const std::vector<double> waits = scan_waits_.Waits(end_s);
    const maps::RiskProfile* profile = scenario_.FindProfile(metrics.profile);
    const Eigen::VectorXd weights =
        scenario_.ProfileWeights(profile != nullptr ? *profile : scenario_.ProfileOrThrow(""));
    double sum = 0.0, weight = 0.0;
    for (std::size_t v = 0; v < waits.size() && v < metrics.valves.size(); ++v) {
      metrics.valves[v].expected_detection_by_scans_s = waits[v];
      metrics.valves[v].seen_by_scans = scan_waits_.LookedAt(static_cast<int>(v));
      const double w = weights[static_cast<Eigen::Index>(v)];
      if (std::isnan(waits[v]) || !(w > 0.0)) continue;
      sum += w * waits[v];
      weight += w;
    }
    metrics.expected_detection_by_scans_s = weight > 0.0 ? sum / weight : std::numeric_limits<double>::quiet_NaN();
    metrics.leak_onsets_from_s = maps::kRandomLeakOnsetFrom * scenario_.duration_s;
    metrics.leak_onsets_to_s = std::min(maps::kRandomLeakOnsetTo * scenario_.duration_s, end_s);
  }
  metrics.leaks.clear();
  for (std::size_t k = 0; k < truth_.size(); ++k) {
    const maps::LeakSpec& spec = scenario_.leaks[k];
    LeakMetrics m;
    m.where = maps::LeakWhere(spec);
    m.position_m = truth_[k].position_m;
    m.valve = truth_[k].valve;
    m.start_s = spec.start_s;
    m.strength = spec.strength;
    // What happened by end_s (a partial metrics.json of a running mission reads the same loop).
    m.detected_s = leaks_[k].detected_s <= end_s ? leaks_[k].detected_s : kNotYet;
    m.confirmed_s = leaks_[k].confirmed_s <= end_s ? leaks_[k].confirmed_s : kNotYet;
    m.detections = leaks_[k].detections;
    // A rate over less than kLeastRateWindow_s says nothing (a detection 0.2 s before the end
    // with one visit read as 300 visits a minute, and swayed a bench's mean): none then.
    if (m.valve >= 0 && !std::isnan(m.detected_s) && end_s - m.detected_s >= kLeastRateWindow_s &&
        static_cast<std::size_t>(m.valve) < metrics.valves.size()) {
      const std::vector<double>& visits = metrics.valves[static_cast<std::size_t>(m.valve)].visit_times_s;
      const auto after = std::count_if(visits.begin(), visits.end(),
                                       [&](double t) { return t >= m.detected_s && t <= end_s; });
      m.visits_per_min_after_detection = 60.0 * static_cast<double>(after) / (end_s - m.detected_s);
    }
    metrics.leaks.push_back(m);
  }
  FalseAlarmMetrics& fa = metrics.false_alarms;
  fa = FalseAlarmMetrics{};
  fa.detections = false_detections_;
  double total_clear = 0.0, most = 0.0;
  for (const Alarm& alarm : alarms_) {
    if (alarm.leak >= 0 || alarm.raised_s > end_s) continue;
    ++fa.raised;
    fa.confirmed += alarm.confirmed ? 1 : 0;
    if (alarm.cleared_s >= 0.0 && alarm.cleared_s <= end_s) {
      ++fa.cleared;
      total_clear += alarm.cleared_s - alarm.raised_s;
      most = std::max(most, alarm.cleared_s - alarm.raised_s);
    }
  }
  if (fa.cleared > 0) {
    fa.mean_time_to_clear_s = total_clear / fa.cleared;
    fa.max_time_to_clear_s = most;
  }
}

RiskLoop::State RiskLoop::Checkpoint() const {
  State s;
  s.belief = belief_.Checkpoint();
  s.held = held_;
  s.last_fused = last_fused_;
  s.leaks = leaks_;
  s.alarms = alarms_;
  s.false_detections = false_detections_;
  s.scans = scans_;
  for (const auto& [key, v] : written_) s.written.emplace_back(KeyCell(key), v);
  std::sort(s.written.begin(), s.written.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  s.scan_waits = scan_waits_.Checkpoint();
  s.look_waits = look_waits_.Checkpoint();
  return s;
}

void RiskLoop::Restore(const State& s) {
  if (s.leaks.size() != truth_.size()) {
    throw std::invalid_argument(fmt::format("risk loop: {} leaks in the checkpoint, {} in the scenario", s.leaks.size(),
                                            truth_.size()));
  }
  belief_.Restore(s.belief);
  held_ = s.held;
  held_keys_.clear();
  for (const agents::ScanReport& scan : held_) held_keys_.insert({scan.id, scan.sensor, scan.cycle});
  last_fused_ = s.last_fused;
  leaks_ = s.leaks;
  alarms_ = s.alarms;
  false_detections_ = s.false_detections;
  scans_ = s.scans;
  written_.clear();
  for (const auto& [c, v] : s.written) written_[CellKey(c)] = v;
  scan_waits_.Restore(s.scan_waits);
  // A checkpoint of a build before the look planner holds none: U stays as if nothing had been
  // looked at since the start (the planner then looks everywhere first).
  if (!s.look_waits.last_look_s.empty() || look_waits_.valves() == 0) look_waits_.Restore(s.look_waits);
}

}  // namespace sage::server
