#include "agents/agent_mission.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "maps/spectral_basis.h"

namespace sage::agents {
namespace {

// Reports kept per vehicle to match the fleet snapshot's accounted seq. The server accounts the
// newest report it has, one cycle and at most a coverage period old: 8 at 0.5 s cover 4 s of a
// server falling behind. (At K = 40 a report is 12.8 kB: 64 kept cost 0.8 MB a vehicle.)
constexpr std::size_t kReportsKept = 8;

}  // namespace

AgentMission::AgentMission(const maps::World& world, const maps::Scenario& scenario, Guidance guidance)
    : scenario_(scenario),
      blocked_(world.blocked()),
      valves_(scenario.AllValves()),
      host_(world, scenario, guidance),
      sensors_(world, scenario) {}

void AgentMission::AddVehicle(VehicleId id, const maps::VehicleSpec& spec, const VehicleResume* resume) {
  maps::VehicleSpec placed = spec;
  if (resume != nullptr) {
    placed.start_m = resume->position_m;
    placed.start_heading_rad = resume->heading_rad;
  } else {
    placed.start_m = maps::JitteredStart(spec, scenario_.seed, id, scenario_.start_jitter_m);
  }
  host_.AddVehicle(id, placed);
  // Hosts add their vehicles in ascending ids: appended, but kept in order whatever comes.
  const auto at = members_.begin() + Slot(id);
  Member& member = at != members_.end() && at->first == id ? at->second : members_.insert(at, {id, Member{}})->second;
  member.name = spec.name;
  member.own_applied = false;  // a vehicle added again has a new controller: its share goes to it again
  if (resume != nullptr && resume->coverage.seq > 0) {
    host_.RestoreCoverage(id, resume->coverage.sums, resume->coverage.kernel_time_s);
    member.seq = resume->coverage.seq;  // the next report is newer than the one the server holds
  }
}

void AgentMission::RemoveVehicle(VehicleId id) {
  const std::ptrdiff_t at = MemberIndex(id);
  if (at < 0) throw std::out_of_range("AgentMission: no vehicle " + std::to_string(id));
  members_.erase(members_.begin() + at);
  host_.RemoveVehicle(id);
}

std::ptrdiff_t AgentMission::Slot(VehicleId id) const {
  // A fleet of ids 0..N-1 on one host (in-process) holds each at its id.
  if (id >= 0 && static_cast<std::size_t>(id) < members_.size() && members_[static_cast<std::size_t>(id)].first == id) {
    return id;
  }
  return std::lower_bound(members_.begin(), members_.end(), id,
                          [](const auto& m, VehicleId value) { return m.first < value; }) -
         members_.begin();
}

std::ptrdiff_t AgentMission::MemberIndex(VehicleId id) const {
  const std::ptrdiff_t at = Slot(id);
  return static_cast<std::size_t>(at) < members_.size() && members_[static_cast<std::size_t>(at)].first == id ? at : -1;
}

AgentMission::Member* AgentMission::FindMember(VehicleId id) {
  return const_cast<Member*>(std::as_const(*this).FindMember(id));
}

const AgentMission::Member* AgentMission::FindMember(VehicleId id) const {
  const std::ptrdiff_t at = MemberIndex(id);
  return at < 0 ? nullptr : &members_[static_cast<std::size_t>(at)].second;
}

const std::string& AgentMission::Name(VehicleId id) const {
  const Member* member = FindMember(id);
  if (member == nullptr) throw std::out_of_range("AgentMission: no vehicle " + std::to_string(id));
  return member->name;
}

std::vector<VehicleId> AgentMission::ids() const {
  std::vector<VehicleId> out;
  for (const auto& [id, member] : members_) out.push_back(id);
  return out;
}

bool AgentMission::Refuse(std::string why) {
  ++rejected_;
  last_rejection_ = std::move(why);
  return false;
}

std::string AgentMission::Refusal(const Assignment& a) const {
  // Named only when refused: at 10,000 vehicles a host checks thousands of assignments a cycle.
  const auto who = [&a] { return fmt::format("assignment for vehicle {} (cycle {})", a.id, a.cycle); };
  // Bounds well beyond any real target, so that no product of them overflows to inf or NaN in
  // the control law (the agent door's fuzzer steered a vehicle on a NaN command): a density's
  // coefficients on a basis of unit norm stay below 2 / sqrt(area) (1e6 for a 4 um^2 box).
  constexpr double kMaxPhi = 1e6, kMinRegion_m = 1e-3, kMinForgetting_s = 1e-3, kMaxTourWeight = 1e12;
  if (!a.phi.allFinite()) return who() + ": phi is not finite";
  if (a.phi.size() > 0 && a.phi.cwiseAbs().maxCoeff() > kMaxPhi) {
    return who() + fmt::format(": a phi coefficient is beyond +-{:g}", kMaxPhi);
  }
  if (a.region_order != 0) {
    const maps::Workspace& w = scenario_.workspace;
    const Eigen::Vector2d hi = a.region_origin_m + a.region_size_m;
    constexpr double kSlack_m = 1e-6;
    if (!a.region_origin_m.allFinite() || !a.region_size_m.allFinite() || (a.region_size_m.array() < kMinRegion_m).any() ||
        (a.region_origin_m.array() < -kSlack_m).any() || hi.x() > w.width_m + kSlack_m || hi.y() > w.height_m + kSlack_m) {
      return who() + fmt::format(": region at ({}, {}) of {} x {} m is not inside the {} x {} m workspace",
                               a.region_origin_m.x(), a.region_origin_m.y(), a.region_size_m.x(), a.region_size_m.y(),
                               w.width_m, w.height_m);
    }
    if (a.region_order < 1 || a.region_order > maps::SpectralBasis::kMaxOrder) {
      return who() + fmt::format(": region basis order {} is outside 1..{}", a.region_order, maps::SpectralBasis::kMaxOrder);
    }
    if (std::isnan(a.region_forgetting_s) || a.region_forgetting_s < 0.0 ||
        (a.region_forgetting_s > 0.0 && a.region_forgetting_s < kMinForgetting_s)) {
      return who() + fmt::format(": region forgetting time {} s is not 0 (the scenario's) or >= {:g} s",
                               a.region_forgetting_s, kMinForgetting_s);
    }
    if (a.phi.size() != 0 && a.phi.size() != a.region_order * a.region_order) {
      return who() + fmt::format(": phi has {} coefficients, its region's basis {}", a.phi.size(),
                               a.region_order * a.region_order);
    }
    if (!a.region_valves.empty()) {
      const int valves = static_cast<int>(valves_.size());
      if (a.region_valves.size() > static_cast<std::size_t>(valves) ||
          std::any_of(a.region_valves.begin(), a.region_valves.end(), [&](int i) { return i < 0 || i >= valves; })) {
        return who() + fmt::format(": its region names {} valves, or one outside 0..{}", a.region_valves.size(), valves - 1);
      }
      if (a.region_weights.size() != static_cast<Eigen::Index>(a.region_valves.size()) || !a.region_weights.allFinite() ||
          (a.region_weights.array() < 0.0).any() || (a.region_weights.array() > kMaxTourWeight).any() ||
          !(a.region_weights.sum() > 0.0)) {
        return who() + ": its region's weights must be one per valve, in [0, 1e12] and not all zero";
      }
    }
  } else if (!a.region_valves.empty()) {
    return who() + ": it names a region's valves but no region";
  } else if (a.phi.size() != 0 && a.phi.size() != host_.basis().size()) {
    return who() + fmt::format(": phi has {} coefficients, the field's basis {}", a.phi.size(), host_.basis().size());
  }
  if (!a.tour.empty()) {
    const int valves = static_cast<int>(valves_.size());
    if (std::any_of(a.tour.begin(), a.tour.end(), [&](int i) { return i < 0 || i >= valves; })) {
      return who() + fmt::format(": the tour names a valve outside 0..{}", valves - 1);
    }
    if (a.tour_weights.size() != static_cast<Eigen::Index>(a.tour.size()) || !a.tour_weights.allFinite() ||
        (a.tour_weights.array() < 0.0).any() || (a.tour_weights.array() > kMaxTourWeight).any() ||
        !(a.tour_weights.sum() > 0.0)) {
      return who() + ": the tour's weights must be one per valve, in [0, 1e12] and not all zero";
    }
  }
  return {};
}

std::string AgentMission::Refusal(const FleetSnapshot& s) const {
  const std::string what = fmt::format("fleet snapshot of cycle {}", s.cycle);
  const Eigen::Index basis = host_.basis().size();
  // As for an assignment, bounds far beyond a real snapshot's keep every product finite; and a
  // negative kernel time could cancel the vehicle's own (its coverage then divided by zero).
  constexpr double kMaxPhi = 1e6, kMaxSum = 1e12, kMaxWeight = 1e12;
  if (s.phi.size() != 0 && (s.phi.size() != basis || !s.phi.allFinite() || s.phi.cwiseAbs().maxCoeff() > kMaxPhi)) {
    return what + fmt::format(": phi must be {} coefficients within +-{:g}", basis, kMaxPhi);
  }
  if (s.coverage.sums.size() != 0 && (s.coverage.sums.size() != basis || !s.coverage.sums.allFinite() ||
                                      s.coverage.sums.cwiseAbs().maxCoeff() > kMaxSum)) {
    return what + fmt::format(": the fleet's sums must be {} numbers within +-{:g}", basis, kMaxSum);
  }
  if (!std::isfinite(s.coverage.time_s) || !std::isfinite(s.coverage.kernel_time_s) || s.coverage.time_s < 0.0 ||
      s.coverage.kernel_time_s < 0.0) {
    return what + ": its times must be finite and >= 0";
  }
  const Eigen::Index valves = static_cast<Eigen::Index>(valves_.size());
  if (s.valve_weights.size() != 0 &&
      (s.valve_weights.size() != valves || !s.valve_weights.allFinite() || (s.valve_weights.array() < 0.0).any() ||
       (s.valve_weights.array() > kMaxWeight).any())) {
    return what + fmt::format(": valve weights must be {} finite numbers >= 0", valves);
  }
  return {};
}

bool AgentMission::OnAssignment(const Assignment& assignment) {
  std::string why;
  const bool applied = Apply(assignment, why);
  return why.empty() ? applied : Refuse(std::move(why));
}

std::size_t AgentMission::OnAssignments(std::span<const Assignment> assignments) {
  // Each assignment touches only its own vehicle (its member here, its controller in the host):
  // a batch that names every vehicle once goes over the host's threads in blocks, as its
  // guidance does. Serial if a vehicle comes twice (the order of its targets counts).
  std::vector<VehicleId> ids;
  ids.reserve(assignments.size());
  for (const Assignment& a : assignments) ids.push_back(a.id);
  std::sort(ids.begin(), ids.end());
  std::size_t applied = 0;
  if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) {
    for (const Assignment& a : assignments) applied += OnAssignment(a) ? 1 : 0;
    return applied;
  }
  std::vector<std::string> refused(assignments.size());
  std::vector<char> took(assignments.size(), 0);
  host_.ForEachBlock(assignments.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) took[i] = Apply(assignments[i], refused[i]) ? 1 : 0;
  });
  // Counted in the batch's order: the last refusal is the one a serial loop would have kept.
  for (std::string& why : refused) {
    if (!why.empty()) Refuse(std::move(why));
  }
  for (const char t : took) applied += static_cast<std::size_t>(t);
  return applied;
}

bool AgentMission::Apply(const Assignment& assignment, std::string& why) {
  Member* found = FindMember(assignment.id);
  if (found == nullptr) return false;
  if (why = Refusal(assignment); !why.empty()) return false;
  Member& m = *found;
  // Never an older target over a newer (targets come on two topics: a first alone, later ones in
  // batches). A new server's start from own_cycle 0 (OnNewServer).
  if (m.has_assignment && assignment.cycle < m.own_cycle) return false;
  Eigen::VectorXd phi;
  if (assignment.region_order > 0 && assignment.phi.size() == 0 && !assignment.region_valves.empty()) {
    phi = RegionPhi(m, assignment, why);
    if (!why.empty()) return false;
  } else {
    phi = assignment.phi;
  }
  if (assignment.region_order == 0) m.region_valves.clear(), m.region_field.reset();
  m.has_assignment = true;
  m.shared = assignment.shared;
  m.own_phi = std::move(phi);
  m.own_cycle = assignment.cycle;
  m.own_applied = false;
  m.in_region = assignment.region_order > 0;
  m.reserve = InReserve(assignment);
  host_.SetReserve(assignment.id, m.reserve);
  if (m.in_region) {
    host_.SetRegion(assignment.id, {assignment.region_origin_m, assignment.region_size_m, assignment.region_order},
                    assignment.region_forgetting_s);
  }
  if (!assignment.tour.empty()) host_.SetTour(assignment.id, assignment.tour, assignment.tour_weights);
  return true;
}

Eigen::VectorXd AgentMission::RegionPhi(Member& m, const Assignment& a, std::string& why) const {
  if (!m.region_field || m.region_valves != a.region_valves) {
    m.region_valves = a.region_valves;
    m.region_field = maps::ShareRegion(m.region_valves, valves_, scenario_, blocked_);
  }
  const maps::RegionBox& box = m.region_field->box();
  if (box.origin_m != a.region_origin_m || box.size_m != a.region_size_m || box.order != a.region_order) {
    why = fmt::format(
        "assignment for vehicle {} (cycle {}): its region ({}, {}) {} x {} m, K = {} is not its {} valves' ({}, {}) "
        "{} x {} m, K = {}: the server's scenario or version differs from this host's",
        a.id, a.cycle, a.region_origin_m.x(), a.region_origin_m.y(), a.region_size_m.x(), a.region_size_m.y(),
        a.region_order, a.region_valves.size(), box.origin_m.x(), box.origin_m.y(), box.size_m.x(), box.size_m.y(),
        box.order);
    return {};
  }
  return m.region_field->Coefficients(a.region_weights);
}

bool AgentMission::OnFleetSnapshot(const FleetSnapshot& snapshot) {
  if (std::string why = Refusal(snapshot); !why.empty()) return Refuse(std::move(why));
  if (snapshot_ && snapshot.cycle <= snapshot_->cycle && !new_server_) return false;
  new_server_ = false;
  snapshot_ = snapshot;
  if (host_.guidance() == Guidance::kAstar && snapshot.valve_weights.size() > 0 &&
      (tour_weights_.size() != snapshot.valve_weights.size() || tour_weights_ != snapshot.valve_weights)) {
    tour_weights_ = snapshot.valve_weights;
    host_.SetTourWeights(tour_weights_);  // taken at the start of each tour's next lap
  }
  return true;
}

void AgentMission::OnNewServer() {
  new_server_ = true;
  for (auto& [id, member] : members_) member.own_cycle = 0;
}

std::optional<VehicleTarget> AgentMission::TargetOf(VehicleId id, Member& member, double time_s) const {
  VehicleTarget target;
  if (member.reserve) return std::nullopt;  // holds where it is
  // Its share already handed over: nothing to ask of the host (a look-up in it and into the
  // vehicle's basis, a cache miss each: 2 of a 10,000-vehicle regions cycle's 40 ms, on one core
  // while the other waited). The share and the host's basis change only by an assignment, and a
  // vehicle added again under its id, which hand it over again.
  if (member.has_assignment && !member.shared && member.own_applied) {
    member.steered_cycle = member.own_cycle;
    return std::nullopt;
  }
  if (member.has_assignment && !member.shared && member.own_phi.size() == host_.BasisSize(id)) {
    // Partition or a region: its share, alone, handed to the host once per assignment (copying
    // every region's phi every cycle was 5 % of a 10,000-vehicle mission).
    member.steered_cycle = member.own_cycle;
    member.own_applied = true;
    target.phi = member.own_phi;
    return target;
  }
  // A region's vehicle steers on nothing else (until its region's phi comes, on its last target).
  if (member.in_region || snapshot_->phi.size() != host_.BasisSize(id)) return std::nullopt;
  // Shared coverage (Mathew & Mezic): the field, and the fleet's coverage less this vehicle's
  // own report that the snapshot holds, aged to now.
  target.phi = snapshot_->phi;
  const auto accounted = snapshot_->coverage.accounted_seq.find(id);
  const maps::CoverageReport* own =
      accounted == snapshot_->coverage.accounted_seq.end() ? nullptr : maps::FindReport(member.reports, accounted->second);
  maps::Coverage others = maps::OthersCoverage(snapshot_->coverage, own, time_s, scenario_.ergodic.forgetting_time_s);
  target.fleet_sums = std::move(others.sums);
  target.fleet_time_s = others.kernel_time_s;
  member.steered_cycle = snapshot_->cycle;
  return target;
}

AgentMission::CycleOutput AgentMission::Step(std::int64_t cycle) {
  CycleOutput out = Steer(cycle);
  Move();
  return out;
}

// States asked for ahead of the loop that reports them (AgentHost::PrefetchState).
constexpr std::size_t kStateAhead = 8;

AgentMission::CycleOutput AgentMission::Steer(std::int64_t cycle) {
  host_.Move();  // the last cycle's physics, if its caller left it (AgentHost::Steer would too)
  const double t = static_cast<double>(cycle) / scenario_.control_rate_hz;
  // The vehicles keep apart on where each reported being last cycle, this host's as the others'.
  host_.SetOwnReported(std::move(reported_));
  reported_.clear();
  CycleOutput out;
  out.states.reserve(members_.size());
  for (std::size_t i = 0; i < members_.size(); ++i) {
    const auto& [id, member] = members_[i];
    // At 10,000 vehicles each state is a cache miss into its Box2D body: asked for ahead.
    if (i + kStateAhead < members_.size()) host_.PrefetchState(members_[i + kStateAhead].first);
    StateReport s;
    s.id = id;
    s.name = member.name;
    s.cycle = cycle;
    s.time_s = t;
    s.state = host_.State(id);
    reported_.emplace_back(id, s.state.position_m);
    out.states.push_back(std::move(s));
  }
  // The sensors look from the states just reported (vehicles holding still look too).
  if (sensors_.any()) {
    for (const StateReport& s : out.states) sensors_.Scan(s.id, cycle, s.state, out.scans);
  }
  // Vehicles hold still until the server's first word.
  if (!snapshot_.has_value()) return out;
  // Each vehicle's target touches only its own member and controller: over the host's threads.
  host_.ForEachBlock(members_.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      auto& [id, member] = members_[i];
      if (const std::optional<VehicleTarget> target = TargetOf(id, member, t)) host_.SetTarget(id, *target);
    }
  });
  host_.Steer(t);
  auto member = members_.cbegin();  // the states are in the members' order
  for (StateReport& s : out.states) {
    s.command_mps = host_.LastCommand(s.id);
    s.target_cycle = (member++)->second.steered_cycle;
  }
  // Every coverage period on the mission clock (cycles 1, 1 + P, 1 + 2P, ...: the first cycle
  // that steers is 1), the same cycles for every host however late it joined, so that a fleet
  // reports the same whether one host simulates it or several.
  const std::int64_t period =
      std::max<std::int64_t>(1, std::llround(scenario_.fleet.coverage_period_s * scenario_.control_rate_hz));
  if (cycle >= 1 && (cycle - 1) % period == 0) {
    for (auto& [id, member] : members_) {
      const CoverageAccumulator* acc = host_.Coverage(id);
      // Only the field's coverage is shared; a region's vehicle covers alone on its own basis.
      if (acc == nullptr || acc->time_s() <= 0.0 || member.in_region) continue;
      maps::CoverageReport report{++member.seq, t, acc->time_s(), acc->sums()};
      member.reports.push_back(report);
      if (member.reports.size() > kReportsKept) member.reports.pop_front();
      out.coverage.push_back({id, std::move(report)});
    }
  }
  return out;
}

}  // namespace sage::agents
