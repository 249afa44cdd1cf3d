#include "server/live/frame_json.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include <fmt/format.h>

namespace sage::live {
namespace {

// A number, or null if it is not finite (JSON has no NaN).
void Number(std::string& out, double value, int decimals) {
  if (!std::isfinite(value)) {
    out += "null";
    return;
  }
  fmt::format_to(std::back_inserter(out), "{:.{}f}", value, decimals);
}

void General(std::string& out, double value) {
  if (!std::isfinite(value)) {
    out += "null";
    return;
  }
  fmt::format_to(std::back_inserter(out), "{:.6g}", value);
}

void AppendString(std::string& out, std::string_view text) {
  out += '"';
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '<': out += "\\u003c"; break;
      case '>': out += "\\u003e"; break;
      case '&': out += "\\u0026"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          fmt::format_to(std::back_inserter(out), "\\u{:04x}", c);
        } else {
          out += ch;
        }
    }
  }
  out += '"';
}

}  // namespace

std::string JsonString(std::string_view text) {
  std::string out;
  AppendString(out, text);
  return out;
}

std::string Base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (two ? static_cast<unsigned char>(bytes[i + 1]) << 8 : 0u);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string SceneJson(const LiveScene& scene) {
  std::string out = "{\"mission\":";
  AppendString(out, scene.mission);
  out += ",\"mode\":";
  AppendString(out, scene.mode);
  out += ",\"width_m\":";
  General(out, scene.width_m);
  out += ",\"height_m\":";
  General(out, scene.height_m);
  out += ",\"duration_s\":";
  General(out, scene.duration_s);
  out += ",\"visit_radius_m\":";
  General(out, scene.visit_radius_m);
  out += ",\"controller\":";
  AppendString(out, scene.controller);
  out += ",\"assignment\":";
  AppendString(out, scene.assignment);
  out += ",\"profile\":";
  AppendString(out, scene.profile);
  out += ",\"actions\":";
  out += scene.actions ? "true" : "false";
  out += ",\"replay_end_s\":";
  General(out, scene.replay_end_s);
  out += ",\"structures\":[";
  for (std::size_t i = 0; i < scene.structures.size(); ++i) {
    const StructureView& s = scene.structures[i];
    if (i > 0) out += ',';
    out += '[';
    AppendString(out, s.name);
    fmt::format_to(std::back_inserter(out), ",{:.3f},{:.3f},{:.3f},{:.3f}]", s.center_m.x(), s.center_m.y(), s.size_m.x(),
                   s.size_m.y());
  }
  // Flowlines as [name, diameter, [x0, y0, x1, y1, ...]], boulders as [x, y, diameter].
  out += "],\"flowlines\":[";
  for (std::size_t i = 0; i < scene.flowlines.size(); ++i) {
    const FlowlineView& f = scene.flowlines[i];
    if (i > 0) out += ',';
    out += '[';
    AppendString(out, f.name);
    fmt::format_to(std::back_inserter(out), ",{:.3f},[", f.diameter_m);
    for (std::size_t k = 0; k < f.points_m.size(); ++k) {
      fmt::format_to(std::back_inserter(out), "{}{:.3f},{:.3f}", k > 0 ? "," : "", f.points_m[k].x(), f.points_m[k].y());
    }
    out += "]]";
  }
  out += "],\"boulders\":[";
  for (std::size_t i = 0; i < scene.boulders.size(); ++i) {
    const BoulderView& b = scene.boulders[i];
    fmt::format_to(std::back_inserter(out), "{}[{:.3f},{:.3f},{:.3f}]", i > 0 ? "," : "", b.center_m.x(), b.center_m.y(),
                   b.diameter_m);
  }
  out += "],\"valves\":[";
  for (std::size_t i = 0; i < scene.valves.size(); ++i) {
    const ValveSite& v = scene.valves[i];
    if (i > 0) out += ',';
    out += '[';
    AppendString(out, v.name);
    out += ',';
    AppendString(out, v.xt);
    // One spread for the page: the standard deviation along the covariance's larger axis.
    const double sigma = std::sqrt(std::max(0.0, 0.5 * (v.covariance_m2.trace() +
                                                       std::sqrt(std::pow(v.covariance_m2(0, 0) - v.covariance_m2(1, 1), 2) +
                                                                 4.0 * v.covariance_m2(0, 1) * v.covariance_m2(1, 0)))));
    fmt::format_to(std::back_inserter(out), ",{:.3f},{:.3f},{:.3f}]", v.position_m.x(), v.position_m.y(), sigma);
  }
  out += "]}";
  return out;
}

std::string FrameJson(const LiveFrame& frame, std::uint64_t seq, std::span<const LoggedEvent> events,
                      std::uint64_t events_total, std::uint64_t heat_seq, bool with_trails) {
  std::string out;
  out.reserve(64 + frame.vehicles.size() * 40 + frame.valves.size() * 28 + events.size() * 80);
  fmt::format_to(std::back_inserter(out), "{{\"seq\":{},\"t\":", seq);
  Number(out, frame.time_s, 3);
  out += ",\"duration\":";
  General(out, frame.duration_s);
  out += ",\"finished\":";
  out += frame.finished ? "true" : "false";
  out += ",\"metric\":";
  General(out, frame.ergodic_metric);
  out += ",\"cycle_ms\":";
  Number(out, frame.cycle_ms, 2);
  fmt::format_to(std::back_inserter(out), ",\"heat_seq\":{}", heat_seq);
  std::size_t counts[4] = {0, 0, 0, 0};
  for (const VehicleView& v : frame.vehicles) ++counts[static_cast<int>(v.status)];
  fmt::format_to(std::back_inserter(out), ",\"counts\":{{\"alive\":{},\"stale\":{},\"lost\":{},\"left\":{}}}", counts[0],
                 counts[1], counts[2], counts[3]);
  out += ",\"v\":[";
  for (std::size_t i = 0; i < frame.vehicles.size(); ++i) {
    const VehicleView& v = frame.vehicles[i];
    if (i > 0) out += ',';
    fmt::format_to(std::back_inserter(out), "[{},", v.id);
    AppendString(out, v.name);
    out += ',';
    Number(out, v.x_m, 2);
    out += ',';
    Number(out, v.y_m, 2);
    out += ',';
    Number(out, v.heading_rad, 2);
    fmt::format_to(std::back_inserter(out), ",{}]", static_cast<int>(v.status));
  }
  out += "],\"valves\":[";
  for (std::size_t i = 0; i < frame.valves.size(); ++i) {
    const ValveView& v = frame.valves[i];
    if (i > 0) out += ',';
    out += '[';
    General(out, v.raw_weight);
    out += ',';
    General(out, v.share);
    out += ',';
    Number(out, v.last_visit_s, 2);
    fmt::format_to(std::back_inserter(out), ",{}]", v.visits);
  }
  out += "],\"events\":[";
  for (std::size_t i = 0; i < events.size(); ++i) {
    const LoggedEvent& e = events[i];
    if (i > 0) out += ',';
    fmt::format_to(std::back_inserter(out), "[{},", e.seq);
    Number(out, e.event.time_s, 2);
    out += ',';
    AppendString(out, e.event.kind);
    out += ',';
    AppendString(out, e.event.text);
    out += ']';
  }
  fmt::format_to(std::back_inserter(out), "],\"events_total\":{}", events_total);
  if (with_trails) {
    out += ",\"trails\":[";
    for (std::size_t i = 0; i < frame.vehicles.size(); ++i) {
      if (i > 0) out += ',';
      out += '[';
      if (i < frame.trails.size()) {
        const std::vector<float>& trail = frame.trails[i];
        for (std::size_t k = 0; k < trail.size(); ++k) {
          if (k > 0) out += ',';
          Number(out, trail[k], 2);
        }
      }
      out += ']';
    }
    out += ']';
  }
  out += '}';
  return out;
}

std::string HeatJson(const HeatGrid& grid, std::uint64_t seq) {
  std::string bytes(grid.values.size(), '\0');
  if (grid.max > 0.0f) {
    for (std::size_t i = 0; i < grid.values.size(); ++i) {
      const float scaled = std::clamp(grid.values[i] / grid.max * 255.0f + 0.5f, 0.0f, 255.0f);
      bytes[i] = static_cast<char>(static_cast<unsigned char>(scaled));
    }
  }
  std::string out = fmt::format("{{\"seq\":{},\"nx\":{},\"ny\":{},\"cell_m\":", seq, grid.nx, grid.ny);
  General(out, grid.cell_m);
  out += ",\"max\":";
  General(out, grid.max);
  out += ",\"data\":\"";
  out += Base64(bytes);
  out += "\"}";
  return out;
}

std::string AnswerJson(bool accepted, std::string_view line) {
  std::string out = accepted ? "{\"accepted\":true,\"line\":" : "{\"accepted\":false,\"line\":";
  AppendString(out, line);
  out += '}';
  return out;
}

}  // namespace sage::live
