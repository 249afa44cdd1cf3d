#include "server/app/field_command.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "maps/scenario/seabed_example.h"
#include "server/app/cli_scenario.h"
#include "server/report/mission_file.h"

namespace sage::server {
namespace {

std::string FileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

maps::FieldOptions WithCountsSizedToEachOther(maps::FieldOptions options, bool xts_given, bool valves_given,
                                              bool vehicles_given) {
  const maps::FieldOptions defaults;
  const double per_xt = static_cast<double>(defaults.valves) / defaults.xts;
  if (valves_given && !xts_given && options.valves < 2) {
    // Said of the count given: the default --xts it would otherwise be held to was not the user's.
    throw maps::ScenarioError(fmt::format("--valves = {}: must be >= 2 (an XT carries 2 to 5 valves)", options.valves));
  }
  if (xts_given && !valves_given && options.xts >= 1) {
    const long long xts = options.xts;
    const long long valves = std::clamp(std::llround(per_xt * static_cast<double>(xts)), 2 * xts, 5 * xts);
    // A count past int's range stays refused by the generator, as a typed one would be.
    options.valves = static_cast<int>(std::min<long long>(valves, std::numeric_limits<int>::max()));
  } else if (valves_given && !xts_given && options.valves >= 2) {
    // At least valves / 5 XTs (rounded up) and at most valves / 2 (rounded down): that range is never empty from 2 on.
    const long long valves = options.valves;
    options.xts = static_cast<int>(std::clamp(std::llround(static_cast<double>(valves) / per_xt), (valves + 4) / 5, valves / 2));
  }
  if (!vehicles_given && (xts_given || valves_given) && options.xts >= 1) {
    const double per_vehicle = static_cast<double>(defaults.xts) / defaults.vehicles;
    options.vehicles = static_cast<int>(std::max(1LL, std::llround(static_cast<double>(options.xts) / per_vehicle)));
  }
  return options;
}

int CmdFieldGenerate(const maps::FieldOptions& options, const std::string& out_path) {
  const auto start = std::chrono::steady_clock::now();
  const maps::Scenario field = maps::GenerateField(options);
  // A field sage wrote (this command's, a run directory's scenario.yaml) is replaced, as a run
  // directory is; any other file is refused: `-o scenarios/fleet_field.yaml` had replaced a
  // hand-written scenario with only a warning. (field seabed refuses another map too.)
  if (std::error_code ec; std::filesystem::exists(out_path, ec)) {
    // Only a regular file is opened to be read: a FIFO or /dev/stdout would block on itself.
    if (!std::filesystem::is_regular_file(out_path, ec)) {
      throw maps::ScenarioError(fmt::format("--out = {}: exists and is not a regular file (a folder, a device?); give a "
                                            "file path",
                                            out_path));
    }
    std::ifstream in(out_path, std::ios::binary);
    std::string first_line;
    std::getline(in, first_line);
    if (first_line != maps::kEmittedScenarioHeader) {
      throw maps::ScenarioError(fmt::format(
          "--out = {}: exists and is a file that sage did not write (a hand-written scenario?); give --out another path, "
          "or remove it first",
          out_path));
    }
    spdlog::warn("{}: replacing the field written there before (give --out another path to keep it)", out_path);
  }
  if (const std::filesystem::path folder = std::filesystem::path(out_path).parent_path(); !folder.empty()) {
    if (std::error_code ec; !std::filesystem::is_directory(folder, ec)) {
      throw maps::ScenarioError(fmt::format("--out = {}: its folder {} does not exist; make it first, or give another path",
                                            out_path, folder.string()));
    }
  }
  try {
    WriteScenarioTo(out_path, field);
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(std::string("--out: ") + e.what());
  }
  const auto counted = [](std::size_t n, const char* one, const char* many) { return fmt::format("{} {}", n, n == 1 ? one : many); };
  std::string sensors;
  for (const maps::SensorSpec& sensor : field.sensors) sensors += (sensors.empty() ? "" : " and a ") + sensor.name;
  const std::string record =
      field.TrajectoryEvery() > 1 ? fmt::format(", trajectory.csv at {:g} Hz", field.trajectory_rate_hz) : "";
  spdlog::info("wrote {}: {}, {}, {}{} on {:.1f} x {:.1f} m (K = {}, A* grid {} m{}) in {:.2f} s; run it "
               "with sage run {}{} or sage launch {}",
               out_path, counted(field.structures.size(), "XT", "XTs"),
               counted(static_cast<std::size_t>(field.ValveCount()), "valve", "valves"),
               counted(field.vehicles.size(), "vehicle", "vehicles"), sensors.empty() ? "" : " with a " + sensors + " each",
               field.workspace.width_m, field.workspace.height_m, field.ergodic.basis_order,
               field.astar.grid_resolution_m, record,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), out_path,
               sensors.empty() ? "" : " --random-leaks 3 (leaks it must find)", out_path);
  WarnOfFleetDensity(field, Flown::kBoth);  // the field flies as regions, and is compared with tours
  return 0;
}

int CmdFieldSeabed(std::uint64_t seed, const std::string& requested_name, const std::string& out_path) {
  // A directory for --out names no file (the map's name, taken from it, had been blamed as --name).
  if (out_path.empty() || out_path.back() == '/' || std::filesystem::is_directory(out_path)) {
    throw maps::ScenarioError("--out = " + out_path + ": a directory; give the scenario file to write (e.g. " +
                              (std::filesystem::path(out_path) / "slope.yaml").lexically_normal().string() + ")");
  }
  // The name is also the map's file name, beside the scenario: by default the scenario file's own
  // (slope11.yaml and slope11.xyz), so that two examples in one folder do not share one map.
  const std::string name = requested_name.empty() ? std::filesystem::path(out_path).stem().string() : requested_name;
  const bool plain = !name.empty() && name.size() <= maps::kMaxNameLength &&
                     std::all_of(name.begin(), name.end(), [](unsigned char c) {
                       return std::isalnum(c) || c == '_' || c == '-' || c == '.';
                     }) && name.front() != '.';
  if (!plain) {
    throw maps::ScenarioError("--name = " + name + ": must be 1-64 letters, digits, '_', '-' or '.' (it names the map file" +
                              (requested_name.empty() ? "; by default the --out file's name" : "") + ")");
  }
  const auto start = std::chrono::steady_clock::now();
  const maps::SeabedExample field = maps::GenerateSeabedExample(seed, name);
  const std::string map_path = (std::filesystem::path(out_path).parent_path() / (name + ".xyz")).string();
  // Another scenario's map is not written over: a scenario beside it would fly on this seabed
  // without a word. Writing the same pair again (the scenario file exists) replaces both.
  std::error_code ec;
  if (std::filesystem::exists(map_path, ec) && !std::filesystem::exists(out_path, ec) &&
      FileText(map_path) != field.map_xyz) {
    throw maps::ScenarioError("--name = " + name + ": " + map_path +
                              " exists and is another seabed (another scenario's map?); choose another --name or --out");
  }
  try {
    WriteFilesTogether({{map_path, field.map_xyz}, {out_path, field.yaml}});
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(std::string("--out: ") + e.what());
  }
  spdlog::info("wrote {} and its seabed {}: {} structures, {} valves, {} flowlines, {} boulders, {} vehicles on "
               "{:.0f} x {:.0f} m in {:.2f} s; run it with sage run {} or sage launch {}",
               out_path, map_path, field.scenario.structures.size(), field.scenario.ValveCount(),
               field.scenario.flowlines.size(), field.scenario.boulders.size(), field.scenario.vehicles.size(),
               field.scenario.workspace.width_m, field.scenario.workspace.height_m,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), out_path, out_path);
  return 0;
}

}  // namespace sage::server
