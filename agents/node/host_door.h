#pragma once
// An agent host's door to what arrives over DDS: the server's mission status, its targets and
// fleet snapshots, its orders to retire a vehicle, and the other hosts' vehicle states, as the
// agent node hands them to the host's mission (agents/agent_mission.h) — apart from DDS itself,
// so that the same code is tested and fuzzed without a domain (tests/fuzz). Words of the
// server are taken only from the mission's server (its instance, announced in its status),
// and nothing that is not finite or does not fit the mission reaches the vehicles.
#include <chrono>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "agents/agent_mission.h"
#include "proto/messages.h"

namespace sage::agents {

/// The mission clock as the current server announces it.
struct MissionClock {
  std::uint64_t instance = 0;  ///< the server's (0: none heard yet)
  long long start_ns = 0;      ///< wall clock (CLOCK_REALTIME, ns) at mission time 0
  double time_scale = 1.0;     ///< mission seconds per wall second
  double MissionTime(long long ns) const { return static_cast<double>(ns - start_ns) * 1e-9 * time_scale; }
  std::chrono::system_clock::time_point WallOf(double mission_s) const {
    return std::chrono::system_clock::time_point(std::chrono::duration_cast<std::chrono::system_clock::duration>(
        std::chrono::nanoseconds(start_ns + static_cast<long long>(mission_s / time_scale * 1e9))));
  }
};

class HostDoor {
 public:
  /// mission outlives the door; fingerprint: maps::VehicleFingerprint of this host's world (and
  /// its guidance), which the server's status must carry.
  HostDoor(AgentMission& mission, std::uint64_t fingerprint) : mission_(mission), fingerprint_(fingerprint) {}

  /// The server's status (a valid sample). A new server instance (the first, a restart, a
  /// resumed mission) brings its clock, and what the last one said is dropped; a status of
  /// another world (fingerprint), with a clock that cannot be (proto::PlausibleClock) or from a
  /// new instance that says the mission is over is refused. Returns false for a refused one.
  bool TakeStatus(const proto::MissionStatus& s);
  const MissionClock& clock() const { return clock_; }
  /// The cycle of the first word this host took from the current server: for a server that
  /// starts (or resumes) with its clock ahead of now, the cycle it begins at, which no host steps
  /// before; for a server already running, about its current cycle.
  std::int64_t clock_first_cycle() const { return clock_first_cycle_; }
  /// The server has said the mission is over.
  bool finished() const { return finished_; }
  /// The first cycle the server did not run, from its status that said the mission is over (its
  /// length's end, or an operator's stop); none before that.
  std::optional<std::uint64_t> ended_at_cycle() const { return ended_at_cycle_; }
  /// The mission's length (s) as the current server announces it (its --duration, not this
  /// host's); NaN before its first status.
  double duration_s() const { return duration_s_; }
  /// A server not followed said its mission is over (a host started after its end hears that first).
  bool ended_elsewhere() const { return ended_elsewhere_; }
  /// A server of another world (scenario or options) was heard.
  bool other_world() const { return other_world_; }

  /// The server's order to retire one of this host's vehicles: its id, or none if the command is
  /// not the current server's "retire" of a vehicle of this host.
  std::optional<VehicleId> TakeCommand(const proto::FleetCommand& c) const;
  /// A vehicle's assignment (every host sees every vehicle's; each takes its own). `now_cycle`:
  /// the host's control cycle; a word of the server stamped more than kMaxLead_s of mission time
  /// past it is refused (counted in ahead_of_the_clock()): taken, it would have made every real
  /// one after it look old (the probe's snapshot of mission time 1e300).
  bool TakeTarget(const proto::ErgodicTarget& m, std::int64_t now_cycle);
  /// TakeTarget in two steps, for many at once: Gather converts a target the mission may see (as
  /// TakeTarget checks it) into `into`; Apply hands them over together (AgentMission::OnAssignments:
  /// over the host's threads; at a new split of a large field each is a region's quadrature),
  /// returning the number the mission took. The same outcome as TakeTarget of each in turn.
  void GatherTarget(const proto::ErgodicTarget& m, std::int64_t now_cycle, std::vector<Assignment>& into);
  std::size_t ApplyTargets(std::span<const Assignment> gathered);
  /// A cycle's batch of changed assignments: each as TakeTarget, if the batch and the element are
  /// of the current server, applied together; the number the mission took.
  std::size_t TakeTargets(const proto::ErgodicTargets& m, std::int64_t now_cycle);
  /// The server's fleet snapshot; true if the mission took it (the newest of its server).
  bool TakeSnapshot(const proto::FleetCoverage& m, std::int64_t now_cycle);
  /// How far ahead of a host's clock the server's words may be: a host that fell behind catches
  /// up within a few cycles; the server's are never seconds ahead.
  static constexpr double kMaxLead_s = 5.0;
  /// The server's words refused for being ahead of the clock.
  std::uint64_t ahead_of_the_clock() const { return ahead_; }

  /// Another host's vehicle's state: `alive` false for a lost or left one (a dispose, a lapsed
  /// lease), which is forgotten. A state of this host's own vehicles is ignored; one with no
  /// finite position is refused (counted) and forgets that vehicle.
  void TakeNeighbour(const proto::VehicleState& m, bool valid_data, bool alive);
  /// The other hosts' vehicles: each one's last few states (cycle, position), newest last.
  const std::map<std::uint32_t, std::deque<std::pair<std::int64_t, Eigen::Vector2d>>>& others() const {
    return others_;
  }
  /// Where the others were at `cycle` (what this host's vehicles keep apart from).
  std::vector<Eigen::Vector2d> OthersAt(std::int64_t cycle) const;
  /// Neighbour states refused (no finite position).
  std::uint64_t bad_neighbours() const { return bad_neighbours_; }
  /// Statuses refused (a clock that cannot be, an end from a server not followed).
  std::uint64_t bad_statuses() const { return bad_statuses_; }

  /// States kept per other vehicle: a host that runs ahead sends its next state before this one
  /// takes the last, and the vehicles keep apart on the last cycle's.
  static constexpr std::size_t kStatesKept = 3;
  /// Other vehicles tracked at most: a flood of made-up ids cannot grow the host without bound.
  static constexpr std::size_t kMaxOthers = 100000;

 private:
  AgentMission& mission_;
  std::uint64_t fingerprint_;
  MissionClock clock_;
  bool finished_ = false;
  std::optional<std::uint64_t> ended_at_cycle_;
  std::int64_t clock_first_cycle_ = 0;
  double duration_s_ = std::numeric_limits<double>::quiet_NaN();
  bool other_world_ = false;
  bool ended_elsewhere_ = false;
  std::map<std::uint32_t, std::deque<std::pair<std::int64_t, Eigen::Vector2d>>> others_;
  // A target the mission may see: of the followed server, for this host's vehicle, not ahead of
  // the clock (counted if it is).
  bool Takes(const proto::ErgodicTarget& m, std::int64_t now_cycle);
  // True if a word of cycle `cycle` (and mission time `time_s`) is past now_cycle + kMaxLead_s.
  bool Ahead(std::uint64_t cycle, double time_s, std::int64_t now_cycle) const;

  std::uint64_t bad_neighbours_ = 0;
  std::uint64_t bad_statuses_ = 0;
  std::uint64_t ahead_ = 0;
};

}  // namespace sage::agents
