#pragma once
// The live view's JSON, written by hand for speed (a 1,000-vehicle frame ten times a second):
// the scene once, then frames, the heat map and the answers to operators. Every string from
// outside (vehicle, valve and XT names, event text) is escaped, '<' and '>' included, and
// numbers that are not finite are written as null. The page (web/app.js) is the one reader.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "server/live/heat_grid.h"
#include "server/live/live_frame.h"

namespace sage::live {

/// An event of the log with its place in it (1, 2, ...), so that a page that has seen some of
/// the log takes only the rest.
struct LoggedEvent {
  std::uint64_t seq = 0;
  EventView event;
};

/// `text` as a JSON string, quotes included.
std::string JsonString(std::string_view text);

/// {"mission", "mode", "width_m", "height_m", "duration_s", "visit_radius_m", "controller",
///  "assignment", "profile", "actions", "replay_end_s",
///  "structures": [[name, cx, cy, w, h]...], "valves": [[name, xt, x, y, sigma]...]}
std::string SceneJson(const LiveScene& scene);

/// {"seq", "t", "duration", "finished", "metric", "cycle_ms", "heat_seq",
///  "counts": {"alive", "stale", "lost", "left"},
///  "v": [[id, name, x, y, heading, status]...], "valves": [[raw, share, last_visit|null, visits]...],
///  "events": [[seq, t, kind, text]...], "events_total",
///  "trails": [[x, y, x, y, ...]...] (aligned with "v"; only with_trails)}
std::string FrameJson(const LiveFrame& frame, std::uint64_t seq, std::span<const LoggedEvent> events,
                      std::uint64_t events_total, std::uint64_t heat_seq, bool with_trails);

/// {"seq", "nx", "ny", "cell_m", "max", "data": base64 of nx * ny bytes, value / max * 255}
std::string HeatJson(const HeatGrid& grid, std::uint64_t seq);

/// {"accepted": bool, "line": "..."}: an operator's answer.
std::string AnswerJson(bool accepted, std::string_view line);

/// Standard base64 (RFC 4648, padded).
std::string Base64(std::string_view bytes);

}  // namespace sage::live
