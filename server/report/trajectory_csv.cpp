// trajectory.csv: writing a recorded mission, and reading one back (ours, or a vehicle's log).
#include "server/report/report.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string_view>

#include <fmt/format.h>

#include "server/report/atomic_write.h"

namespace sage::server {
namespace {

using detail::WriteAtomically;

std::string_view Trim(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

// A field of the file as an error shows it: control characters as '?', at most 64 characters, so
// that the message stays one line (a NUL or ESC in a field had reached the terminal: found by the
// CSV fuzzer).
std::string Shown(std::string_view text) {
  std::string out(text.substr(0, 64));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return text.size() > 64 ? out + "..." : out;
}

std::vector<std::string> SplitCsv(std::string_view line) {
  std::vector<std::string> fields;
  for (std::size_t start = 0;;) {
    const std::size_t comma = line.find(',', start);
    std::string_view field = Trim(line.substr(start, comma - start));
    // Strip one pair of quotes (a quoted vehicle name); embedded commas are not supported.
    if (field.size() >= 2 && field.front() == '"' && field.back() == '"') field = field.substr(1, field.size() - 2);
    fields.emplace_back(field);
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

bool ParseInt(const std::string& text, int* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value);
  return ec == std::errc() && ptr == end && !text.empty();
}

// Vehicle names are written instead of ids when reading them back gives the same ids: every id
// has a plain, unique, non-numeric name, and ids first appear in the order 0, 1, 2, ...
bool CanWriteNames(const Trajectory& trajectory) {
  std::set<std::string> seen_names;
  for (const std::string& name : trajectory.vehicle_names) {
    int unused = 0;
    if (name.empty() || name != Trim(name) || ParseInt(name, &unused) ||
        name.find_first_of(",\"\r\n") != std::string::npos || !seen_names.insert(name).second) {
      return false;
    }
  }
  int next_new = 0;
  std::vector<bool> seen(trajectory.vehicle_names.size(), false);
  for (const TrajectorySample& s : trajectory.samples) {
    if (s.vehicle < 0 || s.vehicle >= static_cast<int>(seen.size())) return false;
    if (!seen[s.vehicle]) {
      if (s.vehicle != next_new++) return false;
      seen[s.vehicle] = true;
    }
  }
  return true;
}

}  // namespace

void WriteTrajectoryCsv(const std::string& path, const Trajectory& trajectory) {
  const bool names = CanWriteNames(trajectory);
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n");
  for (const TrajectorySample& s : trajectory.samples) {
    // "{}" prints the shortest text that parses back to the same double.
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{},{},{},{}\n", s.time_s,
                   names ? trajectory.vehicle_names[s.vehicle] : std::to_string(s.vehicle),
                   s.position_m.x(), s.position_m.y(), s.heading_rad, s.velocity_mps.x(),
                   s.velocity_mps.y(), s.command_mps.x(), s.command_mps.y());
  }
  WriteAtomically(path, std::string_view(out.data(), out.size()));
}

Trajectory ReadTrajectoryCsv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw maps::ScenarioError(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  return ParseTrajectoryCsv(in, path);
}

Trajectory ParseTrajectoryCsv(std::istream& in, const std::string& path) {
  using maps::ScenarioError;
  constexpr int kMaxVehicleId = 65535;  // ids index per-vehicle arrays downstream
  std::string text;
  int line_number = 0;
  std::vector<std::string> header;
  while (header.empty() && std::getline(in, text)) {
    ++line_number;
    // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first column's name.
    if (line_number == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
    if (!Trim(text).empty()) header = SplitCsv(text);
  }
  if (header.empty()) {
    throw ScenarioError(fmt::format("{}: empty file (need a header with t, vehicle, x, y)", path));
  }
  // A first line of numbers is a row, not a header: said as such (a headerless log had read as a
  // duplicate column '0').
  if (std::all_of(header.begin(), header.end(), [](const std::string& name) {
        const std::string_view cell = Trim(name);
        return !cell.empty() && cell.find_first_not_of("0123456789.+-eE") == std::string::npos;
      })) {
    throw ScenarioError(fmt::format("{}:{}: no header: the first line holds numbers (need a header line naming the "
                                    "columns, e.g. t,vehicle,x,y)",
                                    path, line_number));
  }
  std::map<std::string, int> column_of;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (!column_of.emplace(header[c], static_cast<int>(c)).second) {
      throw ScenarioError(fmt::format("{}:{}: duplicate column '{}'", path, line_number, Shown(header[c])));
    }
  }
  for (const char* required : {"t", "vehicle", "x", "y"}) {
    if (!column_of.count(required)) {
      // The header as read, so that a file of other columns or separators says what it holds
      // (a "t;vehicle;x;y" export had read as missing 't' alone).
      std::string read;
      for (const std::string& name : header) read += (read.empty() ? "" : ", ") + Shown(name);
      if (read.size() > 120) read = read.substr(0, 117) + "...";
      throw ScenarioError(fmt::format("{}: missing column '{}' (need t, vehicle, x, y, comma-separated; its header "
                                      "reads {} column(s): {})",
                                      path, required, header.size(), read));
    }
  }
  const auto column = [&](const char* name) {
    const auto it = column_of.find(name);
    return it == column_of.end() ? -1 : it->second;
  };

  struct Row {
    TrajectorySample sample;
    std::string vehicle;
    int line;
  };
  std::vector<Row> rows;
  bool cut_line = false;
  while (std::getline(in, text)) {
    ++line_number;
    if (Trim(text).empty()) continue;
    // A last line with no newline after it that does not read as a row is a record cut short
    // (a crash mid-write: trajectory.csv is appended as the mission runs): left out, and said.
    const bool unterminated = in.eof();
    try {
      const std::vector<std::string> fields = SplitCsv(text);
      if (fields.size() != header.size()) {
        throw ScenarioError(fmt::format("{}:{}: {} fields, the header has {}", path, line_number,
                                        fields.size(), header.size()));
      }
      // A missing optional column reads as 0.
      const auto number = [&](const char* name) {
        const int c = column(name);
        if (c < 0) return 0.0;
        const std::string& field = fields[c];
        const char* begin = field.data() + (!field.empty() && field[0] == '+' ? 1 : 0);
        const char* end = field.data() + field.size();
        double value = 0.0;
        const auto [ptr, ec] = std::from_chars(begin, end, value);
        if (ptr != end || field.empty() || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
          throw ScenarioError(
              fmt::format("{}:{}: column '{}' = '{}': not a number", path, line_number, name, Shown(field)));
        }
        // Out of range is an overflow (1e999, rejected below) or an underflow (1e-400, which
        // strtod rounds to a tiny or zero value, fine for a position or speed).
        if (ec == std::errc::result_out_of_range) value = std::strtod(field.c_str(), nullptr);
        if (!std::isfinite(value)) {
          throw ScenarioError(fmt::format("{}:{}: column '{}' = '{}': not finite", path, line_number, name, Shown(field)));
        }
        return value;
      };
      Row row{{}, fields[column("vehicle")], line_number};
      if (row.vehicle.empty()) {
        throw ScenarioError(fmt::format("{}:{}: column 'vehicle' is empty", path, line_number));
      }
      TrajectorySample& s = row.sample;
      s.time_s = number("t");
      // Mission time starts at 0 (a log at t = -5 had been scored as a mission of 1 s).
      if (s.time_s < 0.0) {
        throw ScenarioError(fmt::format("{}:{}: column 't' = '{}': must be >= 0 (mission seconds from the start)", path,
                                        line_number, Shown(fields[column("t")])));
      }
      s.position_m = {number("x"), number("y")};
      s.heading_rad = number("heading");
      s.velocity_mps = {number("vx"), number("vy")};
      s.command_mps = {number("cmd_x"), number("cmd_y")};
      rows.push_back(std::move(row));
    } catch (const ScenarioError&) {
      if (!unterminated) throw;
      cut_line = true;
    }
  }

  // Integer ids if every row has one; otherwise every value is a name (so "2" in a file of names
  // is a name too), numbered in order of first appearance.
  Trajectory trajectory;
  trajectory.cut_line = cut_line;
  const bool ids = std::all_of(rows.begin(), rows.end(), [](const Row& r) {
    int unused = 0;
    return ParseInt(r.vehicle, &unused);
  });
  std::map<std::string, int> index_of_name;
  for (Row& row : rows) {
    if (ids) {
      ParseInt(row.vehicle, &row.sample.vehicle);
      if (row.sample.vehicle < 0 || row.sample.vehicle > kMaxVehicleId) {
        throw ScenarioError(fmt::format("{}:{}: column 'vehicle' = '{}': must be an id in 0..{} or a name",
                                        path, row.line, Shown(row.vehicle), kMaxVehicleId));
      }
    } else {
      const auto [it, added] = index_of_name.emplace(row.vehicle, static_cast<int>(index_of_name.size()));
      if (added) trajectory.vehicle_names.push_back(row.vehicle);
      row.sample.vehicle = it->second;
    }
    trajectory.samples.push_back(row.sample);
  }
  // A vehicle's samples must go forward in time: a log shuffled or joined out of order would be
  // scored as a different path.
  std::map<int, std::pair<double, int>> last;  // vehicle -> (time, line) of its previous sample
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TrajectorySample& s = trajectory.samples[i];
    const auto [it, first] = last.try_emplace(s.vehicle, s.time_s, rows[i].line);
    if (first) continue;
    if (!(s.time_s > it->second.first)) {
      throw ScenarioError(fmt::format("{}:{}: t = {} for vehicle {} is not after its previous sample (t = {} on line {})",
                                      path, rows[i].line, s.time_s, Shown(rows[i].vehicle), it->second.first,
                                      it->second.second));
    }
    it->second = {s.time_s, rows[i].line};
  }
  std::stable_sort(trajectory.samples.begin(), trajectory.samples.end(), [](const auto& a, const auto& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.vehicle < b.vehicle;
  });
  return trajectory;
}

std::vector<WeightChange> ProfileSchedule(const maps::Scenario& scenario, const maps::RiskProfile& profile) {
  std::vector<WeightChange> schedule;
  Eigen::VectorXd raw = scenario.ProfileWeights(profile);
  schedule.push_back({0.0, raw / raw.sum()});
  for (const maps::RiskEvent& e : profile.events) {
    raw[scenario.ValveIndex(e.valve)] = e.weight;
    schedule.push_back({e.time_s, raw / raw.sum()});
  }
  return schedule;
}

MissionMetrics EvaluateRecorded(const Trajectory& trajectory, const maps::Scenario& scenario,
                                const maps::RiskProfile& profile, std::optional<double> duration_s,
                                const std::string& source, double max_checkpoints) {
  if (trajectory.samples.empty()) throw maps::ScenarioError(source + ": no samples");
  const std::vector<WeightChange> schedule = ProfileSchedule(scenario, profile);
  const double last = trajectory.samples.back().time_s;
  const double duration = duration_s.value_or(last > 0.0 ? last : 1.0 / scenario.control_rate_hz);
  if (!(duration > 0.0) || !std::isfinite(duration)) {
    throw maps::ScenarioError(fmt::format("--duration = {}: must be a finite number > 0", duration));
  }
  MetricsOptions options;
  options.profile = profile.name;
  options.metric_sample_period_s = std::max(1.0, duration / max_checkpoints);
  return ComputeMetrics(trajectory, scenario, schedule, duration, options);
}

}  // namespace sage::server
