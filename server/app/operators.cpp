#include "server/app/operators.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "agents/node/network.h"
#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/mission_clock.h"
#include "proto/qos.h"
#include "server/app/processes.h"
#include "server/app/security_command.h"
#include "server/mission_core.h"
#include "server/operator_requests.h"
#include "server/report/run_record.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
constexpr auto kAnswerTimeout = std::chrono::seconds(5);
constexpr auto kResendEvery = std::chrono::seconds(1);

// How long an operator's command waits to meet the mission's server: 3 s, or 15 s while the
// mission's launcher runs (the mission is there: on a loaded machine its secured handshake takes
// longer; 30 commands at once had been told, a third of them, that no mission was listening). A
// plain command to a secured mission never meets it: 3 s, and it is told why.
std::chrono::seconds MatchWait(const MissionFile& mission, bool insecure) {
  const bool never = insecure && !mission.security_dir.empty();
  return std::chrono::seconds(!never && mission.launcher_pid > 0 && IsRunningLauncher(mission.launcher_pid) ? 15 : 3);
}

int NoMission(const MissionFile& mission, bool insecure) {
  if (!insecure && mission.launcher_pid > 0 && IsRunningLauncher(mission.launcher_pid)) {
    std::fprintf(stderr, "sage: error: the mission's launcher (pid %d) runs, but its server on DDS domain %d did not "
                 "answer within %lld s (the machine is loaded, or the server is stuck: try again, or see sage status)\n",
                 mission.launcher_pid, mission.domain_id, static_cast<long long>(MatchWait(mission, insecure).count()));
    return 1;
  }
  if (insecure && !mission.security_dir.empty()) {
    std::fprintf(stderr, "sage: error: no answer on DDS domain %d: the mission is secured (DDS Security, identities in %s) "
                 "and an --insecure command cannot reach it\n", mission.domain_id, mission.security_dir.c_str());
  } else {
    std::fprintf(stderr, "sage: error: no mission is listening on DDS domain %d (is it still running?)\n", mission.domain_id);
  }
  return 1;
}

// The operator's participant on the mission's domain: with the mission's operator identity when
// it is secured, plain DDS when it is not or when asked (--insecure; a secured mission's
// participants then never match it).
proto::Participant OperatorParticipant(const MissionFile& mission, bool insecure,
                                       proto::SecurityRole role = proto::SecurityRole::kOperator) {
  const std::optional<proto::SecurityIdentity> identity =
      insecure ? std::nullopt : MissionIdentity(mission.security_dir, role, mission.domain_id, "mission.json security_dir");
  return proto::Participant(mission.domain_id, proto::CycloneConfigXml(agents::NetworkOf(mission.network),
                                                                       proto::kMaxLocalParticipants, identity));
}

struct CommandAnswer {
  bool answered = true;  ///< false: the server met the command but said nothing within 5 s
  bool accepted = false;
  std::string reason;
  int first_id = -1;
  double mission_time_s = 0.0;
};

// Sends a fleet command to the server and waits for its answer (matched by the stamp).
std::optional<CommandAnswer> AskServer(proto::Participant& participant, const std::string& verb, std::uint32_t count,
                                       std::uint32_t vehicle_id, std::chrono::seconds match_wait) {
  proto::Reader<proto::FleetCommandResult> results(participant, proto::FleetCommandResultQos());
  proto::Writer<proto::FleetCommand> writer(participant, proto::FleetCommandQos());
  if (!writer.WaitForReaders(1, match_wait) || !results.WaitForWriters(1, match_wait)) {
    return std::nullopt;
  }
  proto::FleetCommand c{};
  c.stamp_ns = proto::NowRealtimeNs();
  c.verb = proto::BorrowString(verb);
  c.count = count;
  c.vehicle_id = vehicle_id;
  // The command topic is also read by the agent hosts (for the server's retire orders), so the
  // writer matching "a reader" does not prove the server's reader has matched it yet, and a
  // volatile command written before that match never reaches the server. The command is sent
  // again every second with the same stamp; the server executes a stamp once and answers a
  // repeat with the first answer.
  writer.Write(c);
  auto next_send = std::chrono::steady_clock::now() + kResendEvery;
  std::optional<CommandAnswer> answer;
  const auto deadline = std::chrono::steady_clock::now() + kAnswerTimeout;
  while (!answer && std::chrono::steady_clock::now() < deadline) {
    if (std::chrono::steady_clock::now() >= next_send) {
      writer.Write(c);
      next_send += kResendEvery;
    }
    results.WaitForData(std::chrono::milliseconds(100));
    results.TakeEach([&](const proto::FleetCommandResult& r, const dds_sample_info_t& info) {
      if (!info.valid_data || r.command_stamp_ns != c.stamp_ns) return;
      answer = CommandAnswer{true, r.accepted, std::string(proto::AsStringView(r.reason)), r.first_id, r.mission_time_s};
    });
  }
  if (!answer) answer = CommandAnswer{false, false, "the server did not answer within 5 s", -1, 0.0};
  return answer;
}

}  // namespace

MissionFile FindMission(const std::string& dir) {
  std::string where = dir;
  if (where.empty()) {
    const char* env = std::getenv("SAGE_MISSION");
    if (env != nullptr) {
      // Said as the environment's (its value alone had read as if typed on the command line).
      try {
        return ReadMissionFile(env);
      } catch (const maps::ScenarioError& e) {
        throw maps::ScenarioError(std::string("SAGE_MISSION = ") + e.what());
      }
    }
    where = "runs/latest";
  }
  return ReadMissionFile(where);
}

std::vector<std::string> RunningMissions(const std::string& runs_dir) {
  std::vector<std::pair<fs::file_time_type, std::string>> running;
  std::error_code ec;
  for (fs::directory_iterator it(runs_dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path file = it->path() / "mission.json";
    if (it->is_symlink(ec) || !fs::is_regular_file(file, ec)) continue;  // runs/latest is a link to one of them
    try {
      const MissionFile m = ReadMissionFile(it->path().string());
      if (IsRunningLauncher(m.launcher_pid)) running.emplace_back(fs::last_write_time(file, ec), it->path().string());
    } catch (const std::exception&) {
      // Not a mission one can reach: not one to point an operator at.
    }
  }
  std::sort(running.begin(), running.end(), std::greater<>());
  std::vector<std::string> dirs;
  for (auto& [when, dir] : running) dirs.push_back(std::move(dir));
  return dirs;
}

std::string StartAddedHost(const MissionFile& mission, int first_id, int count) {
  const std::string log = (fs::path(mission.run_dir) / fmt::format("agents-add-{}.log", first_id)).string();
  std::vector<std::string> args = {"agents", mission.scenario_path, "--add", std::to_string(count), "--first-id",
                                   std::to_string(first_id), "--domain", std::to_string(mission.domain_id), "--controller",
                                   mission.controller};
  // The new host joins a secured mission with the mission's agent-host identity, as launch's own do.
  if (!mission.security_dir.empty()) args.insert(args.end(), {"--security", mission.security_dir});
  // ... and on this machine's network (a vehicle may join from another machine than the server's).
  const std::vector<std::string> network = NetworkArgs(mission.network);
  args.insert(args.end(), network.begin(), network.end());
  const pid_t pid = Spawn(args, log, /*detach=*/true);
  return HostStartedLine(pid, count, first_id, log);
}

int AddVehicles(const MissionFile& mission, int count, bool insecure) {
  CheckAddCount(count);
  proto::Participant participant = OperatorParticipant(mission, insecure);
  const std::optional<CommandAnswer> answer =
      AskServer(participant, "reserve", static_cast<std::uint32_t>(count), 0, MatchWait(mission, insecure));
  if (!answer) return NoMission(mission, insecure);
  if (!answer->accepted) {
    std::fprintf(stderr, "sage: error: %s\n", CommandRefusedLine(answer->reason).c_str());
    return 2;
  }
  std::printf("%s\n", StartAddedHost(mission, answer->first_id, count).c_str());
  return 0;
}

int RemoveVehicle(const MissionFile& mission, const std::string& vehicle, bool insecure) {
  // An id, or a name (every log names the vehicles; rov4 is id 3, and a new user's `vehicle
  // remove rov2` had been refused as not a number).
  const bool by_id = !vehicle.empty() && vehicle.size() <= 9 && vehicle.find_first_not_of("0123456789") == std::string::npos;
  int id = -1;
  if (by_id) {
    id = std::stoi(vehicle);
    CheckVehicleId(id);
  } else if (vehicle.empty() || vehicle.size() > maps::kMaxNameLength) {
    throw maps::ScenarioError(fmt::format("vehicle = {}: give its name (1..{} characters, e.g. rov2) or its id",
                                          vehicle, maps::kMaxNameLength));
  }
  proto::Participant participant = OperatorParticipant(mission, insecure);
  proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateReaderQos());
  // Hear the vehicle before ordering it out: the host's dispose reaches only a reader already
  // matched with it, and DDS Security's handshake takes tenths of a second, seconds on a loaded
  // machine (the leave had gone unseen). A vehicle not heard within 3 s is asked for anyway by
  // id: the server knows one that already left or never was. A name is what the states say.
  const auto heard_by = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  bool heard = false;
  std::map<std::uint32_t, std::string> flying;  // what was heard, for a name not found
  while (!heard && std::chrono::steady_clock::now() < heard_by) {
    states.WaitForData(std::chrono::milliseconds(100));
    states.TakeEach([&](const proto::VehicleState& s, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      flying[s.vehicle_id] = s.name;
      if (!by_id && !heard && vehicle == s.name) id = static_cast<int>(s.vehicle_id);
      heard = heard || s.vehicle_id == static_cast<std::uint32_t>(id);
    }, 1024);
  }
  if (!by_id && id < 0) {
    // Not flying: a vehicle that joined and has gone is found in the record, and the server says
    // when it left (`vehicle remove 0` had said so, `vehicle remove rov1` only listed the fleet).
    try {
      for (const FleetEventRecord& e : ReadFleetEvents(mission.run_dir))
        if (e.what == "joined" && e.name == vehicle) id = e.vehicle_id;
    } catch (const std::exception&) {  // an unreadable record: the name is not known, said below
    }
  }
  if (!by_id && id < 0) {
    // The vehicles heard, a few of them: the line had named all 60 of a fleet (960 characters).
    constexpr std::size_t kNamed = 8;
    std::string names;
    std::size_t named = 0;
    for (const auto& [v, name] : flying) {
      if (named++ == kNamed) break;
      names += fmt::format("{}{} (id {})", names.empty() ? "" : ", ", name, v);
    }
    if (flying.size() > kNamed) names += fmt::format(" and {} more: sage status lists them", flying.size() - kNamed);
    std::fprintf(stderr, "sage: error: vehicle remove: no vehicle named %s is or was in this mission (heard in 3 s: %s)\n",
                 vehicle.c_str(), names.empty() ? "none" : names.c_str());
    return 2;
  }
  const auto heard_name = flying.find(static_cast<std::uint32_t>(id));
  const std::string name = heard_name != flying.end() ? heard_name->second : std::string();
  const std::optional<CommandAnswer> answer =
      AskServer(participant, "remove", 0, static_cast<std::uint32_t>(id), MatchWait(mission, insecure));
  if (!answer) return NoMission(mission, insecure);
  if (!answer->accepted) {
    std::fprintf(stderr, "sage: error: %s\n", CommandRefusedLine(answer->reason).c_str());
    return 2;
  }
  // The server told its host; the vehicle's state is disposed when it has left.
  const auto deadline = std::chrono::steady_clock::now() + kAnswerTimeout;
  bool gone = false;
  while (!gone && std::chrono::steady_clock::now() < deadline) {
    states.WaitForData(std::chrono::milliseconds(100));
    while (states.TakeEach([&](const proto::VehicleState& s, const dds_sample_info_t& info) {
      gone = gone || (s.vehicle_id == static_cast<std::uint32_t>(id) && info.instance_state != DDS_ALIVE_INSTANCE_STATE);
    }, 1024) == 1024) {
    }
  }
  if (!gone) {
    std::fprintf(stderr, "sage: error: %s\n",
                 VehicleNotLeftLine(id, name, answer->mission_time_s, std::chrono::duration<double>(kAnswerTimeout).count())
                     .c_str());
    return 1;
  }
  // The server records the leave when the state is disposed, a cycle or two after its order.
  std::printf("%s (mission in %s)\n", VehicleLeftLine(id, name, answer->mission_time_s).c_str(), mission.run_dir.c_str());
  return 0;
}

int SetRisk(const MissionFile& mission, const std::string& valve, double weight, const std::string& source,
            bool insecure) {
  if (weight == 0.0) weight = 0.0;  // -0 is 0 ("risk -0 applied ... now -0.0 %")
  const maps::Scenario scenario = maps::LoadScenario(mission.scenario_path);
  CheckRiskRequest(scenario, valve, weight);
  proto::Participant participant = OperatorParticipant(mission, insecure);
  // The answer's reader exists before the update is written, so the answer reaches it.
  proto::Reader<proto::RiskUpdateResult> results(participant, proto::RiskUpdateResultQos());
  proto::Writer<proto::RiskUpdate> writer(participant, proto::RiskUpdateQos());
  if (!writer.WaitForReaders(1, MatchWait(mission, insecure)) || !results.WaitForWriters(1, MatchWait(mission, insecure))) {
    return NoMission(mission, insecure);
  }
  proto::RiskUpdate r{};
  r.stamp_ns = proto::NowRealtimeNs();
  r.valve = proto::BorrowString(valve);
  r.weight = weight;
  r.source = proto::BorrowString(source);
  writer.Write(r);
  // The server answers in the cycle it takes the update (every 0.1 mission-s).
  struct Answer {
    bool applied;
    double mission_time_s, new_share;
    std::string reason;
  };
  std::optional<Answer> answer;
  const auto deadline = std::chrono::steady_clock::now() + kAnswerTimeout;
  while (!answer && std::chrono::steady_clock::now() < deadline) {
    results.WaitForData(std::chrono::milliseconds(100));
    results.TakeEach([&](const proto::RiskUpdateResult& a, const dds_sample_info_t& info) {
      if (!info.valid_data || a.update_stamp_ns != r.stamp_ns || proto::AsStringView(a.valve) != valve) return;
      answer = Answer{a.applied, a.mission_time_s, a.new_share, std::string(proto::AsStringView(a.reason))};
    });
  }
  if (!answer) {
    std::fprintf(stderr, "sage: error: risk update sent, but the server did not answer within 5 s\n");
    return 1;
  }
  if (!answer->applied) {
    std::fprintf(stderr, "sage: error: %s\n", RiskRefusedLine(answer->reason).c_str());
    return 2;
  }
  std::printf("%s (mission in %s)\n", RiskAppliedLine(valve, weight, answer->mission_time_s, answer->new_share).c_str(),
              mission.run_dir.c_str());
  return 0;
}

int ShowEndedMission(const std::string& run_dir, const RecordSummary& record) {
  const auto seconds = [](double s) { return std::isfinite(s) ? fmt::format("{:.1f} s", s) : std::string("?"); };
  std::string out = fmt::format("mission in {}: ended{} at t = {}", run_dir,
                                record.stopped_early ? " (stopped early)" : "",
                                seconds(std::isfinite(record.duration_s) ? record.duration_s : record.recorded_until_s));
  if (record.vehicle_count >= 0) out += fmt::format("; {} vehicle(s)", record.vehicle_count);
  if (record.unvisited_valves >= 0 && record.valve_count >= 0) {
    out += fmt::format("; unvisited valves {} of {}", record.unvisited_valves, record.valve_count);
  }
  if (std::isfinite(record.risk_weighted_interval_s)) {
    out += fmt::format("; risk-weighted interval {}{}", record.unvisited_valves > 0 ? ">= " : "",
                       seconds(record.risk_weighted_interval_s));
  }
  if (std::isfinite(record.longest_gap_max_s)) out += "; longest gap " + seconds(record.longest_gap_max_s);
  std::printf("%s\n(its record: %s/metrics.json, trajectory.csv and the plots; sage launch starts another)\n",
              out.c_str(), run_dir.c_str());
  return 0;
}

int ShowStatus(const MissionFile& mission, double listen_s, bool all, bool insecure) {
  const maps::Scenario scenario = maps::LoadScenario(mission.scenario_path);
  constexpr std::int64_t kMaxId = MissionCore::kMaxVehicleId;
  // Read only: the viewer's identity, which may write nothing to the mission.
  proto::Participant participant = OperatorParticipant(mission, insecure, proto::SecurityRole::kViewer);
  proto::Reader<proto::MissionStatus> status(participant, proto::MissionStatusQos());
  proto::Reader<proto::VehicleState> states(participant, proto::VehicleStateReaderQos());
  HeardStatus heard;
  std::map<int, HeardStatus::Vehicle> vehicles;
  const auto refuse = [&](std::string why) {
    ++heard.refused;
    heard.last_refusal = std::move(why);
  };
  std::optional<std::pair<std::int64_t, double>> first_status;  // (stamp, mission time): the pace
  using Clock = std::chrono::steady_clock;
  const auto seconds = [](double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); };
  // DDS Security's handshake takes tenths of a second (seconds on a loaded machine), with the
  // server and with each agent host apart: up to 3 s for the first word, then listen_s, and on
  // (up to 3 s more) while fewer vehicles are heard than the server says fly.
  const Clock::time_point start = Clock::now();
  Clock::time_point end = start + std::chrono::seconds(3), last_chance = end + seconds(listen_s);
  bool listening = false;
  const auto all_heard = [&] { return heard.has_status && static_cast<std::int64_t>(vehicles.size()) >= heard.alive; };
  while (Clock::now() < end || (listening && !all_heard() && Clock::now() < last_chance)) {
    states.WaitForData(std::chrono::milliseconds(50));
    status.TakeEach([&](const proto::MissionStatus& m, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      HeardStatus next = heard;
      next.time_s = m.mission_time_s;
      next.duration_s = m.duration_s;
      next.time_scale = m.time_scale;
      next.cycle_ms = m.cycle_time_ms;
      next.ergodic_metric = m.ergodic_metric;
      next.alive = m.vehicles_alive;
      next.lost = m.vehicles_lost;
      next.finished = m.finished;
      if (std::string why = HeardStatusProblem(next, kMaxId, proto::kMinTimeScale, proto::kMaxTimeScale); !why.empty()) return refuse(std::move(why));
      next.has_status = true;
      if (!first_status) first_status.emplace(m.stamp_ns, m.mission_time_s);
      const double wall_s = 1e-9 * static_cast<double>(m.stamp_ns - first_status->first);
      if (wall_s >= 0.2) next.measured_rate = (m.mission_time_s - first_status->second) / wall_s;
      heard = std::move(next);
    });
    while (states.TakeEach([&](const proto::VehicleState& m, const dds_sample_info_t& info) {
      if (!info.valid_data) return;
      const std::string name(m.name, strnlen(m.name, sizeof(m.name)));
      const double time_s = static_cast<double>(m.cycle) / scenario.control_rate_hz;
      const Eigen::Vector2d position(m.x_m, m.y_m), velocity(m.vx_mps, m.vy_mps);
      if (std::string why = HeardStateProblem(m.vehicle_id, name, time_s, position, velocity, scenario, kMaxId); !why.empty()) {
        return refuse(std::move(why));
      }
      const int id = static_cast<int>(m.vehicle_id);
      HeardStatus::Vehicle& v = vehicles[id];
      if (!v.name.empty() && time_s < v.time_s) return;  // an older state than held
      v = {id, name, time_s, position, velocity.norm()};
    }, 1024) == 1024) {
    }
    if (!listening && (heard.has_status || !vehicles.empty())) {
      listening = true;
      end = Clock::now() + seconds(listen_s);
      last_chance = end + std::chrono::seconds(3);
    }
  }
  heard.listened_s = std::chrono::duration<double>(Clock::now() - start).count();
  // Nothing believed: no mission answered, unless what came was refused (then the report says so).
  if (!heard.has_status && vehicles.empty() && heard.refused == 0) return NoMission(mission, insecure);
  for (auto& [id, v] : vehicles) heard.vehicles.push_back(std::move(v));
  try {  // the record beside what was heard: who left, and the plan flown
    const std::vector<FleetEventRecord> events = ReadFleetEvents(mission.run_dir);
    heard.left = std::count_if(events.begin(), events.end(), [](const FleetEventRecord& e) { return e.what == "left"; });
    for (const FleetEventRecord& e : events) {
      if (e.what == "regions" || e.what == "tours") heard.plan_time_s = e.time_s, heard.plan = e.what + ": " + e.detail;
    }
  } catch (const std::exception&) {  // a record not readable here: the status without it
  }
  std::fputs(StatusReport(heard, scenario.name, mission.run_dir, all ? heard.vehicles.size() : std::size_t{40}).c_str(),
             stdout);
  return heard.has_status || !heard.vehicles.empty() ? 0 : 1;
}

int StopMission(const MissionFile& mission, bool insecure) {
  proto::Participant participant = OperatorParticipant(mission, insecure);
  const std::optional<CommandAnswer> answer = AskServer(participant, "stop", 0, 0, MatchWait(mission, insecure));
  if (!answer || !answer->answered) {
    // A stop that came while the mission was already stopping (a second `sage stop`): its server
    // writes the final set and answers no more; said as the ended mission it is, once its record is
    // complete (it had been an error after 5 s).
    for (int tries = 0; tries < 50; ++tries) {
      if (const RecordSummary record = ReadRecordSummary(mission.run_dir); record.complete) {
        std::printf("the mission had already stopped, at t = %.1f s; its record is in %s\n",
                    std::isfinite(record.duration_s) ? record.duration_s : record.recorded_until_s, mission.run_dir.c_str());
        return 0;
      }
      if (!(mission.launcher_pid > 0 && IsRunningLauncher(mission.launcher_pid))) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    if (!answer) return NoMission(mission, insecure);
  }
  if (!answer->accepted) {
    std::fprintf(stderr, "sage: error: %s\n", answer->reason.c_str());
    return 1;
  }
  std::printf("%s\n", StopLine(answer->mission_time_s, mission.run_dir).c_str());
  return 0;
}

}  // namespace sage::server
