#include "agents/node/agent_node.h"

#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <thread>

#include <spdlog/spdlog.h>

#include "agents/agent_host.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"

namespace sage::agents {
namespace {

using Clock = std::chrono::system_clock;  // CLOCK_REALTIME: shared by every process of the mission
using proto::AsSpan;
using proto::BorrowSequence;
using proto::BorrowString;

// One coverage report as published: kept so the vehicle can take exactly that part out of the
// fleet's sums the server sends back.
struct Report {
  std::uint64_t seq = 0;
  double stamp_s = 0.0;  // mission time
  double kernel_time_s = 0.0;
  Eigen::VectorXd sums;
};

struct Vehicle {
  std::uint32_t id = 0;
  std::string name;
  bool has_assignment = false;
  bool shared = true;
  Eigen::VectorXd own_phi;  // partition: this vehicle's share
  std::uint64_t own_phi_cycle = 0;  // the server cycle of own_phi's ErgodicTarget_
  std::uint64_t steered_cycle = 0;  // the server cycle of the target its last command was steered on
  std::uint64_t seq = 0;
  std::deque<Report> reports;
};

struct FleetSnapshot {
  bool valid = false;
  std::uint64_t cycle = 0;
  double time_s = 0.0;
  Eigen::VectorXd phi;
  Eigen::VectorXd sums;
  double kernel_time_s = 0.0;
  std::map<std::uint32_t, std::uint64_t> accounted;
};

constexpr std::size_t kReportsKept = 64;

}  // namespace

int RunAgentNode(const maps::Scenario& scenario, const AgentNodeOptions& options) {
  AgentHost host(scenario, Guidance::kErgodic);
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

  std::map<std::uint32_t, Vehicle> vehicles;
  for (std::size_t i = 0; i < options.vehicles.size(); ++i) {
    host.AddVehicle(static_cast<VehicleId>(options.ids[i]), options.vehicles[i]);
    Vehicle& v = vehicles[options.ids[i]];
    v.id = options.ids[i];
    v.name = options.vehicles[i].name;
  }

  // The mission clock: the server's start time and time scale, from its (transient-local) status.
  const std::uint64_t fingerprint = maps::VehicleFingerprint(scenario);
  long long start_ns = 0;
  double time_scale = 1.0;
  bool finished = false;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.wait_for_server_s);
  spdlog::info("agents: waiting up to {:.0f} s for the mission's server on DDS domain {}", options.wait_for_server_s,
               options.domain_id);
  while (start_ns == 0) {
    if (options.stop && options.stop->load()) return 0;
    if (std::chrono::steady_clock::now() > give_up) {
      spdlog::error("agents: no SAGE server on DDS domain {} within {:.0f} s", options.domain_id, options.wait_for_server_s);
      return 1;
    }
    status.WaitForData(std::chrono::milliseconds(100));
    bool other_world = false;
    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      other_world = s.vehicle_fingerprint != fingerprint;
      start_ns = s.start_ns;
      time_scale = s.time_scale;
      finished = s.finished;
    });
    if (other_world) {
      spdlog::error("agents: the server on DDS domain {} runs another scenario or other options; start sage agents "
                    "with the server's scenario and the same -n, --seed, -K, --forgetting, --turn-radius and --model",
                    options.domain_id);
      return 2;
    }
  }
  if (finished) return 0;
  auto mission_time = [&](long long ns) { return (ns - start_ns) * 1e-9 * time_scale; };
  auto wall_of = [&](double t) {
    return Clock::time_point(std::chrono::duration_cast<Clock::duration>(
        std::chrono::nanoseconds(start_ns + static_cast<long long>(t / time_scale * 1e9))));
  };
  // k / rate rather than k * period: cycle 3 is t = 0.3, not 0.30000000000000004.
  auto cycle_time = [&](long k) { return static_cast<double>(k) / scenario.control_rate_hz; };
  const double forgetting = scenario.ergodic.forgetting_time_s;
  auto decay = [&](double age) { return std::isfinite(forgetting) ? std::exp(-std::max(0.0, age) / forgetting) : 1.0; };

  auto leave = [&](const Vehicle& v) {
    proto::VehicleState key{};
    key.vehicle_id = v.id;
    key.name = BorrowString(v.name);
    states.Dispose(key);
  };

  FleetSnapshot snapshot;
  auto last_heard = std::chrono::steady_clock::now();
  long k = static_cast<long>(std::ceil(mission_time(proto::NowRealtimeNs()) * scenario.control_rate_hz));
  double next_coverage_t = cycle_time(k);
  spdlog::info("agents: found the server on DDS domain {}; {} vehicle(s) joining the mission at t = {:.1f} s",
               options.domain_id, vehicles.size(), cycle_time(k));
  for (;; ++k) {
    const double t = cycle_time(k);
    std::this_thread::sleep_until(wall_of(t));
    if (options.stop && options.stop->load()) break;

    status.TakeEach([&](const proto::MissionStatus& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      last_heard = std::chrono::steady_clock::now();
      finished = finished || s.finished;
    });
    if (finished) break;
    commands.TakeEach([&](const proto::FleetCommand& c, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      if (proto::AsStringView(c.verb) == "remove" && vehicles.count(c.vehicle_id)) {
        leave(vehicles[c.vehicle_id]);
        host.RemoveVehicle(static_cast<VehicleId>(c.vehicle_id));
        spdlog::info("agents: {} (id {}) left the mission at t = {:.1f} s", vehicles[c.vehicle_id].name, c.vehicle_id, t);
        vehicles.erase(c.vehicle_id);
      }
    });
    if (vehicles.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
      return 0;
    }
    // Every host sees every vehicle's assignment (one topic); take them all, 1,024 at a time.
    auto take_target = [&](const proto::ErgodicTarget& m, const dds_sample_info_t& info) {
      auto it = vehicles.find(m.vehicle_id);
      if (!info.valid_data || it == vehicles.end()) return;
      const auto phi = AsSpan(m.phi);
      it->second.has_assignment = true;
      it->second.shared = m.shared;
      it->second.own_phi_cycle = m.cycle;
      it->second.own_phi = Eigen::Map<const Eigen::VectorXd>(phi.data(), static_cast<Eigen::Index>(phi.size()));
    };
    while (targets.TakeEach(take_target, 1024) == 1024) {
    }
    fleet.TakeEach([&](const proto::FleetCoverage& m, const dds_sample_info_t& info) {
      if (!info.valid_data || m.mission_time_s < snapshot.time_s) return;
      last_heard = std::chrono::steady_clock::now();
      snapshot.valid = true;
      snapshot.cycle = m.cycle;
      snapshot.time_s = m.mission_time_s;
      const auto phi = AsSpan(m.phi), sums = AsSpan(m.sums);
      snapshot.phi = Eigen::Map<const Eigen::VectorXd>(phi.data(), static_cast<Eigen::Index>(phi.size()));
      snapshot.sums = Eigen::Map<const Eigen::VectorXd>(sums.data(), static_cast<Eigen::Index>(sums.size()));
      snapshot.kernel_time_s = m.kernel_time_s;
      snapshot.accounted.clear();
      const auto ids = AsSpan(m.vehicle_ids);
      const auto seqs = AsSpan(m.accounted_seq);
      for (std::size_t i = 0; i < ids.size() && i < seqs.size(); ++i) snapshot.accounted[ids[i]] = seqs[i];
    });
    const double silent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_heard).count();
    if (silent_s > options.server_timeout_s) {
      spdlog::warn("agents: no word from the server for {:.0f} s; stopping", silent_s);
      break;
    }

    auto take_neighbour = [&](const proto::VehicleState& m, const dds_sample_info_t& info) {
      if (vehicles.count(m.vehicle_id)) return;
      if (info.valid_data) {
        others[m.vehicle_id] = Eigen::Vector2d(m.x_m, m.y_m);
      } else {
        others.erase(m.vehicle_id);  // lost or left
      }
    };
    while (neighbours.TakeEach(take_neighbour, 1024) == 1024) {
    }
    std::vector<Eigen::Vector2d> other_positions;
    other_positions.reserve(others.size());
    for (const auto& [id, p] : others) other_positions.push_back(p);
    host.SetOtherVehicles(std::move(other_positions));

    if (snapshot.valid && snapshot.phi.size() == host.basis().size()) {
      for (auto& [id, v] : vehicles) {
        VehicleTarget target;
        if (v.has_assignment && !v.shared && v.own_phi.size() == host.basis().size()) {
          target.phi = v.own_phi;  // partition: its share, alone
          v.steered_cycle = v.own_phi_cycle;
        } else {
          // Shared coverage: the fleet's sums minus this vehicle's own report that the server
          // included (matched by seq), aged to now with the forgetting window.
          target.phi = snapshot.phi;
          target.fleet_sums = snapshot.sums;
          target.fleet_time_s = snapshot.kernel_time_s;
          auto accounted = snapshot.accounted.find(id);
          if (accounted != snapshot.accounted.end()) {
            for (const Report& r : v.reports) {
              if (r.seq != accounted->second) continue;
              const double d = decay(snapshot.time_s - r.stamp_s);
              target.fleet_sums -= d * r.sums;
              target.fleet_time_s -= d * r.kernel_time_s;
            }
          }
          const double age = decay(t - snapshot.time_s);
          target.fleet_sums *= age;
          target.fleet_time_s = std::max(0.0, target.fleet_time_s * age);
          v.steered_cycle = snapshot.cycle;
        }
        host.SetTarget(static_cast<VehicleId>(id), target);
      }
      host.Step(t);  // vehicles hold still until the server's first word
    }

    const long long stamp = proto::NowRealtimeNs();
    for (const auto& [id, v] : vehicles) {
      const VehicleState s = host.State(static_cast<VehicleId>(id));
      proto::VehicleState msg{};
      msg.vehicle_id = id;
      msg.stamp_ns = stamp;
      msg.name = BorrowString(v.name);
      msg.x_m = s.position_m.x();
      msg.y_m = s.position_m.y();
      msg.heading_rad = s.heading_rad;
      msg.vx_mps = s.velocity_mps.x();
      msg.vy_mps = s.velocity_mps.y();
      const Eigen::Vector2d command = host.LastCommand(static_cast<VehicleId>(id));
      msg.cmd_x_mps = command.x();
      msg.cmd_y_mps = command.y();
      msg.target_cycle = v.steered_cycle;
      states.Write(msg);
    }
    if (t + 1e-9 >= next_coverage_t) {
      next_coverage_t = t + scenario.fleet.coverage_period_s;
      for (auto& [id, v] : vehicles) {
        const CoverageAccumulator* acc = host.Coverage(static_cast<VehicleId>(id));
        if (acc == nullptr || acc->time_s() <= 0.0) continue;
        Report r{++v.seq, t, acc->time_s(), acc->sums()};
        proto::VehicleCoverage msg{};
        msg.vehicle_id = id;
        msg.stamp_ns = start_ns + static_cast<long long>(t / time_scale * 1e9);
        msg.seq = r.seq;
        msg.time_s = r.kernel_time_s;
        msg.sums = BorrowSequence(std::span<const double>(r.sums.data(), static_cast<std::size_t>(r.sums.size())));
        coverage.Write(msg);
        v.reports.push_back(std::move(r));
        if (v.reports.size() > kReportsKept) v.reports.pop_front();
      }
    }
  }
  for (const auto& [id, v] : vehicles) leave(v);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let the disposes go out
  return 0;
}

}  // namespace sage::agents
