#include "server/report/mission_file.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <iterator>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/atomic_write.h"
#include "server/report/checkpoint.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

// The time of the last row of a CSV file (its first field), read from the file's end.
double LastRowTime(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return -1.0;
  const std::streamoff size = in.tellg();
  const std::streamoff chunk = std::min<std::streamoff>(size, 64 * 1024);
  in.seekg(size - chunk);
  std::string tail(static_cast<std::size_t>(chunk), '\0');
  in.read(tail.data(), chunk);
  while (!tail.empty() && tail.back() == '\n') tail.pop_back();
  const std::size_t start = tail.rfind('\n');
  const std::string line = tail.substr(start == std::string::npos ? 0 : start + 1);
  try {
    return std::stod(line.substr(0, line.find(',')));
  } catch (const std::exception&) {  // the header only, or a cut line
    return -1.0;
  }
}

}  // namespace

void WriteMissionFile(const std::string& dir, const MissionFile& m) {
  const nlohmann::ordered_json j = {{"domain_id", m.domain_id},   {"scenario", m.scenario_path},
                                    {"run_dir", m.run_dir},        {"time_scale", m.time_scale},
                                    {"controller", m.controller},  {"profile", m.profile},
                                    {"launcher_pid", m.launcher_pid}, {"resumes", m.resumes},
                                    {"security_dir", m.security_dir},
                                    {"network",
                                     {{"interface", m.network.interface_name},
                                      {"peers", m.network.peers},
                                      {"multicast", m.network.multicast}}}};
  detail::WriteAtomically((fs::path(dir) / "mission.json").string(), j.dump(2) + "\n");
}

void WriteRunFile(const std::string& dir, const std::string& name, const std::string& text) {
  detail::WriteAtomically((fs::path(dir) / name).string(), text);
}

MissionFile ReadMissionFile(const std::string& dir) {
  // Said of the directory as given: a file, a missing path or a run of sage run each read as
  // "DIR/mission.json: cannot read" with a hint at an option the command may not have.
  std::error_code error;
  if (!fs::exists(dir, error)) throw maps::ScenarioError(dir + ": no such directory (a run directory of sage launch: start one with sage launch)");
  if (!fs::is_directory(dir, error)) {
    throw maps::ScenarioError(dir + ": a file, not a run directory (a run directory of sage launch holds mission.json)");
  }
  const fs::path file = fs::path(dir) / "mission.json";
  std::ifstream in(file);
  if (!in) {
    throw maps::ScenarioError(dir + ": no mission.json: not the run directory of a sage launch (sage run writes none; "
                              "start a mission with sage launch)");
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    MissionFile m;
    m.domain_id = j.at("domain_id").get<int>();
    m.scenario_path = j.at("scenario").get<std::string>();
    m.run_dir = j.at("run_dir").get<std::string>();
    m.time_scale = j.value("time_scale", 1.0);
    m.controller = j.value("controller", std::string("ergodic"));
    m.profile = j.value("profile", std::string());
    m.launcher_pid = j.value("launcher_pid", -1);
    m.resumes = j.value("resumes", 0);
    m.security_dir = j.value("security_dir", std::string());  // absent in missions launched before DDS Security
    if (j.contains("network")) {  // absent in missions of this machine alone launched before it
      const nlohmann::json& n = j.at("network");
      m.network.interface_name = n.value("interface", std::string("lo"));
      m.network.peers = n.value("peers", std::vector<std::string>());
      m.network.multicast = n.value("multicast", false);
      if (const std::string problem = maps::NetworkProblem(m.network, file.string()); !problem.empty()) {
        throw maps::ScenarioError(problem);
      }
    }
    return m;
  } catch (const nlohmann::json::exception& e) {
    throw maps::ScenarioError(file.string() + ": not a mission file: " + e.what());
  }
}

std::string RunMapName(const maps::Scenario& scenario) {
  if (!scenario.seabed || scenario.seabed->map.empty()) return "";
  return "seabed_map" + fs::path(scenario.seabed->map).extension().string();
}

void KeepSeabedMap(const std::string& dir, const maps::Scenario& scenario) {
  const std::string name = RunMapName(scenario);
  std::error_code error;
  // A run directory used before with another map (or none) keeps no copy of it to mislead.
  std::vector<fs::path> stale;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, error)) {
    const std::string file = entry.path().filename().string();
    if (file.starts_with("seabed_map.") && file != name) stale.push_back(entry.path());
  }
  for (const fs::path& file : stale) fs::remove(file, error);
  if (name.empty()) return;
  const fs::path from(scenario.seabed->map), to = fs::path(dir) / name;
  if (fs::equivalent(from, to, error)) return;  // a resumed mission's map is the copy already
  const fs::path temporary = to.string() + ".tmp";
  if (!fs::copy_file(from, temporary, fs::copy_options::overwrite_existing, error)) {
    throw std::runtime_error(fmt::format("{}: cannot copy the seabed map {} there: {}", to.string(), from.string(),
                                         error.message()));
  }
  fs::rename(temporary, to, error);
  if (error) throw std::runtime_error(fmt::format("{}: cannot write: {}", to.string(), error.message()));
}

maps::Scenario WithKeptSeabedMap(maps::Scenario scenario) {
  if (const std::string name = RunMapName(scenario); !name.empty()) scenario.seabed->map = name;
  return scenario;
}

void WriteScenarioFile(const std::string& dir, const maps::Scenario& scenario) {
  KeepSeabedMap(dir, scenario);
  WriteScenarioTo((fs::path(dir) / "scenario.yaml").string(), WithKeptSeabedMap(scenario));
}

void WriteScenarioTo(const std::string& path, const maps::Scenario& scenario) {
  const std::string text = maps::EmitScenario(scenario);
  // Nothing is written that the loader would refuse to read back.
  if (text.size() > maps::kMaxScenarioBytes) {
    throw maps::ScenarioError(fmt::format("{}: the scenario would be {:.0f} MB, over the {} MB a scenario may be (the "
                                          "loader refuses larger): fewer XTs, valves or vehicles",
                                          path, text.size() / 1e6, maps::kMaxScenarioBytes >> 20));
  }
  detail::WriteAtomically(path, text);
}

void WriteFilesTogether(const std::vector<std::pair<std::string, std::string>>& files) {
  for (const auto& [path, text] : files) detail::WriteTemporary(path, text);
  for (const auto& [path, text] : files) detail::CommitTemporary(path);
}

RecordSummary ReadRecordSummary(const std::string& dir) {
  RecordSummary s;
  const fs::path trajectory = fs::path(dir) / "trajectory.csv";
  const fs::path metrics = fs::path(dir) / "metrics.json";
  s.exists = fs::exists(trajectory) || fs::exists(metrics);
  s.recorded_until_s = LastRowTime(trajectory.string());
  s.has_checkpoint = fs::exists(fs::path(dir) / kCheckpointFile);
  std::ifstream in(metrics);
  if (in) {
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    if (j.is_object()) {
      s.complete = j.value("complete", true);  // a metrics.json without the key is an older, whole run
      if (!s.complete && j.contains("duration_s") && j["duration_s"].is_number()) s.checkpoint_s = j["duration_s"].get<double>();
      // The end's figures, each only if it is there and a number (a record is read, not trusted).
      const auto number = [&j](const char* key, double fallback) {
        return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
      };
      if (s.complete) {
        const double nan = std::numeric_limits<double>::quiet_NaN();
        s.stopped_early = j.contains("stopped_early") && j["stopped_early"].is_boolean() && j["stopped_early"].get<bool>();
        s.duration_s = number("duration_s", nan);
        const auto count = [&](const char* key) { return static_cast<int>(std::clamp(number(key, -1.0), -1.0, 1e9)); };
        s.vehicle_count = count("vehicle_count");
        s.unvisited_valves = count("unvisited_valves");
        s.valve_count = j.contains("valves") && j["valves"].is_array() ? static_cast<int>(j["valves"].size()) : -1;
        s.risk_weighted_interval_s = number("risk_weighted_interval_s", nan);
        if (j.contains("longest_gap_s") && j["longest_gap_s"].is_object()) {
          const nlohmann::json& gap = j["longest_gap_s"];
          if (gap.contains("max") && gap["max"].is_number()) s.longest_gap_max_s = gap["max"].get<double>();
        }
      }
    }
  }
  return s;
}

}  // namespace sage::server
