#include "server/live/foxglove_bridge.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>

#include "maps/scenario/scenario.h"
#include "server/live/foxglove_socket.h"
#include "server/live/frame_json.h"

namespace sage::live {
namespace {

enum Channel : std::uint32_t { kVehicles = 1, kScene = 2, kGrid = 3, kMission = 4 };
constexpr const char* kFrame = "seabed";
// The scene (every valve, every vehicle) is a large message: at most every half wall second.
constexpr auto kScenePeriod = std::chrono::milliseconds(500);

// JSON Schemas of the messages as this server writes them (Foxglove reads the schema name; the
// schema tells it which strings are base64 bytes).
constexpr const char* kTimeSchema =
    R"({"type":"object","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0}}})";
std::string PoseSchema() {
  return R"({"type":"object","properties":{"position":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}},"orientation":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}}})";
}
constexpr const char* kColorSchema =
    R"({"type":"object","properties":{"r":{"type":"number"},"g":{"type":"number"},"b":{"type":"number"},"a":{"type":"number"}}})";
constexpr const char* kVector3Schema =
    R"({"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}})";

std::string PosesSchema() {
  return fmt::format(R"({{"title":"foxglove.PosesInFrame","type":"object","properties":{{"timestamp":{},"frame_id":{{"type":"string"}},"poses":{{"type":"array","items":{}}}}}}})",
                     kTimeSchema, PoseSchema());
}

std::string SceneSchema() {
  const std::string pose = PoseSchema();
  const std::string sized = fmt::format(R"({{"type":"object","properties":{{"pose":{},"size":{},"color":{}}}}})", pose,
                                        kVector3Schema, kColorSchema);
  const std::string arrow = fmt::format(
      R"({{"type":"object","properties":{{"pose":{},"shaft_length":{{"type":"number"}},"shaft_diameter":{{"type":"number"}},"head_length":{{"type":"number"}},"head_diameter":{{"type":"number"}},"color":{}}}}})",
      pose, kColorSchema);
  const std::string text = fmt::format(
      R"({{"type":"object","properties":{{"pose":{},"billboard":{{"type":"boolean"}},"font_size":{{"type":"number"}},"scale_invariant":{{"type":"boolean"}},"color":{},"text":{{"type":"string"}}}}}})",
      pose, kColorSchema);
  const std::string line = fmt::format(
      R"({{"type":"object","properties":{{"type":{{"type":"integer"}},"pose":{},"thickness":{{"type":"number"}},"scale_invariant":{{"type":"boolean"}},"points":{{"type":"array","items":{}}},"color":{},"colors":{{"type":"array","items":{}}},"indices":{{"type":"array","items":{{"type":"integer","minimum":0}}}}}}}})",
      pose, kVector3Schema, kColorSchema, kColorSchema);
  const std::string entity = fmt::format(
      R"({{"type":"object","properties":{{"timestamp":{},"frame_id":{{"type":"string"}},"id":{{"type":"string"}},"lifetime":{},"frame_locked":{{"type":"boolean"}},"metadata":{{"type":"array","items":{{"type":"object","properties":{{"key":{{"type":"string"}},"value":{{"type":"string"}}}}}}}},"arrows":{{"type":"array","items":{}}},"cubes":{{"type":"array","items":{}}},"spheres":{{"type":"array","items":{}}},"texts":{{"type":"array","items":{}}},"lines":{{"type":"array","items":{}}}}}}})",
      kTimeSchema, kTimeSchema, arrow, sized, sized, text, line);
  return fmt::format(
      R"({{"title":"foxglove.SceneUpdate","type":"object","properties":{{"deletions":{{"type":"array","items":{{"type":"object","properties":{{"timestamp":{},"type":{{"type":"integer"}},"id":{{"type":"string"}}}}}}}},"entities":{{"type":"array","items":{}}}}}}})",
      kTimeSchema, entity);
}

std::string GridSchema() {
  return fmt::format(
      R"({{"title":"foxglove.Grid","type":"object","properties":{{"timestamp":{},"frame_id":{{"type":"string"}},"pose":{},"column_count":{{"type":"integer","minimum":0}},"cell_size":{{"type":"object","properties":{{"x":{{"type":"number"}},"y":{{"type":"number"}}}}}},"row_stride":{{"type":"integer","minimum":0}},"cell_stride":{{"type":"integer","minimum":0}},"fields":{{"type":"array","items":{{"type":"object","properties":{{"name":{{"type":"string"}},"offset":{{"type":"integer","minimum":0}},"type":{{"type":"integer"}}}}}}}},"data":{{"type":"string","contentEncoding":"base64"}}}}}})",
      kTimeSchema, PoseSchema());
}

std::string MissionSchema() {
  return R"({"title":"sage.MissionStatus","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"time_s":{"type":"number"},"duration_s":{"type":"number"},"alive":{"type":"integer"},"stale":{"type":"integer"},"lost":{"type":"integer"},"left":{"type":"integer"},"ergodic_metric":{"type":["number","null"]},"cycle_ms":{"type":"number"},"finished":{"type":"boolean"}}})";
}

std::uint64_t Nanoseconds(double time_s) { return static_cast<std::uint64_t>(std::llround(std::max(0.0, time_s) * 1e9)); }

void Time(std::string& out, double time_s) {
  const std::uint64_t ns = Nanoseconds(time_s);
  fmt::format_to(std::back_inserter(out), R"({{"sec":{},"nsec":{}}})", ns / 1000000000ull, ns % 1000000000ull);
}

// A pose on the seabed plane: at (x, y, z), turned by yaw about +z.
void Pose(std::string& out, double x, double y, double z, double yaw) {
  fmt::format_to(std::back_inserter(out),
                 R"({{"position":{{"x":{:.3f},"y":{:.3f},"z":{:.3f}}},"orientation":{{"x":0,"y":0,"z":{:.6f},"w":{:.6f}}}}})",
                 x, y, z, std::sin(0.5 * yaw), std::cos(0.5 * yaw));
}

void Color(std::string& out, double r, double g, double b, double a) {
  fmt::format_to(std::back_inserter(out), R"({{"r":{:.3f},"g":{:.3f},"b":{:.3f},"a":{:.3f}}})", r, g, b, a);
}

// The page's risk colours: blue (least) through yellow to red (most) of the field's largest share.
void RiskColor(std::string& out, double u) {
  u = std::clamp(u, 0.0, 1.0);
  const double r = u < 0.5 ? 0.2 + 1.6 * u : 1.0;
  const double g = u < 0.5 ? 0.4 + 1.0 * u : 0.9 - 1.4 * (u - 0.5);
  const double b = u < 0.5 ? 0.9 - 1.6 * u : 0.1;
  Color(out, r, g, b, 0.9);
}

// A cube or a sphere: its centre at (x, y, z), unturned, of size (sx, sy, sz), in one colour.
void SizedPrimitive(std::string& out, double x, double y, double z, const Eigen::Vector3d& size) {
  out += R"({"pose":)";
  Pose(out, x, y, z, 0.0);
  fmt::format_to(std::back_inserter(out), R"(,"size":{{"x":{:.3f},"y":{:.3f},"z":{:.3f}}},"color":)", size.x(), size.y(),
                 size.z());
}

void EntityStart(std::string& out, const std::string& id, double time_s) {
  out += R"({"timestamp":)";
  Time(out, time_s);
  fmt::format_to(std::back_inserter(out), R"(,"frame_id":"{}","id":"{}","lifetime":{{"sec":0,"nsec":0}},"frame_locked":false,"metadata":[])",
                 kFrame, id);
}

}  // namespace

std::string PosesInFrameJson(const LiveFrame& frame) {
  std::string out = R"({"timestamp":)";
  Time(out, frame.time_s);
  fmt::format_to(std::back_inserter(out), R"(,"frame_id":"{}","poses":[)", kFrame);
  bool first = true;
  for (const VehicleView& v : frame.vehicles) {
    if (v.status == VehicleStatus::kLost || v.status == VehicleStatus::kLeft) continue;
    if (!first) out += ',';
    first = false;
    Pose(out, v.x_m, v.y_m, 0.0, v.heading_rad);
  }
  out += "]}";
  return out;
}

std::string SceneUpdateJson(const LiveScene& scene, const LiveFrame& frame) {
  std::string out = R"({"deletions":[],"entities":[)";
  // The XTs.
  EntityStart(out, "structures", frame.time_s);
  out += R"(,"arrows":[],"cubes":[)";
  for (std::size_t i = 0; i < scene.structures.size(); ++i) {
    const StructureView& s = scene.structures[i];
    if (i > 0) out += ',';
    SizedPrimitive(out, s.center_m.x(), s.center_m.y(), 0.5, Eigen::Vector3d(s.size_m.x(), s.size_m.y(), 1.0));
    Color(out, 0.45, 0.45, 0.5, 1.0);
    out += '}';
  }
  out += R"(],"spheres":[],"texts":[)";
  for (std::size_t i = 0; i < scene.structures.size(); ++i) {
    const StructureView& s = scene.structures[i];
    if (i > 0) out += ',';
    out += R"({"pose":)";
    Pose(out, s.center_m.x(), s.center_m.y(), 1.3, 0.0);
    out += R"(,"billboard":true,"font_size":12,"scale_invariant":true,"color":)";
    Color(out, 0.9, 0.9, 0.9, 1.0);
    out += R"(,"text":)";
    out += JsonString(s.name);
    out += '}';
  }
  out += "]},";
  // The valves, coloured by their share of the risk (against the largest), with the time since
  // their last visit.
  double largest = 0.0;
  for (const ValveView& v : frame.valves) largest = std::max(largest, v.share);
  EntityStart(out, "valves", frame.time_s);
  out += R"(,"arrows":[],"cubes":[],"spheres":[)";
  const std::size_t valves = std::min(scene.valves.size(), frame.valves.size());
  const double diameter = std::max(0.1, 2.0 * scene.visit_radius_m);
  for (std::size_t i = 0; i < valves; ++i) {
    if (i > 0) out += ',';
    SizedPrimitive(out, scene.valves[i].position_m.x(), scene.valves[i].position_m.y(), 0.2,
                   Eigen::Vector3d::Constant(diameter));
    RiskColor(out, largest > 0.0 ? frame.valves[i].share / largest : 0.0);
    out += '}';
  }
  out += R"(],"texts":[)";
  for (std::size_t i = 0; i < valves; ++i) {
    if (i > 0) out += ',';
    const ValveView& v = frame.valves[i];
    out += R"({"pose":)";
    Pose(out, scene.valves[i].position_m.x(), scene.valves[i].position_m.y(), 0.6, 0.0);
    out += R"(,"billboard":true,"font_size":11,"scale_invariant":true,"color":)";
    Color(out, 1.0, 1.0, 1.0, 0.9);
    out += R"(,"text":)";
    out += JsonString(std::isfinite(v.last_visit_s)
                          ? fmt::format("{} {:.1f}% {:.0f}s", scene.valves[i].name, 100.0 * v.share, frame.time_s - v.last_visit_s)
                          : fmt::format("{} {:.1f}% never", scene.valves[i].name, 100.0 * v.share));
    out += '}';
  }
  out += "]},";
  // The vehicles: an arrow along each heading, grey when not heard lately, lost or gone.
  EntityStart(out, "vehicles", frame.time_s);
  out += R"(,"arrows":[)";
  for (std::size_t i = 0; i < frame.vehicles.size(); ++i) {
    const VehicleView& v = frame.vehicles[i];
    if (i > 0) out += ',';
    out += R"({"pose":)";
    Pose(out, v.x_m, v.y_m, 0.3, v.heading_rad);
    out += R"(,"shaft_length":0.35,"shaft_diameter":0.12,"head_length":0.25,"head_diameter":0.3,"color":)";
    if (v.status == VehicleStatus::kAlive) Color(out, 1.0, 0.55, 0.0, 1.0);
    else Color(out, 0.55, 0.55, 0.55, v.status == VehicleStatus::kStale ? 0.9 : 0.5);
    out += '}';
  }
  out += R"(],"cubes":[],"spheres":[],"texts":[)";
  for (std::size_t i = 0; i < frame.vehicles.size(); ++i) {
    const VehicleView& v = frame.vehicles[i];
    if (i > 0) out += ',';
    out += R"({"pose":)";
    Pose(out, v.x_m, v.y_m, 0.8, 0.0);
    out += R"(,"billboard":true,"font_size":11,"scale_invariant":true,"color":)";
    Color(out, 1.0, 0.85, 0.6, 1.0);
    out += R"(,"text":)";
    out += JsonString(v.status == VehicleStatus::kAlive ? v.name : v.name + " (" + ToString(v.status) + ")");
    out += '}';
  }
  out += "]},";
  // The seabed's pipes (a line strip each, at its diameter, on the seabed) and its boulders
  // (half-buried spheres of their diameter), in the page's ochre.
  EntityStart(out, "seabed", frame.time_s);
  out += R"(,"arrows":[],"cubes":[],"spheres":[)";
  for (std::size_t i = 0; i < scene.boulders.size(); ++i) {
    const BoulderView& b = scene.boulders[i];
    if (i > 0) out += ',';
    SizedPrimitive(out, b.center_m.x(), b.center_m.y(), 0.0, Eigen::Vector3d::Constant(b.diameter_m));
    Color(out, 0.42, 0.35, 0.23, 1.0);
    out += '}';
  }
  out += R"(],"texts":[],"lines":[)";
  for (std::size_t i = 0; i < scene.flowlines.size(); ++i) {
    const FlowlineView& f = scene.flowlines[i];
    if (i > 0) out += ',';
    out += R"({"type":0,"pose":)";  // LINE_STRIP
    Pose(out, 0.0, 0.0, 0.0, 0.0);
    fmt::format_to(std::back_inserter(out), R"(,"thickness":{:.3f},"scale_invariant":false,"points":[)", f.diameter_m);
    for (std::size_t k = 0; k < f.points_m.size(); ++k) {
      fmt::format_to(std::back_inserter(out), R"({}{{"x":{:.3f},"y":{:.3f},"z":{:.3f}}})", k > 0 ? "," : "",
                     f.points_m[k].x(), f.points_m[k].y(), 0.5 * f.diameter_m);
    }
    out += R"(],"color":)";
    Color(out, 0.61, 0.48, 0.2, 1.0);
    out += R"(,"colors":[],"indices":[]})";
  }
  out += "]}]}";
  return out;
}

std::string GridJson(const HeatGrid& grid, double time_s) {
  std::string bytes(grid.values.size() * 4, '\0');
  for (std::size_t i = 0; i < grid.values.size(); ++i) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &grid.values[i], 4);
    for (int k = 0; k < 4; ++k) bytes[4 * i + k] = static_cast<char>((bits >> (8 * k)) & 0xff);  // little-endian
  }
  std::string out = R"({"timestamp":)";
  Time(out, time_s);
  fmt::format_to(std::back_inserter(out), R"(,"frame_id":"{}","pose":)", kFrame);
  Pose(out, 0.0, 0.0, 0.0, 0.0);
  fmt::format_to(std::back_inserter(out),
                 R"(,"column_count":{},"cell_size":{{"x":{:.6f},"y":{:.6f}}},"row_stride":{},"cell_stride":4,"fields":[{{"name":"risk","offset":0,"type":7}}],"data":")",
                 grid.nx, grid.cell_m, grid.cell_m, grid.nx * 4);
  out += Base64(bytes);
  out += "\"}";
  return out;
}

std::string MissionStatusJson(const LiveFrame& frame) {
  std::size_t counts[4] = {0, 0, 0, 0};
  for (const VehicleView& v : frame.vehicles) ++counts[static_cast<int>(v.status)];
  std::string out = R"({"timestamp":)";
  Time(out, frame.time_s);
  fmt::format_to(std::back_inserter(out),
                 R"(,"time_s":{:.3f},"duration_s":{},"alive":{},"stale":{},"lost":{},"left":{},"ergodic_metric":{},"cycle_ms":{:.3f},"finished":{}}})",
                 frame.time_s, frame.duration_s, counts[0], counts[1], counts[2], counts[3],
                 std::isfinite(frame.ergodic_metric) ? fmt::format("{:.6g}", frame.ergodic_metric) : "null", frame.cycle_ms,
                 frame.finished ? "true" : "false");
  return out;
}

FoxgloveBridge::FoxgloveBridge(const LiveScene& scene, int port, std::string token)
    : scene_(scene), token_(std::move(token)) {
  if (port < 0 || port > 65535) {
    throw maps::ScenarioError(fmt::format("--foxglove = {}: must be a port in 0..65535 (0: any free one) or off", port));
  }
  std::vector<FoxgloveChannel> channels = {
      {kVehicles, "/sage/vehicles", "json", "foxglove.PosesInFrame", PosesSchema(), "jsonschema"},
      {kScene, "/sage/scene", "json", "foxglove.SceneUpdate", SceneSchema(), "jsonschema"},
      {kGrid, "/sage/risk_grid", "json", "foxglove.Grid", GridSchema(), "jsonschema"},
      {kMission, "/sage/mission", "json", "sage.MissionStatus", MissionSchema(), "jsonschema"},
  };
  try {
    socket_ = std::make_unique<FoxgloveSocket>(port, token_, "SAGE Fleet: " + scene.mission, std::move(channels));
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(fmt::format("--foxglove = {}: {} (0 takes any free port)", port, e.what()));
  }
}

FoxgloveBridge::~FoxgloveBridge() = default;

int FoxgloveBridge::port() const { return socket_->port(); }

std::size_t FoxgloveBridge::clients() const { return socket_->clients(); }

std::string FoxgloveBridge::Url() const { return fmt::format("ws://127.0.0.1:{}/?token={}", port(), token_); }

void FoxgloveBridge::Publish(const LiveFrame& frame, const HeatGrid* heat, std::uint64_t heat_seq) {
  const std::uint64_t stamp = Nanoseconds(frame.time_s);
  socket_->SendTime(stamp);
  if (socket_->Subscribed(kVehicles)) socket_->Send(kVehicles, stamp, PosesInFrameJson(frame));
  if (socket_->Subscribed(kMission)) socket_->Send(kMission, stamp, MissionStatusJson(frame));
  const auto now = std::chrono::steady_clock::now();
  if (socket_->Subscribed(kScene) && (now - last_scene_wall_ >= kScenePeriod || frame.finished)) {
    last_scene_wall_ = now;
    socket_->Send(kScene, stamp, SceneUpdateJson(scene_, frame));
  }
  // The grid whenever it changed, subscribed or not: the socket keeps it for whoever subscribes later.
  if (heat != nullptr && heat_seq != last_heat_seq_) {
    last_heat_seq_ = heat_seq;
    socket_->Send(kGrid, stamp, GridJson(*heat, frame.time_s));
  }
}

}  // namespace sage::live
