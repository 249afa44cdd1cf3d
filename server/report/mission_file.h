#pragma once
// mission.json: what a running (or crashed) launch's run directory says about its mission, so
// that operators' commands find it (sage risk set, vehicle add, stop) and `sage launch
// --resume` can bring it back: its DDS domain, scenario, clock pace, controller and profile.
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "maps/scenario/scenario.h"

namespace sage::server {

struct MissionFile {
  int domain_id = 0;
  std::string scenario_path;  ///< the run's effective scenario.yaml
  std::string run_dir;        ///< absolute
  double time_scale = 1.0;
  std::string controller = "ergodic";
  std::string profile;
  int launcher_pid = -1;
  int resumes = 0;            ///< times the mission was resumed
  std::string security_dir;   ///< absolute DDS Security directory (sage security init); empty: plain DDS (--insecure)
  maps::NetworkSettings network;  ///< where the mission's DDS traffic goes (the scenario's network)
};

/// Writes DIR/mission.json atomically. Throws std::runtime_error naming the file.
void WriteMissionFile(const std::string& dir, const MissionFile& mission);
/// Reads DIR/mission.json. Throws maps::ScenarioError with one line if it is missing or wrong.
MissionFile ReadMissionFile(const std::string& dir);

/// Writes DIR/NAME (a file of the run directory another tool reads, e.g. cyclonedds.xml)
/// atomically. Throws std::runtime_error naming the file.
void WriteRunFile(const std::string& dir, const std::string& name, const std::string& text);

/// The run directory's copy of the scenario's seabed map: "seabed_map" and the map's extension.
/// Empty without a map.
std::string RunMapName(const maps::Scenario& scenario);

/// Copies the scenario's seabed map into DIR as RunMapName (unless it is that copy already: a
/// resumed mission's) and removes any other seabed_map.* a mission before left there, so the
/// directory flies, resumes and runs again without the file it came from (a run's scenario.yaml
/// had named the map by its absolute path, and failed once that file changed or was elsewhere).
/// Once, as the mission starts: the copy is the map it flew. Throws std::runtime_error naming the
/// file it could not write.
void KeepSeabedMap(const std::string& dir, const maps::Scenario& scenario);

/// `scenario` with its seabed map named as the run directory's copy (RunMapName, relative to the
/// directory's scenario.yaml).
maps::Scenario WithKeptSeabedMap(maps::Scenario scenario);

/// Writes DIR/scenario.yaml (the effective scenario every process of the mission reads, its map
/// kept: KeepSeabedMap, WithKeptSeabedMap) atomically. Throws std::runtime_error naming the file.
void WriteScenarioFile(const std::string& dir, const maps::Scenario& scenario);

/// Writes a scenario file at `path` atomically. Throws std::runtime_error naming the file.
void WriteScenarioTo(const std::string& path, const maps::Scenario& scenario);
/// Writes each (path, text) as a temporary first, then renames them all: a generated scenario and
/// the map beside it appear together or not at all. Throws std::runtime_error naming the file.
void WriteFilesTogether(const std::vector<std::pair<std::string, std::string>>& files);

/// How far a run directory's record goes.
struct RecordSummary {
  bool exists = false;              ///< a mission was recorded here (trajectory.csv or metrics.json)
  bool complete = false;            ///< metrics.json says "complete": true
  double recorded_until_s = -1.0;   ///< the last trajectory row's time
  double checkpoint_s = -1.0;       ///< the partial metrics' (and checkpoint's) time; -1 if none
  bool has_checkpoint = false;
  /// From a complete metrics.json (NaN / -1 where it has none): how the mission ended, for
  /// `sage status` of an ended mission.
  bool stopped_early = false;
  double duration_s = std::numeric_limits<double>::quiet_NaN();
  int vehicle_count = -1, valve_count = -1, unvisited_valves = -1;
  double risk_weighted_interval_s = std::numeric_limits<double>::quiet_NaN();
  double longest_gap_max_s = std::numeric_limits<double>::quiet_NaN();
};
RecordSummary ReadRecordSummary(const std::string& dir);

}  // namespace sage::server
