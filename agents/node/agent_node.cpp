#include "agents/node/agent_node.h"

#include <chrono>
#include <cmath>
#include <map>
#include <thread>

#include <spdlog/spdlog.h>

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

// The mission clock as the current server announces it.
struct MissionClock {
  std::uint64_t instance = 0;
  long long start_ns = 0;
  double time_scale = 1.0;
  double MissionTime(long long ns) const { return static_cast<double>(ns - start_ns) * 1e-9 * time_scale; }
  Clock::time_point WallOf(double mission_s) const {
    return Clock::time_point(std::chrono::duration_cast<Clock::duration>(
        std::chrono::nanoseconds(start_ns + static_cast<long long>(mission_s / time_scale * 1e9))));
  }
};

}  // namespace

int RunAgentNode(const maps::Scenario& scenario, const AgentNodeOptions& options) {
  const maps::World world(scenario);
  AgentMission mission(world, scenario, options.guidance);
  for (std::size_t i = 0; i < options.vehicles.size(); ++i) {
    const VehicleResume* resume = i < options.resume.size() && options.resume[i] ? &*options.resume[i] : nullptr;
    mission.AddVehicle(static_cast<VehicleId>(options.ids[i]), options.vehicles[i], resume);
  }
  proto::Participant participant(options.domain_id, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
  const auto lease = std::chrono::milliseconds(std::lround(scenario.fleet.liveliness_lease_s * 1000.0));
  proto::Writer<proto::VehicleState> states(participant, proto::VehicleStateWriterQos(lease));
  proto::Writer<proto::VehicleCoverage> coverage(participant, proto::VehicleCoverageQos());
  proto::Reader<proto::ErgodicTarget> targets(participant, proto::ErgodicTargetQos());
  proto::Reader<proto::FleetCoverage> fleet(participant, proto::FleetCoverageQos());
  proto::Reader<proto::MissionStatus> status(participant, proto::MissionStatusQos());
  proto::Reader<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  // The other hosts' vehicles, so this host's keep apart from them too.
  proto::Reader<proto::VehicleState> neighbours(participant, proto::VehicleStateReaderQos());
  std::map<std::uint32_t, Eigen::Vector2d> others;
  std::uint64_t bad_neighbours = 0, reported_rejections = 0;  // refused at the door (logged)
  std::int64_t next_rejection_report = 0;

  const std::uint64_t fingerprint =
      maps::VehicleFingerprint(scenario) ^ (options.guidance == Guidance::kAstar ? 0x5A5Aull : 0ull);
  MissionClock clock;
  bool finished = false, other_world = false;
  // Takes the server's status: a new instance (the first, a restart, a resumed mission) brings
  // its clock, and what the last one said is dropped.
  const auto take_status = [&] {
    bool heard = false;
    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      heard = true;
      if (s.vehicle_fingerprint != fingerprint) {
        other_world = true;
        return;
      }
      if (s.server_instance != clock.instance) {
        if (clock.instance != 0) {
          spdlog::info("agents: a new server runs the mission (t = {:.1f} s on its clock); following it",
                       s.mission_time_s);
          mission.OnNewServer();
        }
        clock = {s.server_instance, s.start_ns, s.time_scale};
      }
      finished = finished || s.finished;
    });
    return heard;
  };

  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.wait_for_server_s);
  spdlog::info("agents: waiting up to {:.0f} s for the mission's server on DDS domain {}", options.wait_for_server_s,
               options.domain_id);
  while (clock.instance == 0) {
    if (options.stop && options.stop->load()) return 0;
    if (std::chrono::steady_clock::now() > give_up) {
      spdlog::error("agents: no SAGE server on DDS domain {} within {:.0f} s", options.domain_id, options.wait_for_server_s);
      return 1;
    }
    status.WaitForData(std::chrono::milliseconds(100));
    take_status();
    if (other_world) {
      spdlog::error("agents: the server on DDS domain {} runs another scenario or other options; start sage agents "
                    "with the server's scenario and the same -n, --seed, -K, --forgetting, --turn-radius, --model "
                    "and --controller",
                    options.domain_id);
      return 2;
    }
  }
  if (finished) return 0;

  const auto leave = [&](VehicleId id) {
    proto::VehicleState key{};
    key.vehicle_id = static_cast<std::uint32_t>(id);
    const std::string name = mission.Name(id);
    key.name = proto::BorrowString(name);
    states.Dispose(key);
  };
  const double rate = scenario.control_rate_hz;
  auto last_heard = std::chrono::steady_clock::now();
  std::int64_t k = static_cast<std::int64_t>(std::ceil(clock.MissionTime(proto::NowRealtimeNs()) * rate));
  spdlog::info("agents: found the server on DDS domain {}; {} vehicle(s) joining the mission at t = {:.1f} s",
               options.domain_id, mission.vehicle_count(), static_cast<double>(k) / rate);
  for (;; ++k) {
    std::this_thread::sleep_until(clock.WallOf(static_cast<double>(k) / rate));
    if (options.stop && options.stop->load()) break;
    const std::uint64_t instance = clock.instance;
    if (take_status()) last_heard = std::chrono::steady_clock::now();
    if (finished) break;
    if (clock.instance != instance) {  // a new clock: this cycle's number is on it
      k = static_cast<std::int64_t>(std::ceil(clock.MissionTime(proto::NowRealtimeNs()) * rate));
    }
    commands.TakeEach([&](const proto::FleetCommand& c, const dds_sample_info_t& info) {
      if (!info.valid_data || c.server_instance != clock.instance || proto::AsStringView(c.verb) != "retire") return;
      const VehicleId id = static_cast<VehicleId>(c.vehicle_id);
      if (!mission.Contains(id)) return;
      spdlog::info("agents: {} (id {}) leaves the mission at t = {:.1f} s", mission.Name(id), id,
                   static_cast<double>(k) / rate);
      leave(id);
      mission.RemoveVehicle(id);
    });
    if (mission.vehicle_count() == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
      return 0;
    }
    // Every host sees every vehicle's assignment (one topic); each takes its own.
    while (targets.TakeEach([&](const proto::ErgodicTarget& m, const dds_sample_info_t& info) {
      if (info.valid_data && m.server_instance == clock.instance) mission.OnAssignment(wire::FromWire(m));
    }, 1024) == 1024) {
    }
    fleet.TakeEach([&](const proto::FleetCoverage& m, const dds_sample_info_t& info) {
      if (!info.valid_data || m.server_instance != clock.instance) return;
      if (mission.OnFleetSnapshot(wire::FromWire(m))) last_heard = std::chrono::steady_clock::now();
    });
    const double silent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_heard).count();
    if (silent_s > options.server_timeout_s) {
      spdlog::warn("agents: no word from the server for {:.0f} s; stopping", silent_s);
      break;
    }
    while (neighbours.TakeEach([&](const proto::VehicleState& m, const dds_sample_info_t& info) {
      if (mission.Contains(static_cast<VehicleId>(m.vehicle_id))) return;
      if (info.valid_data && info.instance_state == DDS_ALIVE_INSTANCE_STATE) {
        const Eigen::Vector2d p(m.x_m, m.y_m);
        if (p.allFinite()) {
          others[m.vehicle_id] = p;
        } else {
          ++bad_neighbours;  // not a place to keep clear of
          others.erase(m.vehicle_id);
        }
      } else {
        others.erase(m.vehicle_id);  // lost or left
      }
    }, 1024) == 1024) {
    }
    if (mission.rejected() != reported_rejections && k >= next_rejection_report) {
      spdlog::warn("agents: refused {} message(s) from the server so far; the last: {}", mission.rejected(),
                   mission.last_rejection());
      reported_rejections = mission.rejected();
      next_rejection_report = k + static_cast<std::int64_t>(rate);  // at most one warning a second
    }
    std::vector<Eigen::Vector2d> other_positions;
    other_positions.reserve(others.size());
    for (const auto& [id, p] : others) other_positions.push_back(p);
    mission.SetOtherVehicles(std::move(other_positions));

    const AgentMission::CycleOutput out = mission.Step(k);
    const long long stamp = proto::NowRealtimeNs();
    for (const StateReport& s : out.states) states.Write(wire::ToWire(s, clock.instance, stamp));
    for (const CoverageMessage& c : out.coverage) coverage.Write(wire::ToWire(c, stamp));
  }
  for (const VehicleId id : mission.ids()) leave(id);
  if (mission.rejected() > 0 || bad_neighbours > 0) {
    spdlog::warn("agents: refused {} message(s) from the server and {} neighbour state(s) with no finite position",
                 mission.rejected(), bad_neighbours);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
  return 0;
}

}  // namespace sage::agents
