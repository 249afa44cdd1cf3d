// Scenario YAML: reading (with typo and type checks), validation and writing. yaml-cpp is used
// only in this file. Every user-facing problem becomes one ScenarioError line
// "FILE: FIELD = VALUE: RULE", so a bad file never shows a yaml-cpp message alone or a trace.
#include "maps/scenario.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string_view>

#include <yaml-cpp/yaml.h>

namespace sage::maps {
namespace {

using Keys = std::initializer_list<std::string_view>;

// Shortest text that reads back to the very same double (std::to_chars), so that emitting and
// re-parsing is exact; YAML spellings for the non-finite values.
std::string FormatNumber(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string FormatVector(const Eigen::Vector2d& v) {
  return "[" + FormatNumber(v.x()) + ", " + FormatNumber(v.y()) + "]";
}

std::string FormatMatrix(const Eigen::Matrix2d& m) {
  return "[" + FormatVector(m.row(0).transpose()) + ", " + FormatVector(m.row(1).transpose()) + "]";
}

// Messages reach the user as one line, whatever text was quoted into them.
std::string OneLine(std::string text) {
  std::replace_if(text.begin(), text.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  return text;
}

// A node as the user wrote it, on one line and short enough to quote in a message.
std::string Show(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return node.Scalar().empty() ? "\"\"" : OneLine(node.Scalar());
  YAML::Emitter out;
  out.SetSeqFormat(YAML::Flow);
  out.SetMapFormat(YAML::Flow);
  out << node;
  std::string text = OneLine(out.c_str());
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

// Turns YAML nodes into typed values; every failure names file, field path and value.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& path, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + path + ": " + rule));
  }
  [[noreturn]] void Fail(const std::string& path, const YAML::Node& node, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + path + " = " + Show(node) + ": " + rule));
  }

  // A map with unique plain keys, each in `allowed` (any key if `allowed` is empty).
  void ExpectMap(const YAML::Node& node, const std::string& path, Keys allowed) const {
    if (!node.IsMap()) Fail(path, node, "must be a map");
    std::vector<std::string> seen;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) Fail(path, entry.first, "keys must be plain names");
      const std::string& key = entry.first.Scalar();
      const std::string key_path = Join(path, key);
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) Fail(key_path, "duplicate key");
      seen.push_back(key);
      if (allowed.size() != 0 && std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        std::string list;
        for (std::string_view name : allowed) list += (list.empty() ? "" : ", ") + std::string(name);
        Fail(key_path, "unknown key (allowed: " + list + ")");
      }
    }
  }
  void ExpectList(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence()) Fail(path, node, "must be a list");
  }
  YAML::Node Require(const YAML::Node& map, const std::string& key, const std::string& path) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined()) Fail(Join(path, key), "missing (required)");
    return node;
  }
  static std::string Join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

  // Accepts YAML's .inf as well as inf and infinity (any case, optional sign) for infinity.
  double Number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(path, node, "must be a number");
    std::string text = node.Scalar();
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
    bool negative = false;
    std::string_view body = text;
    if (!body.empty() && (body[0] == '+' || body[0] == '-')) {
      negative = body[0] == '-';
      body.remove_prefix(1);
    }
    if (body == ".inf" || body == "inf" || body == "infinity") {
      return negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    }
    if (body == ".nan" || body == "nan") return std::numeric_limits<double>::quiet_NaN();
    double value = 0.0;
    const auto result = std::from_chars(body.data(), body.data() + body.size(), value);
    if (body.empty() || body[0] == '+' || body[0] == '-' || result.ec != std::errc() ||
        result.ptr != body.data() + body.size()) {
      Fail(path, node, "must be a number");
    }
    return negative ? -value : value;
  }
  template <typename Integer>
  Integer WholeNumber(const YAML::Node& node, const std::string& path, const char* rule) const {
    Integer value = 0;
    const std::string text = node.IsScalar() ? node.Scalar() : std::string();
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || result.ec != std::errc() || result.ptr != text.data() + text.size()) {
      Fail(path, node, rule);
    }
    return value;
  }
  bool Bool(const YAML::Node& node, const std::string& path) const {
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) Fail(path, node, "must be true or false");
    return value;
  }
  std::string Text(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(path, node, "must be a name (text)");
    return node.Scalar();
  }
  Eigen::Vector2d Vector(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence() || node.size() != 2) Fail(path, node, "must be a list of 2 numbers [x, y]");
    return {Number(node[0], path + "[0]"), Number(node[1], path + "[1]")};
  }
  Eigen::Matrix2d Matrix(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence() || node.size() != 2) Fail(path, node, "must be [[xx, xy], [yx, yy]]");
    Eigen::Matrix2d m;
    m.row(0) = Vector(node[0], path + "[0]").transpose();
    m.row(1) = Vector(node[1], path + "[1]").transpose();
    return m;
  }

  template <typename Read>
  void Optional(const YAML::Node& map, const std::string& key, const std::string& path, Read read) const {
    const YAML::Node node = map[key];
    if (node.IsDefined()) read(node, Join(path, key));
  }
  void OptionalNumber(const YAML::Node& map, const std::string& key, const std::string& path, double& out) const {
    Optional(map, key, path, [&](const YAML::Node& n, const std::string& p) { out = Number(n, p); });
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

Valve ReadValve(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"name", "position_m", "sigma_m", "covariance_m2"});
  Valve valve;
  valve.name = r.Text(r.Require(node, "name", path), path + ".name");
  valve.position_m = r.Vector(r.Require(node, "position_m", path), path + ".position_m");
  if (node["sigma_m"].IsDefined() && node["covariance_m2"].IsDefined()) {
    r.Fail(path, "give sigma_m or covariance_m2, not both");
  }
  r.Optional(node, "sigma_m", path, [&](const YAML::Node& n, const std::string& p) {
    const double sigma = r.Number(n, p);
    // Checked here: squaring would hide a negative sigma from Validate().
    if (!(std::isfinite(sigma) && sigma > 0)) r.Fail(p, n, "must be > 0");
    valve.covariance_m2 = sigma * sigma * Eigen::Matrix2d::Identity();
  });
  r.Optional(node, "covariance_m2", path,
             [&](const YAML::Node& n, const std::string& p) { valve.covariance_m2 = r.Matrix(n, p); });
  return valve;
}

ChristmasTree ReadStructure(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"name", "center_m", "size_m", "height_m", "valves"});
  ChristmasTree tree;
  tree.name = r.Text(r.Require(node, "name", path), path + ".name");
  tree.center_m = r.Vector(r.Require(node, "center_m", path), path + ".center_m");
  r.Optional(node, "size_m", path, [&](const YAML::Node& n, const std::string& p) { tree.size_m = r.Vector(n, p); });
  r.OptionalNumber(node, "height_m", path, tree.height_m);
  r.Optional(node, "valves", path, [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      tree.valves.push_back(ReadValve(r, list[i], p + "[" + std::to_string(i) + "]"));
    }
  });
  return tree;
}

VehicleSpec ReadVehicle(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"name", "start_m", "start_heading_rad", "model", "transit_speed_mps"});
  VehicleSpec vehicle;
  vehicle.name = r.Text(r.Require(node, "name", path), path + ".name");
  vehicle.start_m = r.Vector(r.Require(node, "start_m", path), path + ".start_m");
  r.OptionalNumber(node, "start_heading_rad", path, vehicle.start_heading_rad);
  r.Optional(node, "model", path, [&](const YAML::Node& n, const std::string& p) {
    vehicle.model = ParseMotionModel(r.Text(n, p), r.file() + ": " + p);
  });
  r.OptionalNumber(node, "transit_speed_mps", path, vehicle.transit_speed_mps);
  return vehicle;
}

// One change of the fleet: {time_s: T, join: {a vehicle}} or {time_s: T, lose: NAME} or
// {time_s: T, leave: NAME}.
FleetEvent ReadFleetEvent(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"time_s", "join", "lose", "leave"});
  FleetEvent event;
  event.time_s = r.Number(r.Require(node, "time_s", path), path + ".time_s");
  const int kinds = static_cast<int>(node["join"].IsDefined()) + static_cast<int>(node["lose"].IsDefined()) +
                    static_cast<int>(node["leave"].IsDefined());
  if (kinds != 1) r.Fail(path, node, "must give exactly one of join, lose, leave");
  if (node["join"].IsDefined()) {
    event.kind = FleetEvent::Kind::kJoin;
    event.vehicle = ReadVehicle(r, node["join"], path + ".join");
  } else if (node["lose"].IsDefined()) {
    event.kind = FleetEvent::Kind::kLose;
    event.vehicle.name = r.Text(node["lose"], path + ".lose");
  } else {
    event.kind = FleetEvent::Kind::kLeave;
    event.vehicle.name = r.Text(node["leave"], path + ".leave");
  }
  return event;
}

RiskProfile ReadProfile(const Reader& r, const std::string& name, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"weights", "events"});
  RiskProfile profile;
  profile.name = name;
  const YAML::Node weights = r.Require(node, "weights", path);
  r.ExpectMap(weights, path + ".weights", {});
  for (const auto& entry : weights) {
    const std::string valve = entry.first.Scalar();
    profile.weights[valve] = r.Number(entry.second, path + ".weights." + valve);
  }
  r.Optional(node, "events", path, [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string event_path = p + "[" + std::to_string(i) + "]";
      r.ExpectMap(list[i], event_path, {"time_s", "valve", "weight"});
      RiskEvent event;
      event.time_s = r.Number(r.Require(list[i], "time_s", event_path), event_path + ".time_s");
      event.valve = r.Text(r.Require(list[i], "valve", event_path), event_path + ".valve");
      event.weight = r.Number(r.Require(list[i], "weight", event_path), event_path + ".weight");
      profile.events.push_back(event);
    }
  });
  return profile;
}

Scenario ReadScenario(const Reader& r, const YAML::Node& root, const std::string& source) {
  if (!root.IsMap()) r.Fail("scenario", root, "must be a YAML map of sections (workspace, structures, ...)");
  r.ExpectMap(root, "", {"name", "workspace", "duration_s", "control_rate_hz", "physics_rate_hz",
                         "visit_radius_m", "rearm_radius_m", "seed", "ergodic", "guard", "astar",
                         "structures", "vehicles", "default_profile", "profiles", "fleet", "fleet_events"});
  Scenario s;
  s.source_path = source;
  s.name = source.empty() ? "scenario" : std::filesystem::path(source).stem().string();
  r.Optional(root, "name", "", [&](const YAML::Node& n, const std::string& p) { s.name = r.Text(n, p); });
  r.Optional(root, "workspace", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"width_m", "height_m"});
    r.OptionalNumber(n, "width_m", p, s.workspace.width_m);
    r.OptionalNumber(n, "height_m", p, s.workspace.height_m);
  });
  r.OptionalNumber(root, "duration_s", "", s.duration_s);
  r.OptionalNumber(root, "control_rate_hz", "", s.control_rate_hz);
  r.OptionalNumber(root, "physics_rate_hz", "", s.physics_rate_hz);
  r.OptionalNumber(root, "visit_radius_m", "", s.visit_radius_m);
  r.OptionalNumber(root, "rearm_radius_m", "", s.rearm_radius_m);
  r.Optional(root, "seed", "", [&](const YAML::Node& n, const std::string& p) {
    s.seed = r.WholeNumber<std::uint64_t>(n, p, "must be a whole number >= 0");
  });
  r.Optional(root, "ergodic", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"basis_order", "forgetting_time_s"});
    r.Optional(n, "basis_order", p, [&](const YAML::Node& v, const std::string& q) {
      s.ergodic.basis_order = r.WholeNumber<int>(v, q, "must be a whole number");
    });
    r.OptionalNumber(n, "forgetting_time_s", p, s.ergodic.forgetting_time_s);
  });
  r.Optional(root, "guard", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"enabled", "weight_floor", "revisit_bound_s"});
    r.Optional(n, "enabled", p, [&](const YAML::Node& v, const std::string& q) { s.guard.enabled = r.Bool(v, q); });
    r.OptionalNumber(n, "weight_floor", p, s.guard.weight_floor);
    r.OptionalNumber(n, "revisit_bound_s", p, s.guard.revisit_bound_s);
  });
  r.Optional(root, "astar", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"grid_resolution_m", "clearance_m", "wait_per_lap_s"});
    r.OptionalNumber(n, "grid_resolution_m", p, s.astar.grid_resolution_m);
    r.OptionalNumber(n, "clearance_m", p, s.astar.clearance_m);
    r.OptionalNumber(n, "wait_per_lap_s", p, s.astar.wait_per_lap_s);
  });
  const YAML::Node structures = r.Require(root, "structures", "");
  r.ExpectList(structures, "structures");
  for (std::size_t i = 0; i < structures.size(); ++i) {
    s.structures.push_back(ReadStructure(r, structures[i], "structures[" + std::to_string(i) + "]"));
  }
  const YAML::Node vehicles = r.Require(root, "vehicles", "");
  r.ExpectList(vehicles, "vehicles");
  for (std::size_t i = 0; i < vehicles.size(); ++i) {
    s.vehicles.push_back(ReadVehicle(r, vehicles[i], "vehicles[" + std::to_string(i) + "]"));
  }
  const YAML::Node profiles = r.Require(root, "profiles", "");
  r.ExpectMap(profiles, "profiles", {});
  for (const auto& entry : profiles) {
    const std::string name = entry.first.Scalar();
    s.profiles.push_back(ReadProfile(r, name, entry.second, "profiles." + name));
  }
  r.Optional(root, "default_profile", "", [&](const YAML::Node& n, const std::string& p) {
    s.default_profile = r.Text(n, p);
  });
  if (s.default_profile.empty() && !s.profiles.empty()) s.default_profile = s.profiles.front().name;
  r.Optional(root, "fleet", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"assignment", "coverage_period_s", "liveliness_lease_s"});
    r.Optional(n, "assignment", p, [&](const YAML::Node& v, const std::string& q) {
      s.fleet.assignment = ParseFleetAssignment(r.Text(v, q), r.file() + ": " + q);
    });
    r.OptionalNumber(n, "coverage_period_s", p, s.fleet.coverage_period_s);
    r.OptionalNumber(n, "liveliness_lease_s", p, s.fleet.liveliness_lease_s);
  });
  r.Optional(root, "fleet_events", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      s.fleet_events.push_back(ReadFleetEvent(r, list[i], p + "[" + std::to_string(i) + "]"));
    }
  });
  return s;
}

std::string Position(const YAML::Mark& mark) {
  if (mark.is_null()) return "";
  return "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) + ": ";
}

}  // namespace

namespace {

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
    if (!(v > 0)) Fail(field, FormatNumber(v), "must be > 0");
  }
  void NonNegative(const std::string& field, double v) const {
    Finite(field, v);
    if (!(v >= 0)) Fail(field, FormatNumber(v), "must be >= 0");
  }
  // A non-empty name not used before by another entry of the same kind.
  void UniqueName(std::map<std::string, std::string>& seen, const std::string& field, const std::string& name) const {
    if (name.empty()) Fail(field, "\"\"", "must not be empty");
    const auto [it, inserted] = seen.emplace(name, field);
    if (!inserted) Fail(field, name, "duplicate name (also " + it->second + ")");
  }

 private:
  std::string file_;
};

bool InsideBox(const Eigen::Vector2d& p, const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}

const char* EventKey(FleetEvent::Kind kind) {
  switch (kind) {
    case FleetEvent::Kind::kJoin: return "join";
    case FleetEvent::Kind::kLose: return "lose";
    case FleetEvent::Kind::kLeave: return "leave";
  }
  return "unknown";
}

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

}  // namespace

void Scenario::Validate() const {
  const Checker c(source_path.empty() ? "<scenario>" : source_path);
  if (name.empty()) c.Fail("name", "\"\"", "must not be empty");
  c.Positive("workspace.width_m", workspace.width_m);
  c.Positive("workspace.height_m", workspace.height_m);
  const Eigen::Vector2d workspace_max(workspace.width_m, workspace.height_m);
  const std::string workspace_text = "[0, " + FormatNumber(workspace.width_m) + "] x [0, " +
                                     FormatNumber(workspace.height_m) + "]";
  c.Positive("duration_s", duration_s);
  c.Positive("control_rate_hz", control_rate_hz);
  c.Positive("physics_rate_hz", physics_rate_hz);
  // Whole number of physics steps per control step, up to rounding of the decimal rates.
  const double steps = physics_rate_hz / control_rate_hz;
  if (steps < 1 - 1e-9 || std::abs(steps - std::round(steps)) > 1e-9 * steps) {
    c.Fail("physics_rate_hz", FormatNumber(physics_rate_hz),
           "must be a whole multiple of control_rate_hz = " + FormatNumber(control_rate_hz));
  }
  c.Positive("visit_radius_m", visit_radius_m);
  c.Positive("rearm_radius_m", rearm_radius_m);
  if (!(rearm_radius_m > visit_radius_m)) {
    c.Fail("rearm_radius_m", FormatNumber(rearm_radius_m), "must be > visit_radius_m = " + FormatNumber(visit_radius_m));
  }
  if (ergodic.basis_order < 1 || ergodic.basis_order > 64) {
    c.Fail("ergodic.basis_order", std::to_string(ergodic.basis_order), "must be in 1..64");
  }
  c.Positive("ergodic.forgetting_time_s", ergodic.forgetting_time_s, /*infinity_ok=*/true);
  c.Positive("astar.grid_resolution_m", astar.grid_resolution_m);
  c.NonNegative("astar.clearance_m", astar.clearance_m);
  c.NonNegative("astar.wait_per_lap_s", astar.wait_per_lap_s);

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
    if (!InsideBox(tree.center_m - tree.size_m / 2, Eigen::Vector2d::Zero(), workspace_max) ||
        !InsideBox(tree.center_m + tree.size_m / 2, Eigen::Vector2d::Zero(), workspace_max)) {
      c.Fail(path + ".center_m", FormatVector(tree.center_m),
             "footprint of size " + FormatVector(tree.size_m) + " must lie inside the workspace " + workspace_text);
    }
  }
  // Checked after all footprints are known: a valve may sit inside another XT's footprint.
  const auto inside_structure = [&](const Eigen::Vector2d& p) -> const ChristmasTree* {
    for (const ChristmasTree& tree : structures) {
      const Eigen::Vector2d half = tree.size_m / 2;
      if (((p - tree.center_m).array().abs() < half.array()).all()) return &tree;
    }
    return nullptr;
  };
  for (std::size_t i = 0; i < structures.size(); ++i) {
    for (std::size_t j = 0; j < structures[i].valves.size(); ++j) {
      const Valve& valve = structures[i].valves[j];
      const std::string path = "structures[" + std::to_string(i) + "].valves[" + std::to_string(j) + "]";
      c.UniqueName(valve_names, path + ".name", valve.name);
      c.Finite(path + ".position_m", valve.position_m);
      if (!InsideBox(valve.position_m, Eigen::Vector2d::Zero(), workspace_max)) {
        c.Fail(path + ".position_m", FormatVector(valve.position_m), "must be inside the workspace " + workspace_text);
      }
      if (const ChristmasTree* tree = inside_structure(valve.position_m)) {
        c.Fail(path + ".position_m", FormatVector(valve.position_m), "must not be inside the footprint of " + tree->name);
      }
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
  const auto valve_list = [&] {
    std::string list;
    for (const Valve& valve : AllValves()) list += (list.empty() ? "" : ", ") + valve.name;
    return "(valves: " + list + ")";
  };

  // A vehicle of `vehicles:` or one joining later; names are unique across both.
  const auto check_vehicle = [&](const std::string& path, const VehicleSpec& vehicle) {
    c.UniqueName(vehicle_names, path + ".name", vehicle.name);
    c.Finite(path + ".start_m", vehicle.start_m);
    if (!InsideBox(vehicle.start_m, Eigen::Vector2d::Zero(), workspace_max)) {
      c.Fail(path + ".start_m", FormatVector(vehicle.start_m), "must be inside the workspace " + workspace_text);
    }
    if (const ChristmasTree* tree = inside_structure(vehicle.start_m)) {
      c.Fail(path + ".start_m", FormatVector(vehicle.start_m), "must not be inside the footprint of " + tree->name);
    }
    c.Finite(path + ".start_heading_rad", vehicle.start_heading_rad);
    if (vehicle.model != MotionModel::kSingleIntegrator && vehicle.model != MotionModel::kBlueRov2) {
      c.Fail(path + ".model", std::to_string(static_cast<int>(vehicle.model)), "must be single_integrator or bluerov2");
    }
    c.Positive(path + ".transit_speed_mps", vehicle.transit_speed_mps);
  };
  if (vehicles.empty()) c.Fail("vehicles", "must list at least one vehicle");
  for (std::size_t i = 0; i < vehicles.size(); ++i) check_vehicle("vehicles[" + std::to_string(i) + "]", vehicles[i]);

  if (fleet.assignment != FleetAssignment::kShared && fleet.assignment != FleetAssignment::kPartition) {
    c.Fail("fleet.assignment", std::to_string(static_cast<int>(fleet.assignment)), "must be shared or partition");
  }
  c.Positive("fleet.coverage_period_s", fleet.coverage_period_s);
  c.Positive("fleet.liveliness_lease_s", fleet.liveliness_lease_s);
  CheckFleetEvents(c, fleet_events, vehicles, duration_s, check_vehicle);

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
      c.NonNegative(path + ".weights." + valve, weight);
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
      c.NonNegative(event_path + ".weight", event.weight);
    }
  }
  if (FindProfile(default_profile) == nullptr) {
    std::string list;
    for (const RiskProfile& profile : profiles) list += (list.empty() ? "" : ", ") + profile.name;
    c.Fail("default_profile", default_profile.empty() ? "\"\"" : default_profile, "must name a profile (" + list + ")");
  }
}

std::vector<Valve> Scenario::AllValves() const {
  std::vector<Valve> valves;
  for (const ChristmasTree& tree : structures) valves.insert(valves.end(), tree.valves.begin(), tree.valves.end());
  return valves;
}

std::vector<Eigen::Vector2d> Scenario::ValvePositions() const {
  std::vector<Eigen::Vector2d> points;
  for (const Valve& valve : AllValves()) points.push_back(valve.position_m);
  return points;
}

int Scenario::ValveIndex(const std::string& valve_name) const {
  int index = 0;
  for (const ChristmasTree& tree : structures) {
    for (const Valve& valve : tree.valves) {
      if (valve.name == valve_name) return index;
      ++index;
    }
  }
  return -1;
}

const RiskProfile* Scenario::FindProfile(const std::string& profile_name) const {
  for (const RiskProfile& profile : profiles) {
    if (profile.name == profile_name) return &profile;
  }
  return nullptr;
}

const char* ToString(MotionModel model) {
  switch (model) {
    case MotionModel::kSingleIntegrator: return "single_integrator";
    case MotionModel::kBlueRov2: return "bluerov2";
  }
  return "unknown";
}

MotionModel ParseMotionModel(const std::string& text, const std::string& where) {
  if (text == "single_integrator") return MotionModel::kSingleIntegrator;
  if (text == "bluerov2") return MotionModel::kBlueRov2;
  throw ScenarioError(OneLine((where.empty() ? "model" : where) + " = " + text +
                              ": must be single_integrator or bluerov2"));
}

const char* ToString(FleetAssignment assignment) {
  switch (assignment) {
    case FleetAssignment::kShared: return "shared";
    case FleetAssignment::kPartition: return "partition";
  }
  return "unknown";
}

FleetAssignment ParseFleetAssignment(const std::string& text, const std::string& where) {
  if (text == "shared") return FleetAssignment::kShared;
  if (text == "partition") return FleetAssignment::kPartition;
  throw ScenarioError(OneLine((where.empty() ? "assignment" : where) + " = " + (text.empty() ? "\"\"" : text) +
                              ": must be shared or partition"));
}

Scenario ParseScenario(const std::string& yaml_text, const std::string& source) {
  const Reader reader(source);
  Scenario scenario;
  try {
    scenario = ReadScenario(reader, YAML::Load(yaml_text), source);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(OneLine(source + ": " + Position(e.mark) + "YAML syntax error: " + e.msg));
  } catch (const YAML::Exception& e) {
    // Safety net: ReadScenario checks types itself, so yaml-cpp should not throw past it.
    throw ScenarioError(OneLine(source + ": " + Position(e.mark) + "cannot read: " + e.msg));
  }
  scenario.Validate();
  for (RiskProfile& profile : scenario.profiles) {
    std::stable_sort(profile.events.begin(), profile.events.end(),
                     [](const RiskEvent& a, const RiskEvent& b) { return a.time_s < b.time_s; });
  }
  std::stable_sort(scenario.fleet_events.begin(), scenario.fleet_events.end(),
                   [](const FleetEvent& a, const FleetEvent& b) { return a.time_s < b.time_s; });
  return scenario;
}

Scenario LoadScenario(const std::string& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ScenarioError(path + ": cannot open: " + std::strerror(errno));
  std::string text;
  char buffer[4096];
  std::size_t count = 0;
  while ((count = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) text.append(buffer, count);
  if (std::ferror(file.get())) throw ScenarioError(path + ": cannot read: " + std::strerror(errno));
  return ParseScenario(text, path);
}

std::string EmitScenario(const Scenario& s) {
  // Numbers go out as shortest round-trip text so ParseScenario(EmitScenario(s)) == s exactly;
  // the covariance is always written in full.
  YAML::Emitter out;
  const auto key = [&](const std::string& name) -> YAML::Emitter& { return out << YAML::Key << name << YAML::Value; };
  const auto number = [&](const std::string& name, double v) { key(name) << FormatNumber(v); };
  const auto vector = [&](const Eigen::Vector2d& v) {
    out << YAML::Flow << YAML::BeginSeq << FormatNumber(v.x()) << FormatNumber(v.y()) << YAML::EndSeq;
  };
  const auto vehicle_map = [&](const VehicleSpec& vehicle) {
    out << YAML::Flow << YAML::BeginMap;
    key("name") << vehicle.name;
    key("start_m"); vector(vehicle.start_m);
    number("start_heading_rad", vehicle.start_heading_rad);
    key("model") << ToString(vehicle.model);
    number("transit_speed_mps", vehicle.transit_speed_mps);
    out << YAML::EndMap;
  };
  out << YAML::Comment("SAGE Fleet scenario (written by EmitScenario); units are in the field names");
  out << YAML::BeginMap;
  key("name") << s.name;
  key("workspace") << YAML::Flow << YAML::BeginMap;
  number("width_m", s.workspace.width_m);
  number("height_m", s.workspace.height_m);
  out << YAML::EndMap;
  number("duration_s", s.duration_s);
  number("control_rate_hz", s.control_rate_hz);
  number("physics_rate_hz", s.physics_rate_hz);
  number("visit_radius_m", s.visit_radius_m);
  number("rearm_radius_m", s.rearm_radius_m);
  key("seed") << std::to_string(s.seed);
  key("ergodic") << YAML::Flow << YAML::BeginMap;
  key("basis_order") << std::to_string(s.ergodic.basis_order);
  number("forgetting_time_s", s.ergodic.forgetting_time_s);
  out << YAML::EndMap;
  key("guard") << YAML::Flow << YAML::BeginMap;
  key("enabled") << s.guard.enabled;
  number("weight_floor", s.guard.weight_floor);
  number("revisit_bound_s", s.guard.revisit_bound_s);
  out << YAML::EndMap;
  key("astar") << YAML::Flow << YAML::BeginMap;
  number("grid_resolution_m", s.astar.grid_resolution_m);
  number("clearance_m", s.astar.clearance_m);
  number("wait_per_lap_s", s.astar.wait_per_lap_s);
  out << YAML::EndMap;
  key("structures") << YAML::BeginSeq;
  for (const ChristmasTree& tree : s.structures) {
    out << YAML::BeginMap;
    key("name") << tree.name;
    key("center_m"); vector(tree.center_m);
    key("size_m"); vector(tree.size_m);
    number("height_m", tree.height_m);
    key("valves");
    if (tree.valves.empty()) out << YAML::Flow;  // "valves: []" on one line
    out << YAML::BeginSeq;
    for (const Valve& valve : tree.valves) {
      out << YAML::Flow << YAML::BeginMap;
      key("name") << valve.name;
      key("position_m"); vector(valve.position_m);
      key("covariance_m2") << YAML::BeginSeq;
      vector(valve.covariance_m2.row(0).transpose());
      vector(valve.covariance_m2.row(1).transpose());
      out << YAML::EndSeq << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
  key("vehicles") << YAML::BeginSeq;
  for (const VehicleSpec& vehicle : s.vehicles) vehicle_map(vehicle);
  out << YAML::EndSeq;
  key("fleet") << YAML::Flow << YAML::BeginMap;
  key("assignment") << ToString(s.fleet.assignment);
  number("coverage_period_s", s.fleet.coverage_period_s);
  number("liveliness_lease_s", s.fleet.liveliness_lease_s);
  out << YAML::EndMap;
  key("fleet_events");
  if (s.fleet_events.empty()) out << YAML::Flow;  // "fleet_events: []" on one line
  out << YAML::BeginSeq;
  for (const FleetEvent& event : s.fleet_events) {
    out << YAML::Flow << YAML::BeginMap;
    number("time_s", event.time_s);
    key(EventKey(event.kind));
    if (event.kind == FleetEvent::Kind::kJoin) vehicle_map(event.vehicle);
    else out << event.vehicle.name;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  key("default_profile") << s.default_profile;
  key("profiles") << YAML::BeginMap;
  for (const RiskProfile& profile : s.profiles) {
    key(profile.name) << YAML::BeginMap;
    key("weights") << YAML::Flow << YAML::BeginMap;
    for (const auto& [valve, weight] : profile.weights) number(valve, weight);
    out << YAML::EndMap;
    key("events") << YAML::Flow << YAML::BeginSeq;
    for (const RiskEvent& event : profile.events) {
      out << YAML::BeginMap;
      number("time_s", event.time_s);
      key("valve") << event.valve;
      number("weight", event.weight);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {

// Starts added by WithVehicleCount keep clear of footprints and of each other: a BlueROV2 hull is
// 0.46 x 0.58 m (0.74 m across), so 1 m between starts leaves two hulls apart whatever headings.
constexpr double kStartEdgeMargin_m = 0.5;       // from the workspace edges
constexpr double kStartFootprintMargin_m = 0.5;  // added to each side of every footprint
constexpr double kStartSeparation_m = 1.0;       // from every other start, joiners' included
constexpr double kDenseStartSeparation_m = 0.8;  // large fleets, when 1.0 m does not fit
constexpr std::size_t kLineStartsMax = 50;       // more added vehicles than this fill a lattice
constexpr double kStartSearchStep_m = 0.05;      // grid step of the search for a free start

bool IsFreeStart(const Scenario& s, const std::vector<Eigen::Vector2d>& taken, const Eigen::Vector2d& p) {
  for (const ChristmasTree& tree : s.structures) {
    const Eigen::Vector2d half = tree.size_m / 2 + Eigen::Vector2d::Constant(kStartFootprintMargin_m);
    if (((p - tree.center_m).array().abs() < half.array()).all()) return false;
  }
  for (const Eigen::Vector2d& other : taken) {
    if ((p - other).norm() < kStartSeparation_m) return false;
  }
  return true;
}

// Of the points wanted + kStartSearchStep_m * (i, j), to the mm, inside the workspace less its edge
// margin, the free one nearest to `wanted` (ties: the first found). Rings of growing Chebyshev
// radius are searched until no point of a further ring can be nearer than the best so far.
std::optional<Eigen::Vector2d> NearestFreeStart(const Scenario& s, const std::vector<Eigen::Vector2d>& taken,
                                                const Eigen::Vector2d& wanted) {
  const Eigen::Vector2d size(s.workspace.width_m, s.workspace.height_m);
  const Eigen::Vector2d margin = (size / 2).cwiseMin(Eigen::Vector2d::Constant(kStartEdgeMargin_m));
  // A hair of tolerance so that the wanted point on the margin line itself counts as inside.
  const Eigen::Vector2d low = margin.array() - 1e-9, high = (size - margin).array() + 1e-9;
  const int last_ring = static_cast<int>(std::ceil(size.maxCoeff() / kStartSearchStep_m)) + 1;
  std::optional<Eigen::Vector2d> best;
  double best_distance = std::numeric_limits<double>::infinity();
  const auto consider = [&](int i, int j) {
    // Whole millimetres, so a written scenario reads cleanly; the rules are checked on this value.
    const Eigen::Vector2d p =
        ((wanted + kStartSearchStep_m * Eigen::Vector2d(i, j)) * 1000.0).array().round().matrix() / 1000.0;
    const double distance = (p - wanted).norm();
    if (distance >= best_distance || !InsideBox(p, low, high)) return;
    if (!IsFreeStart(s, taken, p)) return;
    best = p;
    best_distance = distance;
  };
  for (int ring = 0; ring <= last_ring && ring * kStartSearchStep_m <= best_distance; ++ring) {
    if (ring == 0) {
      consider(0, 0);
      continue;
    }
    for (int i = -ring; i <= ring; ++i) {
      consider(i, -ring);
      consider(i, ring);
    }
    for (int j = -ring + 1; j < ring; ++j) {
      consider(-ring, j);
      consider(ring, j);
    }
  }
  return best;
}

}  // namespace

Scenario WithVehicleCount(const Scenario& scenario, int count) {
  const std::string option = "--vehicles = " + std::to_string(count);
  if (count < 1) throw ScenarioError(option + ": must be >= 1");
  Scenario s = scenario;
  const std::size_t wanted = static_cast<std::size_t>(count);
  if (wanted <= s.vehicles.size()) {
    std::set<std::string> dropped;
    for (std::size_t i = wanted; i < s.vehicles.size(); ++i) dropped.insert(s.vehicles[i].name);
    s.vehicles.resize(wanted);
    std::erase_if(s.fleet_events, [&](const FleetEvent& event) {
      return event.kind != FleetEvent::Kind::kJoin && dropped.count(event.vehicle.name) != 0;
    });
  } else {
    const VehicleSpec first = s.vehicles.empty() ? VehicleSpec() : s.vehicles.front();
    std::set<std::string> used;
    std::vector<Eigen::Vector2d> taken;
    for (const VehicleSpec& vehicle : s.vehicles) {
      used.insert(vehicle.name);
      taken.push_back(vehicle.start_m);
    }
    for (const FleetEvent& event : s.fleet_events) {
      if (event.kind != FleetEvent::Kind::kJoin) continue;
      used.insert(event.vehicle.name);
      taken.push_back(event.vehicle.start_m);
    }
    const std::size_t added = wanted - s.vehicles.size();
    const double width = s.workspace.width_m;
    const double y = std::min(kStartEdgeMargin_m, s.workspace.height_m / 2);
    std::size_t number = s.vehicles.size() + 1;
    auto make_vehicle = [&](const Eigen::Vector2d& start) {
      VehicleSpec vehicle;
      while (used.count("rov" + std::to_string(number)) != 0) ++number;
      vehicle.name = "rov" + std::to_string(number);
      used.insert(vehicle.name);
      vehicle.model = first.model;
      vehicle.transit_speed_mps = first.transit_speed_mps;
      vehicle.start_heading_rad = 0.0;
      vehicle.start_m = start;
      taken.push_back(start);
      s.vehicles.push_back(vehicle);
    };
    if (added > kLineStartsMax) {
      // A large fleet (scale runs): fill a lattice row by row from the bottom edge, 1.0 m apart,
      // or 0.8 m (still clear of a 0.73 m hull diagonal) if that is the only way to fit them.
      const std::size_t existing = taken.size();
      for (double spacing : {kStartSeparation_m, kDenseStartSeparation_m}) {
        std::vector<Eigen::Vector2d> lattice;
        for (double y = kStartEdgeMargin_m; y <= s.workspace.height_m - kStartEdgeMargin_m && lattice.size() < added;
             y += spacing) {
          for (double x = kStartEdgeMargin_m; x <= width - kStartEdgeMargin_m && lattice.size() < added; x += spacing) {
            const Eigen::Vector2d p(x, y);
            bool free = true;
            for (const ChristmasTree& tree : s.structures) {
              const Eigen::Vector2d half = tree.size_m / 2 + Eigen::Vector2d::Constant(kStartFootprintMargin_m);
              if (((p - tree.center_m).cwiseAbs() - half).maxCoeff() < 0.0) free = false;
            }
            for (std::size_t i = 0; i < existing && free; ++i) free = (p - taken[i]).norm() >= spacing;
            if (free) lattice.push_back(p);
          }
        }
        if (lattice.size() < added) continue;
        for (const Eigen::Vector2d& p : lattice) make_vehicle(p);
        break;
      }
      if (s.vehicles.size() < wanted) {
        throw ScenarioError(option + ": the workspace has room for fewer vehicles (" +
                            FormatNumber(kDenseStartSeparation_m) + " m apart, " +
                            FormatNumber(kStartFootprintMargin_m) + " m from structures)");
      }
    }
    for (std::size_t k = 0; s.vehicles.size() < wanted; ++k) {
      // Evenly from x = 0.5 to width - 0.5 along y = 0.5, each then moved to the nearest free point.
      const double x = (added == 1 || width <= 2 * kStartEdgeMargin_m)
                           ? width / 2
                           : kStartEdgeMargin_m + (width - 2 * kStartEdgeMargin_m) * static_cast<double>(k) /
                                                      static_cast<double>(added - 1);
      const std::optional<Eigen::Vector2d> start = NearestFreeStart(s, taken, Eigen::Vector2d(x, y));
      if (!start) {
        throw ScenarioError(option + ": no free start for rov" + std::to_string(number) + " in the workspace (" +
                            FormatNumber(kStartSeparation_m) + " m from other vehicles, " +
                            FormatNumber(kStartFootprintMargin_m) + " m from structures)");
      }
      make_vehicle(*start);
    }
  }
  // Dropping vehicles can make a kept vehicle's loss leave the fleet empty; say which option did it.
  try {
    s.Validate();
  } catch (const ScenarioError& e) {
    throw ScenarioError(std::string(e.what()) + " (with " + option + ")");
  }
  return s;
}

}  // namespace sage::maps
