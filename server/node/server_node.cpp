#include "server/node/server_node.h"

#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "agents/node/network.h"
#include "agents/node/wire.h"
#include "maps/world.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"
#include "proto/wire_size.h"
#include "server/live/live_view.h"
#include "server/lockstep.h"
#include "server/live/mission_frames.h"
#include "server/operator_requests.h"
#include "server/report/checkpoint.h"
#include "server/report/report.h"
#include "server/node/server_door.h"
#include "server/report/run_directory.h"
#include "server/report/view_token.h"

namespace sage::server {
namespace {

// Milliseconds of CPU a thread's usage counts (user and system).
double CpuMs(const rusage& usage) {
  return 1e3 * static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-3 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

using proto::BorrowString;
using proto::NowRealtimeNs;
using SteadyClock = std::chrono::steady_clock;

// Up to this many joins of one cycle are logged by name; more are summed up in one line.
constexpr std::size_t kJoinsNamed = 5;

// The record, and the log lines an operator reads: joins, losses and risk changes as they
// happen (joins of one cycle summed up when many).
class LoggedRecord final : public MissionRecorder {
 public:
  explicit LoggedRecord(RunDirectory& run) : run_(run) {}
  void OnSample(const TrajectorySample& s, const std::string& name) override { run_.OnSample(s, name); }
  void OnSamples(const std::vector<TrajectorySample>& samples, const std::vector<const std::string*>& names) override {
    run_.OnSamples(samples, names);
  }
  void OnFleetEvent(const FleetEventRecord& e) override {
    run_.OnFleetEvent(e);
    if (live_ != nullptr) live_->OnEvent(live::EventOf(e));
    if (e.what == "joined" || e.what == "rejoined") {
      joins_.push_back(e);
    } else if (e.vehicle_id >= 0) {
      spdlog::info("server: {} (id {}) {} at t = {:.1f} s ({})", e.name, e.vehicle_id, e.what, e.time_s, e.detail);
    } else if (e.what == "tours" || e.what == "regions" || e.what == "resumed" || e.what == "stopped") {
      spdlog::info("server: t = {:.1f} s: {}: {}", e.time_s, e.what, e.detail);  // the plan, as it goes
    } else {
      spdlog::warn("server: t = {:.1f} s: {}: {}", e.time_s, e.what, e.detail);  // an outage, a fleet gone
    }
  }
  void OnRegions(double t, const std::vector<RegionRecord>& r) override { run_.OnRegions(t, r); }
  void OnRiskEvent(const RiskEventRecord& e) override {
    run_.OnRiskEvent(e);
    if (live_ != nullptr) live_->OnEvent(live::EventOf(e));
    spdlog::info("server: risk of {} set to {} by {} at t = {:.1f} s ({:.1f} % of the field's risk)", e.valve,
                 e.raw_weight, e.source, e.time_s, 100.0 * e.new_share);
  }
  /// The cycle's joins, in one line when there are many.
  void LogJoins(std::size_t alive) {
    if (joins_.size() <= kJoinsNamed) {
      for (const FleetEventRecord& e : joins_) {
        spdlog::info("server: {} (id {}) {} at t = {:.1f} s", e.name, e.vehicle_id, e.what, e.time_s);
      }
    } else {
      spdlog::info("server: {} vehicles joined at t = {:.1f} s: {} (id {}) .. {} (id {}); {} alive", joins_.size(),
                   joins_.front().time_s, joins_.front().name, joins_.front().vehicle_id, joins_.back().name,
                   joins_.back().vehicle_id, alive);
    }
    joins_.clear();
  }
  /// The live view's event log hears the record's events from now on.
  void ShowIn(live::LiveView* live) { live_ = live; }

 private:
  RunDirectory& run_;
  live::LiveView* live_ = nullptr;
  std::vector<FleetEventRecord> joins_;
};

std::uint64_t NewServerInstance() {
  std::random_device device;
  return (static_cast<std::uint64_t>(device()) << 32) ^ device() ^ static_cast<std::uint64_t>(NowRealtimeNs());
}

}  // namespace

int RunServerNode(const maps::Scenario& scenario, const ServerNodeOptions& options) {
  maps::World world(scenario);
  malloc_trim(0);  // what reading the scenario freed (0.46 GB for a 10,000-vehicle field's YAML) back to the machine
  RunDirectoryOptions record_options;
  record_options.transport = "dds";
  record_options.resume = options.resume;
  record_options.resumes = options.resumes;
  record_options.checkpoint_period_s = options.checkpoint_period_s;
  // At least every mission second too, so a record cut by a crash ends within one mission
  // second of it however fast the mission runs.
  record_options.flush_period_s = std::min(1.0, 1.0 / options.time_scale);
  MissionCheckpoint checkpoint;
  if (options.resume) checkpoint = ReadCheckpoint(options.out_dir);  // before the record is touched
  RunDirectory run(options.out_dir, scenario, record_options);
  LoggedRecord record(run);
  MissionCore core(world, scenario, options.profile, options.controller, &record);
  core.SetRegionPhiMadeByHosts(true);  // a region's target goes as its valves and weights (agents/node/wire.h)
  std::int64_t first_cycle = 0;
  if (options.resume) {
    core.Restore(checkpoint);
    const RecordTail tail = ReadRecordTail(options.out_dir, checkpoint.time_s);
    first_cycle = core.Replay(tail.samples, tail.fleet_events, tail.risk_events) + 1;
    std::map<int, int> index_of_id;
    for (const auto& [id, member] : core.roster().members()) index_of_id[id] = member.index;
    run.RestorePlot(index_of_id);
    // The outage in the record: how long the mission had no server (since the record's last write).
    std::error_code error;
    const auto written = std::filesystem::last_write_time(std::filesystem::path(options.out_dir) / "trajectory.csv", error);
    if (!error) {
      const double down_s =
          std::chrono::duration<double>(std::chrono::file_clock::now() - written).count();
      core.Note("outage", fmt::format("no server for {:.1f} s of wall time after the record's last write; nothing was "
                                      "recorded meanwhile",
                                      down_s));
    }
    core.Note("resumed", fmt::format("from the checkpoint at t = {:.1f} s and the record to t = {:.1f} s ({} samples "
                                     "replayed); the mission's clock goes on from there",
                                     checkpoint.time_s, core.time_s(), tail.samples.size()));
  }

  // Batched like the hosts' writes: a cycle's region targets (~800 a cycle at 10,000 vehicles, ~100
  // bytes each since they name their valves) go out many to a datagram, one RTPS-level cipher
  // operation and one sendmsg for each datagram, not for each target. Every writer is flushed
  // where it writes, so nothing waits for the next cycle.
  proto::Participant participant(options.domain_id,
                                 proto::WithBatchedWrites(proto::CycloneConfigXml(
                                     agents::NetworkOf(scenario.network), proto::kMaxLocalParticipants, options.security)));
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
  if (options.on_started) options.on_started();
  // The live view: the page and the Foxglove WebSocket on 127.0.0.1, behind the mission's token
  // (a new one for a new mission; a resumed mission keeps its own, so open pages go on).
  std::unique_ptr<live::LiveView> live;
  const live::MissionFrameMaker frames(scenario);
  if (options.http_port || options.foxglove_port) {
    live::LiveViewOptions view;
    view.http_port = options.http_port;
    view.foxglove_port = options.foxglove_port;
    view.token = MissionToken(options.out_dir, options.resume);
    live::LiveScene scene = live::SceneOf(scenario);
    scene.controller = ToString(options.controller);
    scene.profile = options.profile.empty() ? scenario.default_profile : options.profile;
    // A resumed mission listens where it listened (open pages reconnect by themselves), if it can.
    const std::optional<LiveEndpoints> before = options.resume ? ReadLiveEndpoints(options.out_dir) : std::nullopt;
    if (before && view.http_port == 0 && before->http_port > 0) view.http_port = before->http_port;
    if (before && view.foxglove_port == 0 && before->foxglove_port > 0) view.foxglove_port = before->foxglove_port;
    try {
      live = std::make_unique<live::LiveView>(scene, view);
    } catch (const maps::ScenarioError& e) {
      if (!before) throw;
      spdlog::warn("server: the live view cannot listen where it did before the outage ({}); it takes free ports",
                   e.what());
      view.http_port = options.http_port;
      view.foxglove_port = options.foxglove_port;
      live = std::make_unique<live::LiveView>(scene, view);
    }
    record.ShowIn(live.get());
    WriteLiveEndpoints(options.out_dir, live->http_port(), live->foxglove_port());
    if (options.http_port) spdlog::info("server: live view: {}", live->PageUrl());
    if (options.foxglove_port) spdlog::info("server: Foxglove (foxglove.websocket.v1): {}", live->FoxgloveUrl());
  } else {
    WriteLiveEndpoints(options.out_dir, -1, -1);  // both off: a resume keeps them off (sage launch --resume)
  }
  proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateRecordQos());
  proto::Reader<proto::VehicleCoverage> coverage(participant, proto::VehicleCoverageQos());
  // The vehicles' leak-sensor scans (issue 9), where the scenario gives them sensors.
  std::optional<proto::Reader<proto::Detection>> detections;
  if (!scenario.sensors.empty()) detections.emplace(participant, proto::DetectionQos());
  proto::Reader<proto::RiskUpdate> risk_updates(participant, proto::RiskUpdateQos());
  proto::Writer<proto::RiskUpdateResult> risk_results(participant, proto::RiskUpdateResultQos());
  proto::Reader<proto::FleetCommand> commands(participant, proto::FleetCommandQos());
  proto::Writer<proto::FleetCommand> retire(participant, proto::FleetCommandQos());
  proto::Writer<proto::FleetCommandResult> command_results(participant, proto::FleetCommandResultQos());
  proto::Writer<proto::ErgodicTarget> targets(participant, proto::ErgodicTargetQos());
  proto::Writer<proto::ErgodicTargets> target_batches(participant, proto::ErgodicTargetsQos());
  proto::Writer<proto::FleetCoverage> fleet_coverage(participant, proto::FleetCoverageQos());
  proto::Writer<proto::MissionStatus> status(participant, proto::MissionStatusQos());

  const double rate = scenario.control_rate_hz;
  const std::int64_t cycles_total = std::llround(scenario.duration_s * rate);
  const std::uint64_t instance = NewServerInstance();
  ServerDoor door(core, instance, scenario.control_rate_hz);
  const std::uint32_t order = static_cast<std::uint32_t>(scenario.ergodic.basis_order);
  // The mission clock: cycle k is at mission time k / rate; the first cycle (t = 0, or a resumed
  // mission's next) is start_in_s from now, so that the hosts started with this server are all in
  // by then (a resumed mission's restarted vehicles had rejoined 2 s of wall time late, a hole in
  // the record). Vehicles step at k / rate, the server half a period later, when their states of
  // cycle k are in.
  const double lead_s = std::max(0.0, options.start_in_s);
  const long long start_ns =
      NowRealtimeNs() + static_cast<long long>(lead_s * 1e9) -
      static_cast<long long>(static_cast<double>(first_cycle) / rate / options.time_scale * 1e9);
  const auto wall_of = [&](double mission_s) {
    return std::chrono::system_clock::time_point(std::chrono::duration_cast<std::chrono::system_clock::duration>(
        std::chrono::nanoseconds(start_ns + static_cast<long long>(mission_s / options.time_scale * 1e9))));
  };
  const double lease_s = scenario.fleet.liveliness_lease_s;
  const std::uint64_t fingerprint =
      maps::VehicleFingerprint(scenario) ^ (options.controller == ControllerKind::kAstar ? 0x5A5Aull : 0ull);

  double last_cycle_ms = 0.0, total_cycle_ms = 0.0, max_cycle_ms = 0.0;
  // The cycles' time on a core (the rest of their wall time the thread was preempted or blocked),
  // and how often it was switched out while runnable (preempted) or while waiting (a lock, a send).
  double total_cycle_cpu_ms = 0.0;
  long cycle_preempted = 0, cycle_blocked = 0;
  long cycles_run = 0;
  std::uint64_t messages_in = 0, messages_out = 0;
  // Payload bytes of the valid samples taken and of the samples written (proto/wire_size.h);
  // a sample written once counts once, however many readers it reaches.
  std::uint64_t bytes_in = 0, bytes_out = 0;
  std::vector<double> cycle_ms;  // every cycle's compute time, for the p99
  cycle_ms.reserve(static_cast<std::size_t>(std::max<std::int64_t>(0, cycles_total - first_cycle + 1)));
  bool stop_requested = false;
  std::string stop_by;  // who asked first, for the record
  auto publish_status = [&](std::int64_t cycle, double t, bool finished) {
    proto::MissionStatus s{};
    s.stamp_ns = NowRealtimeNs();
    s.server_instance = instance;
    s.start_ns = start_ns;
    s.time_scale = options.time_scale;
    s.cycle = static_cast<std::uint64_t>(std::max<std::int64_t>(cycle, 0));
    s.mission_time_s = t;
    s.duration_s = scenario.duration_s;
    s.vehicles_alive = static_cast<std::uint32_t>(core.roster().alive_count());
    s.vehicles_lost = static_cast<std::uint32_t>(core.roster().lost_count());
    s.cycle_time_ms = last_cycle_ms;
    s.ergodic_metric = core.ergodic_metric();
    s.finished = finished;
    s.vehicle_fingerprint = fingerprint;
    status.Write(s);
    status.Flush();
    ++messages_out;
    bytes_out += proto::WireBytes(s);
  };
  auto answer_command = [&](const proto::FleetCommand& c, const OperatorAnswer& a) {
    proto::FleetCommandResult r{};
    r.command_stamp_ns = c.stamp_ns;
    r.verb = c.verb;
    r.accepted = a.accepted;
    r.reason = BorrowString(a.reason);
    r.first_id = a.first_id;
    r.count = c.count;
    r.vehicle_id = c.vehicle_id;
    r.mission_time_s = core.time_s();
    command_results.Write(r);
    command_results.Flush();
    ++messages_out;
    bytes_out += proto::WireBytes(r);
  };

  // The server's order to the vehicle's host that it leave (an operator removed it).
  auto send_retire = [&](std::uint32_t vehicle_id) {
    proto::FleetCommand order{};
    order.stamp_ns = NowRealtimeNs();
    order.server_instance = instance;
    std::string retire_verb = "retire";
    order.verb = BorrowString(retire_verb);
    order.vehicle_id = vehicle_id;
    retire.Write(order);
    retire.Flush();
    ++messages_out;
    bytes_out += proto::WireBytes(order);
  };
  // An operator's command from the page: the checks and answers of the door's (DDS) commands.
  auto carry_out = [&](std::string_view verb, std::uint32_t count, std::uint32_t vehicle_id) {
    if (verb == "stop") {
      if (!stop_requested) stop_by = "the live page";
      stop_requested = true;
      return OperatorAnswer{true, "", 0.0, -1};
    }
    if (verb == "reserve") return core.ReserveIds(static_cast<int>(count));
    const OperatorAnswer a = core.RemoveRequest(static_cast<int>(vehicle_id));
    if (a.accepted) send_retire(vehicle_id);
    return a;
  };
  // The page's removals are answered once the vehicle has gone, as `sage vehicle remove` waits.
  struct PendingRemoval {
    std::shared_ptr<live::PendingAction> action;
    int id;
    double told_at_s;
    SteadyClock::time_point deadline;
  };
  constexpr double kRemovalWait_s = 5.0;
  std::vector<PendingRemoval> removals;
  const std::string run_dir = std::filesystem::absolute(options.out_dir).string();
  double live_copy_ms = 0.0;  // the loop's part of the live view: copying the core's state
  long live_frames = 0;

  // The mission's wall time runs from its first cycle's time (after the start-up lead).
  const auto wall_start = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                                   std::chrono::duration<double>(lead_s));
  publish_status(first_cycle, static_cast<double>(first_cycle) / rate, false);
  // What the fleet flies: A* tours, or ergodic control with its way of sharing the field (an A*
  // mission had been announced as "shared coverage").
  const std::string flown = options.controller == ControllerKind::kAstar
                                ? std::string("A* tours")
                                : fmt::format("ergodic, {} coverage", ToString(scenario.fleet.assignment));
  spdlog::info("server: mission '{}' on DDS domain {}, {:.0f} s at {}x real time, {}{}", scenario.name, options.domain_id,
               scenario.duration_s, options.time_scale, flown,
               options.resume ? fmt::format(", resumed at t = {:.1f} s", core.time_s()) : std::string());

  // Liveliness losses seen while this server itself was stalled wait two leases for the
  // vehicle's next state (a stopped server is not a fleet loss).
  std::map<int, SteadyClock::time_point> suspect;
  SteadyClock::time_point stalled_until = SteadyClock::now();
  // A resumed mission's vehicles must be heard from again: one whose host is gone (and was not
  // restarted) is lost once its hosts had time to start and discover this server.
  if (options.resume) {
    const auto deadline = wall_start + std::chrono::seconds(10);  // ten seconds from the first cycle
    for (const int id : core.roster().alive()) suspect.emplace(id, deadline);
  }
  bool empty_warned = false;
  std::int64_t cycle = first_cycle;
  std::vector<std::uint32_t> ids_scratch;
  std::vector<proto::ErgodicTarget> batch_scratch;
  std::vector<std::uint64_t> seqs_scratch;
  std::vector<std::pair<std::int64_t, int>> scenario_joins;  // (cycle, vehicle id) of each fleet_events join
  for (const maps::FleetEvent& e : scenario.fleet_events) {
    if (e.kind != maps::FleetEvent::Kind::kJoin) continue;
    scenario_joins.emplace_back(scenario.CycleAt(e.time_s), JoinVehicleId(scenario, e.vehicle.name));
  }
  // Each vehicle's newest state's cycle, for the lockstep wait. The scenario's joins are waited
  // for from their cycle on, for a second at most.
  LockstepWait lockstep(scenario.VehicleEndCycles(), std::move(scenario_joins), static_cast<std::int64_t>(rate));
  long cycles_not_in_step = 0;
  double first_not_in_step_s = -1.0;
  SteadyClock::time_point compute_start;
  auto on_state = [&](const proto::VehicleState& m, const dds_sample_info_t& info) {
      ++messages_in;
      const int id = static_cast<int>(m.vehicle_id);
      if (info.valid_data) {
        bytes_in += proto::WireBytes(m);
        suspect.erase(id);  // heard: alive
        // A state on another server's clock (sent before its host heard of this one) is not a
        // sample of this mission's time line; the host follows this server within a cycle.
        if (m.server_instance != instance) return;
        lockstep.Heard(id, m.cycle);
        door.TakeState(m, info.publication_handle);
        // A dispose or a lapsed lease that arrives while the vehicle's last state is still
        // unread comes as that (valid) sample with a not-alive instance state.
        if (info.instance_state == DDS_ALIVE_INSTANCE_STATE) return;
      }
      const bool lost = info.instance_state == DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE;
      if (lost && compute_start < stalled_until) {
        suspect.emplace(id, stalled_until);
      } else {
        core.OnVehicleGone(id, lost);
      }
    };
  // Every long-lived thread is started by now (DDS, the live view): the cycle's priority is its own.
  const CyclePriority priority(options.cycle_priority);
  // The default refused (a user without root, most launches) is not news on every launch: said in
  // the debug log only; a priority asked for and refused is warned of.
  const bool asked = options.cycle_priority != kDefaultCyclePriority && options.cycle_priority > 0;
  const bool refused = options.cycle_priority > 0 && !priority.realtime();
  spdlog::log(!refused ? spdlog::level::info : asked ? spdlog::level::warn : spdlog::level::debug, "server: {}",
              priority.line());
  for (; cycle <= cycles_total; ++cycle) {
    const double t = static_cast<double>(cycle) / rate;
    const auto due = wall_of(t + 0.5 / rate);
    std::this_thread::sleep_until(due);
    if ((options.stop && options.stop->load()) || stop_requested) break;
    compute_start = SteadyClock::now();
    if (std::chrono::system_clock::now() - due > std::chrono::duration<double>(lease_s)) {
      stalled_until = compute_start + std::chrono::duration_cast<SteadyClock::duration>(
                                          std::chrono::duration<double>(2 * lease_s));
    }

    core.SetClock(static_cast<double>(proto::NowRealtimeNs() - start_ns) * 1e-9 * options.time_scale);
    // Take until empty: one take returns at most what is asked, and a large fleet sends
    // thousands of states a cycle.
    auto take_all = [](auto& reader, auto&& visit) {
      while (reader.TakeEach(visit, 1024) == 1024) {
      }
    };
    take_all(states, on_state);
    // Lockstep where it can be: the cycle waits (up to 0.45 of a period) for every live vehicle's
    // state of this cycle, so that it accounts what the in-process mission would (a vehicle that
    // died is waited for until its lease runs out); a cycle that
    // has to go on without one is counted (the mission is then no longer the in-process one).
    // Behind its schedule by more than its budget (a long cycle of its own: splitting a 1,000-vehicle
    // field took 1.1 s), it waits up to kSlowHostWait from now, as the hosts wait for it: they held
    // their cycle for its word and now answer in a burst (each host reads a thousand targets
    // first; 0.45 of a period from now had missed 5 cycles).
    constexpr double kSlowHostWait_s = 2.0;
    const auto now_wall = std::chrono::system_clock::now();
    const double wait_s = now_wall - due > std::chrono::duration<double>(0.45 / rate / options.time_scale)
                              ? kSlowHostWait_s
                              : 0.45 / rate / options.time_scale;
    const auto lockstep_deadline = std::max(due, now_wall) + std::chrono::duration_cast<std::chrono::system_clock::duration>(
                                                                 std::chrono::duration<double>(wait_s));
    while (!lockstep.AllIn(core.roster().alive(), cycle)) {
      if (std::chrono::system_clock::now() >= lockstep_deadline) {
        if (cycles_not_in_step++ == 0) first_not_in_step_s = t;
        break;
      }
      std::this_thread::sleep_for(proto::kStreamPoll);
      take_all(states, on_state);
    }
    const auto cycle_start = SteadyClock::now();  // the cycle's own work starts here
    rusage cycle_usage{};
    getrusage(RUSAGE_THREAD, &cycle_usage);
    for (auto it = suspect.begin(); it != suspect.end();) {
      if (compute_start < it->second) {
        ++it;
        continue;
      }
      core.OnVehicleGone(it->first, /*lost=*/true);
      it = suspect.erase(it);
    }
    take_all(coverage, [&](const proto::VehicleCoverage& m, const dds_sample_info_t& info) {
      ++messages_in;
      if (!info.valid_data) return;
      bytes_in += proto::WireBytes(m);
      door.TakeCoverage(m, info.publication_handle);
    });
    if (detections) {
      take_all(*detections, [&](const proto::Detection& m, const dds_sample_info_t& info) {
        ++messages_in;
        if (!info.valid_data) return;
        bytes_in += proto::WireBytes(m);
        if (m.server_instance != instance) return;  // on another server's clock, as states
        core.OnScan(agents::wire::FromWire(m, rate));
      });
    }
    risk_updates.TakeEach([&](const proto::RiskUpdate& r, const dds_sample_info_t& info) {
      ++messages_in;
      if (!info.valid_data) return;
      bytes_in += proto::WireBytes(r);
      // The sender is the DDS writer (its instance handle), which an update cannot name falsely.
      const std::optional<OperatorAnswer> answer = door.TakeRiskUpdate(r, info.publication_handle);
      if (!answer) return;  // a flood's refusal, answered only at its 1st, 10th, 100th, ...
      const OperatorAnswer& a = *answer;
      proto::RiskUpdateResult result{};
      result.update_stamp_ns = r.stamp_ns;
      result.valve = r.valve;
      result.mission_time_s = t;
      result.applied = a.accepted;
      result.new_share = a.new_share;
      result.reason = BorrowString(a.reason);
      risk_results.Write(result);
      risk_results.Flush();
      ++messages_out;
      bytes_out += proto::WireBytes(result);
    });
    commands.TakeEach([&](const proto::FleetCommand& c, const dds_sample_info_t& info) {
      ++messages_in;
      if (!info.valid_data) return;
      bytes_in += proto::WireBytes(c);
      const CommandOutcome done = door.TakeCommand(c);
      if (done.ignored) return;
      if (done.stop && !stop_requested) stop_by = done.stop_by;
      stop_requested = stop_requested || done.stop;
      if (done.retire) send_retire(c.vehicle_id);
      answer_command(c, done.answer);
    });
    if (live) {
      // The page's requests, with the checks and answers of the operators' commands.
      for (const std::shared_ptr<live::PendingAction>& action : live->TakeActions()) {
        const live::ActionRequest& r = action->request();
        try {
          if (r.verb == "risk") {
            CheckRiskRequest(scenario, r.valve, r.weight);
            const OperatorAnswer a = core.OnRiskUpdate(r.valve, r.weight, "operator (live view)", "live view");
            action->Answer(a.accepted, a.accepted ? RiskAppliedLine(r.valve, r.weight, t, a.new_share)
                                                  : RiskRefusedLine(a.reason));
          } else if (r.verb == "add") {
            CheckAddCount(r.count);
            if (!options.start_added_vehicles) {
              action->Answer(false, "this server starts no agent hosts (run it with sage launch or sage server)");
              continue;
            }
            const OperatorAnswer a = carry_out("reserve", static_cast<std::uint32_t>(r.count), 0);
            action->Answer(a.accepted, a.accepted ? options.start_added_vehicles(a.first_id, r.count)
                                                  : CommandRefusedLine(a.reason));
          } else if (r.verb == "remove") {
            CheckVehicleId(r.id);
            const OperatorAnswer a = carry_out("remove", 0, static_cast<std::uint32_t>(r.id));
            if (!a.accepted) {
              action->Answer(false, CommandRefusedLine(a.reason));
            } else {
              removals.push_back({action, r.id, t,
                                  SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                                           std::chrono::duration<double>(kRemovalWait_s))});
            }
          } else if (r.verb == "stop") {
            carry_out("stop", 0, 0);
            action->Answer(true, StopLine(t, run_dir));
          } else {
            action->Answer(false, "unknown request");
          }
        } catch (const std::exception& e) {  // a bad request, or a host that cannot be started
          action->Answer(false, e.what());
        }
      }
      std::erase_if(removals, [&](const PendingRemoval& p) {
        const Roster::Member* m = core.roster().Find(p.id);
        if (m != nullptr && m->status != Roster::Status::kAlive) {
          p.action->Answer(true, VehicleLeftLine(p.id, m->name, p.told_at_s));
          return true;
        }
        if (SteadyClock::now() < p.deadline) return false;
        p.action->Answer(false, VehicleNotLeftLine(p.id, m != nullptr ? m->name : std::string(), p.told_at_s,
                                                   kRemovalWait_s));
        return true;
      });
    }

    const CycleOutput out = core.Cycle(cycle);
    record.LogJoins(core.roster().alive_count());
    const long long stamp = NowRealtimeNs();
    // The cycle's targets first, then its snapshot: a host steps on once it has the snapshot, and
    // a target written after it could come a cycle late (at the first split of 1,000 regions the
    // vehicles stood still 0.7 s longer than in sage run).
    // A vehicle's first target since it joined alone, the rest in one sample (ServerDoor::Batched).
    batch_scratch.clear();
    for (const agents::Assignment& a : out.assignments) {
      const proto::ErgodicTarget target = agents::wire::ToWire(a, instance, order, stamp);
      if (door.Batched(a.id, a.cycle)) {
        batch_scratch.push_back(target);  // borrows a's memory, alive until the write below
        continue;
      }
      targets.Write(target);
      ++messages_out;
      bytes_out += proto::WireBytes(target);
    }
    targets.Flush();
    if (!batch_scratch.empty()) {
      const proto::ErgodicTargets batch = agents::wire::ToWire(batch_scratch, instance, out.snapshot.cycle, stamp);
      target_batches.Write(batch);
      target_batches.Flush();
      ++messages_out;
      bytes_out += proto::WireBytes(batch);
    }
    const proto::FleetCoverage snapshot =
        agents::wire::ToWire(out.snapshot, instance, order, stamp, ids_scratch, seqs_scratch);
    fleet_coverage.Write(snapshot);
    fleet_coverage.Flush();
    ++messages_out;
    bytes_out += proto::WireBytes(snapshot);
    if (out.fleet_empty && !empty_warned && cycle > first_cycle + 2 * static_cast<std::int64_t>(rate)) {
      spdlog::warn("server: no vehicle is alive at t = {:.1f} s; the mission goes on for vehicles that join", t);
    }
    empty_warned = out.fleet_empty;
    run.Tick(core);
    // The live view's frame, a copy of the core's state (at most ten a second); the view's own
    // thread does the rest.
    if (live && live->FrameDue()) {
      const auto copy_start = SteadyClock::now();
      live->Publish(frames.Make(core, last_cycle_ms, /*finished=*/false));
      live_copy_ms += std::chrono::duration<double, std::milli>(SteadyClock::now() - copy_start).count();
      ++live_frames;
    }
    last_cycle_ms = std::chrono::duration<double, std::milli>(SteadyClock::now() - cycle_start).count();
    total_cycle_ms += last_cycle_ms;
    {
      rusage end{};
      getrusage(RUSAGE_THREAD, &end);
      total_cycle_cpu_ms += CpuMs(end) - CpuMs(cycle_usage);
      cycle_preempted += end.ru_nivcsw - cycle_usage.ru_nivcsw;
      cycle_blocked += end.ru_nvcsw - cycle_usage.ru_nvcsw;
    }
    max_cycle_ms = std::max(max_cycle_ms, last_cycle_ms);
    cycle_ms.push_back(last_cycle_ms);
    ++cycles_run;
    if (cycle % 5 == 0) publish_status(cycle, t, false);
    if (options.show_progress && cycle % std::max<std::int64_t>(1, cycles_total / 20) == 0) {
      std::fprintf(stderr, "server  t = %5.0f / %.0f s  vehicles %zu (lost %zu)  metric %.2e  cycle %.2f ms%s\n", t,
                   scenario.duration_s, core.roster().alive_count(), core.roster().lost_count(), core.ergodic_metric(),
                   last_cycle_ms,
                   core.rejected_samples() > 0 ? ("  rejected " + core.rejections().Summary()).c_str() : "");
    }
  }
  const bool stopped_early = cycle <= cycles_total;
  if (stopped_early && options.stop && options.stop->load() && options.launcher_gone && options.launcher_gone()) {
    // Its launcher died (its agent hosts went with it): the mission keeps its record as of this
    // cycle and stays resumable; a status of "finished" would end hosts started apart from it.
    run.Checkpoint(core);
    if (live) live->Close("the mission's launcher has gone; the mission can be resumed");
    // On stderr itself: the launcher relayed the server's log from its stdout, and is gone.
    fmt::print(stderr,
               "sage: sage launch ended without stopping the mission; its record is kept, unfinished, to t = {:.1f} "
               "s: resume it with sage launch --resume {}\n",
               core.time_s(), options.out_dir);
    return 1;
  }
  // Who ended the mission early stands in fleet_events.csv beside the fleet's other events (not for
  // a launcher gone: that mission is resumable, not ended).
  if (stopped_early) {
    core.Note("stopped", stop_requested ? "a stop request from " + stop_by : "a signal to the server (Ctrl-C, SIGTERM)");
  }
  const double end_time = std::max(1.0 / rate, std::min(scenario.duration_s, core.time_s()));
  // The real-time factor is the mission loop's; writing the final set is timed on its own.
  const double wall_s = std::chrono::duration<double>(SteadyClock::now() - wall_start).count();
  const auto finish_start = SteadyClock::now();
  run.Finish(core, world, end_time, stopped_early);
  const double finish_s = std::chrono::duration<double>(SteadyClock::now() - finish_start).count();
  publish_status(cycle, end_time, true);
  if (live) {
    live->Publish(frames.Make(core, last_cycle_ms, /*finished=*/true));
    for (const PendingRemoval& p : removals) {
      p.action->Answer(false, fmt::format("the mission ended before vehicle {} left (told to at t = {:.1f} s)", p.id,
                                          p.told_at_s));
    }
    live->Close("the mission has ended");
  }

  const double mission_s = end_time - static_cast<double>(first_cycle) / rate;
  std::cout << FormatTable({core.Metrics(end_time)});
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);  // ru_maxrss: KiB on Linux
  const double peak_rss_mb = static_cast<double>(usage.ru_maxrss) * 1024.0 / 1e6;
  const double p99_ms = cycle_ms.empty() ? 0.0 : NearestRankPercentile(std::move(cycle_ms), 0.99);
  if (options.resume) {
    // The figures below are this server's own: a resumed mission's first part ran on another.
    spdlog::info("server: resumed at t = {:.1f} s: the mission ran to t = {:.1f} s; the figures below are of this "
                 "server's {:.0f} s",
                 static_cast<double>(first_cycle) / rate, end_time, mission_s);
  }
  // One line that scripts and `sage bench scale` parse (tests/bench/launch_scale.sh): keep its order.
  spdlog::info("server: {:.0f} s of mission in {:.1f} s wall ({:.2f}x real time); {} messages in, {} out ({:.0f}/s); "
               "{:.3f} MB in, {:.3f} MB out at {:.3f} MB/s; server cycle {:.2f} ms mean, {:.2f} ms p99, {:.2f} ms max; "
               "peak RSS {:.1f} MB; wrote {} in {:.1f} s",
               mission_s, wall_s, mission_s / std::max(1e-9, wall_s), messages_in, messages_out,
               (messages_in + messages_out) / std::max(1e-9, wall_s), bytes_in / 1e6, bytes_out / 1e6,
               (bytes_in + bytes_out) / 1e6 / std::max(1e-9, wall_s), total_cycle_ms / std::max(1L, cycles_run), p99_ms,
               max_cycle_ms, peak_rss_mb, options.out_dir, finish_s);
  // A cycle's wall time against its thread's CPU time: what the other threads and processes on the
  // cores took from it (a page on the mission's own machine shows here).
  spdlog::info("server: cycle on the CPU {:.3f} ms mean of its {:.3f} ms; switched out {} times preempted, {} waiting",
               total_cycle_cpu_ms / std::max(1L, cycles_run), total_cycle_ms / std::max(1L, cycles_run), cycle_preempted,
               cycle_blocked);
  if (live) {
    // What the live view cost: the loop's copy (inside the cycle times above) and its own thread.
    spdlog::info("server: live view: {} frames, {:.3f} ms a frame in the server's loop, {:.3f} ms in the view's thread "
                 "({:.3f} ms of it on the CPU)",
                 live_frames, live_copy_ms / std::max(1L, live_frames), live->publisher_ms_per_frame(),
                 live->publisher_cpu_ms_per_frame());
  }
  // In lockstep the mission is the one sage run flies with the same scenario and seed.
  spdlog::info("server: {} of {} cycles in lockstep with the vehicles{}", cycles_run - cycles_not_in_step, cycles_run,
               cycles_not_in_step == 0
                   ? std::string()
                   : fmt::format(" (the others went on without a state, the first at t = {:.1f} s: a late one, or a "
                                 "vehicle that died, until its lease ran out)",
                                 first_not_in_step_s));
  if (door.targets_resent() > 0) {
    spdlog::info("server: {} targets sent again alone: a host lacked them (restarted, or a batch it missed)",
                 door.targets_resent());
  }
  return 0;
}

}  // namespace sage::server
