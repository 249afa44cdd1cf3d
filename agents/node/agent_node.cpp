#include "agents/node/agent_node.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <csignal>
#include <limits>
#include <map>
#include <optional>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "agents/node/host_door.h"
#include "agents/node/out_of_step.h"
#include "agents/node/network.h"
#include "agents/node/wire.h"
#include "maps/world.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"

namespace sage::agents {
namespace {

using Clock = std::chrono::system_clock;  // CLOCK_REALTIME: shared by every process of the mission
constexpr std::chrono::seconds kSlowServerWait{2};

}  // namespace

int RunAgentNode(const maps::Scenario& scenario, const AgentNodeOptions& options) {
  const maps::World world(scenario, maps::WorldUse::kVehicles);  // the OctoMap and the risk field are the server's
  // Hand back what reading the scenario and voxelising the seabed freed: glibc keeps it in the heap
  // otherwise. A host of a 10,000-vehicle field stayed at 1.16 GB before its first vehicle moved;
  // its world is 0.19 GB, and the machine may run other hosts and the server.
  malloc_trim(0);
  AgentMission mission(world, scenario, options.guidance);
  // The guidance of a cycle on the machine's cores (a thread per 256 vehicles at most; the
  // commands are the same for any count): one host of many vehicles rather than many hosts.
  mission.SetThreads(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  for (std::size_t i = 0; i < options.vehicles.size(); ++i) {
    const VehicleResume* resume = i < options.resume.size() && options.resume[i] ? &*options.resume[i] : nullptr;
    mission.AddVehicle(static_cast<VehicleId>(options.ids[i]), options.vehicles[i], resume);
  }
  proto::Participant participant(
      options.domain_id,
      // Batched: a cycle's states (one per vehicle) go out many to a datagram, each writer flushed
      // once the cycle's writes are done.
      proto::WithBatchedWrites(
          proto::CycloneConfigXml(NetworkOf(scenario.network), proto::kMaxLocalParticipants, options.security)));
  const auto lease = std::chrono::milliseconds(std::lround(scenario.fleet.liveliness_lease_s * 1000.0));
  proto::Writer<proto::VehicleState> states(participant, proto::VehicleStateWriterQos(lease));
  proto::Writer<proto::VehicleCoverage> coverage(participant, proto::VehicleCoverageQos());
  // The leak sensors' scans, where the scenario gives the vehicles sensors.
  std::optional<proto::Writer<proto::Detection>> detections;
  if (!scenario.sensors.empty()) detections.emplace(participant, proto::DetectionQos());
  std::vector<double> detections_scratch;
  proto::Reader<proto::ErgodicTarget> targets(participant, proto::ErgodicTargetQos());
  proto::Reader<proto::ErgodicTargets> target_batches(participant, proto::ErgodicTargetsQos());
  proto::Reader<proto::FleetCoverage> fleet(participant, proto::FleetCoverageQos());
  proto::Reader<proto::MissionStatus> status(participant, proto::MissionStatusQos());
  proto::Reader<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  // The other hosts' vehicles, so this host's keep apart from them too.
  // Three deep: a host that runs ahead sends its next state before this one takes the last, and
  // the vehicles keep apart on the last cycle's.
  proto::Reader<proto::VehicleState> neighbours(participant, proto::NeighbourStateQos(3));
  std::uint64_t reported_rejections = 0;  // refused at the door (logged)
  // Cycles that went on without the server's last word, and the cycles stepped.
  OutOfStepCycles not_in_step;
  long cycles_run = 0;
  std::int64_t last_stepped = -1;
  std::int64_t next_rejection_report = 0;

  const std::uint64_t fingerprint =
      maps::VehicleFingerprint(scenario) ^ (options.guidance == Guidance::kAstar ? 0x5A5Aull : 0ull);
  HostDoor door(mission, fingerprint);
  const MissionClock& clock = door.clock();
  // Takes the server's status: a new instance (the first, a restart, a resumed mission) brings
  // its clock, and what the last one said is dropped.
  const auto take_status = [&] {
    bool heard = false;
    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (info.valid_data && door.TakeStatus(s)) heard = true;
    });
    return heard;
  };

  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.wait_for_server_s);
  spdlog::info("agents: waiting up to {:.0f} s for the mission's server on DDS domain {}", options.wait_for_server_s,
               options.domain_id);
  while (clock.instance == 0) {
    if (options.stop && options.stop->load()) return 0;
    if (door.ended_elsewhere()) {
      spdlog::info("agents: the mission on DDS domain {} has ended", options.domain_id);
      return 0;
    }
    if (std::chrono::steady_clock::now() > give_up) {
      spdlog::error("agents: no SAGE server on DDS domain {} within {:.0f} s", options.domain_id, options.wait_for_server_s);
      return 1;
    }
    status.WaitForData(std::chrono::milliseconds(100));
    take_status();
    if (door.other_world()) {
      spdlog::error("agents: the server on DDS domain {} runs another scenario or other options; start sage agents "
                    "with the server's scenario and the same -n, --seed, -K, --forgetting, --turn-radius, --model "
                    "and --controller",
                    options.domain_id);
      return 2;
    }
  }
  if (door.finished()) return 0;

  const auto leave = [&](VehicleId id) {
    proto::VehicleState key{};
    key.vehicle_id = static_cast<std::uint32_t>(id);
    (void)proto::CopyBounded(key.name, mission.Name(id));  // a key sample: the id is what counts
    states.Dispose(key);
    states.Flush();  // a leave goes out now, not with the next cycle's states
  };
  const double rate = scenario.control_rate_hz;
  const std::map<int, std::int64_t> scenario_ends = scenario.VehicleEndCycles();
  auto last_heard = std::chrono::steady_clock::now();
  Clock::time_point last_snapshot_at{};  // wall time the last fleet snapshot of this server arrived
  // The server's readers matched before the first report: a state or coverage report written
  // before discovery is done is lost (a join started ahead has seconds for it).
  states.WaitForReaders(1, std::chrono::milliseconds(2000));
  coverage.WaitForReaders(1, std::chrono::milliseconds(2000));
  if (detections) detections->WaitForReaders(1, std::chrono::milliseconds(2000));
  const std::int64_t first_cycle = scenario.CycleAt(options.start_at_s);
  const std::int64_t end_cycle =
      std::isfinite(options.end_at_s) ? scenario.CycleAt(options.end_at_s) : std::numeric_limits<std::int64_t>::max();
  // Not before the server's own first cycle: a resumed server's clock starts a lead ahead, while
  // the hosts it restarts come up.
  std::int64_t k = std::max({first_cycle, door.clock_first_cycle(),
                             static_cast<std::int64_t>(std::ceil(clock.MissionTime(proto::NowRealtimeNs()) * rate))});
  spdlog::info("agents: found the server on DDS domain {}; {} vehicle(s) joining the mission at t = {:.1f} s",
               options.domain_id, mission.vehicle_count(), static_cast<double>(k) / rate);
  const std::int64_t own_first_cycle = k;  // this host's first cycle: it steps it without the server's word
  for (;; ++k) {
    std::this_thread::sleep_until(clock.WallOf(static_cast<double>(k) / rate));
    if (options.stop && options.stop->load()) break;
    if (k >= end_cycle) {  // the scenario's loss or leave, at its cycle
      if (options.end_by_sigkill) {
        spdlog::warn("agents: the scenario loses this host's vehicles at t = {:.1f} s: SIGKILL", static_cast<double>(k) / rate);
        spdlog::default_logger()->flush();
        std::raise(SIGKILL);
      }
      spdlog::info("agents: the scenario's vehicles leave at t = {:.1f} s", static_cast<double>(k) / rate);
      break;
    }
    const std::uint64_t instance = clock.instance;
    if (take_status()) last_heard = std::chrono::steady_clock::now();
    if (door.finished()) break;
    if (clock.instance != instance) {  // a new clock: this cycle's number is on it, from the server's first on
      k = std::max(door.clock_first_cycle(),
                   static_cast<std::int64_t>(std::ceil(clock.MissionTime(proto::NowRealtimeNs()) * rate)));
      // A resumed server's first cycle may lie ahead (its start-up lead): wait for it, as at the start.
      std::this_thread::sleep_until(clock.WallOf(static_cast<double>(k) / rate));
    }
    commands.TakeEach([&](const proto::FleetCommand& c, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      const std::optional<VehicleId> retired = door.TakeCommand(c);
      if (!retired) return;
      const VehicleId id = *retired;
      spdlog::info("agents: {} (id {}) leaves the mission at t = {:.1f} s", mission.Name(id), id,
                   static_cast<double>(k) / rate);
      leave(id);
      mission.RemoveVehicle(id);
    });
    if (mission.vehicle_count() == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
      return 0;
    }
    std::vector<Assignment> first_targets;
    const auto take_targets = [&] {
      // Every host sees every vehicle's assignment (one topic); each takes its own, all of them
      // at once (a 10,000-vehicle fleet's first targets are 10,000 regions' quadratures).
      first_targets.clear();
      while (targets.TakeEach([&](const proto::ErgodicTarget& m, const dds_sample_info_t& info) {
        if (info.valid_data) door.GatherTarget(m, k, first_targets);
      }, 1024) == 1024) {
      }
      door.ApplyTargets(first_targets);
      // Then the later changes (a vehicle's first target goes alone; an older one is not taken
      // over a newer, whichever comes first).
      target_batches.TakeEach([&](const proto::ErgodicTargets& m, const dds_sample_info_t& info) {
        if (info.valid_data) door.TakeTargets(m, k);
      }, static_cast<std::size_t>(proto::kErgodicTargetsDepth));
    };
    const auto take_server_words = [&] {
      take_targets();
      bool snapshot = false;
      fleet.TakeEach([&](const proto::FleetCoverage& m, const dds_sample_info_t& info) {
        if (!info.valid_data) return;
        if (door.TakeSnapshot(m, k)) {
          snapshot = true;
          last_heard = std::chrono::steady_clock::now();
          last_snapshot_at = Clock::now();
        }
      });
      // A cycle's targets are written before its snapshot, but on another topic: when the two
      // come together (after a long server cycle, such as taking a 1,000-valve split) the targets
      // may land between the two takes. Taken again, they steer this cycle as they do in-process.
      if (snapshot) take_targets();
    };
    take_server_words();
    const auto server_silent = [&] {
      const double silent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_heard).count();
      if (silent_s <= options.server_timeout_s) return false;
      spdlog::warn("agents: no word from the server for {:.0f} s; stopping", silent_s);
      return true;
    };
    // Past the mission's last cycle (the server's length, t = duration) nothing is steered: the
    // server has no cycle left to answer, and a host that stepped on waited for that answer and
    // counted it as a cycle out of lockstep at the end of every launch. It waits for the server's
    // word that the mission is over.
    if (std::isfinite(door.duration_s()) && k > std::llround(door.duration_s() * rate)) {
      if (server_silent()) break;
      continue;
    }
    // Lockstep where it can be: cycle k steers on the server's word of cycle k - 1 (its snapshot
    // numbered k), as in the in-process mission; it waits up to 0.45 of a period for it, then goes
    // on (counted). (It had waited only for the word of cycle k - 2: unseen while the server is
    // quick, but after a long server cycle every vehicle steered a cycle on its old target.) A server
    // heard within kSlowServerWait is waited for that long: a long cycle of its own (splitting a
    // 1,000-vehicle field into regions took 0.8 s) is not a silence. The host then catches up
    // with the clock; a server gone silent costs that wait once.
    // The server's first word (its snapshot of this host's first cycle) is waited for as a slow
    // cycle: at the first split of 1,000 regions the vehicles had stood still 0.7 s over DDS and
    // moved from the second cycle in sage run.
    if (last_snapshot_at == Clock::time_point{}) last_snapshot_at = Clock::now();
    const auto behind_server = [&] {
      return mission.has_snapshot() ? mission.snapshot_cycle() < static_cast<std::uint64_t>(std::max<std::int64_t>(k, 1))
                                    : k > own_first_cycle;
    };
    if (behind_server()) {
      const auto deadline = std::max(clock.WallOf((static_cast<double>(k) + 0.45) / rate),
                                     last_snapshot_at + std::chrono::duration_cast<Clock::duration>(kSlowServerWait));
      while (behind_server()) {
        if (std::chrono::system_clock::now() >= deadline) {
          not_in_step.Mark(k);
          break;
        }
        fleet.WaitForData(std::chrono::milliseconds(1));
        take_server_words();
      }
    }
    if (server_silent()) break;
    const auto take_neighbours = [&] {
      while (neighbours.TakeEach(
                 [&](const proto::VehicleState& m, const dds_sample_info_t& info) {
                   door.TakeNeighbour(m, info.valid_data, info.instance_state == DDS_ALIVE_INSTANCE_STATE);
                 },
                 1024) == 1024) {
      }
    };
    take_neighbours();
    // Lockstep for the neighbours too: a vehicle of another host near one of this host's whose
    // state of the last cycle is not in yet is waited for (within the same budget).
    const auto near_ones_in = [&] {
      for (const auto& [other, seen] : door.others()) {
        if (seen.empty() || seen.back().first >= k - 1 || seen.back().first < k - 3) continue;  // in, or gone
        // The scenario lost it or took it out at its cycle (its lease tells this host later).
        if (const auto end = scenario_ends.find(static_cast<int>(other));
            end != scenario_ends.end() && k - 1 >= end->second) {
          continue;
        }
        for (const VehicleId id : mission.ids())
          if ((mission.host().State(id).position_m - seen.back().second).squaredNorm() < 3.0 * 3.0) return false;
      }
      return true;
    };
    if (!near_ones_in()) {
      // Behind the clock (catching up after a long server cycle, as every host is), 0.45 of a
      // period from now: the other hosts' states of the last cycle are on their way.
      const auto now = std::chrono::system_clock::now();
      const bool behind = now > clock.WallOf((static_cast<double>(k) + 0.45) / rate);
      const auto deadline = behind ? now + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(0.45 / rate / clock.time_scale))
                                   : clock.WallOf((static_cast<double>(k) + 0.45) / rate);
      while (!near_ones_in()) {
        if (std::chrono::system_clock::now() >= deadline) {
          not_in_step.Mark(k);
          break;
        }
        std::this_thread::sleep_for(proto::kStreamPoll);
        take_neighbours();
      }
    }
    if (mission.rejected() != reported_rejections && k >= next_rejection_report) {
      spdlog::warn("agents: refused {} message(s) from the server so far; the last: {}", mission.rejected(),
                   mission.last_rejection());
      reported_rejections = mission.rejected();
      next_rejection_report = k + static_cast<std::int64_t>(rate);  // at most one warning a second
    }
    // The others as of last cycle, as this host's own vehicles see each other (AgentMission):
    // a host that is ahead may have sent this cycle's state already, and a state older than the
    // last cycle's is a vehicle that stopped reporting (lost, or late), not a place.
    mission.SetOtherVehicles(door.OthersAt(k - 1));

    // Steered and moved, then reported. (Reporting before the physics, so that the server's cycle
    // ran beside it, gave a secured 10,000-vehicle bench in regions 0.88x and 1.01x real time with
    // a server cycle of 45 and 36 ms, against 1.01x and 29 ms: on two cores both sides are busy
    // already, and the overlap made them contend.)
    const AgentMission::CycleOutput out = mission.Step(k);
    ++cycles_run;
    last_stepped = k;
    const long long stamp = proto::NowRealtimeNs();
    // Coverage and scans first: the server waits for the states of the cycle, and by then a
    // report sent before them is in as well.
    for (const CoverageMessage& c : out.coverage) coverage.Write(wire::ToWire(c, stamp));
    if (detections) {
      for (const ScanReport& scan : out.scans) detections->Write(wire::ToWire(scan, clock.instance, stamp, detections_scratch));
    }
    for (const StateReport& s : out.states) states.Write(wire::ToWire(s, clock.instance, stamp));
    coverage.Flush();
    if (detections) detections->Flush();
    states.Flush();
  }
  for (const VehicleId id : mission.ids()) leave(id);
  // A mission the server ended before its length (an operator's stop) leaves the host a cycle or
  // two past the server's last one, waiting for a word that no cycle sends: those are not the
  // mission's and not counted.
  if (const std::optional<std::uint64_t> ended = door.ended_at_cycle()) {
    const auto end = static_cast<std::int64_t>(*ended);
    not_in_step.DropAfter(end);
    cycles_run -= static_cast<long>(std::max<std::int64_t>(0, last_stepped - end));
  }
  if (not_in_step.count() > 0) {
    spdlog::warn("agents: {} of {} cycles went on without the last cycle's word of the server or a neighbour (not in "
                 "lockstep), the first at t = {:.1f} s",
                 not_in_step.count(), cycles_run, static_cast<double>(*not_in_step.first()) / rate);
  }
  if (mission.rejected() > 0 || door.bad_neighbours() > 0 || door.bad_statuses() > 0 || door.ahead_of_the_clock() > 0) {
    spdlog::warn("agents: refused {} message(s) from the server, {} more stamped over {:.0f} s ahead of the clock, {} "
                 "status(es) with a clock that cannot be and {} neighbour state(s) with no finite position (or beyond "
                 "{} vehicles)",
                 mission.rejected(), door.ahead_of_the_clock(), HostDoor::kMaxLead_s, door.bad_statuses(),
                 door.bad_neighbours(), HostDoor::kMaxOthers);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
  return 0;
}

}  // namespace sage::agents
