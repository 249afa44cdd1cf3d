#include "agents/node/host_door.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <spdlog/spdlog.h>

#include "agents/node/wire.h"
#include "proto/mission_clock.h"

namespace sage::agents {

bool HostDoor::TakeStatus(const proto::MissionStatus& s) {
  if (s.vehicle_fingerprint != fingerprint_) {
    other_world_ = true;
    return false;
  }
  // No server of a mission says so: no instance, a clock that cannot be, or a first word that is
  // the mission's end (a forged "finished" from a new instance had sent every host home).
  if (s.server_instance == 0 || !proto::PlausibleClock(s.start_ns, s.time_scale) ||
      (s.finished && s.server_instance != clock_.instance)) {
    ++bad_statuses_;
    ended_elsewhere_ = ended_elsewhere_ || s.finished;
    return false;
  }
  if (s.server_instance != clock_.instance) {
    if (clock_.instance != 0) {
      spdlog::info("agents: a new server runs the mission (t = {:.1f} s on its clock); following it",
                   std::isfinite(s.mission_time_s) ? s.mission_time_s : 0.0);
      mission_.OnNewServer();
    }
    clock_ = {s.server_instance, s.start_ns, s.time_scale};
    clock_first_cycle_ = static_cast<std::int64_t>(std::min<std::uint64_t>(s.cycle, INT64_MAX));
  }
  if (s.finished && !finished_) ended_at_cycle_ = s.cycle;
  finished_ = finished_ || s.finished;
  if (std::isfinite(s.duration_s) && s.duration_s > 0.0) duration_s_ = s.duration_s;
  return true;
}

std::optional<VehicleId> HostDoor::TakeCommand(const proto::FleetCommand& c) const {
  if (c.server_instance != clock_.instance || clock_.instance == 0 || proto::AsStringView(c.verb) != "retire") {
    return std::nullopt;
  }
  const VehicleId id = static_cast<VehicleId>(c.vehicle_id);
  if (!mission_.Contains(id)) return std::nullopt;
  return id;
}

bool HostDoor::Ahead(std::uint64_t cycle, double time_s, std::int64_t now_cycle) const {
  const double period = mission_.control_period_s();
  const double latest = (static_cast<double>(std::max<std::int64_t>(now_cycle, 0)) + std::ceil(kMaxLead_s / period)) * period;
  return static_cast<double>(cycle) * period > latest || !(time_s <= latest);
}

bool HostDoor::Takes(const proto::ErgodicTarget& m, std::int64_t now_cycle) {
  if (m.server_instance != clock_.instance || clock_.instance == 0) return false;
  // Only this host's vehicles' assignments are converted (every host reads every vehicle's).
  if (!mission_.Contains(static_cast<VehicleId>(m.vehicle_id))) return false;
  if (Ahead(m.cycle, 0.0, now_cycle)) {
    ++ahead_;
    return false;
  }
  return true;
}

bool HostDoor::TakeTarget(const proto::ErgodicTarget& m, std::int64_t now_cycle) {
  return Takes(m, now_cycle) && mission_.OnAssignment(wire::FromWire(m));
}

void HostDoor::GatherTarget(const proto::ErgodicTarget& m, std::int64_t now_cycle, std::vector<Assignment>& into) {
  if (Takes(m, now_cycle)) into.push_back(wire::FromWire(m));
}

std::size_t HostDoor::ApplyTargets(std::span<const Assignment> gathered) { return mission_.OnAssignments(gathered); }

std::size_t HostDoor::TakeTargets(const proto::ErgodicTargets& m, std::int64_t now_cycle) {
  if (m.server_instance != clock_.instance || clock_.instance == 0) return 0;
  std::vector<Assignment> mine;
  for (const proto::ErgodicTarget& target : proto::AsSpan(m.targets)) GatherTarget(target, now_cycle, mine);
  return ApplyTargets(mine);
}

bool HostDoor::TakeSnapshot(const proto::FleetCoverage& m, std::int64_t now_cycle) {
  if (m.server_instance != clock_.instance || clock_.instance == 0) return false;
  if (Ahead(m.cycle, m.mission_time_s, now_cycle)) {
    ++ahead_;
    return false;
  }
  return mission_.OnFleetSnapshot(wire::FromWire(m));
}

void HostDoor::TakeNeighbour(const proto::VehicleState& m, bool valid_data, bool alive) {
  if (mission_.Contains(static_cast<VehicleId>(m.vehicle_id))) return;
  if (!valid_data || !alive) {
    others_.erase(m.vehicle_id);  // lost or left
    return;
  }
  const Eigen::Vector2d p(m.x_m, m.y_m);
  if (!p.allFinite()) {
    ++bad_neighbours_;  // not a place to keep clear of
    others_.erase(m.vehicle_id);
    return;
  }
  if (m.server_instance != clock_.instance) return;
  const auto known = others_.find(m.vehicle_id);
  if (known == others_.end() && others_.size() >= kMaxOthers) {
    ++bad_neighbours_;
    return;
  }
  auto& seen = known != others_.end() ? known->second : others_[m.vehicle_id];
  seen.emplace_back(static_cast<std::int64_t>(m.cycle), p);
  if (seen.size() > kStatesKept) seen.pop_front();
}

std::vector<Eigen::Vector2d> HostDoor::OthersAt(std::int64_t cycle) const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(others_.size());
  for (const auto& [id, seen] : others_) {
    for (const auto& [at, position] : seen)
      if (at == cycle) out.push_back(position);
  }
  return out;
}

}  // namespace sage::agents
