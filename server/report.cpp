#include "server/report.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <string_view>

#include <Eigen/LU>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace sage::server {
namespace {

constexpr int kTableWidth = 100;  // the terminal width the table must fit

// Writes path + ".tmp" and renames it over path, so a crash or a full disk never leaves a half
// file where a reader (or the next run's comparison) expects a complete one.
void WriteAtomically(const std::string& path, std::string_view content) {
  const std::string tmp = path + ".tmp";
  const auto fail = [&](int error) {
    std::remove(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(error)));
  };
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (file == nullptr) fail(errno);
  const bool written = std::fwrite(content.data(), 1, content.size(), file) == content.size();
  int error = errno;
  const bool closed = std::fclose(file) == 0;
  if (written && !closed) error = errno;
  if (!written || !closed) fail(error);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail(errno);
}

// ---- Table 1 ----------------------------------------------------------------------------------

struct Column {
  std::string header;
  std::vector<std::string> cells;  // one per valve row
  bool left_aligned = false;
};

// A group of columns under one label (a run), with one spanning cell per summary row.
struct Block {
  std::string label;
  std::vector<Column> columns;
  std::vector<std::string> summary;
};

std::string Pad(const std::string& text, std::size_t width, bool left) {
  const std::string fill(width > text.size() ? width - text.size() : 0, ' ');
  return left ? text + fill : fill + text;
}

// `gap` spaces separate the columns inside a block; blocks are separated by " | ".
std::string RenderTable(const std::vector<Block>& blocks, std::size_t rows, std::size_t gap) {
  struct Layout {
    std::vector<std::size_t> widths;
    std::size_t inner = 0, width = 0;
  };
  std::vector<Layout> layouts;
  for (const Block& block : blocks) {
    Layout layout;
    for (const Column& column : block.columns) {
      std::size_t w = column.header.size();
      for (const std::string& cell : column.cells) w = std::max(w, cell.size());
      layout.widths.push_back(w);
      layout.inner += w + (layout.widths.size() > 1 ? gap : 0);
    }
    layout.width = std::max(layout.inner, block.label.size());
    for (const std::string& cell : block.summary) layout.width = std::max(layout.width, cell.size());
    layouts.push_back(layout);
  }
  // One line: each block's text padded to its width, blocks joined by " | ".
  const auto line = [&](auto block_text) {
    std::string out;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      if (b > 0) out += " | ";
      out += Pad(block_text(b), layouts[b].width, true);
    }
    out.erase(out.find_last_not_of(' ') + 1);
    return out + "\n";
  };
  const auto cells = [&](std::size_t b, auto cell_of) {
    // Spare width goes before the numbers (they hug the " | "), or into a leading name column.
    const Block& block = blocks[b];
    const std::size_t spare = layouts[b].width - layouts[b].inner;
    const bool names_first = block.columns.front().left_aligned;
    std::string out(names_first ? 0 : spare, ' ');
    for (std::size_t c = 0; c < block.columns.size(); ++c) {
      if (c > 0) out.append(gap, ' ');
      const std::size_t width = layouts[b].widths[c] + (names_first && c == 0 ? spare : 0);
      out += Pad(cell_of(block.columns[c]), width, block.columns[c].left_aligned);
    }
    return out;
  };
  const auto rule = [&] {
    std::string out;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      out += (b > 0 ? "-+-" : "") + std::string(layouts[b].width, '-');
    }
    return out + "\n";
  };

  std::string out = line([&](std::size_t b) {
    return b == 0 ? cells(0, [](const Column& c) { return c.header; }) : blocks[b].label;
  });
  out += line([&](std::size_t b) {
    return b == 0 ? std::string() : cells(b, [](const Column& c) { return c.header; });
  });
  out += rule();
  for (std::size_t r = 0; r < rows; ++r) {
    out += line([&](std::size_t b) { return cells(b, [r](const Column& c) { return c.cells[r]; }); });
  }
  out += rule();
  for (std::size_t s = 0; s < blocks.front().summary.size(); ++s) {
    out += line([&](std::size_t b) {
      return b == 0 ? blocks[b].summary[s] : Pad(blocks[b].summary[s], layouts[b].width, false);
    });
  }
  return out;
}

std::string Seconds(double s) { return std::isfinite(s) ? fmt::format("{:.1f} s", s) : "---"; }

std::string BuildTable(const std::vector<MissionMetrics>& runs, bool with_gaps, std::size_t gap) {
  const MissionMetrics& first = runs.front();
  const std::size_t rows = first.valves.size();
  const auto valve_of = [](const MissionMetrics& run, const std::string& name) -> const ValveMetrics* {
    for (const ValveMetrics& v : run.valves) {
      if (v.name == name) return &v;
    }
    return nullptr;
  };
  // One Weight column if every run prints the same weights (the paper's case), else one per run.
  bool same_profile = true, same_weights = true;
  for (const MissionMetrics& run : runs) {
    same_profile = same_profile && run.profile == first.profile;
    for (const ValveMetrics& v : first.valves) {
      const ValveMetrics* other = valve_of(run, v.name);
      same_weights = same_weights && other != nullptr &&
                     fmt::format("{:.2f}", other->weight) == fmt::format("{:.2f}", v.weight);
    }
  }

  Block lead{"", {{"Valve", {}, true}}, {"corr(visits, weight)", "ergodic metric", "time at boundary"}};
  for (const ValveMetrics& v : first.valves) lead.columns[0].cells.push_back(v.name);
  if (same_weights) {
    lead.columns.push_back({"Weight", {}});
    for (const ValveMetrics& v : first.valves) lead.columns[1].cells.push_back(fmt::format("{:.2f}", v.weight));
  }
  std::vector<Block> blocks = {lead};
  for (const MissionMetrics& run : runs) {
    Block block;
    block.label = run.controller;
    if (!same_profile && !run.profile.empty()) block.label += " (" + run.profile + ")";
    Column weight{"weight", {}}, visits{"visits", {}}, interval{"interval", {}}, gap{"longest gap", {}};
    for (const ValveMetrics& v : first.valves) {
      const ValveMetrics* m = valve_of(run, v.name);
      weight.cells.push_back(m ? fmt::format("{:.2f}", m->weight) : "-");
      visits.cells.push_back(m ? fmt::format("{}", m->visits) : "-");
      interval.cells.push_back(m ? Seconds(m->mean_interval_s) : "-");
      gap.cells.push_back(m ? Seconds(m->max_gap_s) : "-");
    }
    if (!same_weights) block.columns.push_back(weight);
    block.columns.push_back(visits);
    block.columns.push_back(interval);
    if (with_gaps) block.columns.push_back(gap);
    const double vehicle_time = run.duration_s * run.vehicle_count;
    block.summary = {
        std::isnan(run.visit_weight_correlation) ? "undefined"
                                                 : fmt::format("{:+.2f}", run.visit_weight_correlation),
        std::isfinite(run.ergodic_metric) ? fmt::format("{:.2e}", run.ergodic_metric) : "---",
        vehicle_time > 0.0
            ? fmt::format("{:.1f} %", 100.0 * (run.time_outside_s + run.time_pinned_s) / vehicle_time)
            : "---"};
    blocks.push_back(std::move(block));
  }
  return RenderTable(blocks, rows, gap);
}

// ---- trajectory.csv ---------------------------------------------------------------------------

std::string_view Trim(std::string_view text) {
  const auto begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
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


// ---- plot.svg ---------------------------------------------------------------------------------

std::string XmlEscape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Sequential light-to-dark red (ColorBrewer "Reds"), v in [0, 1].
std::string RedScale(double v) {
  static constexpr double kStops[5][3] = {
      {255, 245, 240}, {252, 187, 161}, {251, 106, 74}, {203, 24, 29}, {103, 0, 13}};
  const double x = std::clamp(v, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  const auto channel = [&](int c) {
    return static_cast<int>(std::lround(kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c])));
  };
  return fmt::format("#{:02x}{:02x}{:02x}", channel(0), channel(1), channel(2));
}

// The mixture density up to its constant factor (the raster is scaled to its maximum anyway);
// computed here rather than through maps::RiskField, which would need a spectral basis.
double MixtureDensity(const std::vector<maps::Valve>& valves, const Eigen::VectorXd& weights,
                      const Eigen::Vector2d& x) {
  double density = 0.0;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const Eigen::Matrix2d& sigma = valves[i].covariance_m2;
    const double det = sigma.determinant();
    if (!(det > 0.0)) continue;  // not SPD: the scenario validator reports it, the plot skips it
    const Eigen::Vector2d d = x - valves[i].position_m;
    density += weights[i] * std::exp(-0.5 * d.dot(sigma.inverse() * d)) / std::sqrt(det);
  }
  return density;
}

}  // namespace

std::string FormatTable(const std::vector<MissionMetrics>& runs) {
  if (runs.empty()) return "(no runs)\n";
  const auto widest_line = [](const std::string& text) {
    std::size_t widest = 0;
    for (std::size_t start = 0, end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
      widest = std::max(widest, end - start);
    }
    return widest;
  };
  // To fit the terminal, drop the longest-gap column first, then tighten the column spacing.
  std::string table;
  for (const auto& [with_gaps, gap] : {std::pair{true, 2}, std::pair{false, 2}, std::pair{false, 1}}) {
    table = BuildTable(runs, with_gaps, gap);
    if (widest_line(table) <= static_cast<std::size_t>(kTableWidth)) break;
  }
  return table;
}

void WriteMetricsJson(const std::string& path, const MissionMetrics& metrics) {
  using Json = nlohmann::ordered_json;  // keys in the documented order, easier to read
  const auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };
  Json over_time = Json::array();
  for (const MetricSample& s : metrics.metric_over_time) {
    over_time.push_back({{"t", s.time_s}, {"ergodic_metric", number(s.ergodic_metric)}});
  }
  Json valves = Json::array();
  for (const ValveMetrics& v : metrics.valves) {
    Json times = Json::array();
    for (double t : v.visit_times_s) times.push_back(number(t));
    valves.push_back({{"name", v.name},
                      {"weight", number(v.weight)},
                      {"visits", v.visits},
                      {"mean_interval_s", number(v.mean_interval_s)},
                      {"max_gap_s", number(v.max_gap_s)},
                      {"time_near_s", number(v.time_near_s)},
                      {"visit_times_s", times}});
  }
  Json events = Json::array();
  for (const EventResponse& e : metrics.events) {
    events.push_back({{"time_s", number(e.time_s)},
                      {"valve", e.valve},
                      {"new_weight", number(e.new_weight)},
                      {"heading_change_rad", number(e.heading_change_rad)},
                      {"time_to_next_visit_s", number(e.time_to_next_visit_s)},
                      {"interval_before_s", number(e.interval_before_s)},
                      {"interval_after_s", number(e.interval_after_s)}});
  }
  const Json json = {{"controller", metrics.controller},
                     {"profile", metrics.profile},
                     {"duration_s", number(metrics.duration_s)},
                     {"vehicle_count", metrics.vehicle_count},
                     {"visit_weight_correlation", number(metrics.visit_weight_correlation)},
                     {"ergodic_metric", number(metrics.ergodic_metric)},
                     {"time_outside_s", number(metrics.time_outside_s)},
                     {"time_pinned_s", number(metrics.time_pinned_s)},
                     {"metric_over_time", over_time},
                     {"valves", valves},
                     {"events", events}};
  WriteAtomically(path, json.dump(2) + "\n");
}

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
  using maps::ScenarioError;
  constexpr int kMaxVehicleId = 65535;  // ids index per-vehicle arrays downstream
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ScenarioError(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));

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
  std::map<std::string, int> column_of;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (!column_of.emplace(header[c], static_cast<int>(c)).second) {
      throw ScenarioError(fmt::format("{}:{}: duplicate column '{}'", path, line_number, header[c]));
    }
  }
  for (const char* required : {"t", "vehicle", "x", "y"}) {
    if (!column_of.count(required)) {
      throw ScenarioError(fmt::format("{}: missing column '{}' (need t, vehicle, x, y)", path, required));
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
  while (std::getline(in, text)) {
    ++line_number;
    if (Trim(text).empty()) continue;
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
        throw ScenarioError(fmt::format("{}:{}: column '{}' = '{}': not a number", path, line_number, name, field));
      }
      // Out of range is an overflow (1e999, rejected below) or an underflow (1e-400, which
      // strtod rounds to a tiny or zero value, fine for a position or speed).
      if (ec == std::errc::result_out_of_range) value = std::strtod(field.c_str(), nullptr);
      if (!std::isfinite(value)) {
        throw ScenarioError(fmt::format("{}:{}: column '{}' = '{}': not finite", path, line_number, name, field));
      }
      return value;
    };
    Row row{{}, fields[column("vehicle")], line_number};
    if (row.vehicle.empty()) {
      throw ScenarioError(fmt::format("{}:{}: column 'vehicle' is empty", path, line_number));
    }
    TrajectorySample& s = row.sample;
    s.time_s = number("t");
    s.position_m = {number("x"), number("y")};
    s.heading_rad = number("heading");
    s.velocity_mps = {number("vx"), number("vy")};
    s.command_mps = {number("cmd_x"), number("cmd_y")};
    rows.push_back(std::move(row));
  }

  // Integer ids if every row has one; otherwise every value is a name (so "2" in a file of names
  // is a name too), numbered in order of first appearance.
  Trajectory trajectory;
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
                                        path, row.line, row.vehicle, kMaxVehicleId));
      }
    } else {
      const auto [it, added] = index_of_name.emplace(row.vehicle, static_cast<int>(index_of_name.size()));
      if (added) trajectory.vehicle_names.push_back(row.vehicle);
      row.sample.vehicle = it->second;
    }
    trajectory.samples.push_back(row.sample);
  }
  std::stable_sort(trajectory.samples.begin(), trajectory.samples.end(), [](const auto& a, const auto& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.vehicle < b.vehicle;
  });
  return trajectory;
}


void WritePlotSvg(const std::string& path, const maps::Scenario& scenario, const Eigen::VectorXd& weights,
                  const Trajectory& trajectory, const std::string& title) {
  const std::vector<maps::Valve> valves = scenario.AllValves();
  if (weights.size() != static_cast<Eigen::Index>(valves.size())) {
    throw std::invalid_argument(fmt::format("WritePlotSvg: {} weights for {} valves", weights.size(), valves.size()));
  }
  constexpr double kWidthPx = 800.0, kSide = 30.0, kTop = 44.0, kMaxPointsPerPath = 5000.0;
  static constexpr const char* kPalette[] = {"#1f77b4", "#2ca02c", "#9467bd", "#17becf", "#ff7f0e",
                                             "#8c564b", "#e377c2", "#bcbd22", "#000080", "#7f7f7f"};
  const double width_m = scenario.workspace.width_m, height_m = scenario.workspace.height_m;
  const double scale = (kWidthPx - 2.0 * kSide) / width_m;  // px per metre
  const double plot_h = height_m * scale;
  // World (m, y up) to SVG (px, y down).
  const auto px = [&](double x) { return kSide + x * scale; };
  const auto py = [&](double y) { return kTop + (height_m - y) * scale; };

  std::map<int, std::vector<Eigen::Vector2d>> paths;
  for (const TrajectorySample& s : trajectory.samples) paths[s.vehicle].push_back(s.position_m);
  const auto vehicle_name = [&](int v) {
    const bool named = v >= 0 && v < static_cast<int>(trajectory.vehicle_names.size()) &&
                       !trajectory.vehicle_names[v].empty();
    return named ? trajectory.vehicle_names[v] : fmt::format("vehicle {}", v);
  };
  // Legend entries below the plot, wrapped into rows of kPerRow.
  constexpr int kPerRow = 4;
  const int legend_items = static_cast<int>(paths.size()) + 2;
  const double legend_y = kTop + plot_h + 26.0;
  const double height_px = legend_y + 20.0 * ((legend_items + kPerRow - 1) / kPerRow) + 6.0;

  fmt::memory_buffer out;
  const auto put = [&]<typename... A>(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(out), format, std::forward<A>(args)...);
  };
  put("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
      "font-family=\"sans-serif\">\n", kWidthPx, height_px, kWidthPx, height_px);
  put("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  put("<text x=\"{}\" y=\"28\" font-size=\"16\">{}</text>\n", kSide, XmlEscape(title));

  // Risk density raster, about 80 cells across, normalised to its maximum.
  const int nx = 80, ny = std::clamp(static_cast<int>(std::lround(nx * height_m / width_m)), 1, 200);
  const Eigen::VectorXd w = weights.sum() > 0.0 ? Eigen::VectorXd(weights / weights.sum()) : weights;
  Eigen::MatrixXd density(nx, ny);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      density(i, j) = MixtureDensity(valves, w, {(i + 0.5) * width_m / nx, (j + 0.5) * height_m / ny});
    }
  }
  const double peak = density.maxCoeff() > 0.0 ? density.maxCoeff() : 1.0;
  const double cell_w = width_m * scale / nx, cell_h = plot_h / ny;
  // The lightest colour fills the whole box once; only cells darker than it are drawn, which
  // keeps the file small (most of the box is far from every valve).
  const std::string background = RedScale(0.0);
  put("<g shape-rendering=\"crispEdges\">\n<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n",
      kSide, kTop, width_m * scale, plot_h, background);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const std::string fill = RedScale(density(i, j) / peak);
      if (fill == background) continue;
      // Cells overlap by half a pixel so no seams show between them.
      put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n",
          kSide + i * cell_w, kTop + (ny - 1 - j) * cell_h, cell_w + 0.5, cell_h + 0.5, fill);
    }
  }
  put("</g>\n");

  for (const maps::ChristmasTree& xt : scenario.structures) {
    const Eigen::Vector2d lo = xt.center_m - 0.5 * xt.size_m;
    put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#404040\"/>\n",
        px(lo.x()), py(lo.y() + xt.size_m.y()), xt.size_m.x() * scale, xt.size_m.y() * scale);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" fill=\"white\" text-anchor=\"middle\">{}</text>\n",
        px(xt.center_m.x()), py(xt.center_m.y()) + 4.0, XmlEscape(xt.name));
  }
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const double x = px(valves[i].position_m.x()), y = py(valves[i].position_m.y());
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"none\" stroke=\"#222\" stroke-dasharray=\"4 3\"/>\n",
        x, y, scenario.visit_radius_m * scale);
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"#222\"/>\n", x, y);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" stroke=\"white\" stroke-width=\"3\" "
        "paint-order=\"stroke\">{} ({:.2f})</text>\n", x + 6.0, y - 6.0, XmlEscape(valves[i].name), w[i]);
  }

  int colour = 0;
  for (const auto& [vehicle, points] : paths) {
    const char* stroke = kPalette[colour++ % std::size(kPalette)];
    // Keep every stride-th point and the last, at most ~5000: the eye cannot tell more apart.
    const std::size_t stride = static_cast<std::size_t>(std::ceil(points.size() / kMaxPointsPerPath));
    put("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" stroke-opacity=\"0.85\" points=\"", stroke);
    for (std::size_t k = 0; k < points.size(); k += stride) {
      put("{:.1f},{:.1f} ", px(points[k].x()), py(points[k].y()));
    }
    put("{:.1f},{:.1f}\"/>\n", px(points.back().x()), py(points.back().y()));
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"5\" fill=\"{}\" stroke=\"white\" stroke-width=\"1.5\"/>\n",
        px(points.front().x()), py(points.front().y()), stroke);
  }
  put("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"black\"/>\n", kSide,
      kTop, width_m * scale, plot_h);

  // Legend: one entry per vehicle, then the valve and XT symbols.
  int item = 0;
  const auto slot = [&] {
    const int k = item++;
    return std::pair<double, double>(kSide + (k % kPerRow) * 160.0, legend_y + (k / kPerRow) * 20.0);
  };
  colour = 0;
  for (const auto& [vehicle, points] : paths) {
    const auto [x, y] = slot();
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"3\"/>\n", x,
        y - 4.0, x + 22.0, y - 4.0, kPalette[colour++ % std::size(kPalette)]);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">{}</text>\n", x + 28.0, y, XmlEscape(vehicle_name(vehicle)));
  }
  auto [vx, vy] = slot();
  put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"7\" fill=\"none\" stroke=\"#222\" stroke-dasharray=\"4 3\"/>\n",
      vx + 11.0, vy - 4.0);
  put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">valve, visit radius</text>\n", vx + 28.0, vy);
  auto [tx, ty] = slot();
  put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"22\" height=\"10\" fill=\"#404040\"/>\n", tx, ty - 9.0);
  put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">XT footprint</text>\n", tx + 28.0, ty);
  put("</svg>\n");
  WriteAtomically(path, std::string_view(out.data(), out.size()));
}

}  // namespace sage::server
