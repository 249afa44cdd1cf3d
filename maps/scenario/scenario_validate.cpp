// Scenario::Validate: the rules on a loaded scenario. Every broken rule becomes one ScenarioError
// line "FILE: FIELD = VALUE: RULE", with field paths as in the YAML.
#include "maps/scenario/scenario.h"
#include "maps/scenario/duration_rule.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "maps/scenario/scenario_detail.h"
#include "maps/scenario/printable_text.h"

namespace sage::maps {
std::string detail::NameProblem(const std::string& name) {
  if (name.empty()) return "\"\": must not be empty";
  // Shown as printable UTF-8 (a cut never splits a character, a control shows as ?).
  if (name.size() > kMaxNameLength) {
    return PrintableUtf8(name, 20) + ": must be at most " + std::to_string(kMaxNameLength) + " characters";
  }
  if (FirstNonUtf8(name) != std::string::npos) {
    return PrintableUtf8(name, 20) + ": must be UTF-8 text (a byte that is not shown as ?)";
  }
  const auto control = [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; };
  if (std::any_of(name.begin(), name.end(), control)) {
    return PrintableUtf8(name, kMaxNameLength) + ": must not hold control characters (newline, tab, escape: shown as ?)";
  }
  return {};
}

std::string detail::DirectoryNameProblem(const std::string& name) {
  if (std::string problem = NameProblem(name); !problem.empty()) return problem;
  if (name.find_first_of("/\\") != std::string::npos) {
    return name + ": must not hold / or \\ (the name is a directory's: runs/<name>_...)";
  }
  if (name == "." || name == "..") return name + ": must not be . or .. (the name is a directory's: runs/<name>_...)";
  return {};
}

namespace {

using detail::EventKey;
using detail::FormatNumber;
using detail::InsideBox;
using detail::OneLine;

// std::string("[") rather than "[": "[" + std::string&& trips a GCC 12 -Wrestrict false positive.
std::string FormatVector(const Eigen::Vector2d& v) {
  return std::string("[") + FormatNumber(v.x()) + ", " + FormatNumber(v.y()) + "]";
}

std::string FormatMatrix(const Eigen::Matrix2d& m) {
  return std::string("[") + FormatVector(m.row(0).transpose()) + ", " + FormatVector(m.row(1).transpose()) + "]";
}

// Rules on the loaded structs. Field paths match the YAML, so a message points at the line to fix.
class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& value, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + field + " = " + value + ": " + rule));
  }
  [[noreturn]] void Fail(const std::string& field, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + field + ": " + rule));
  }
  void Finite(const std::string& field, double v) const {
    if (!std::isfinite(v)) Fail(field, FormatNumber(v), "must be a finite number");
  }
  void Finite(const std::string& field, const Eigen::Vector2d& v) const {
    if (!v.allFinite()) Fail(field, FormatVector(v), "must be finite numbers");
  }
  // Infinity is accepted only where it means "never" (forgetting time, revisit bound).
  void Positive(const std::string& field, double v, bool infinity_ok = false) const {
    if (!(infinity_ok && v == std::numeric_limits<double>::infinity())) Finite(field, v);
    if (!(v > 0)) Fail(field, FormatNumber(v), infinity_ok ? "must be > 0, or .inf for never" : "must be > 0");
  }
  void AtMost(const std::string& field, double v, double most, const std::string& unit) const {
    if (v > most) Fail(field, FormatNumber(v), "must be <= " + FormatNumber(most) + " " + unit);
  }
  void NonNegative(const std::string& field, double v) const {
    Finite(field, v);
    if (!(v >= 0)) Fail(field, FormatNumber(v), "must be >= 0");
  }
  void RawWeight(const std::string& field, double v) const {
    NonNegative(field, v);
    if (v > kMaxRawWeight) Fail(field, FormatNumber(v), "must be in [0, 1e12] (weights are relative)");
  }
  // A name goes into logs, tables and CSV files: 1..kMaxNameLength characters, none a control
  // character (a valve named with a newline or ESC forged log lines and broke fleet_events.csv).
  void Name(const std::string& field, const std::string& name) const {
    const std::string problem = detail::NameProblem(name);
    if (!problem.empty()) throw ScenarioError(OneLine(file_ + ": " + field + " = " + problem));
  }
  // A valid name not used before by another entry of the same kind.
  // The scenario's own name, which names its run directories too.
  void DirectoryName(const std::string& field, const std::string& name) const {
    const std::string problem = detail::DirectoryNameProblem(name);
    if (!problem.empty()) throw ScenarioError(OneLine(file_ + ": " + field + " = " + problem));
  }
  void UniqueName(std::map<std::string, std::string>& seen, const std::string& field, const std::string& name) const {
    Name(field, name);
    const auto [it, inserted] = seen.emplace(name, field);
    if (!inserted) Fail(field, name, "duplicate name (also " + it->second + ")");
  }

 private:
  std::string file_;
};

std::string ShowName(const std::string& name) { return name.empty() ? "\"\"" : name; }

// Fleet events: times and joined vehicles in file order, then who is present, walking the events
// in time order (stable, as they are sorted on load) but naming each by its index in the file.
template <typename CheckVehicle>
void CheckFleetEvents(const Checker& c, const std::vector<FleetEvent>& events, const std::vector<VehicleSpec>& vehicles,
                      double duration_s, const CheckVehicle& check_vehicle) {
  const auto path_of = [](std::size_t i) { return "fleet_events[" + std::to_string(i) + "]"; };
  std::map<std::string, double> join_time;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const FleetEvent& event = events[i];
    if (!(event.time_s >= 0 && event.time_s <= duration_s)) {
      c.Fail(path_of(i) + ".time_s", FormatNumber(event.time_s),
             "must be in [0, duration_s = " + FormatNumber(duration_s) + "]");
    }
    if (event.kind == FleetEvent::Kind::kJoin) {
      check_vehicle(path_of(i) + ".join", event.vehicle);
      join_time[event.vehicle.name] = event.time_s;
    } else if (event.kind != FleetEvent::Kind::kLose && event.kind != FleetEvent::Kind::kLeave) {
      c.Fail(path_of(i), std::to_string(static_cast<int>(event.kind)), "must be a join, lose or leave");
    }
  }
  std::vector<std::size_t> order(events.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return events[a].time_s < events[b].time_s; });
  std::vector<std::string> present;
  for (const VehicleSpec& vehicle : vehicles) present.push_back(vehicle.name);
  std::map<std::string, std::string> gone;  // name -> "was lost at t = 400"
  for (std::size_t i : order) {
    const FleetEvent& event = events[i];
    const std::string& name = event.vehicle.name;
    if (event.kind == FleetEvent::Kind::kJoin) {
      present.push_back(name);
      continue;
    }
    const std::string field = path_of(i) + "." + EventKey(event.kind);
    const std::string time_text = "t = " + FormatNumber(event.time_s);
    const auto it = std::find(present.begin(), present.end(), name);
    if (it == present.end()) {
      std::string list;
      for (const std::string& other : present) list += (list.empty() ? "" : ", ") + other;
      std::string why;
      if (gone.count(name) != 0) why = "; " + name + " " + gone[name];
      else if (join_time.count(name) != 0) why = "; " + name + " joins only at t = " + FormatNumber(join_time[name]);
      c.Fail(field, ShowName(name), "must name a vehicle present at " + time_text + " (present: " + list + ")" + why);
    }
    if (present.size() == 1) c.Fail(field, name, "would leave no vehicle");
    present.erase(it);
    gone[name] = std::string(event.kind == FleetEvent::Kind::kLose ? "was lost" : "left") + " at " + time_text;
  }
}

// The seabed sections: the map's kind and frame, the altitude band, the flowlines and boulders
// (in the workspace, sizes bounded). Whether a valve or a start lies on blocked seabed needs the
// map itself: maps/seabed checks that when it builds the world.
void CheckSeabed(const Checker& c, const Scenario& s, const std::string& workspace_text) {
  const Eigen::Vector2d workspace_max(s.workspace.width_m, s.workspace.height_m);
  const double grid = s.astar.grid_resolution_m;
  if (s.seabed) {
    const SeabedSettings& b = *s.seabed;
    const SeabedMapFormat format = SeabedMapFormatOf(b.map);
    if (!b.map.empty() && format == SeabedMapFormat::kUnknown) {
      c.Fail("seabed.map", b.map, "must end in .tif or .tiff (GeoTIFF), .xyz or .csv (gridded x y z) or .bt or .ot (OctoMap)");
    }
    if (b.origin_m) {
      c.Finite("seabed.origin_m", *b.origin_m);
      if (b.map.empty()) c.Fail("seabed.origin_m", FormatVector(*b.origin_m), "places a map: give seabed.map too");
    }
    if (b.values != SeabedValues::kElevation && b.values != SeabedValues::kDepth) {
      c.Fail("seabed.values", std::to_string(static_cast<int>(b.values)), "must be elevation or depth");
    }
    if (b.values == SeabedValues::kDepth && format == SeabedMapFormat::kOctoMap) {
      c.Fail("seabed.values", "depth", "an OctoMap holds heights (z up): leave values out or give elevation");
    }
    const std::string band = FormatVector(Eigen::Vector2d(b.altitude_min_m, b.altitude_max_m));
    if (!std::isfinite(b.altitude_min_m) || !std::isfinite(b.altitude_max_m) || b.altitude_min_m < 0 ||
        b.altitude_max_m > kMaxAltitude_m) {
      c.Fail("seabed.altitude_band_m", band, "must lie in [0, " + FormatNumber(kMaxAltitude_m) + "] m above the seabed");
    }
    // A band thinner than a voxel could hold no voxel centre: nothing would ever block.
    if (!(b.altitude_max_m - b.altitude_min_m >= grid)) {
      c.Fail("seabed.altitude_band_m", band,
             "the ceiling must exceed the floor by at least astar.grid_resolution_m = " + FormatNumber(grid) +
                 " m (the seabed map's voxel)");
    }
    c.Positive("seabed.trend_radius_m", b.trend_radius_m);
    if (b.trend_radius_m < grid || b.trend_radius_m > 1000.0) {
      c.Fail("seabed.trend_radius_m", FormatNumber(b.trend_radius_m),
             "must be in [astar.grid_resolution_m = " + FormatNumber(grid) + ", 1000] m");
    }
  }
  std::size_t points = 0;
  for (const Flowline& f : s.flowlines) points += f.points_m.size();
  if (points > kMaxFlowlinePoints) {
    c.Fail("flowlines", std::to_string(points) + " points", "must hold at most " + std::to_string(kMaxFlowlinePoints));
  }
  std::map<std::string, std::string> names;
  for (std::size_t i = 0; i < s.flowlines.size(); ++i) {
    const Flowline& f = s.flowlines[i];
    const std::string path = "flowlines[" + std::to_string(i) + "]";
    c.UniqueName(names, path + ".name", f.name);
    c.Positive(path + ".diameter_m", f.diameter_m);
    c.AtMost(path + ".diameter_m", f.diameter_m, kMaxFlowlineDiameter_m, "m");
    if (f.points_m.size() < 2) c.Fail(path + ".points_m", "must list at least 2 points (the pipe's axis)");
    for (std::size_t k = 0; k < f.points_m.size(); ++k) {
      const std::string field = path + ".points_m[" + std::to_string(k) + "]";
      c.Finite(field, f.points_m[k]);
      if (!InsideBox(f.points_m[k], Eigen::Vector2d::Zero(), workspace_max)) {
        c.Fail(field, FormatVector(f.points_m[k]), "must be inside the workspace " + workspace_text);
      }
      if (k > 0 && f.points_m[k] == f.points_m[k - 1]) {
        c.Fail(field, FormatVector(f.points_m[k]), "repeats the point before it");
      }
    }
  }
  if (s.boulders.size() > kMaxBoulders) {
    c.Fail("boulders", std::to_string(s.boulders.size()), "must hold at most " + std::to_string(kMaxBoulders));
  }
  for (std::size_t i = 0; i < s.boulders.size(); ++i) {
    const Boulder& b = s.boulders[i];
    const std::string path = "boulders[" + std::to_string(i) + "]";
    c.Finite(path + ".center_m", b.center_m);
    if (!InsideBox(b.center_m, Eigen::Vector2d::Zero(), workspace_max)) {
      c.Fail(path + ".center_m", FormatVector(b.center_m), "must be inside the workspace " + workspace_text);
    }
    c.Positive(path + ".diameter_m", b.diameter_m);
    c.AtMost(path + ".diameter_m", b.diameter_m, kMaxBoulderSize_m, "m");
    c.Positive(path + ".height_m", b.height_m);
    c.AtMost(path + ".height_m", b.height_m, kMaxBoulderSize_m, "m");
  }
}

bool IsIpv4(const std::string& text) {
  int parts = 0;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t dot = std::min(text.find('.', at), text.size());
    const std::string part = text.substr(at, dot - at);
    if (part.empty() || part.size() > 3 || part.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(part) > 255) {
      return false;
    }
    ++parts;
    at = dot + 1;
  }
  return parts == 4;
}

bool OnlyOf(const std::string& text, const std::string& punctuation) {
  return std::all_of(text.begin(), text.end(), [&](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           punctuation.find(ch) != std::string::npos;
  });
}

// RFC 1123 host name labels (a fully qualified name's one trailing dot allowed): "a..b", ".a" and
// "-a" are not names any resolver finds.
bool HostNameLabels(const std::string& given) {
  const std::string name = given.size() > 1 && given.back() == '.' ? given.substr(0, given.size() - 1) : given;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = std::min(name.find('.', begin), name.size());
    const std::size_t length = end - begin;
    if (length == 0 || length > 63 || name[begin] == '-' || name[end - 1] == '-') return false;
    if (end == name.size()) return true;
    begin = end + 1;
  }
}

// Shown in a one-line error: printable UTF-8, control characters as '?', at most 64 characters.
std::string Shown(const std::string& text) { return text.empty() ? "\"\"" : PrintableUtf8(text, 64); }

}  // namespace

std::string DurationRangeProblem(double duration_s) {
  if (duration_s > 0.0 && duration_s <= kMaxDuration_s) return "";
  return "must be > 0 and <= " + FormatNumber(kMaxDuration_s) + " s (a week)";
}

std::string DurationCycleProblem(double duration_s, double control_rate_hz) {
  // As the mission counts its cycles (std::llround: half a cycle rounds up to one).
  if (duration_s * control_rate_hz >= 0.5) return "";
  return "must fly at least one control cycle (>= " + FormatNumber(0.5 / control_rate_hz) +
         " s at control_rate_hz = " + FormatNumber(control_rate_hz) +
         ": a mission flies round(duration_s x control_rate_hz) cycles)";
}

std::string TrajectoryRateRule(double rate_hz, double control_rate_hz) {
  if (rate_hz == 0.0) return "";  // every cycle
  // k to five significant figures, so that 3.33333 reads as 10 Hz / 3.
  const double every = control_rate_hz / rate_hz;
  const bool whole = std::abs(every - std::round(every)) <= 1e-5 * every;
  if (rate_hz > 0.0 && whole && std::round(every) >= 1 && std::round(every) <= kMaxTrajectoryEvery) return "";
  std::string nearest;
  if (rate_hz > 0.0 && std::isfinite(every)) {
    const double low = std::clamp(std::floor(every), 1.0, kMaxTrajectoryEvery);
    const double high = std::clamp(std::ceil(every), 1.0, kMaxTrajectoryEvery);
    const auto k = [](double v) { return std::to_string(static_cast<long long>(v)); };
    // Six significant figures: what the rule above takes back (3.33333 for 10 Hz / 3), not the
    // double's seventeen.
    const auto rate = [&](double v) {
      std::ostringstream out;
      out << std::setprecision(6) << control_rate_hz / v;
      return out.str();
    };
    nearest = "; the nearest: " + rate(low) + " (k = " + k(low) + ")";
    if (high != low) nearest += " and " + rate(high) + " (k = " + k(high) + ")";
  }
  return "must be control_rate_hz = " + FormatNumber(control_rate_hz) + " over a whole number k in 1.." +
         std::to_string(static_cast<long long>(kMaxTrajectoryEvery)) + " (a row every k-th control cycle" + nearest +
         "), or 0 for every cycle";
}

std::string NetworkProblem(const NetworkSettings& network, const std::string& where) {
  const std::string& name = network.interface_name;
  if (!IsIpv4(name) && (name.empty() || name.size() > 15 || !OnlyOf(name, "_.:-"))) {
    return where + ": network.interface = " + Shown(name) +
           ": must be a network interface name (1-15 characters of letters, digits, _ . : -) or an IPv4 address";
  }
  if (network.peers.size() > kMaxPeers) {
    return where + ": network.peers = " + std::to_string(network.peers.size()) + " peers: at most " +
           std::to_string(kMaxPeers);
  }
  for (std::size_t i = 0; i < network.peers.size(); ++i) {
    const std::string& peer = network.peers[i];
    if (!IsIpv4(peer) && (peer.empty() || peer.size() > 253 || !OnlyOf(peer, ".-") || !HostNameLabels(peer))) {
      return where + ": network.peers[" + std::to_string(i) + "] = " + Shown(peer) +
             ": must be an IPv4 address or a host name (dot-separated labels of 1-63 letters, digits and -, "
             "no label starting or ending with -)";
    }
  }
  return {};
}

void Scenario::Validate() const {
  const Checker c(source_path.empty() ? "<scenario>" : source_path);
  c.DirectoryName("name", name);
  c.Positive("workspace.width_m", workspace.width_m);
  c.Positive("workspace.height_m", workspace.height_m);
  const Eigen::Vector2d workspace_max(workspace.width_m, workspace.height_m);
  const std::string workspace_text = "[0, " + FormatNumber(workspace.width_m) + "] x [0, " +
                                     FormatNumber(workspace.height_m) + "]";
  c.Positive("duration_s", duration_s);
  c.AtMost("duration_s", duration_s, kMaxDuration_s, "s (a week)");
  c.Positive("control_rate_hz", control_rate_hz);
  c.AtMost("control_rate_hz", control_rate_hz, kMaxControlRate_hz, "Hz");
  if (const std::string problem = DurationCycleProblem(duration_s, control_rate_hz); !problem.empty()) {
    c.Fail("duration_s", FormatNumber(duration_s), problem);
  }
  c.Positive("physics_rate_hz", physics_rate_hz);
  c.AtMost("physics_rate_hz", physics_rate_hz, kMaxPhysicsRate_hz, "Hz");
  // Whole number of physics steps per control step, up to rounding of the decimal rates.
  const double steps = physics_rate_hz / control_rate_hz;
  if (steps < 1 - 1e-9 || std::abs(steps - std::round(steps)) > 1e-9 * steps) {
    c.Fail("physics_rate_hz", FormatNumber(physics_rate_hz),
           "must be a whole multiple of control_rate_hz = " + FormatNumber(control_rate_hz));
  }
  if (const std::string rule = TrajectoryRateRule(trajectory_rate_hz, control_rate_hz); !rule.empty()) {
    c.Fail("trajectory_rate_hz", FormatNumber(trajectory_rate_hz), rule);
  }
  c.Positive("visit_radius_m", visit_radius_m);
  c.Positive("rearm_radius_m", rearm_radius_m);
  if (!(rearm_radius_m > visit_radius_m)) {
    c.Fail("rearm_radius_m", FormatNumber(rearm_radius_m), "must be > visit_radius_m = " + FormatNumber(visit_radius_m));
  }
  c.NonNegative("start_jitter_m", start_jitter_m);
  if (start_jitter_m > kMaxStartJitter_m) {
    c.Fail("start_jitter_m", FormatNumber(start_jitter_m),
           "must be in [0, " + FormatNumber(kMaxStartJitter_m) + "] m (0 = start exactly at start_m)");
  }
  if (ergodic.basis_order < 1 || ergodic.basis_order > 64) {
    c.Fail("ergodic.basis_order", std::to_string(ergodic.basis_order), "must be in 1..64");
  }
  c.Positive("ergodic.forgetting_time_s", ergodic.forgetting_time_s, /*infinity_ok=*/true);
  c.NonNegative("ergodic.min_turn_radius_m", ergodic.min_turn_radius_m);
  c.NonNegative("ergodic.weight_exponent", ergodic.weight_exponent);
  c.AtMost("ergodic.weight_exponent", ergodic.weight_exponent, kMaxWeightExponent, "(1 = by risk, 0.5 = the square-root law)");
  if (!(ergodic.final_approach_m >= 0.0 && ergodic.final_approach_m <= kMaxFinalApproach_m)) {
    c.Fail("ergodic.final_approach_m", FormatNumber(ergodic.final_approach_m),
           "must be in [0, " + FormatNumber(kMaxFinalApproach_m) + "] m (0 = off, the paper's law)");
  }
  c.Positive("astar.grid_resolution_m", astar.grid_resolution_m);
  if (astar.grid_resolution_m < kMinGridResolution_m) {
    c.Fail("astar.grid_resolution_m", FormatNumber(astar.grid_resolution_m),
           "must be >= " + FormatNumber(kMinGridResolution_m) + " m");
  }
  if (const double cells = std::ceil(workspace.width_m / astar.grid_resolution_m) *
                           std::ceil(workspace.height_m / astar.grid_resolution_m);
      cells > kMaxGridCells) {
    // The coarsest grid that fits, rounded up to two significant digits; the default named, as a
    // file that leaves the key out never wrote the value this complains of (a 100 km workspace).
    const double fits_m = std::sqrt(workspace.width_m * workspace.height_m / kMaxGridCells);
    const double step = std::pow(10.0, std::floor(std::log10(fits_m)) - 1.0);
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step))));
    std::ostringstream fits;
    fits << std::fixed << std::setprecision(decimals) << std::ceil(fits_m / step * (1.0 + 1e-12)) * step;
    c.Fail("astar.grid_resolution_m", FormatNumber(astar.grid_resolution_m),
           "gives " + std::to_string(std::llround(cells / 1e6)) + " million cells over the workspace; at most " +
               FormatNumber(kMaxGridCells / 1e6) + " million (a grid of " + fits.str() + " m or coarser fits; " +
               FormatNumber(AstarSettings{}.grid_resolution_m) + " m is the default when the file leaves the key out)");
  }
  // The seabed OctoMap is voxelised at the grid resolution and its keys span +-2^15 voxels: a
  // wider workspace cannot be mapped (it overflowed the keys and crashed).
  const double span_m = kMaxOctoMapVoxels * astar.grid_resolution_m;
  if (std::max(workspace.width_m, workspace.height_m) > span_m) {
    c.Fail("workspace", FormatNumber(workspace.width_m) + " x " + FormatNumber(workspace.height_m),
           "wider than the seabed map spans at astar.grid_resolution_m = " + FormatNumber(astar.grid_resolution_m) +
               " (" + FormatNumber(std::floor(span_m * 100.0) / 100.0) + " m): use a coarser grid or a smaller field");
  }
  c.NonNegative("astar.clearance_m", astar.clearance_m);
  c.AtMost("astar.clearance_m", astar.clearance_m, kMaxClearance_m, "m");
  c.NonNegative("astar.wait_per_lap_s", astar.wait_per_lap_s);
  c.NonNegative("astar.weight_exponent", astar.weight_exponent);
  c.AtMost("astar.weight_exponent", astar.weight_exponent, kMaxWeightExponent, "(1 = by risk, 0.5 = the square-root law)");
  c.NonNegative("astar.replan_delay_s", astar.replan_delay_s);
  c.NonNegative("astar.look_exponent", astar.look_exponent);
  c.AtMost("astar.look_exponent", astar.look_exponent, kMaxWeightExponent, "(1 = by risk)");
  c.NonNegative("astar.look_leak_weight", astar.look_leak_weight);
  c.AtMost("astar.look_leak_weight", astar.look_leak_weight, 1e6, "(times a valve's chance of a leak, against the risks' 1)");
  if (astar.order == AstarSettings::Order::kLooks && sensors.empty()) {
    c.Fail("astar.order", "looks", "the look planner chooses on the vehicles' scans: give the vehicles sensors, or order: shortest");
  }

  if (structures.empty()) c.Fail("structures", "must list at least one structure");
  std::map<std::string, std::string> structure_names, valve_names, vehicle_names, profile_names;
  for (std::size_t i = 0; i < structures.size(); ++i) {
    const ChristmasTree& tree = structures[i];
    const std::string path = "structures[" + std::to_string(i) + "]";
    c.UniqueName(structure_names, path + ".name", tree.name);
    c.Finite(path + ".center_m", tree.center_m);
    if (!(tree.size_m.array() > 0).all() || !tree.size_m.allFinite()) {
      c.Fail(path + ".size_m", FormatVector(tree.size_m), "must be > 0 and finite");
    }
    c.Positive(path + ".height_m", tree.height_m);
    c.AtMost(path + ".height_m", tree.height_m, kMaxStructureHeight_m, "m");
    if (!InsideBox(tree.center_m - tree.size_m / 2, Eigen::Vector2d::Zero(), workspace_max) ||
        !InsideBox(tree.center_m + tree.size_m / 2, Eigen::Vector2d::Zero(), workspace_max)) {
      c.Fail(path + ".center_m", FormatVector(tree.center_m),
             "footprint of size " + FormatVector(tree.size_m) + " must lie inside the workspace " + workspace_text);
    }
  }
  // No two footprints overlap (two XTs in one place had flown without a word). By their left
  // edges, so each looks only at those that start before it ends along x.
  {
    std::vector<std::size_t> by_left;
    for (std::size_t i = 0; i < structures.size(); ++i) by_left.push_back(i);
    const auto left = [&](std::size_t i) { return structures[i].center_m.x() - structures[i].size_m.x() / 2; };
    std::sort(by_left.begin(), by_left.end(),
              [&](std::size_t a, std::size_t b) { return left(a) < left(b) || (left(a) == left(b) && a < b); });
    for (std::size_t a = 0; a < by_left.size(); ++a) {
      const ChristmasTree& first = structures[by_left[a]];
      const double right = first.center_m.x() + first.size_m.x() / 2;
      for (std::size_t b = a + 1; b < by_left.size() && left(by_left[b]) < right; ++b) {
        const ChristmasTree& other = structures[by_left[b]];
        if (std::abs(other.center_m.y() - first.center_m.y()) >= (other.size_m.y() + first.size_m.y()) / 2) continue;
        const std::size_t later = std::max(by_left[a], by_left[b]);
        const ChristmasTree& named = structures[std::min(by_left[a], by_left[b])];
        c.Fail("structures[" + std::to_string(later) + "].center_m", FormatVector(structures[later].center_m),
               "the footprint of " + structures[later].name + " overlaps that of " + named.name);
      }
    }
  }
  // Checked after all footprints are known: a valve may sit inside another XT's footprint. The
  // footprints by the x of their centres, so a point looks only at those whose x-extent can hold
  // it (each valve and start against every footprint had been 450 million tests on a generated
  // 10,000-XT field); the first footprint in the file's order that holds it is named.
  std::vector<std::size_t> by_x(structures.size());
  double widest_half_m = 0.0;
  for (std::size_t i = 0; i < structures.size(); ++i) {
    by_x[i] = i;
    if (!std::isnan(structures[i].size_m.x())) widest_half_m = std::max(widest_half_m, structures[i].size_m.x() / 2);
  }
  const auto centre_x = [&](std::size_t i) { return structures[i].center_m.x(); };
  std::erase_if(by_x, [&](std::size_t i) { return !std::isfinite(centre_x(i)); });  // refused above; holds nothing
  std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) { return centre_x(a) < centre_x(b); });
  const auto inside_structure = [&](const Eigen::Vector2d& p) -> const ChristmasTree* {
    const ChristmasTree* first = nullptr;
    auto it = std::lower_bound(by_x.begin(), by_x.end(), p.x() - widest_half_m,
                               [&](std::size_t i, double x) { return centre_x(i) < x; });
    for (; it != by_x.end() && centre_x(*it) <= p.x() + widest_half_m; ++it) {
      const ChristmasTree& tree = structures[*it];
      const Eigen::Vector2d half = tree.size_m / 2;
      if (((p - tree.center_m).array().abs() < half.array()).all() && (first == nullptr || &tree < first)) first = &tree;
    }
    return first;
  };
  // A valve or a vehicle's start: finite, inside the workspace, outside every footprint.
  const auto check_in_open_water = [&](const std::string& field, const Eigen::Vector2d& p) {
    c.Finite(field, p);
    if (!InsideBox(p, Eigen::Vector2d::Zero(), workspace_max)) {
      c.Fail(field, FormatVector(p), "must be inside the workspace " + workspace_text);
    }
    if (const ChristmasTree* tree = inside_structure(p)) {
      c.Fail(field, FormatVector(p), "must not be inside the footprint of " + tree->name);
    }
  };
  for (std::size_t i = 0; i < structures.size(); ++i) {
    for (std::size_t j = 0; j < structures[i].valves.size(); ++j) {
      const Valve& valve = structures[i].valves[j];
      const std::string path = "structures[" + std::to_string(i) + "].valves[" + std::to_string(j) + "]";
      c.UniqueName(valve_names, path + ".name", valve.name);
      check_in_open_water(path + ".position_m", valve.position_m);
      const Eigen::Matrix2d& m = valve.covariance_m2;
      if (!m.allFinite() || std::abs(m(0, 1) - m(1, 0)) > 1e-12 * m.cwiseAbs().maxCoeff()) {
        c.Fail(path + ".covariance_m2", FormatMatrix(m), "must be symmetric and finite");
      }
      // Sylvester's criterion for a symmetric 2x2 matrix.
      if (!(m(0, 0) > 0) || !(m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0) > 0)) {
        c.Fail(path + ".covariance_m2", FormatMatrix(m), "must be positive definite");
      }
    }
  }
  if (valve_names.empty()) c.Fail("structures", "must hold at least one valve");
  const auto valve_list = [&] { return "(valves: " + ValveNames() + ")"; };

  // The footprint nearest to p within reach_m (Euclidean distance to its box), if any.
  const auto nearest_footprint = [&](const Eigen::Vector2d& p, double reach_m) {
    std::pair<const ChristmasTree*, double> nearest{nullptr, reach_m};
    if (!p.allFinite()) return nearest;
    auto it = std::lower_bound(by_x.begin(), by_x.end(), p.x() - widest_half_m - reach_m,
                               [&](std::size_t i, double x) { return centre_x(i) < x; });
    for (; it != by_x.end() && centre_x(*it) <= p.x() + widest_half_m + reach_m; ++it) {
      const ChristmasTree& tree = structures[*it];
      const double d = ((p - tree.center_m).cwiseAbs() - tree.size_m / 2).cwiseMax(0.0).norm();
      if (d < nearest.second) nearest = {&tree, d};
    }
    return nearest;
  };
  // A vehicle of `vehicles:` or one joining later; names are unique across both.
  const auto check_vehicle = [&](const std::string& path, const VehicleSpec& vehicle) {
    c.UniqueName(vehicle_names, path + ".name", vehicle.name);
    check_in_open_water(path + ".start_m", vehicle.start_m);
    // The start jitter may move it up to start_jitter_m, and a BlueROV2's hull reaches
    // kVehicleClearance_m from its centre: closer than that to a footprint, it could start inside
    // the XT (the physics then shoves it out), as on blocked seabed (seabed_obstacles.cpp).
    const bool hull = vehicle.model == MotionModel::kBlueRov2;
    const double reach = StartFootprintReach(start_jitter_m, hull);
    const auto mm = [](double v) { return FormatNumber(std::round(v * 1000.0) / 1000.0); };  // 0.6, not 0.6000000000000001
    if (!inside_structure(vehicle.start_m)) {
      // (A hair of tolerance: a start exactly that far, as written to the mm, is clear.)
      if (const auto [tree, d] = nearest_footprint(vehicle.start_m, reach - 1e-9); tree != nullptr) {
        c.Fail(path + ".start_m", FormatVector(vehicle.start_m),
               vehicle.name + " starts " + mm(d) + " m from the footprint of " + tree->name + "; it must start at least " +
                   mm(reach) + " m from it (start_jitter_m " +
                   FormatNumber(start_jitter_m) +
                   (hull ? " and the BlueROV2's hull " + FormatNumber(kVehicleClearance_m) + " m" : "") +
                   ")");
      }
    }
    c.Finite(path + ".start_heading_rad", vehicle.start_heading_rad);
    if (vehicle.model != MotionModel::kSingleIntegrator && vehicle.model != MotionModel::kBlueRov2) {
      c.Fail(path + ".model", std::to_string(static_cast<int>(vehicle.model)), "must be single_integrator or bluerov2");
    }
    c.Positive(path + ".transit_speed_mps", vehicle.transit_speed_mps);
    if (vehicle.model == MotionModel::kBlueRov2 && vehicle.transit_speed_mps > kBlueRov2TopSpeed_mps) {
      c.Fail(path + ".transit_speed_mps", FormatNumber(vehicle.transit_speed_mps),
             "must be <= 0.85 for model bluerov2 (its top speed in surge)");
    }
  };
  if (vehicles.empty()) c.Fail("vehicles", "must list at least one vehicle");
  for (std::size_t i = 0; i < vehicles.size(); ++i) check_vehicle("vehicles[" + std::to_string(i) + "]", vehicles[i]);
  // BlueROV2s that start together must not start in each other's hull (two at one start_m had
  // been flown, 0.2 m apart after the jitter, hulls overlapping). By x, so a start looks only at
  // those within a hull's diagonal along x.
  {
    std::vector<std::size_t> rovs;
    for (std::size_t i = 0; i < vehicles.size(); ++i) {
      if (vehicles[i].model == MotionModel::kBlueRov2 && vehicles[i].start_m.allFinite()) rovs.push_back(i);
    }
    std::sort(rovs.begin(), rovs.end(), [&](std::size_t a, std::size_t b) {
      const double xa = vehicles[a].start_m.x(), xb = vehicles[b].start_m.x();
      return xa < xb || (xa == xb && a < b);
    });
    for (std::size_t a = 0; a < rovs.size(); ++a) {
      for (std::size_t b = a + 1;
           b < rovs.size() && vehicles[rovs[b]].start_m.x() - vehicles[rovs[a]].start_m.x() < kBlueRov2Diagonal_m; ++b) {
        const VehicleSpec& first = vehicles[std::min(rovs[a], rovs[b])];
        const VehicleSpec& second = vehicles[std::max(rovs[a], rovs[b])];
        const double d = (first.start_m - second.start_m).norm();
        if (d >= kBlueRov2Diagonal_m - 1e-9) continue;
        c.Fail("vehicles[" + std::to_string(std::max(rovs[a], rovs[b])) + "].start_m", FormatVector(second.start_m),
               second.name + " starts " + FormatNumber(std::round(d * 1000.0) / 1000.0) + " m from " + first.name +
                   "; BlueROV2s must start at least " + FormatNumber(kBlueRov2Diagonal_m) + " m apart (a hull's diagonal)");
      }
    }
  }

  if (fleet.assignment != FleetAssignment::kShared && fleet.assignment != FleetAssignment::kPartition &&
      fleet.assignment != FleetAssignment::kRegions) {
    c.Fail("fleet.assignment", std::to_string(static_cast<int>(fleet.assignment)), "must be shared, partition or regions");
  }
  c.Positive("fleet.coverage_period_s", fleet.coverage_period_s);
  c.Positive("fleet.liveliness_lease_s", fleet.liveliness_lease_s);
  if (!(fleet.age_weighting_laps >= 0.0 && fleet.age_weighting_laps <= 100.0)) {
    c.Fail("fleet.age_weighting_laps", FormatNumber(fleet.age_weighting_laps), "must be in [0, 100] laps (0 = off)");
  }
  if (!(fleet.risk_share >= 0.0 && fleet.risk_share <= 10.0)) {
    c.Fail("fleet.risk_share", FormatNumber(fleet.risk_share), "must be in [0, 10] (0 = regions balanced on laps alone)");
  }
  if (const std::string problem = NetworkProblem(network, source_path.empty() ? "<scenario>" : source_path);
      !problem.empty()) {
    throw ScenarioError(problem);
  }
  CheckFleetEvents(c, fleet_events, vehicles, duration_s, check_vehicle);
  std::size_t fleet_size = 0;
  double room_needed_m2 = 0.0;
  const auto count_in = [&](const VehicleSpec& v) {
    ++fleet_size;
    room_needed_m2 += v.model == MotionModel::kBlueRov2 ? kMinAreaPerBlueRov2_m2 : kMinAreaPerPointVehicle_m2;
  };
  for (const VehicleSpec& v : vehicles) count_in(v);
  for (const FleetEvent& event : fleet_events) {
    if (event.kind == FleetEvent::Kind::kJoin) count_in(event.vehicle);
  }
  if (const double area_m2 = workspace.width_m * workspace.height_m; room_needed_m2 > area_m2 * (1.0 + 1e-12)) {
    c.Fail("vehicles", std::to_string(fleet_size) + " vehicles (joins included)",
           "need " + FormatNumber(room_needed_m2) + " m^2 (" + FormatNumber(kMinAreaPerBlueRov2_m2) + " a BlueROV2, " +
               FormatNumber(kMinAreaPerPointVehicle_m2) + " a point vehicle); the workspace has " + FormatNumber(area_m2));
  }

  const std::size_t valve_count = valve_names.size();
  c.Positive("guard.revisit_bound_s", guard.revisit_bound_s, /*infinity_ok=*/true);
  c.NonNegative("guard.weight_floor", guard.weight_floor);
  // M floors of 1/M or more would leave no weight for the risk itself; only matters when enabled.
  if (guard.enabled && !(guard.weight_floor * static_cast<double>(valve_count) < 1)) {
    c.Fail("guard.weight_floor", FormatNumber(guard.weight_floor),
           "must be < 1/M = " + FormatNumber(1.0 / static_cast<double>(valve_count)) + " for M = " +
               std::to_string(valve_count) + " valves");
  }

  if (profiles.empty()) c.Fail("profiles", "must define at least one profile");
  for (const RiskProfile& profile : profiles) {
    const std::string path = "profiles." + profile.name;
    c.UniqueName(profile_names, path, profile.name);
    double total = 0;
    for (const auto& [valve, weight] : profile.weights) {
      if (valve_names.count(valve) == 0) c.Fail(path + ".weights." + valve, FormatNumber(weight), "unknown valve " + valve_list());
      c.RawWeight(path + ".weights." + valve, weight);
      total += weight;
    }
    for (const Valve& valve : AllValves()) {
      if (profile.weights.count(valve.name) == 0) c.Fail(path + ".weights", "missing valve " + valve.name);
    }
    if (!(total > 0)) c.Fail(path + ".weights", "must not all be zero");
    for (std::size_t k = 0; k < profile.events.size(); ++k) {
      const RiskEvent& event = profile.events[k];
      const std::string event_path = path + ".events[" + std::to_string(k) + "]";
      if (!(event.time_s >= 0 && event.time_s <= duration_s)) {
        c.Fail(event_path + ".time_s", FormatNumber(event.time_s), "must be in [0, duration_s = " + FormatNumber(duration_s) + "]");
      }
      if (valve_names.count(event.valve) == 0) c.Fail(event_path + ".valve", event.valve, "unknown valve " + valve_list());
      c.RawWeight(event_path + ".weight", event.weight);
    }
  }
  if (FindProfile(default_profile) == nullptr) {
    std::string list;
    for (const RiskProfile& profile : profiles) list += (list.empty() ? "" : ", ") + profile.name;
    c.Fail("default_profile", default_profile.empty() ? "\"\"" : default_profile, "must name a profile (" + list + ")");
  }
  CheckSeabed(c, *this, workspace_text);
  detail::ValidatePerception(*this, source_path.empty() ? "<scenario>" : source_path);
}

}  // namespace sage::maps
