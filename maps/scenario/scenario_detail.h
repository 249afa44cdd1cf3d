#pragma once
// Helpers shared by the scenario sources (maps/scenario*.cpp) and by nothing else: not part of
// the sage_maps API, so include it only from those files.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"

namespace sage::maps::detail {

/// What is wrong with a name of the scenario or of one of its entries (shown in logs, tables and
/// CSV files: 1..kMaxNameLength characters of UTF-8, none a control character), with the name as
/// it can be shown: "" if it is a good name. The loader and the field generator both ask it.
std::string NameProblem(const std::string& name);
/// NameProblem's rules, and those of a name that becomes a directory's (the scenario's: its runs go
/// to runs/<name>_<profile>_<controller>): no / or \\, not "." or ".." (a shared scenario named
/// ../../x had written its run two directories above runs/).
std::string DirectoryNameProblem(const std::string& name);

// Shortest text that reads back to the very same double (std::to_chars), so that emitting and
// re-parsing is exact; YAML spellings for the non-finite values.
inline std::string FormatNumber(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// Messages reach the user as one line, whatever text was quoted into them.
inline std::string OneLine(std::string text) {
  std::replace_if(text.begin(), text.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  // Any other control character (a key holding ESC or GS) as '?': the line reaches a terminal
  // (found by the scenario fuzzer).
  std::replace_if(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }, '?');
  // And stays a line: a 1 MB value is not shown whole.
  constexpr std::size_t kMaxLength = 2000;
  if (text.size() > kMaxLength) text = text.substr(0, kMaxLength) + "...";
  return text;
}

// Closed box: a point on the edge is inside.
inline bool InsideBox(const Eigen::Vector2d& p, const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
}

// The YAML key of a fleet event: join, lose or leave.
inline const char* EventKey(FleetEvent::Kind kind) {
  switch (kind) {
    case FleetEvent::Kind::kJoin: return "join";
    case FleetEvent::Kind::kLose: return "lose";
    case FleetEvent::Kind::kLeave: return "leave";
  }
  return "unknown";
}

// ParseScenario's step for a seabed map: the path resolved against the folder of `source` (the
// scenario file) to an absolute one, the file checked at the door (a known kind, a regular file
// of at most kMaxSeabedMapBytes) and its bytes hashed into map_fnv1a. Throws ScenarioError.
void ResolveSeabedMap(SeabedSettings& seabed, const std::string& source);

// The rules on sensors, leaks and fusion (scenario_perception.cpp); Scenario::Validate calls it
// last. `file` starts each message.
void ValidatePerception(const Scenario& scenario, const std::string& file);

// Indices bucketed in square cells (the field generator's spacing checks, the added vehicles'
// start lattice): Any() looks at the 3 x 3 cells around a point, so it sees everything within
// one cell side of it at a cost that does not grow with the field.
class Buckets {
 public:
  explicit Buckets(double cell_m) : cell_m_(cell_m) {}
  void Add(const Eigen::Vector2d& p, int index) { cells_[Key(p, 0, 0)].push_back(index); }
  template <typename Conflict>
  bool Any(const Eigen::Vector2d& p, const Conflict& conflict) const {
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        const auto it = cells_.find(Key(p, i, j));
        if (it != cells_.end() && std::any_of(it->second.begin(), it->second.end(), conflict)) return true;
      }
    }
    return false;
  }

 private:
  std::int64_t Key(const Eigen::Vector2d& p, int i, int j) const {
    return (static_cast<std::int64_t>(std::floor(p.x() / cell_m_)) + i) * (std::int64_t{1} << 32) +
           static_cast<std::int64_t>(std::floor(p.y() / cell_m_)) + j;
  }
  double cell_m_;
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
};

}  // namespace sage::maps::detail
