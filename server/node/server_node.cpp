#include "server/node/server_node.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "maps/seabed_map.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"
#include "server/fleet_server.h"
#include "server/mission.h"
#include "server/report/atomic_write.h"
#include "server/report/report.h"

namespace sage::server {

namespace {

namespace fs = std::filesystem;
using proto::NowRealtimeNs;
using proto::AsSpan;
using proto::AsStringView;
using proto::BorrowSequence;
using proto::BorrowString;

struct FleetLogEntry {
  double time_s;
  std::string what;  // joined, lost, left
  unsigned vehicle_id;
  std::string name;
};

// Fleets larger than this get one log line per cycle for their joins instead of one per vehicle.
constexpr std::size_t kJoinsLoggedOneByOne = 20;

struct KnownVehicle {
  int index = 0;  // dense index: trajectory.vehicle_names[index]
  bool alive = false;
  proto::VehicleState last{};
  bool has_state = false;
  bool target_sent = false;
};

// A risk event whose heading change waits for the first command vehicle_id steers on the
// event's target (its state's target_cycle reaches `cycle`).
struct PendingHeadingChange {
  std::size_t response;  // index into FleetServer::responses()
  std::uint64_t cycle;   // the server cycle whose FleetCoverage_ first carried the new field
  unsigned vehicle_id;
};

Eigen::Vector2d CommandOf(const proto::VehicleState& s) { return {s.cmd_x_mps, s.cmd_y_mps}; }

}  // namespace

int RunServerNode(const maps::Scenario& scenario, const ServerNodeOptions& options) {
  PrepareRunDirectory(options.out_dir);  // a mission of minutes must not end in "cannot write"
  // The effective scenario beside the results, as sage run and sage launch leave it.
  detail::WriteAtomically((fs::path(options.out_dir) / "scenario.yaml").string(), maps::EmitScenario(scenario));
  FleetServer server(scenario, options.profile);
  const bool partition = scenario.fleet.assignment == maps::FleetAssignment::kPartition;
  proto::Participant participant(options.domain_id, proto::LocalhostConfigXml(proto::kMaxLocalParticipants));
  {
    // Two servers on one domain would both adopt the same vehicles and clocks: refuse to be the
    // second. Asked before this server's own status writer exists; discovery on loopback takes
    // a few ms, so 0.5 s finds any server already running.
    proto::Reader<proto::MissionStatus> others(participant, proto::MissionStatusQos());
    if (others.WaitForWriters(1, std::chrono::milliseconds(500))) {
      throw maps::ScenarioError(fmt::format("--domain = {}: another mission's server is running on this DDS domain",
                                            options.domain_id));
    }
  }
  proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateReaderQos());
  proto::Reader<proto::VehicleCoverage> coverage(participant, proto::VehicleCoverageQos());
  proto::Reader<proto::RiskUpdate> risk_updates(participant, proto::RiskUpdateQos());
  proto::Writer<proto::RiskUpdateResult> risk_results(participant, proto::RiskUpdateResultQos());
  proto::Reader<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  proto::Writer<proto::ErgodicTarget> targets(participant, proto::ErgodicTargetQos());
  proto::Writer<proto::FleetCoverage> fleet_coverage(participant, proto::FleetCoverageQos());
  proto::Writer<proto::MissionStatus> status(participant, proto::MissionStatusQos());

  const double dt = 1.0 / scenario.control_rate_hz;
  const long cycles_total = std::lround(scenario.duration_s / dt);
  const long long start_ns = NowRealtimeNs();
  const auto wall_start = std::chrono::steady_clock::now();
  auto mission_time = [&](long long stamp_ns) { return (stamp_ns - start_ns) * 1e-9 * options.time_scale; };

  std::map<unsigned, KnownVehicle> vehicles;
  std::vector<FleetLogEntry> fleet_log;
  Trajectory trajectory;
  std::uint32_t lost_count = 0;
  double last_cycle_ms = 0.0, total_cycle_ms = 0.0, max_cycle_ms = 0.0;
  long cycles_run = 0;
  std::uint64_t messages_in = 0, messages_out = 0;
  bool stop_requested = false;
  std::vector<PendingHeadingChange> pending_heading_changes;
  // In-process the heading change compares one state's command with and without the event. Over
  // DDS the nearest is the first command steered on the event's target against the command
  // before it, one cycle earlier (more if a best-effort state was lost on the way).
  auto answer_heading_changes = [&](unsigned id, const proto::VehicleState& before, const proto::VehicleState& now) {
    std::erase_if(pending_heading_changes, [&](const PendingHeadingChange& p) {
      if (p.vehicle_id != id || now.target_cycle < p.cycle) return false;
      if (before.target_cycle < p.cycle) {
        server.responses()[p.response].heading_change_rad = HeadingChange(CommandOf(before), CommandOf(now));
      }
      return true;
    });
  };

  const std::uint64_t vehicle_fingerprint = maps::VehicleFingerprint(scenario);
  auto publish_status = [&](long cycle, double t, bool finished) {
    proto::MissionStatus s{};
    s.stamp_ns = NowRealtimeNs();
    s.start_ns = start_ns;
    s.time_scale = options.time_scale;
    s.cycle = static_cast<std::uint64_t>(cycle);
    s.mission_time_s = t;
    s.duration_s = scenario.duration_s;
    s.vehicles_alive = static_cast<std::uint32_t>(server.alive().size());
    s.vehicles_lost = lost_count;
    s.cycle_time_ms = last_cycle_ms;
    s.ergodic_metric = server.FleetMetric();
    s.finished = finished;
    s.vehicle_fingerprint = vehicle_fingerprint;
    status.Write(s);
    ++messages_out;
  };

  auto publish_target = [&](unsigned id, long cycle) {
    Eigen::VectorXd phi;
    const bool shared = !partition;
    if (!shared) phi = server.TargetFor(static_cast<int>(id)).phi;
    proto::ErgodicTarget msg{};
    msg.vehicle_id = id;
    msg.stamp_ns = NowRealtimeNs();
    msg.cycle = static_cast<std::uint64_t>(cycle);
    msg.basis_order = static_cast<std::uint32_t>(scenario.ergodic.basis_order);
    msg.shared = shared;
    msg.phi = BorrowSequence(std::span<const double>(phi.data(), static_cast<std::size_t>(phi.size())));
    targets.Write(msg);
    ++messages_out;
  };

  publish_status(0, 0.0, false);
  spdlog::info("server: mission '{}' on DDS domain {}, {:.0f} s at {}x real time, {} coverage", scenario.name,
               options.domain_id, scenario.duration_s, options.time_scale, ToString(scenario.fleet.assignment));

  long cycle = 0;
  std::vector<std::vector<int>> last_assignment;
  Eigen::VectorXd last_weights;
  for (; cycle <= cycles_total; ++cycle) {
    // cycle / rate rather than cycle * dt: cycle 3 is t = 0.3, not 0.30000000000000004.
    const double t = static_cast<double>(cycle) / scenario.control_rate_hz;
    std::this_thread::sleep_until(wall_start + std::chrono::duration<double>(t / options.time_scale));
    if ((options.stop && options.stop->load()) || stop_requested) break;
    const auto compute_start = std::chrono::steady_clock::now();

    // Vehicles: joins (first state), deaths (liveliness lapsed) and clean leaves (disposed).
    int joined_this_cycle = 0;
    // Take until empty: one take returns at most 256 samples, and a 1,000-vehicle fleet sends 1,000 a cycle.
    auto take_all = [](auto& reader, auto&& visit) {
      while (reader.TakeEach(visit, 1024) == 1024) {
      }
    };
    take_all(states, [&](const proto::VehicleState& s, const dds_sample_info_t& info) {
      ++messages_in;
      KnownVehicle& v = vehicles[s.vehicle_id];
      if (info.valid_data) {
        if (!v.alive) {
          if (!v.has_state) {  // first heard of: it gets the next trajectory index
            v.index = static_cast<int>(trajectory.vehicle_names.size());
            trajectory.vehicle_names.emplace_back(AsStringView(s.name));
          }
          v.alive = true;
          server.AddVehicle(static_cast<int>(s.vehicle_id), std::string(AsStringView(s.name)));
          fleet_log.push_back({t, "joined", s.vehicle_id, std::string(AsStringView(s.name))});
          if (vehicles.size() <= kJoinsLoggedOneByOne) {
            spdlog::info("server: {} (id {}) joined at t = {:.1f} s", AsStringView(s.name), s.vehicle_id, t);
          }
          ++joined_this_cycle;
        } else {
          answer_heading_changes(s.vehicle_id, v.last, s);
        }
        v.last = s;
        v.last.name = nullptr;  // the name lives in trajectory.vehicle_names; the sample's memory is a loan
        v.has_state = true;
        // A dispose or a lapsed lease that arrives while the vehicle's last state is still
        // unread comes as that (valid) sample with a not-alive instance state, not as a sample
        // of its own: take the state, then the leave.
        if (info.instance_state == DDS_ALIVE_INSTANCE_STATE) return;
      }
      if (!v.alive) return;
      const bool lost = info.instance_state == DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE;
      v.alive = false;
      // Its answer to a pending event never comes: that heading change stays unknown (NaN).
      std::erase_if(pending_heading_changes,
                    [&](const PendingHeadingChange& p) { return p.vehicle_id == s.vehicle_id; });
      server.RemoveVehicle(static_cast<int>(s.vehicle_id), lost, t);
      lost_count += lost ? 1 : 0;
      const std::string& name = trajectory.vehicle_names.at(v.index);
      fleet_log.push_back({t, lost ? "lost" : "left", s.vehicle_id, name});
      spdlog::info("server: {} (id {}) {} at t = {:.1f} s (last heard at t = {:.1f} s)", name, s.vehicle_id,
                   lost ? "lost" : "left", t, mission_time(v.last.stamp_ns));
    });
    if (vehicles.size() > kJoinsLoggedOneByOne && joined_this_cycle > 0) {
      spdlog::info("server: {} vehicles joined at t = {:.1f} s ({} alive)", joined_this_cycle, t, server.alive().size());
    }
    take_all(coverage, [&](const proto::VehicleCoverage& c, const dds_sample_info_t& info) {
      ++messages_in;
      if (!info.valid_data) return;
      const auto sums = AsSpan(c.sums);
      server.OnCoverage(static_cast<int>(c.vehicle_id), c.seq, mission_time(c.stamp_ns), c.time_s,
                        Eigen::Map<const Eigen::VectorXd>(sums.data(), static_cast<Eigen::Index>(sums.size())));
    });
    const std::size_t responses_before = server.responses().size();
    risk_updates.TakeEach([&](const proto::RiskUpdate& r, const dds_sample_info_t& info) {
      ++messages_in;
      if (!info.valid_data) return;
      proto::RiskUpdateResult result{};
      result.update_stamp_ns = r.stamp_ns;
      result.valve = r.valve;
      result.mission_time_s = t;
      std::string reason;
      try {
        server.SetRiskWeight(std::string(AsStringView(r.valve)), r.weight, t, std::string(AsStringView(r.source)));
        result.applied = true;
        result.new_share = server.responses().back().new_weight;
        spdlog::info("server: risk of {} set to {} by {} at t = {:.1f} s", AsStringView(r.valve), r.weight,
                     AsStringView(r.source), t);
      } catch (const std::exception& e) {  // an operator's message must never end the mission
        reason = e.what();
        spdlog::warn("server: ignored {}", reason);
      }
      result.reason = proto::BorrowString(reason);
      risk_results.Write(result);
      ++messages_out;
    });
    commands.TakeEach([&](const proto::FleetCommand& c, const dds_sample_info_t& info) {
      ++messages_in;
      if (info.valid_data && AsStringView(c.verb) == "stop") stop_requested = true;
    });

    for (auto& [id, v] : vehicles) {
      if (!v.alive || !v.has_state) continue;
      const Eigen::Vector2d position(v.last.x_m, v.last.y_m);
      server.OnState(static_cast<int>(id), t, position);
      trajectory.samples.push_back({t, v.index, position, v.last.heading_rad, Eigen::Vector2d(v.last.vx_mps, v.last.vy_mps),
                                    CommandOf(v.last)});
    }
    server.Cycle(t);
    // This cycle's risk changes (operators' and the profile's): measured on the first vehicle, as
    // in-process; unknown (NaN, null in metrics.json) until its answer arrives, or if none is alive.
    const std::vector<int> alive = server.alive();
    for (std::size_t i = responses_before; i < server.responses().size(); ++i) {
      server.responses()[i].heading_change_rad = std::numeric_limits<double>::quiet_NaN();
      if (!alive.empty()) {
        pending_heading_changes.push_back({i, static_cast<std::uint64_t>(cycle), static_cast<unsigned>(alive.front())});
      }
    }

    const FleetCoverage& fc = server.coverage();
    std::vector<std::uint32_t> ids;
    std::vector<std::uint64_t> seqs;
    for (const auto& [id, seq] : fc.accounted_seq) {
      ids.push_back(static_cast<std::uint32_t>(id));
      seqs.push_back(seq);
    }
    proto::FleetCoverage msg{};
    msg.stamp_ns = NowRealtimeNs();
    msg.cycle = static_cast<std::uint64_t>(cycle);
    msg.mission_time_s = t;
    msg.basis_order = static_cast<std::uint32_t>(scenario.ergodic.basis_order);
    msg.phi = BorrowSequence(std::span<const double>(server.phi().data(), server.phi().size()));
    msg.sums = BorrowSequence(std::span<const double>(fc.sums.data(), fc.sums.size()));
    msg.kernel_time_s = fc.kernel_time_s;
    msg.vehicle_ids = BorrowSequence(std::span<const std::uint32_t>(ids));
    msg.accounted_seq = BorrowSequence(std::span<const std::uint64_t>(seqs));
    fleet_coverage.Write(msg);
    ++messages_out;

    // A partition target is the vehicle's share of the valves weighted by the current risk, so
    // it is sent again when the shares change and when the risk does (an operator's update, a
    // profile event, the guard); in-process every vehicle gets it every cycle.
    const Eigen::VectorXd& weights = server.effective_weights();
    const bool reweighted = weights.size() != last_weights.size() ||
                            (weights.size() > 0 && (weights - last_weights).cwiseAbs().maxCoeff() > 0.0);
    // Also after any risk event, even one that left the weights as they were: its heading change
    // waits for a command steered on a target of this cycle or later.
    const bool risk_event = server.responses().size() > responses_before;
    const bool reassigned = partition && (server.assignment() != last_assignment || reweighted || risk_event);
    if (reassigned) {
      last_assignment = server.assignment();
      last_weights = weights;
    }
    for (auto& [id, v] : vehicles) {
      if (!v.alive || (v.target_sent && !reassigned)) continue;
      publish_target(id, cycle);
      v.target_sent = true;
    }
    last_cycle_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - compute_start).count();
    total_cycle_ms += last_cycle_ms;
    max_cycle_ms = std::max(max_cycle_ms, last_cycle_ms);
    ++cycles_run;
    if (cycle % 5 == 0) publish_status(cycle, t, false);
    if (options.show_progress && cycle % std::max(1L, cycles_total / 20) == 0) {
      std::fprintf(stderr, "server  t = %5.0f / %.0f s  vehicles %zu (lost %u)  metric %.2e  cycle %.2f ms\n", t,
                   scenario.duration_s, server.alive().size(), lost_count, server.FleetMetric(), last_cycle_ms);
    }
  }
  const double end_time = std::min(scenario.duration_s, static_cast<double>(cycle) / scenario.control_rate_hz);
  publish_status(cycle, end_time, true);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  // Samples of one cycle were taken in id order; the file lists them by (time, trajectory index),
  // so names read back to the same indices.
  std::stable_sort(trajectory.samples.begin(), trajectory.samples.end(), [](const auto& a, const auto& b) {
    return a.time_s < b.time_s || (a.time_s == b.time_s && a.vehicle < b.vehicle);
  });
  MetricsOptions metrics_options;
  metrics_options.controller = "ergodic";
  metrics_options.profile = server.profile().name;
  MissionMetrics metrics = ComputeMetrics(trajectory, scenario, server.schedule(), std::max(dt, end_time), metrics_options);
  metrics.events = server.responses();
  FillEventResponses(scenario, metrics);
  std::cout << FormatTable({metrics});
  fs::create_directories(options.out_dir);
  const fs::path dir(options.out_dir);
  WriteTrajectoryCsv((dir / "trajectory.csv").string(), trajectory);
  WriteMetricsJson((dir / "metrics.json").string(), metrics);
  WritePlotSvg((dir / "plot.svg").string(), scenario, server.schedule().back().weights, trajectory,
               fmt::format("{}: fleet of {} over DDS, {:.0f} s", scenario.name, trajectory.vehicle_names.size(), end_time));
  maps::SeabedMap(scenario, scenario.astar.grid_resolution_m).WriteBinary((dir / "seabed.bt").string());
  std::ofstream log(dir / "fleet_events.csv");
  log << "t,event,vehicle_id,name\n";
  for (const FleetLogEntry& e : fleet_log) log << e.time_s << "," << e.what << "," << e.vehicle_id << "," << e.name << "\n";
  spdlog::info("server: {:.0f} s of mission in {:.1f} s wall ({:.2f}x real time); {} messages in, {} out ({:.0f}/s); "
               "server cycle {:.2f} ms mean, {:.2f} ms max; wrote {}",
               end_time, wall_s, end_time / std::max(1e-9, wall_s), messages_in, messages_out,
               (messages_in + messages_out) / std::max(1e-9, wall_s), total_cycle_ms / std::max(1L, cycles_run),
               max_cycle_ms, dir.string());
  return 0;
}

}  // namespace sage::server
