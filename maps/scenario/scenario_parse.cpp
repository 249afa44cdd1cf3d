// Scenario YAML reading, with typo and type checks. Every user-facing problem becomes one
// ScenarioError line "FILE: FIELD = VALUE: RULE", so a bad file never shows a yaml-cpp message
// alone or a trace.
#include "maps/scenario/scenario.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_set>

#include <yaml-cpp/yaml.h>

#include "maps/scenario/printable_text.h"
#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::OneLine;

using Keys = std::initializer_list<std::string_view>;

// A node as the user wrote it, on one line and short enough to quote in a message.
constexpr std::size_t kShownChars = 60;
std::string Show(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar() && node.Scalar().empty()) return "\"\"";
  // A scalar is cut too: a data file given as the scenario had been quoted whole (2 kB of XYZ).
  if (node.IsScalar()) return PrintableUtf8(OneLine(node.Scalar()), kShownChars);
  YAML::Emitter out;
  out.SetSeqFormat(YAML::Flow);
  out.SetMapFormat(YAML::Flow);
  out << node;
  return PrintableUtf8(OneLine(out.c_str()), kShownChars);
}

// Turns YAML nodes into typed values; every failure names file, field path and value.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& path, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + (path.empty() ? "" : path + ": ") + rule));
  }
  [[noreturn]] void Fail(const std::string& path, const YAML::Node& node, const std::string& rule) const {
    throw ScenarioError(OneLine(file_ + ": " + path + " = " + Show(node) + ": " + rule));
  }

  // A map with unique plain keys, each in `allowed` (any key if `allowed` is empty).
  void ExpectMap(const YAML::Node& node, const std::string& path, Keys allowed) const {
    if (!node.IsMap()) Fail(path, node, "must be a map");
    // A hash set: a field's profile names every valve (35,000 on the largest generated field), and
    // a scan of the keys seen so far for each made loading it quadratic (5 % of a 10,000-vehicle bench).
    std::unordered_set<std::string> seen;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) {
        // Where, when the parser knows: a stray comma or colon in a flow map makes a null key
        // ("{width_m: 5.6,, height_m: 4.3}"), and the map's path alone did not find it.
        const YAML::Mark at = entry.first.Mark().is_null() ? node.Mark() : entry.first.Mark();
        Fail(path, entry.first,
             at.is_null() ? std::string("keys must be plain names")
                          : "keys must be plain names (line " + std::to_string(at.line + 1) + ", column " +
                                std::to_string(at.column + 1) + ": a stray comma or colon?)");
      }
      const std::string& key = entry.first.Scalar();
      if (!seen.insert(key).second) {
        // Which of the two: the second's line (a long profile's repeated valve had been hard to find).
        const YAML::Mark at = entry.first.Mark();
        Fail(Join(path, key), at.is_null() ? std::string("duplicate key")
                                           : "duplicate key (again on line " + std::to_string(at.line + 1) + ")");
      }
      if (allowed.size() != 0 && std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        std::string list;
        for (std::string_view name : allowed) list += (list.empty() ? "" : ", ") + std::string(name);
        Fail(Join(path, key), "unknown key (allowed: " + list + ")");
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

// The seabed: {map: FILE, origin_m: [x, y], values: elevation|depth, altitude_band_m: [floor,
// ceiling], trend_radius_m: R}, every key optional. The map's path is resolved and its file
// checked by ParseScenario (ResolveSeabedMap), once the whole file has been read.
SeabedSettings ReadSeabed(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"map", "origin_m", "values", "altitude_band_m", "trend_radius_m"});
  SeabedSettings seabed;
  r.Optional(node, "map", path, [&](const YAML::Node& n, const std::string& p) { seabed.map = r.Text(n, p); });
  r.Optional(node, "origin_m", path,
             [&](const YAML::Node& n, const std::string& p) { seabed.origin_m = r.Vector(n, p); });
  r.Optional(node, "values", path, [&](const YAML::Node& n, const std::string& p) {
    const std::string text = r.Text(n, p);
    if (text == "elevation") seabed.values = SeabedValues::kElevation;
    else if (text == "depth") seabed.values = SeabedValues::kDepth;
    else r.Fail(p, n, "must be elevation (heights, up) or depth (depths, down)");
  });
  r.Optional(node, "altitude_band_m", path, [&](const YAML::Node& n, const std::string& p) {
    if (!n.IsSequence() || n.size() != 2) r.Fail(p, n, "must be [floor, ceiling] in m above the local seabed");
    seabed.altitude_min_m = r.Number(n[0], p + "[0]");
    seabed.altitude_max_m = r.Number(n[1], p + "[1]");
  });
  r.OptionalNumber(node, "trend_radius_m", path, seabed.trend_radius_m);
  return seabed;
}

Flowline ReadFlowline(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"name", "diameter_m", "points_m"});
  Flowline flowline;
  flowline.name = r.Text(r.Require(node, "name", path), path + ".name");
  r.OptionalNumber(node, "diameter_m", path, flowline.diameter_m);
  const YAML::Node points = r.Require(node, "points_m", path);
  r.ExpectList(points, path + ".points_m");
  for (std::size_t i = 0; i < points.size(); ++i) {
    flowline.points_m.push_back(r.Vector(points[i], path + ".points_m[" + std::to_string(i) + "]"));
  }
  return flowline;
}

Boulder ReadBoulder(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"center_m", "diameter_m", "height_m"});
  Boulder boulder;
  boulder.center_m = r.Vector(r.Require(node, "center_m", path), path + ".center_m");
  r.OptionalNumber(node, "diameter_m", path, boulder.diameter_m);
  r.OptionalNumber(node, "height_m", path, boulder.height_m);
  return boulder;
}

// The seabed's three sections, each optional: the seabed itself, and what lies on it.
void ReadSeabedSections(const Reader& r, const YAML::Node& root, Scenario& s) {
  r.Optional(root, "seabed", "", [&](const YAML::Node& n, const std::string& p) { s.seabed = ReadSeabed(r, n, p); });
  r.Optional(root, "flowlines", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      s.flowlines.push_back(ReadFlowline(r, list[i], p + "[" + std::to_string(i) + "]"));
    }
  });
  r.Optional(root, "boulders", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      s.boulders.push_back(ReadBoulder(r, list[i], p + "[" + std::to_string(i) + "]"));
    }
  });
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

// ---- Leak sensing: sensors, leaks, fusion (maps/scenario/perception.h) ----

SensorSpec ReadSensor(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"name", "kind", "range_m", "fov_deg", "p_detect", "half_range_m", "false_alarms_per_s",
                           "position_sigma_m", "rate_hz"});
  SensorSpec sensor;
  sensor.name = r.Text(r.Require(node, "name", path), path + ".name");
  r.Optional(node, "kind", path, [&](const YAML::Node& n, const std::string& p) {
    const std::string kind = r.Text(n, p);
    if (kind == "camera") sensor.kind = SensorKind::kCamera;
    else if (kind == "sonar") sensor.kind = SensorKind::kSonar;
    else r.Fail(p, n, "must be camera or sonar");
  });
  r.OptionalNumber(node, "range_m", path, sensor.range_m);
  r.OptionalNumber(node, "fov_deg", path, sensor.fov_deg);
  r.OptionalNumber(node, "p_detect", path, sensor.p_detect);
  r.OptionalNumber(node, "half_range_m", path, sensor.half_range_m);
  r.OptionalNumber(node, "false_alarms_per_s", path, sensor.false_alarms_per_s);
  r.OptionalNumber(node, "position_sigma_m", path, sensor.position_sigma_m);
  r.OptionalNumber(node, "rate_hz", path, sensor.rate_hz);
  return sensor;
}

// {at: {valve: P1} | {flowline: FL-A, s_m: X} | {point_m: [x, y]}, start_s: T, strength: S}
LeakSpec ReadLeak(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path, {"at", "start_s", "strength"});
  LeakSpec leak;
  const YAML::Node at = r.Require(node, "at", path);
  const std::string at_path = path + ".at";
  r.ExpectMap(at, at_path, {"valve", "point_m", "flowline", "s_m"});
  const int given = (at["valve"].IsDefined() ? 1 : 0) + (at["point_m"].IsDefined() ? 1 : 0) + (at["flowline"].IsDefined() ? 1 : 0);
  if (given != 1) r.Fail(at_path, at, "must give exactly one of valve, point_m, flowline (with s_m)");
  if (at["flowline"].IsDefined() != at["s_m"].IsDefined()) {
    r.Fail(at_path, at, "a flowline leak gives both flowline (its name) and s_m (metres along it), and nothing else does");
  }
  r.Optional(at, "valve", at_path, [&](const YAML::Node& n, const std::string& p) { leak.valve = r.Text(n, p); });
  r.Optional(at, "flowline", at_path, [&](const YAML::Node& n, const std::string& p) { leak.flowline = r.Text(n, p); });
  r.OptionalNumber(at, "s_m", at_path, leak.s_m);
  r.Optional(at, "point_m", at_path, [&](const YAML::Node& n, const std::string& p) { leak.point_m = r.Vector(n, p); });
  leak.start_s = r.Number(r.Require(node, "start_s", path), path + ".start_s");
  r.OptionalNumber(node, "strength", path, leak.strength);
  return leak;
}

void ReadFusion(const Reader& r, const YAML::Node& node, const std::string& path, FusionSettings& f) {
  r.ExpectMap(node, path, {"steer", "prior_probability", "relax_time_s", "confirm_probability", "alarm_probability",
                           "leak_mass", "spread_m", "max_log_odds", "min_evidence", "regrowth",
                           "joint_prior_probability"});
  r.Optional(node, "steer", path, [&](const YAML::Node& n, const std::string& p) {
    const std::string text = r.Text(n, p);
    if (text == "posterior") f.steer = true;
    else if (text == "prior") f.steer = false;
    else r.Fail(p, n, "must be posterior (the Bayesian loop) or prior (the profile's weights alone)");
  });
  r.OptionalNumber(node, "prior_probability", path, f.prior_probability);
  r.OptionalNumber(node, "relax_time_s", path, f.relax_time_s);
  r.OptionalNumber(node, "confirm_probability", path, f.confirm_probability);
  r.OptionalNumber(node, "alarm_probability", path, f.alarm_probability);
  r.OptionalNumber(node, "leak_mass", path, f.leak_mass);
  r.OptionalNumber(node, "spread_m", path, f.spread_m);
  r.OptionalNumber(node, "max_log_odds", path, f.max_log_odds);
  r.OptionalNumber(node, "min_evidence", path, f.min_evidence);
  r.OptionalNumber(node, "joint_prior_probability", path, f.joint_prior_probability);
  r.Optional(node, "regrowth", path, [&](const YAML::Node& n, const std::string& p) {
    const std::string text = r.Text(n, p);
    if (text == "relax") f.onset_regrowth = false;
    else if (text == "onset") f.onset_regrowth = true;
    else r.Fail(p, n, "must be relax (back to the prior exponentially) or onset (linearly, at the leak onset hazard)");
  });
}

void ReadPerception(const Reader& r, const YAML::Node& root, Scenario& s) {
  r.Optional(root, "sensors", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) s.sensors.push_back(ReadSensor(r, list[i], p + "[" + std::to_string(i) + "]"));
  });
  r.Optional(root, "leaks", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) s.leaks.push_back(ReadLeak(r, list[i], p + "[" + std::to_string(i) + "]"));
  });
  r.Optional(root, "gaze", "", [&](const YAML::Node& n, const std::string& p) {
    const std::string text = r.Text(n, p);
    if (text == "travel") s.gaze = Gaze::kTravel;
    else if (text == "valves") s.gaze = Gaze::kValves;
    else r.Fail(p, n, "must be travel (look ahead) or valves (turn to the valve in reach where a look is worth most)");
  });
  r.Optional(root, "fusion", "", [&](const YAML::Node& n, const std::string& p) { ReadFusion(r, n, p, s.fusion); });
}

Scenario ReadScenario(const Reader& r, const YAML::Node& root, const std::string& source) {
  if (root.IsNull()) r.Fail("", "holds no scenario (empty, or comments only; a scenario is a YAML map of sections: workspace, structures, ...)");
  if (!root.IsMap()) r.Fail("scenario", root, "must be a YAML map of sections (workspace, structures, ...)");
  r.ExpectMap(root, "", {"name", "workspace", "duration_s", "control_rate_hz", "physics_rate_hz", "trajectory_rate_hz",
                         "visit_radius_m", "rearm_radius_m", "seed", "start_jitter_m", "ergodic", "guard", "astar",
                         "structures", "vehicles", "default_profile", "profiles", "fleet", "fleet_events",
                         "seabed", "flowlines", "boulders", "network", "sensors", "gaze", "leaks", "fusion"});
  Scenario s;
  s.source_path = source;
  s.name = source.empty() ? "scenario" : std::filesystem::path(source).stem().string();
  r.Optional(root, "name", "", [&](const YAML::Node& n, const std::string& p) { s.name = r.Text(n, p); });
  {
    // Required: a mission silently flown in a default box would cover the wrong water.
    const YAML::Node workspace = r.Require(root, "workspace", "");
    r.ExpectMap(workspace, "workspace", {"width_m", "height_m"});
    s.workspace.width_m = r.Number(r.Require(workspace, "width_m", "workspace"), "workspace.width_m");
    s.workspace.height_m = r.Number(r.Require(workspace, "height_m", "workspace"), "workspace.height_m");
  }
  r.OptionalNumber(root, "duration_s", "", s.duration_s);
  r.OptionalNumber(root, "control_rate_hz", "", s.control_rate_hz);
  r.OptionalNumber(root, "physics_rate_hz", "", s.physics_rate_hz);
  r.OptionalNumber(root, "trajectory_rate_hz", "", s.trajectory_rate_hz);
  r.OptionalNumber(root, "visit_radius_m", "", s.visit_radius_m);
  r.OptionalNumber(root, "rearm_radius_m", "", s.rearm_radius_m);
  r.Optional(root, "seed", "", [&](const YAML::Node& n, const std::string& p) {
    s.seed = r.WholeNumber<std::uint64_t>(n, p, "must be a whole number >= 0");
  });
  r.OptionalNumber(root, "start_jitter_m", "", s.start_jitter_m);
  r.Optional(root, "ergodic", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"basis_order", "forgetting_time_s", "min_turn_radius_m", "weight_exponent", "final_approach_m"});
    r.Optional(n, "basis_order", p, [&](const YAML::Node& v, const std::string& q) {
      s.ergodic.basis_order = r.WholeNumber<int>(v, q, "must be a whole number");
    });
    r.OptionalNumber(n, "forgetting_time_s", p, s.ergodic.forgetting_time_s);
    r.OptionalNumber(n, "min_turn_radius_m", p, s.ergodic.min_turn_radius_m);
    r.OptionalNumber(n, "weight_exponent", p, s.ergodic.weight_exponent);
    r.OptionalNumber(n, "final_approach_m", p, s.ergodic.final_approach_m);
  });
  r.Optional(root, "guard", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"enabled", "weight_floor", "revisit_bound_s"});
    r.Optional(n, "enabled", p, [&](const YAML::Node& v, const std::string& q) { s.guard.enabled = r.Bool(v, q); });
    r.OptionalNumber(n, "weight_floor", p, s.guard.weight_floor);
    r.OptionalNumber(n, "revisit_bound_s", p, s.guard.revisit_bound_s);
  });
  r.Optional(root, "astar", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"grid_resolution_m", "clearance_m", "wait_per_lap_s", "weight_exponent", "replan_delay_s", "order", "look_exponent", "look_leak_weight"});
    r.OptionalNumber(n, "grid_resolution_m", p, s.astar.grid_resolution_m);
    r.OptionalNumber(n, "clearance_m", p, s.astar.clearance_m);
    r.OptionalNumber(n, "wait_per_lap_s", p, s.astar.wait_per_lap_s);
    r.OptionalNumber(n, "weight_exponent", p, s.astar.weight_exponent);
    r.OptionalNumber(n, "replan_delay_s", p, s.astar.replan_delay_s);
    r.Optional(n, "order", p, [&](const YAML::Node& v, const std::string& q) {
      const std::string text = r.Text(v, q);
      if (text == "shortest") s.astar.order = AstarSettings::Order::kShortest;
      else if (text == "looks") s.astar.order = AstarSettings::Order::kLooks;
      else r.Fail(q, v, "must be shortest (the closed tour, lap after lap) or looks (the next valves chosen on the scans: needs sensors)");
    });
    r.OptionalNumber(n, "look_exponent", p, s.astar.look_exponent);
    r.OptionalNumber(n, "look_leak_weight", p, s.astar.look_leak_weight);
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
    r.ExpectMap(n, p, {"assignment", "coverage_period_s", "liveliness_lease_s", "age_weighting_laps", "risk_share"});
    r.Optional(n, "assignment", p, [&](const YAML::Node& v, const std::string& q) {
      s.fleet.assignment = ParseFleetAssignment(r.Text(v, q), r.file() + ": " + q);
    });
    r.OptionalNumber(n, "coverage_period_s", p, s.fleet.coverage_period_s);
    r.OptionalNumber(n, "liveliness_lease_s", p, s.fleet.liveliness_lease_s);
    r.OptionalNumber(n, "age_weighting_laps", p, s.fleet.age_weighting_laps);
    r.OptionalNumber(n, "risk_share", p, s.fleet.risk_share);
  });
  r.Optional(root, "fleet_events", "", [&](const YAML::Node& list, const std::string& p) {
    r.ExpectList(list, p);
    for (std::size_t i = 0; i < list.size(); ++i) {
      s.fleet_events.push_back(ReadFleetEvent(r, list[i], p + "[" + std::to_string(i) + "]"));
    }
  });
  ReadSeabedSections(r, root, s);
  r.Optional(root, "network", "", [&](const YAML::Node& n, const std::string& p) {
    r.ExpectMap(n, p, {"interface", "peers", "multicast"});
    r.Optional(n, "interface", p, [&](const YAML::Node& v, const std::string& q) { s.network.interface_name = r.Text(v, q); });
    r.Optional(n, "peers", p, [&](const YAML::Node& list, const std::string& q) {
      r.ExpectList(list, q);
      for (std::size_t i = 0; i < list.size(); ++i) s.network.peers.push_back(r.Text(list[i], q + "[" + std::to_string(i) + "]"));
    });
    r.Optional(n, "multicast", p, [&](const YAML::Node& v, const std::string& q) { s.network.multicast = r.Bool(v, q); });
  });
  ReadPerception(r, root, s);
  return s;
}

std::string Position(const YAML::Mark& mark) {
  if (mark.is_null()) return "";
  return "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) + ": ";
}

}  // namespace

Scenario ParseScenario(const std::string& yaml_text, const std::string& source) {
  // YAML is UTF-8 text; a stray byte would reach the names in logs, CSV and JSON (which refuses it).
  if (const std::size_t bad = FirstNonUtf8(yaml_text); bad != std::string::npos) {
    const std::size_t line_start = yaml_text.rfind('\n', bad == 0 ? 0 : bad - 1);
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(yaml_text.begin(), yaml_text.begin() + static_cast<std::ptrdiff_t>(bad), '\n'));
    const std::size_t column = line_start == std::string::npos || bad == 0 ? bad + 1 : bad - line_start;
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(yaml_text[bad])));
    throw ScenarioError(OneLine(source) + ": line " + std::to_string(line) + ", column " + std::to_string(column) +
                        ": byte " + hex + " is not UTF-8 text (a scenario is UTF-8)");
  }
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
  if (scenario.seabed && !scenario.seabed->map.empty()) detail::ResolveSeabedMap(*scenario.seabed, source);
  scenario.Validate();
  for (RiskProfile& profile : scenario.profiles) {
    std::stable_sort(profile.events.begin(), profile.events.end(),
                     [](const RiskEvent& a, const RiskEvent& b) { return a.time_s < b.time_s; });
  }
  std::stable_sort(scenario.fleet_events.begin(), scenario.fleet_events.end(),
                   [](const FleetEvent& a, const FleetEvent& b) { return a.time_s < b.time_s; });
  std::stable_sort(scenario.leaks.begin(), scenario.leaks.end(),
                   [](const LeakSpec& a, const LeakSpec& b) { return a.start_s < b.start_s; });
  return scenario;
}

Scenario LoadScenario(const std::string& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ScenarioError(path + ": cannot open: " + std::strerror(errno));
  std::string text;
  char buffer[4096];
  std::size_t count = 0;
  // Read no further than a scenario may be: a 100 MB file had taken 104 s and 6.8 GB to refuse.
  while ((count = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) {
    text.append(buffer, count);
    if (text.size() > kMaxScenarioBytes) {
      throw ScenarioError(path + ": over " + std::to_string(kMaxScenarioBytes >> 20) +
                          " MB: too large for a scenario (a 10,000-XT field is 6.3 MB)");
    }
  }
  if (std::ferror(file.get())) throw ScenarioError(path + ": cannot read: " + std::strerror(errno));
  return ParseScenario(text, path);
}

}  // namespace sage::maps
