#include "server/mission_core.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "agents/tour_planner.h"
#include "maps/prefetch.h"
#include "maps/scenario/printable_text.h"

namespace sage::server {
namespace {

constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();  // a measure not (yet) known
// A host may run at most this far ahead of the server's clock (s of mission time): a state
// stamped later than that is not from this mission's clock.
constexpr double kMaxStateLead_s = 5.0;
// Ids an operator may reserve at once (sage vehicle add --count).
constexpr int kMaxIdsPerRequest = 10000;

// A vehicle's name as the record keeps it: printable, no field separators, never empty.
std::string SafeName(const std::string& name, int id) {
  // Printable UTF-8 (controls and stray bytes as '_'), at most 64 characters, no CSV separators.
  std::string out = maps::PrintableUtf8(name, 64, '_', "");
  std::replace_if(out.begin(), out.end(), [](char c) { return c == ',' || c == '"'; }, '_');
  const bool numeric = !out.empty() && out.find_first_not_of("0123456789") == std::string::npos;
  return out.empty() || numeric ? fmt::format("vehicle{}", id) : out;
}

// Who sent a refused report: the vehicle it names and, over DDS, the writer that sent it (a report
// can name any vehicle, but not another writer).
std::string SenderName(int vehicle_id, std::uint64_t writer) {
  return writer == 0 ? fmt::format("vehicle {}", vehicle_id) : fmt::format("vehicle {} (writer {:x})", vehicle_id, writer);
}

// The tours' and regions' notes on the vehicles held in reserve (more vehicles than valves): ""
// for none.
std::string ReserveNote(std::size_t reserve) {
  return reserve == 0 ? std::string()
                      : fmt::format("; {} vehicle(s) held in reserve (one vehicle a valve flies; a reserve takes a "
                                    "lost one's place)",
                                    reserve);
}

}  // namespace

const char* ToString(ControllerKind kind) { return kind == ControllerKind::kErgodic ? "ergodic" : "astar"; }

ControllerKind ParseControllerKind(const std::string& text) {
  if (text == "ergodic") return ControllerKind::kErgodic;
  if (text == "astar") return ControllerKind::kAstar;
  throw maps::ScenarioError("--controller = " + text + ": must be one of ergodic, astar");
}

double HeadingChange(const Eigen::Vector2d& before_mps, const Eigen::Vector2d& after_mps) {
  if (before_mps.norm() < 1e-12 || after_mps.norm() < 1e-12) return 0.0;
  return std::acos(std::clamp(before_mps.dot(after_mps) / (before_mps.norm() * after_mps.norm()), -1.0, 1.0));
}

int FirstFreeVehicleId(const maps::Scenario& scenario) {
  int joins = 0;
  for (const maps::FleetEvent& e : scenario.fleet_events) joins += e.kind == maps::FleetEvent::Kind::kJoin ? 1 : 0;
  return static_cast<int>(scenario.vehicles.size()) + joins;
}

int JoinVehicleId(const maps::Scenario& scenario, const std::string& name) {
  const int id = scenario.VehicleId(name);
  return id >= static_cast<int>(scenario.vehicles.size()) ? id : -1;
}

maps::VehicleSpec SpecForVehicle(const maps::Scenario& scenario, int id, const std::string& name) {
  if (id >= 0 && id < static_cast<int>(scenario.vehicles.size())) return scenario.vehicles[id];
  for (const maps::FleetEvent& e : scenario.fleet_events) {
    if (e.kind == maps::FleetEvent::Kind::kJoin && JoinVehicleId(scenario, e.vehicle.name) == id) return e.vehicle;
  }
  maps::VehicleSpec spec = scenario.vehicles.front();
  spec.name = name;
  return spec;
}

MissionCore::MissionCore(maps::World& world, const maps::Scenario& scenario, const std::string& profile,
                         ControllerKind controller, MissionRecorder* recorder)
    : world_(world),
      scenario_(scenario),
      controller_(controller),
      recorder_(recorder),
      fleet_(world, scenario, profile),
      layer_(maps::RiskLayer::OverWorld(world, maps::RiskLayerOptions::Fitting(scenario.workspace.width_m,
                                                                              scenario.workspace.height_m))),
      loop_(scenario, world, layer_),
      metrics_(scenario, world.basis(), world.risk(),
               MetricsOptions{ToString(controller), fleet_.profile().name}),
      roster_(FirstFreeVehicleId(scenario)) {
  fleet_.UseVisits(&metrics_.visits());
  metrics_.OnWeights(0.0, fleet_.schedule().front().weights);
  schedule_seen_ = 1;
}

bool MissionCore::OnState(const agents::StateReport& s, std::uint64_t writer) {
  const bool finite = s.state.position_m.allFinite() && s.state.velocity_mps.allFinite() &&
                      std::isfinite(s.state.heading_rad) && s.command_mps.allFinite() && std::isfinite(s.time_s);
  // A vehicle flies inside the workspace (a little beyond its edge at most): one reported a whole
  // workspace away from it is no vehicle of this mission (such a place, 1e154 m, had made the
  // tour plan's matching costs infinite).
  const bool on_field = finite && scenario_.workspace.Reaches(s.state.position_m);
  const Roster::Member* known = roster_.Find(s.id);
  const bool joins = known == nullptr || known->status != Roster::Status::kAlive;
  const char* refusal = !finite                                                      ? "state not finite"
                        : !on_field                                                    ? "state far outside the workspace"
                        : s.id < 0                                                     ? "state of no vehicle (id < 0)"
                        : s.id > kMaxVehicleId                                         ? "state of no vehicle (id too large)"
                        : s.time_s < 0.0                                               ? "state before the mission"
                        : s.time_s > std::max(time_s_, clock_s_) + kMaxStateLead_s ? "state ahead of the clock"
                        : joins && roster_.alive_count() >= Room()                     ? "state of a vehicle beyond the workspace's room"
                                                                                       : nullptr;
  if (refusal != nullptr) {
    rejected_.Count(refusal, SenderName(s.id, writer));
    return false;
  }
  if (joins) {
    // Names reach logs and CSV files: made safe, and unique (another vehicle's name gets its id).
    std::string name = known != nullptr ? known->name : SafeName(s.name, s.id);
    if (known == nullptr && roster_.NameTaken(name)) name = fmt::format("{}#{}", name, s.id);
    const FleetEventRecord* joined = roster_.Join(s.id, name, next_time_s());
    fleet_.AddVehicle(s.id, name);
    Record(joined);
  }
  Roster::Member& m = *roster_.Find(s.id);
  if (m.has_state && s.cycle <= m.last.cycle) return false;  // seen already (or older)
  if (m.has_state) {
    // A risk event's heading change: the first command steered on a target that carries the
    // event, against the command before it.
    std::erase_if(pending_heading_changes_, [&](const PendingHeadingChange& p) {
      if (p.vehicle_id != s.id || s.target_cycle < p.cycle) return false;
      if (m.last.target_cycle < p.cycle) {
        fleet_.responses()[p.response].heading_change_rad = HeadingChange(m.last.command_mps, s.command_mps);
      }
      return true;
    });
  }
  m.last = s;
  m.has_state = true;
  roster_.Heard(m);
  fleet_.SetPosition(s.id, s.state.position_m);
  if (s.time_s <= scenario_.duration_s + 1e-9) {
    samples_.push_back({s.time_s, m.index, s.state.position_m, s.state.heading_rad, s.state.velocity_mps, s.command_mps});
  }
  return true;
}

void MissionCore::PrefetchVehicle(int id) const {
  maps::PrefetchObject(roster_.Find(id));
  fleet_.PrefetchVehicle(id);
}

void MissionCore::OnVehicleGone(int id, bool lost) {
  const FleetEventRecord* event = roster_.Leave(id, lost, next_time_s());
  if (event == nullptr) return;
  RecordSamples();  // its last samples go into the record before it leaves
  // Its answer to a pending risk event never comes: that heading change stays unknown (NaN).
  std::erase_if(pending_heading_changes_, [&](const PendingHeadingChange& p) { return p.vehicle_id == id; });
  fleet_.RemoveVehicle(id, lost, next_time_s());
  metrics_.Retire(roster_.Find(id)->index);
  Record(event);
}

bool MissionCore::OnCoverage(const agents::CoverageMessage& c, std::uint64_t writer) {
  const maps::CoverageReport& r = c.report;
  const char* refusal =
      !r.sums.allFinite() || !std::isfinite(r.kernel_time_s) || !std::isfinite(r.stamp_s) ? "coverage not finite"
      : r.kernel_time_s < 0.0                                                            ? "coverage of negative time"
      : r.stamp_s > std::max(time_s_, clock_s_) + kMaxStateLead_s                     ? "coverage ahead of the clock"
                                                                                         : nullptr;
  if (refusal != nullptr) {
    rejected_.Count(refusal, SenderName(c.id, writer));
    return false;
  }
  return fleet_.OnCoverage(c.id, r.seq, r.stamp_s, r.kernel_time_s, r.sums);
}

bool MissionCore::OnScan(const agents::ScanReport& scan) {
  if (!loop_.sensing()) {
    rejected_.Count("scan in a mission without sensors", fmt::format("vehicle {}", scan.id));
    return false;
  }
  if (const char* refusal = loop_.Take(scan, std::max(time_s_, clock_s_))) {
    rejected_.Count(refusal, fmt::format("vehicle {}", scan.id));
    return false;
  }
  return true;
}

OperatorAnswer MissionCore::OnRiskUpdate(const std::string& valve, double weight, const std::string& source,
                                         const std::string& sender) {
  if (!risk_limits_.Allow(sender.empty() ? source : sender, next_time_s())) {
    OperatorAnswer answer;
    answer.reason = fmt::format("rate limit: at most {:.0f} risk updates at once, then {:.0f} a second, per sender",
                                kRiskUpdateBurst, kRiskUpdatesPerSecond);
    return answer;
  }
  return ApplyRiskUpdate(valve, weight, source);
}

OperatorAnswer MissionCore::ApplyRiskUpdate(const std::string& valve, double weight, const std::string& source) {
  OperatorAnswer answer;
  try {
    fleet_.SetRiskWeight(valve, weight, next_time_s(), source);
    answer.accepted = true;
    answer.new_share = fleet_.responses().back().new_weight;
    // Recorded now with its source; the heading change is measured when the cycle sends it.
    if (recorder_ != nullptr) {
      recorder_->OnRiskEvent({fleet_.responses().back().time_s, valve, weight, answer.new_share, source});
    }
    risk_recorded_ = fleet_.responses().size();
  } catch (const maps::ScenarioError& e) {  // an operator's message never ends the mission
    answer.reason = e.what();
  }
  return answer;
}

OperatorAnswer MissionCore::RemoveRequest(int id) const {
  OperatorAnswer answer;
  const Roster::Member* m = roster_.Find(id);
  if (m == nullptr) {
    answer.reason = fmt::format("no vehicle with id {} in this mission (ids 0..{} have been used)", id,
                                roster_.next_id() - 1);
  } else if (m->status != Roster::Status::kAlive) {
    answer.reason = fmt::format("{} (id {}) {} at t = {:.1f} s", m->name, id,
                                m->status == Roster::Status::kLost ? "was lost" : "already left", m->gone_s);
  } else if (roster_.alive_count() <= 1) {
    answer.reason = fmt::format("{} (id {}) is the mission's last vehicle; stop the mission instead (sage stop)",
                                m->name, id);
  } else {
    answer.accepted = true;
  }
  return answer;
}

OperatorAnswer MissionCore::ReserveIds(int count) {
  OperatorAnswer answer;
  if (count < 1 || count > kMaxIdsPerRequest) {
    answer.reason = fmt::format("count = {}: must be in 1..{}", count, kMaxIdsPerRequest);
    return answer;
  }
  // The fleet must still fit the workspace as a scenario's must (maps::kMinAreaPerBlueRov2_m2):
  // a probe's `sage vehicle add --count 100000` on a 12 x 9.5 m field had taken the server to 20 GB.
  const std::size_t room = Room();
  const std::size_t alive = roster_.alive_count();
  if (alive + static_cast<std::size_t>(count) > room) {
    answer.reason = fmt::format("count = {}: the {} x {} m workspace holds {} vehicles ({} m^2 each) and {} {} in the mission",
                                count, scenario_.workspace.width_m, scenario_.workspace.height_m, room,
                                maps::kMinAreaPerBlueRov2_m2, alive, alive == 1 ? "is" : "are");
    return answer;
  }
  if (roster_.next_id() > kMaxVehicleId + 1 - count) {
    answer.reason = fmt::format("count = {}: the mission has issued ids up to {} of 0..{}", count, roster_.next_id() - 1,
                                kMaxVehicleId);
    return answer;
  }
  answer.accepted = true;
  answer.first_id = roster_.ReserveIds(count);
  return answer;
}

std::size_t MissionCore::Room() const {
  const double area_m2 = scenario_.workspace.width_m * scenario_.workspace.height_m;
  const auto bluerov2s = static_cast<std::size_t>(std::floor(area_m2 / maps::kMinAreaPerBlueRov2_m2));
  // A scenario of point vehicles may hold more than BlueROV2s would; its own fleet always fits.
  return std::max(bluerov2s, static_cast<std::size_t>(FirstFreeVehicleId(scenario_)));
}

void MissionCore::Record(const FleetEventRecord* event) {
  if (event != nullptr && recorder_ != nullptr) recorder_->OnFleetEvent(*event);
}

void MissionCore::Note(const std::string& what, const std::string& detail) {
  Record(roster_.Note(std::max(time_s_, 0.0), what, detail));
}

double MissionCore::next_time_s() const {
  return static_cast<double>(cycle_ + 1) / scenario_.control_rate_hz;
}

// The states received since the last cycle go into the record and the metrics in (time,
// vehicle index) order, whatever order the transport delivered them in.
void MissionCore::RecordSamples() {
  std::stable_sort(samples_.begin(), samples_.end(), [](const TrajectorySample& a, const TrajectorySample& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.vehicle < b.vehicle;
  });
  // Visits now (the guard and the targets below read them); the metric's share on a helper thread
  // while this cycle goes on, settled at its end (AccountMetrics).
  metrics_.AddCycle(samples_);
  if (recorder_ != nullptr && !samples_.empty()) {
    recorder_->OnSamples(samples_, roster_.names_by_index());
  }
  samples_.clear();
}

CycleOutput MissionCore::Cycle(std::int64_t cycle) {
  cycle_ = cycle;
  time_s_ = static_cast<double>(cycle) / scenario_.control_rate_hz;
  RecordSamples();

  // The Bayesian loop (no-op without sensors): this cycle's scans into the belief, its evidence
  // into the weights and the layer the vehicles steer on.
  loop_.Fuse(cycle, time_s_, roster_, rejected_);
  if (loop_.steers()) fleet_.SetWeightFactors(loop_.ValveFactors(time_s_));
  CycleOutput out;
  out.risk_events = fleet_.Cycle(time_s_);
  const std::int64_t leaves_before = layer_.nonzero_leaves();
  const double mass_before = layer_.excess_mass();
  loop_.UpdateLayer(time_s_);
  layer_changed_ = layer_.nonzero_leaves() != leaves_before || layer_.excess_mass() != mass_before;
  // The profile's events of this cycle (operators' were recorded as they came).
  for (; risk_recorded_ < fleet_.responses().size(); ++risk_recorded_) {
    const EventResponse& r = fleet_.responses()[risk_recorded_];
    if (recorder_ != nullptr) {
      recorder_->OnRiskEvent({r.time_s, r.valve, fleet_.raw_weights()[scenario_.ValveIndex(r.valve)], r.new_weight,
                              "scenario"});
    }
  }
  // Every risk change since the last cycle (operators' and the profile's) is measured on the
  // first live vehicle: unknown (NaN, null in metrics.json) until its answer arrives.
  const std::uint64_t snapshot_cycle = static_cast<std::uint64_t>(cycle) + 1;
  const std::vector<int>& alive = roster_.alive();
  const bool risk_changed = fleet_.responses().size() > risk_measured_;
  for (; risk_measured_ < fleet_.responses().size(); ++risk_measured_) {
    const EventResponse& response = fleet_.responses()[risk_measured_];
    metrics_.WatchVisits(scenario_.ValveIndex(response.valve), response.time_s);  // how it was answered
    fleet_.responses()[risk_measured_].heading_change_rad = kUnknown;
    if (!alive.empty()) pending_heading_changes_.push_back({risk_measured_, snapshot_cycle, alive.front()});
  }

  out.snapshot.cycle = snapshot_cycle;
  // Only shared coverage (and a partition's vehicle without valves) steers on the field's phi_k;
  // regions and tours leave it out (at 35,000 valves it is 143 Mflop a cycle, 32 kB a host).
  const bool field_phi = controller_ == ControllerKind::kErgodic &&
                         scenario_.fleet.assignment != maps::FleetAssignment::kRegions;
  if (field_phi) out.snapshot.phi = layer_.coefficients();  // the field's phi_k itself while no leaf is raised
  out.snapshot.coverage = fleet_.coverage();
  // What tours split their waits by; the ergodic fleet does not read it. Worked out again only
  // when the risk changes: at 35,000 valves the power of every weight was a millisecond a cycle.
  if (controller_ == ControllerKind::kAstar) {
    if (tour_weights_for_ != fleet_.schedule().size()) {
      tour_weights_ = fleet_.schedule().back().weights.array().pow(scenario_.astar.weight_exponent);
      tour_weights_for_ = fleet_.schedule().size();
    }
    out.snapshot.valve_weights = tour_weights_;
  }

  if (controller_ == ControllerKind::kAstar) {
    AssignTours(alive, risk_changed, out);
  } else if (scenario_.fleet.assignment == maps::FleetAssignment::kRegions) {
    AssignRegions(alive, out);
  } else {
    AssignTargets(alive, risk_changed, out);
  }
  out.fleet_empty = alive.empty();
  if (out.fleet_empty && !empty_noted_ && !roster_.members().empty()) {
    Note("empty", "no vehicle is alive in the mission");
  }
  empty_noted_ = out.fleet_empty;
  AccountMetrics();
  return out;
}

// The cycle's weights and checkpoints into the metrics, after the samples' holds (AddCycle's
// helper, waited for here): last in the cycle, so that the helper ran beside the rest of it.
void MissionCore::AccountMetrics() {
  for (; schedule_seen_ < fleet_.schedule().size(); ++schedule_seen_) {
    const WeightChange& change = fleet_.schedule()[schedule_seen_];
    metrics_.OnWeights(change.time_s, change.weights);
  }
  metrics_.Advance(time_s_);
}

// A partition target is the vehicle's share weighted by the current risk: sent again when the
// shares change and when the risk does (an update, a profile event, the guard), and after any
// risk event (its heading change waits for a command steered on this cycle's target or later).
// In shared coverage a vehicle's assignment is sent once, when it joins.
void MissionCore::AssignTargets(const std::vector<int>& alive, bool risk_changed, CycleOutput& out) {
  const bool partition = scenario_.fleet.assignment == maps::FleetAssignment::kPartition;
  const Eigen::VectorXd& weights = fleet_.effective_weights();
  const bool reweighted = weights.size() != last_weights_.size() ||
                          (weights.size() > 0 && (weights - last_weights_).cwiseAbs().maxCoeff() > 0.0);
  const bool reassigned =
      partition && (fleet_.assignment() != last_assignment_ || reweighted || risk_changed || layer_changed_);
  if (reassigned) {
    last_assignment_ = fleet_.assignment();
    last_weights_ = weights;
  }
  for (int id : alive) {
    Roster::Member& m = *roster_.Find(id);
    if (m.target_sent && !reassigned) continue;
    agents::Assignment a;
    a.id = id;
    a.cycle = out.snapshot.cycle;
    a.phi = partition ? ShareOfLayer(id) : Eigen::VectorXd();
    a.shared = a.phi.size() == 0;
    out.assignments.push_back(std::move(a));
    m.target_sent = true;
  }
}

// The fleet's tours, as an operator flies them: planned once every starting vehicle is in (or
// 2 s after the first), and planned again replan_delay_s after a vehicle joins, is lost or
// leaves, or a risk changes; meanwhile the old tours are flown (a lost vehicle's valves wait for
// the re-plan, a new vehicle holds station). Waits within a tour follow risk changes at once,
// from each tour's next lap (the snapshot's weights). On a field of 1,000 valves or more a plan
// is made on a thread of its own and taken when due (RegionSplitDelayCycles, as the regions'
// split), the fleet flying its old tours meanwhile, or at the start each valve's nearest vehicle's
// (QuickFleetTours): the 10,000-vehicle field's first plan had taken 9-14 s in one server cycle.
void MissionCore::AssignTours(const std::vector<int>& alive, bool risk_changed, CycleOutput& out) {
  constexpr double kFirstPlanWait_s = 2.0;
  TourPlan& plan = tour_plan_;
  if (plan.pending && cycle_ >= plan.pending->due_cycle()) {
    TakeTours(plan.pending->Take(), plan.pending_for, time_s_ - plan.pending_started_s, out);
    plan.pending.reset();
  }
  if (alive.empty()) return;
  if (plan.first_join_s < 0.0) plan.first_join_s = time_s_;
  if (plan.planned && (alive != plan.planned_for || risk_changed) && plan.change_s < 0.0) plan.change_s = time_s_;
  const bool due =
      !plan.pending && (plan.planned ? plan.change_s >= 0.0 && time_s_ - plan.change_s >= scenario_.astar.replan_delay_s - 1e-9
                                     : alive.size() >= scenario_.vehicles.size() || time_s_ - plan.first_join_s >= kFirstPlanWait_s);
  if (due) {
    plan.planned = true;
    plan.planned_for = alive;
    plan.change_s = -1.0;
    const std::int64_t delay = RegionSplitDelayCycles(scenario_.ValvePositions().size(), scenario_.control_rate_hz);
    if (delay == 0) {
      TakeTours(PlanShares(alive, scenario_.astar.weight_exponent), alive, 0.0, out);
    } else {
      // The fleet as it is now, copied for the planning thread (the grid and scenario are fixed).
      const bool first = plan.tours.empty();
      std::vector<agents::FleetVehicle> vehicles = FleetVehicles(alive);
      Eigen::VectorXd weights = fleet_.schedule().back().weights;
      if (first) TakeTours(QuickFleetTours(scenario_, vehicles, weights, scenario_.astar.weight_exponent), alive, -1.0, out);
      agents::FleetTourOptions options = TourOptions(scenario_.astar.weight_exponent);
      // The hosts plan their own legs: without them (a third of the 10,000-vehicle field's plan)
      // each lap is priced on the search's grid distances, at most 8.2 % above the flown legs.
      options.legs = false;
      plan.pending = std::make_unique<PendingPlan<agents::FleetTourPlan>>(
          [&grid = world_.astar_grid(), valves = scenario_.ValvePositions(), weights = std::move(weights),
           vehicles = std::move(vehicles), wait_s = scenario_.astar.wait_per_lap_s,
           options](const std::atomic<bool>* cancel) mutable {
            options.cancel = cancel;
            return agents::PlanFleetTours(grid, valves, weights, vehicles, wait_s, options);
          },
          cycle_ + delay, true);
      plan.pending_for = alive;
      plan.pending_started_s = time_s_;
    }
  }
  if (scenario_.astar.order == maps::AstarSettings::Order::kLooks) ChooseLooks(alive, out.snapshot.cycle);
  for (int id : alive) {
    Roster::Member& m = *roster_.Find(id);
    const auto tour = plan.tours.find(id);
    if (m.target_sent || tour == plan.tours.end()) continue;
    out.assignments.push_back(tour->second);
    m.target_sent = true;
  }
}

// Tours take effect: each vehicle they were planned for (planned_for, in the plan's order) gets
// its own, sent on this cycle (a vehicle gone meanwhile leaves its valves unflown until the next
// plan). planning_s: how long the plan took in mission time (0 within the cycle, < 0 provisional).
void MissionCore::TakeTours(const agents::FleetTourPlan& tours, const std::vector<int>& planned_for, double planning_s,
                            const CycleOutput& out) {
  TourPlan& plan = tour_plan_;
  plan.tours.clear();
  for (std::size_t k = 0; k < planned_for.size(); ++k) {
    const agents::VehicleTour& v = tours.vehicles[k];
    agents::Assignment a;
    a.id = planned_for[k];
    a.cycle = out.snapshot.cycle;
    a.shared = false;
    for (int i : v.tour.order) a.tour.push_back(v.valves[i]);
    std::vector<int>& share = plan.shares[a.id];
    share = a.tour;
    std::sort(share.begin(), share.end());
    a.tour_weights.resize(static_cast<Eigen::Index>(v.tour.order.size()));
    for (std::size_t i = 0; i < v.tour.order.size(); ++i) a.tour_weights[static_cast<Eigen::Index>(i)] = v.weights[v.tour.order[i]];
    plan.tours[a.id] = std::move(a);
    if (Roster::Member* m = roster_.Find(planned_for[k])) m->target_sent = false;
  }
  const std::string how = planning_s < 0.0 ? " (provisional: each valve to its nearest vehicle while the tours are planned)"
                          : planning_s > 0.0 ? fmt::format(", planned over {:.1f} s (laps on grid distances)", planning_s)
                                             : std::string();
  // A vehicle in reserve (more vehicles than valves) gets an empty tour: it holds out of the valves' way.
  const std::size_t flown = tours.vehicles.size() - static_cast<std::size_t>(tours.reserve);
  Note("tours", fmt::format("{} tour{} planned for {} vehicle{}{}: laps {:.1f} s at most, {:.1f} s on average{}{}",
                            flown, flown == 1 ? "" : "s", planned_for.size(), planned_for.size() == 1 ? "" : "s", how,
                            tours.max_lap_s, tours.mean_lap_s, ReserveNote(static_cast<std::size_t>(tours.reserve)),
                            tours.ok ? "" : " (some leg has no path)"));
}

// A share of more valves than this flies its shortest tour: the planner's n (n - 1) legs and its
// search (depth 4 at 12 valves) grow beyond a cycle's time.
constexpr std::size_t kMaxLookShare = 12;

// The look planner's turn: a vehicle that has reached the valve it flies to (within the visit
// radius, or as near as the grid lets it stand), or has not within twice the leg's time and 10 s
// more, gets the next valves of its share chosen on the scans fused so far: U from the risk loop,
// and each valve's weight its risk (the profile's, normalised) plus the chance of a leak there
// the scans give. Its tour is then that sequence (the last valve back to the first if nothing
// new comes), sent this cycle.
void MissionCore::ChooseLooks(const std::vector<int>& alive, std::uint64_t cycle) {
  TourPlan& plan = tour_plan_;
  const std::vector<maps::SensorModel>& sensors = loop_.belief().sensors();
  if (sensors.empty()) return;
  if (look_valve_positions_.empty()) look_valve_positions_ = scenario_.ValvePositions();
  const std::vector<Eigen::Vector2d>& positions = look_valve_positions_;
  const Eigen::VectorXd& risk = fleet_.schedule().back().weights;
  // What the scans say, worked out at the first plan of the cycle (most cycles plan none).
  std::optional<Eigen::VectorXd> undetected, leak;
  // The longest-reaching sensor: the camera a tour vehicle turns to the valves.
  const maps::SensorModel* sensor = &sensors.front();
  for (const maps::SensorModel& m : sensors) {
    if (m.spec().range_m > sensor->spec().range_m) sensor = &m;
  }
  const double risk_sum = risk.sum() > 0.0 ? risk.sum() : 1.0;
  bool built = false;  // one planner a cycle: a share's n (n - 1) A* legs take time
  int too_large = 0;
  for (int id : alive) {
    const auto share = plan.shares.find(id);
    const auto tour = plan.tours.find(id);
    Roster::Member* m = roster_.Find(id);
    if (share == plan.shares.end() || tour == plan.tours.end() || m == nullptr || !m->has_state || share->second.empty()) continue;
    LookTour& look = looks_[id];
    const maps::VehicleSpec spec = SpecForVehicle(scenario_, id, m->name);
    if (share->second.size() > kMaxLookShare) {
      // It flies its share's shortest tour (TakeTours'), said once a split.
      if (look.valves != share->second) ++too_large;
      look = LookTour{};
      look.valves = share->second;
      continue;
    }
    if (look.valves != share->second || !look.planner) {
      if (built) continue;  // next cycle; meanwhile the tour it has
      built = true;
      look.valves = share->second;
      std::vector<Eigen::Vector2d> at;
      look.reach_m.clear();
      for (int v : look.valves) {
        at.push_back(positions[static_cast<std::size_t>(v)]);
        const std::vector<Eigen::Vector2d> stand = agents::PlanGridPath(world_.astar_grid(), at.back(), at.back());
        const double off = stand.empty() ? 0.0 : (stand.front() - at.back()).norm();
        look.reach_m.push_back(off + 0.15);
      }
      look.planner = std::make_unique<agents::LookPlanner>(world_.astar_grid(), std::move(at), *sensor, spec.transit_speed_mps);
      look.target = -1;
    } else if (look.target >= 0 && tour->second.tour != look.sent) {
      // The shares were planned again with the same valves: it keeps flying its looks.
      tour->second.tour = look.sent;
      tour->second.tour_weights = look.sent_weights;
    }
    const auto send = [&](std::vector<int> valves, Eigen::VectorXd waits) {
      look.sent = valves;
      look.sent_weights = waits;
      tour->second.tour = std::move(valves);
      tour->second.tour_weights = std::move(waits);
      tour->second.cycle = cycle;
      m->target_sent = false;
    };
    const Eigen::Vector2d x = m->last.state.position_m;
    int from = -1;
    if (look.target < 0 || time_s_ >= look.due_s) {
      if (look.target >= 0) {
        // Held on the way (a structure's corner, a neighbour): not that valve first again for a
        // minute, or the same leg brings it back to the same corner (a reviewer saw 27 s twice).
        look.missed = look.target;
        look.missed_until_s = time_s_ + 60.0;
      }
      // From the share's valve nearest to where it is.
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < look.valves.size(); ++k) {
        const double d = (positions[static_cast<std::size_t>(look.valves[k])] - x).norm();
        if (d < best) {
          best = d;
          from = static_cast<int>(k);
        }
      }
      if (look.target < 0) {
        look.target = from;
        look.due_s = time_s_ + 10.0 + 2.0 * (positions[static_cast<std::size_t>(look.valves[static_cast<std::size_t>(from)])] - x).norm() / spec.transit_speed_mps;
        send({look.valves[static_cast<std::size_t>(look.target)]}, Eigen::VectorXd::Ones(1));
        continue;
      }
    } else if ((positions[static_cast<std::size_t>(look.valves[static_cast<std::size_t>(look.target)])] - x).norm() <=
               look.reach_m[static_cast<std::size_t>(look.target)]) {
      from = look.target;
    }
    if (from < 0) continue;
    if (!undetected) {
      undetected = loop_.Undetected(time_s_);
      leak = loop_.ValveLeakProbabilities(time_s_);
    }
    const auto n = static_cast<Eigen::Index>(look.valves.size());
    Eigen::VectorXd u(n), w(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const auto v = static_cast<Eigen::Index>(look.valves[static_cast<std::size_t>(k)]);
      u[k] = undetected->size() > v ? (*undetected)[v] : 0.0;
      w[k] = std::pow(risk[v] / risk_sum, scenario_.astar.look_exponent) +
             scenario_.astar.look_leak_weight * (leak->size() > v ? (*leak)[v] : 0.0);
    }
    const std::vector<int> next = look.planner->Plan(from, u, w, time_s_ < look.missed_until_s ? look.missed : -1);
    look.target = next.front();
    const double leg_s = look.planner->leg(from, look.target).duration_s;
    look.due_s = time_s_ + 10.0 + 2.0 * (std::isfinite(leg_s) ? leg_s : 0.0);
    // The tour starts at the valve it has reached, so that it flies the very legs the planner
    // priced (a path planned from beside the valve may pass a structure on the other side).
    std::vector<int> sequence{look.valves[static_cast<std::size_t>(from)]};
    for (int k : next) sequence.push_back(look.valves[static_cast<std::size_t>(k)]);
    if (sequence == look.sent) continue;  // a share of one valve: nothing new to send
    Eigen::VectorXd waits = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(sequence.size()));
    waits[0] = 0.0;  // no wait where it already is
    send(std::move(sequence), std::move(waits));
  }
  if (too_large > 0) {
    Note("looks", fmt::format("{} {} the shortest tour of {} share: more than {} valves for the look planner", too_large,
                              too_large == 1 ? "vehicle flies" : "vehicles fly", too_large == 1 ? "its" : "their",
                              kMaxLookShare));
  }
}

std::vector<agents::FleetVehicle> MissionCore::FleetVehicles(const std::vector<int>& alive) const {
  std::vector<agents::FleetVehicle> vehicles;
  vehicles.reserve(alive.size());
  for (int id : alive) {
    const Roster::Member& m = *roster_.Find(id);
    const maps::VehicleSpec spec = SpecForVehicle(scenario_, id, m.name);
    vehicles.push_back({m.has_state ? m.last.state.position_m : spec.start_m, spec.transit_speed_mps});
  }
  return vehicles;
}

agents::FleetTourOptions MissionCore::TourOptions(double weight_exponent) const {
  agents::FleetTourOptions options;
  options.seed = scenario_.seed;
  options.weight_exponent = weight_exponent;
  return options;
}

agents::FleetTourPlan MissionCore::PlanShares(const std::vector<int>& alive, double weight_exponent) const {
  const std::vector<agents::FleetVehicle> vehicles = FleetVehicles(alive);
  return agents::PlanFleetTours(world_.astar_grid(), scenario_.ValvePositions(), fleet_.schedule().back().weights,
                                vehicles, scenario_.astar.wait_per_lap_s, TourOptions(weight_exponent));
}

Eigen::VectorXd MissionCore::ShareOfLayer(int id) const {
  Eigen::VectorXd phi = fleet_.ShareOf(id);
  if (phi.size() == 0 || layer_.nonzero_leaves() == 0) return phi;
  // The share's leaves: those whose nearest valve is one of its valves.
  const std::vector<int>& mine = fleet_.vehicles().at(id).valves;
  const std::vector<Eigen::Vector2d> valves = scenario_.ValvePositions();
  const auto nearest_is_mine = [&](const Eigen::Vector2d& x) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < valves.size(); ++i)
      if ((valves[i] - x).squaredNorm() < (valves[best] - x).squaredNorm()) best = i;
    return std::find(mine.begin(), mine.end(), static_cast<int>(best)) != mine.end();
  };
  double mass = 0.0;
  const Eigen::VectorXd excess = layer_.ExcessOn(world_.basis(), Eigen::Vector2d::Zero(), nearest_is_mine, mass);
  if (mass == 0.0) return phi;
  // The share's phi holds mass 1 for its valves' weight W of the field's; the excess is in the
  // field's units (the valves' prior holds 1).
  double own = 0.0;
  for (int i : mine) own += fleet_.effective_weights()[i];
  return (own * phi + excess) / (own + mass);
}

// The share of the field's current risk (the operators' and the profile's weights) these valves hold.
double MissionCore::RiskMass(const std::vector<int>& valves) const {
  const Eigen::VectorXd& w = fleet_.schedule().back().weights;
  double mass = 0.0;
  for (int i : valves) mass += w[i];
  return mass / w.sum();
}

// A split of the field into regions takes effect: each vehicle it was planned for gets its
// share (a vehicle gone meanwhile leaves its share unflown until the next split), the guard
// watches each valve against its share's lap, and the split goes into the record.
void MissionCore::TakeSplit(RegionSplit split) {
  // Measured against 2.5 (shorter worst gaps, the same revisit intervals) and, with the final
  // approach, against 2: on seventeen generated fields the longest gap 1.03-1.87x the tours'
  // against 1.03-2.11x, on three fields not tuned to 1.14-1.70x against 1.47-1.99x, for a
  // risk-weighted interval 1-3 % longer (0.69-0.87x the tours' against 0.66-0.85x).
  constexpr double kGuardLaps = 1.5;
  RegionPlan& plan = region_plan_;
  const std::vector<maps::Valve> valves = scenario_.AllValves();
  plan.shares.clear();
  std::vector<RegionRecord> records;
  std::size_t most = 0;
  double largest = 0.0;
  Eigen::VectorXd bounds = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(valves.size()), scenario_.guard.revisit_bound_s);
  plan.reserve.clear();
  for (std::size_t k = 0; k < split.regions.size(); ++k) {
    PlannedRegion& region = split.regions[k];
    const int id = split.input.vehicle_ids[k];
    if (region.valves.empty()) {  // in reserve: more vehicles than valves
      plan.reserve.push_back(id);
      if (Roster::Member* m = roster_.Find(id)) m->target_sent = false;
      continue;
    }
    RegionShare share;
    share.valves = std::move(region.valves);
    share.lap_time_s = region.lap_time_s;
    share.split_mass = RiskMass(share.valves);
    share.field = std::move(region.field);
    const Roster::Member* member = roster_.Find(id);
    RegionRecord record{id, member != nullptr ? member->name : std::string(), share.field->box(), {}};
    for (int i : share.valves) {
      record.valves.push_back(valves[i].name);
      // No valve waits longer than kGuardLaps laps of the tour its vehicle could fly instead
      // (nor the scenario's bound).
      bounds[i] = std::min(bounds[i], kGuardLaps * share.lap_time_s);
    }
    records.push_back(std::move(record));
    most = std::max(most, share.valves.size());
    largest = std::max(largest, share.field->box().size_m.maxCoeff());
    plan.shares.emplace_back(id, std::move(share));
  }
  std::sort(plan.shares.begin(), plan.shares.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  plan.walk_valves.clear();
  for (auto& [id, share] : plan.shares) {
    share.walk_at = plan.walk_valves.size();
    plan.walk_valves.insert(plan.walk_valves.end(), share.valves.begin(), share.valves.end());
  }
  plan.walk_sent.assign(plan.walk_valves.size(), 0.0);
  plan.planned_for = split.input.vehicle_ids;
  plan.risk_seen = plan.pending_risk_seen;
  fleet_.SetRevisitBounds(bounds);
  if (recorder_ != nullptr) recorder_->OnRegions(time_s_, records);
  const double planning_s = time_s_ - plan.pending_started_s;
  const std::string boost = std::lround(bounds.minCoeff()) == std::lround(bounds.maxCoeff())
                                ? fmt::format("{:.0f} s", bounds.minCoeff())
                                : fmt::format("{:.0f}-{:.0f} s", bounds.minCoeff(), bounds.maxCoeff());
  Note("regions", fmt::format("{} region{} for {} vehicle{}{}{}: up to {} valve{} and {:.1f} m a side each; the guard "
                              "boosts a valve after {}{}",
                              plan.shares.size(), plan.shares.size() == 1 ? "" : "s", split.input.vehicle_ids.size(),
                              split.input.vehicle_ids.size() == 1 ? "" : "s",
                              split.provisional ? " (provisional: each valve to its nearest vehicle while the split is planned)"
                              : split.input.by_risk ? " (the risk moved)" : "",
                              planning_s > 0.0 ? fmt::format(", planned over {:.1f} s", planning_s) : std::string(),
                              most, most == 1 ? "" : "s", largest, boost, ReserveNote(plan.reserve.size())));
}

// Regions: the live vehicles split the valves as the fleet's tours would (balanced on travel),
// each share a box of its own with its own basis; a vehicle steers alone on its share's risk
// there. The first split waits for the fleet to be in (every starting vehicle, or 2 s); then a
// vehicle joining, lost or leaving re-apportions the field as soon as the fleet has held still
// for half a second (a host's vehicles join over a few cycles); a risk change (or the guard)
// re-sends the shares' phi, the boxes stay. A field of 1,000 valves or more is split in the
// background and the split taken when due (region_split.h), the fleet flying on meanwhile.
void MissionCore::AssignRegions(const std::vector<int>& alive, CycleOutput& out) {
  constexpr double kFirstPlanWait_s = 2.0, kSettle_s = 0.5;
  // A target goes again when the layer's excess in its box moved by more than this share of its mass.
  constexpr double kSameProportionOfExcess = 0.05;
  RegionPlan& plan = region_plan_;
  if (plan.pending && cycle_ >= plan.pending->due_cycle()) {
    TakeSplit(plan.pending->Take());
    plan.pending.reset();
  }
  if (alive.empty()) return;
  if (plan.first_join_s < 0.0) plan.first_join_s = time_s_;
  if (alive != plan.last_seen) {
    plan.last_seen = alive;
    plan.changed_s = time_s_;
  }
  bool replan =
      !plan.pending && alive != plan.planned_for &&
      (plan.planned_for.empty() ? alive.size() >= scenario_.vehicles.size() || time_s_ - plan.first_join_s >= kFirstPlanWait_s
                                : time_s_ - plan.changed_s >= kSettle_s - 1e-9);
  // Split by risk (fleet.risk_share > 0): a leak, or an operator's risk change, that moves some
  // region's share of the field's risk by more than kResplitRatio either way splits the field
  // again on the next cycle; smaller changes only re-weight the regions' targets (hysteresis).
  constexpr double kResplitRatio = 1.5;
  bool by_risk = false;
  if (!replan && !plan.pending && scenario_.fleet.risk_share > 0.0 && !plan.shares.empty() &&
      fleet_.schedule().size() > plan.risk_seen) {
    plan.risk_seen = fleet_.schedule().size();
    for (const auto& [id, share] : plan.shares) {
      const double ratio = (RiskMass(share.valves) + 1e-12) / (share.split_mass + 1e-12);
      if (ratio > kResplitRatio || ratio < 1.0 / kResplitRatio) {
        replan = by_risk = true;
        break;  // one share moved is enough: the whole field is split again
      }
    }
  }
  if (replan) {
    // Planned now from the fleet as it is; taken at once on a small field, on a large one when
    // its plan is due (RegionSplitDelayCycles) while the fleet flies its old regions on.
    RegionSplitInput input{alive, FleetVehicles(alive), fleet_.schedule().back().weights, scenario_.fleet.risk_share, by_risk};
    const std::int64_t delay = RegionSplitDelayCycles(scenario_.ValvePositions().size(), scenario_.control_rate_hz);
    // The first split of a large field: each valve to its nearest vehicle until it is due, not
    // the field's shared basis (region_split.h); made before the planning thread starts, so that
    // its two threads have the cores.
    std::optional<RegionSplit> provisional;
    if (delay > 0 && plan.shares.empty()) provisional = QuickRegionSplit(world_.blocked(), scenario_, input);
    plan.pending = std::make_unique<PendingRegionSplit>(world_.astar_grid(), world_.blocked(), scenario_, std::move(input),
                                                        cycle_ + delay, delay > 0);
    plan.pending_started_s = time_s_;
    plan.pending_risk_seen = fleet_.schedule().size();
    if (delay == 0) {
      TakeSplit(plan.pending->Take());
      plan.pending.reset();
    } else if (provisional) {
      TakeSplit(std::move(*provisional));
    }
  }
  // A target is sent again only when its own share's weights change: at fleet scale the guard
  // boosts some valve somewhere nearly every cycle, and re-sending every share then was 21 of the
  // 22 MB/s a 1,000-vehicle mission sent.
  const Eigen::VectorXd& weights = fleet_.effective_weights();
  auto found = plan.shares.begin();  // both ascending by id: walked together, not looked up
  // Each vehicle's roster entry lies apart on the heap (at 10,000 vehicles a cache miss each on
  // the walk), so it is asked for a few vehicles ahead; the shares' valves and sent proportions
  // are read as one run (walk_valves, walk_sent). Once a share's valve indices are known, their
  // weights (the field's, 35,000 of them) are asked for too, with their last visits (the age
  // weighting's clock): scattered reads that were half of the walk's time at 10,000 vehicles.
  constexpr std::size_t kAhead = 8, kWeightsAhead = 3;
  const bool aged = scenario_.fleet.age_weighting_laps > 0.0;
  const auto PrefetchShareWeights = [&](const RegionShare& share) {
    for (std::size_t k = 0; k < share.valves.size(); ++k) {
      const int v = plan.walk_valves[share.walk_at + k];
      maps::PrefetchObject(&weights[v]);
      if (aged) fleet_.PrefetchLastVisit(v);  // read by the age weighting, as scattered
    }
  };
  for (std::size_t i = 0; i < alive.size(); ++i) {
    const int id = alive[i];
    if (i + kAhead < alive.size()) maps::PrefetchObject(roster_.Find(alive[i + kAhead]));
    const std::size_t at = static_cast<std::size_t>(found - plan.shares.begin());
    if (at + kWeightsAhead < plan.shares.size()) PrefetchShareWeights(plan.shares[at + kWeightsAhead].second);
    Roster::Member& m = *roster_.Find(id);
    while (found != plan.shares.end() && found->first < id) ++found;
    if (found == plan.shares.end() || found->first != id) {
      // Not in the split yet (it is coming): the field's shared target meanwhile. Held in reserve
      // (more vehicles than valves): an assignment of nothing, on which it holds where it is.
      if (m.target_sent) continue;
      agents::Assignment a;
      a.id = id;
      a.cycle = out.snapshot.cycle;
      a.shared = !std::binary_search(plan.reserve.begin(), plan.reserve.end(), id);
      out.assignments.push_back(std::move(a));
      m.target_sent = true;
      continue;
    }
    RegionShare& share = found->second;
    Eigen::VectorXd& own = share_weights_scratch_;  // no allocation a share a cycle
    const std::span<const int> valves(plan.walk_valves.data() + share.walk_at, share.valves.size());
    Eigen::Map<Eigen::VectorXd> sent(plan.walk_sent.data() + share.walk_at, static_cast<Eigen::Index>(valves.size()));
    own.resize(static_cast<Eigen::Index>(valves.size()));
    for (std::size_t k = 0; k < valves.size(); ++k) own[static_cast<Eigen::Index>(k)] = weights[valves[k]];
    // Age weighting: w (1 + age / (L lap)); a valve just seen weighs its risk, one unseen for a
    // lap twice that (L = 1). A leak is as likely to have started at a valve as its risk and the
    // time since anyone looked: the target leans to where one would go unnoticed longest.
    const double laps = scenario_.fleet.age_weighting_laps;
    if (laps > 0.0) {
      const double scale = laps * std::max(share.lap_time_s, 1.0);
      for (std::size_t k = 0; k < valves.size(); ++k) {
        const double age = time_s_ - std::max(0.0, fleet_.LastVisit(valves[k]));
        own[static_cast<Eigen::Index>(k)] *= 1.0 + std::max(age, 0.0) / scale;
      }
    }
    if (!(own.sum() > 0.0)) own.setOnes();  // a share whose valves all weigh zero is still watched, evenly
    // Its weight in the field's units, for the layer's leaves in its box (below).
    double share_weight = 0.0;
    for (int i : valves) share_weight += weights[i];
    own /= own.sum();  // the target is the share's mixture: only the weights' proportions count
    double excess_mass = 0.0;
    Eigen::VectorXd excess;
    if (layer_.nonzero_leaves() > 0) {
      const maps::RegionBox& box = share.field->box();
      excess = layer_.ExcessOn(share.field->basis(), box.origin_m,
                               [&](const Eigen::Vector2d& x) { return box.Contains(x); }, excess_mass);
    }
    // The layer's leaves in its box moved (a detection, or one relaxing): the target goes again.
    const bool excess_moved = std::abs(excess_mass - share.sent_excess) >
                              kSameProportionOfExcess * (share_weight + std::max(excess_mass, share.sent_excess));
    // The field's weights are normalised over all valves and the guard's floor is absolute, so a
    // boost anywhere nudges every share's proportions a little (at 1,000 vehicles: ~430 targets a
    // cycle, 11 MB/s), and age weighting moves them all the time. A share's target is sent again
    // when one of its proportions has moved by more than 5 % of itself since it was sent: a visit
    // to one of its valves, its own guard boosts, risk changes, operators'.
    constexpr double kSameProportion = 0.05;
    if (m.target_sent && share.sent && !excess_moved &&
        ((own - sent).array().abs() <= kSameProportion * sent.array()).all()) {
      continue;
    }
    sent = own;
    share.sent = true;
    share.sent_excess = excess_mass;
    agents::Assignment a;
    a.id = id;
    a.cycle = out.snapshot.cycle;
    a.shared = false;
    if (excess_mass > 0.0) {
      const double w = share_weight > 0.0 ? share_weight : 1.0;
      a.phi = (w * share.field->Coefficients(own) + excess) / (w + excess_mass);
    } else {
      if (!region_phi_by_hosts_) a.phi = share.field->Coefficients(own);
      a.region_valves = share.valves;  // phi is their mixture alone: the wire sends these instead
      a.region_weights = own;
    }
    a.region_origin_m = share.field->box().origin_m;
    a.region_size_m = share.field->box().size_m;
    a.region_order = share.field->box().order;
    // A share's coverage is forgotten over two laps of its tour (or the scenario's forgetting, if
    // shorter): with forgetting of 60 s (generated fields) or none (fleet_large) a vehicle left
    // its valves to cover old deficits (measured with the narrowed targets, region_split.h: over
    // ten graded fields, three seeds each, the risk-weighted revisit interval went from
    // 0.91-1.04x the tours' to 0.88-0.98x, the worst longest gap from 2.05x to 1.92x).
    constexpr double kForgettingLaps = 2.0;
    a.region_forgetting_s = std::min(scenario_.ergodic.forgetting_time_s, kForgettingLaps * std::max(share.lap_time_s, 1.0));
    out.assignments.push_back(std::move(a));
    m.target_sent = true;
  }
}

RejectionCounts MissionCore::rejections() const {
  RejectionCounts all = rejected_;
  if (const std::size_t refused = metrics_.refused_samples(); refused > 0) {
    all.Count("sample not after its vehicle's last", "", refused);
  }
  return all;
}

MissionMetrics MissionCore::Metrics(double end_s) const {
  MissionMetrics metrics = metrics_.Result(std::max(end_s, 1.0 / scenario_.control_rate_hz));
  metrics.events = fleet_.responses();
  FillEventResponses(metrics_.visits(), metrics);
  loop_.Fill(metrics, std::max(end_s, 1.0 / scenario_.control_rate_hz));
  // The A* tours fly the profile's weights whatever the belief says; under astar.order looks
  // their next valves are chosen on the scans (tours_on_scans).
  metrics.steered_on_posterior = metrics.steered_on_posterior && controller_ == ControllerKind::kErgodic;
  metrics.tours_on_scans = controller_ == ControllerKind::kAstar && scenario_.astar.order == maps::AstarSettings::Order::kLooks;
  return metrics;
}

MissionCheckpoint MissionCore::Checkpoint() const {
  MissionCheckpoint c;
  if (!scenario_hash_) scenario_hash_ = maps::ScenarioHash(scenario_);
  c.scenario_hash = *scenario_hash_;
  c.profile = fleet_.profile().name;
  c.controller = ToString(controller_);
  c.cycle = cycle_;
  c.time_s = time_s_;
  c.fleet = fleet_.Checkpoint();
  c.roster = roster_.Checkpoint();
  c.metrics = metrics_.state();
  c.disarmed = metrics_.visits().disarmed();
  c.visits = metrics_.visits().visits();
  c.visit_watches = metrics_.visits().watches();
  c.rejected_samples = rejected_.total();
  c.rejected_by_kind = rejected_.by_kind();
  c.rejected_by_sender = rejected_.by_sender();
  if (layer_.nonzero_leaves() > 0) c.risk_layer_ot = layer_.OtBytes();
  c.risk_loop = loop_.Checkpoint();
  return c;
}

void MissionCore::Restore(const MissionCheckpoint& c) {
  if (c.scenario_hash != maps::ScenarioHash(scenario_)) {
    throw maps::ScenarioError("checkpoint: it was taken of another scenario (or other options) than the one given");
  }
  if (c.profile != fleet_.profile().name || c.controller != ToString(controller_)) {
    throw maps::ScenarioError(fmt::format("checkpoint: it is of profile {} under {}, not {} under {}", c.profile,
                                          c.controller, fleet_.profile().name, ToString(controller_)));
  }
  try {
    fleet_.Restore(c.fleet);
    roster_.Restore(c.roster);
    VisitTracker visits = metrics_.visits();
    visits.Restore(c.disarmed, c.visits, c.visit_watches);
    metrics_.Restore(c.metrics, std::move(visits));
    // A checkpoint of before the watches: each risk event's watched from what the record holds.
    if (c.visit_watches.empty()) {
      for (const EventResponse& r : fleet_.responses()) metrics_.WatchVisits(scenario_.ValveIndex(r.valve), r.time_s);
    }
    loop_.Restore(c.risk_loop);
    if (!c.risk_layer_ot.empty()) {
      std::istringstream ot(c.risk_layer_ot);
      layer_.LoadExcess(ot, "checkpoint: risk layer");
    }
  } catch (const std::runtime_error& e) {  // the layer's .ot bytes
    throw maps::ScenarioError(std::string("checkpoint: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw maps::ScenarioError(std::string("checkpoint: does not fit the scenario: ") + e.what());
  }
  fleet_.UseVisits(&metrics_.visits());
  cycle_ = c.cycle;
  time_s_ = c.time_s;
  // A checkpoint of before the counts had kinds: the total as one kind.
  std::map<std::string, std::size_t> by_kind = c.rejected_by_kind;
  if (by_kind.empty() && c.rejected_samples > 0) by_kind["refused (kind not recorded)"] = c.rejected_samples;
  rejected_.Restore(c.rejected_samples, std::move(by_kind), c.rejected_by_sender);
  risk_recorded_ = risk_measured_ = fleet_.responses().size();
  schedule_seen_ = fleet_.schedule().size();
  last_assignment_.clear();
  last_weights_.resize(0);
  pending_heading_changes_.clear();
  // A new server: every live vehicle gets its assignment again.
  for (int id : roster_.alive()) roster_.Find(id)->target_sent = false;
}

std::int64_t MissionCore::Replay(const std::vector<std::pair<TrajectorySample, std::string>>& samples,
                                 const std::vector<FleetEventRecord>& fleet_events,
                                 const std::vector<RiskEventRecord>& risk_events) {
  MissionRecorder* recorder = recorder_;
  recorder_ = nullptr;  // all of it is in the record already
  std::map<std::string, int> id_of;
  for (const auto& [id, m] : roster_.members()) id_of[m.name] = id;
  std::int64_t last = cycle_;
  for (const auto& [sample, name] : samples) last = std::max<std::int64_t>(last, std::llround(sample.time_s * scenario_.control_rate_hz));
  std::size_t next_sample = 0, next_fleet = 0, next_risk = 0;
  for (std::int64_t k = cycle_ + 1; k <= last; ++k) {
    const double t = static_cast<double>(k) / scenario_.control_rate_hz;
    for (; next_fleet < fleet_events.size() && fleet_events[next_fleet].time_s <= t + 1e-9; ++next_fleet) {
      const FleetEventRecord& e = fleet_events[next_fleet];
      if (e.vehicle_id < 0) continue;  // outage, empty: notes of the record only
      if (e.what == "joined" || e.what == "rejoined") {
        Record(roster_.Join(e.vehicle_id, e.name, t));
        fleet_.AddVehicle(e.vehicle_id, e.name);
        id_of[e.name] = e.vehicle_id;
      } else if (e.what == "lost" || e.what == "left") {
        OnVehicleGone(e.vehicle_id, e.what == "lost");
      }
    }
    for (; next_risk < risk_events.size() && risk_events[next_risk].time_s <= t + 1e-9; ++next_risk) {
      const RiskEventRecord& r = risk_events[next_risk];
      // The profile's fire by themselves; the record holds only updates that were applied.
      if (r.source != "scenario") ApplyRiskUpdate(r.valve, r.raw_weight, r.source);
    }
    for (; next_sample < samples.size() &&
           std::llround(samples[next_sample].first.time_s * scenario_.control_rate_hz) <= k;
         ++next_sample) {
      const auto& [sample, name] = samples[next_sample];
      const auto id = id_of.find(name);
      Roster::Member* m = id == id_of.end() ? nullptr : roster_.Find(id->second);
      if (m == nullptr) continue;  // a row of a vehicle the record never joined: not ours
      TrajectorySample s = sample;
      s.vehicle = m->index;
      m->last.cycle = k;
      m->last.time_s = s.time_s;
      m->last.state.position_m = s.position_m;
      m->last.state.velocity_mps = s.velocity_mps;
      m->last.state.heading_rad = s.heading_rad;
      m->last.command_mps = s.command_mps;
      m->has_state = true;
      roster_.Heard(*m);
      fleet_.SetPosition(m->id, s.position_m);
      samples_.push_back(s);
    }
    Cycle(k);
  }
  recorder_ = recorder;
  return cycle_;
}

}  // namespace sage::server
