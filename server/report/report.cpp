// The terminal table in the layout of the paper's Table 1, and metrics.json. trajectory.csv and
// the charts are written by trajectory_csv.cpp and plot_files.cpp (drawn in plots/).
#include "server/report/report.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string_view>
#include <system_error>
#include <cmath>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/atomic_write.h"
#include "server/report/plots/weight_text.h"

namespace sage::server {

void PrepareRunDirectory(const std::string& dir) {
  const auto fail = [&](const std::string& reason) {
    throw maps::ScenarioError("--out = " + dir + ": cannot write there: " + reason);
  };
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) fail(error.message());
  if (!std::filesystem::is_directory(dir, error)) fail("not a directory");
  const std::string probe = (std::filesystem::path(dir) / ".sage_write_probe").string();
  std::FILE* file = std::fopen(probe.c_str(), "wb");
  if (file == nullptr) fail(std::strerror(errno));
  std::fclose(file);
  std::filesystem::remove(probe, error);
}

void CheckOutDirectory(const std::string& dir, const std::string& flag) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    // To be made for the run: where it would be made is a directory this user may write, said
    // before any work (evaluate had scored a record, then failed on "blk/sub" with blk a file).
    fs::path existing = fs::absolute(fs::path(dir), error).lexically_normal();
    while (!existing.empty() && !fs::exists(existing, error) && existing != existing.parent_path()) {
      existing = existing.parent_path();
    }
    const auto fail = [&](const std::string& reason) {
      throw maps::ScenarioError(fmt::format("{} = {}: cannot write there: {}", flag, dir, reason));
    };
    if (fs::exists(existing, error) && !fs::is_directory(existing, error)) fail(existing.string() + " is not a directory");
    if (fs::is_directory(existing, error) && ::access(existing.c_str(), W_OK | X_OK) != 0) {
      fail(existing.string() + ": " + std::strerror(errno));
    }
    return;
  }
  const auto holds = [&](const fs::path& inner) { return fs::exists(fs::path(dir) / inner, error); };
  for (const fs::path& mark : {fs::path("metrics.json"), fs::path("trajectory.csv"), fs::path("mission.json"),
                               fs::path("ergodic") / "metrics.json", fs::path("astar") / "metrics.json", fs::path("scale.json"),
                               fs::path("leaks.json")}) {
    if (holds(mark)) return;  // an earlier run's: replaced, as its command says
  }
  std::vector<std::string> others;
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name != ".launch.lock" && name != ".sage_write_probe") others.push_back(name);
  }
  if (others.empty()) return;
  std::sort(others.begin(), others.end());
  throw maps::ScenarioError(fmt::format(
      "{} = {}: holds files that are not a run's ({}{}); a run writes scenario.yaml, metrics.json, plot.svg, ... "
      "there over files of those names: give a new or empty directory, or an earlier run's",
      flag, dir, others.front(), others.size() > 1 ? fmt::format(" and {} more", others.size() - 1) : std::string()));
}

namespace {

using detail::WriteAtomically;

constexpr int kTableWidth = 100;  // the terminal width the table must fit
// A field's valves are all listed up to kTableRows (fleet_large's 240); beyond, the
// kTableRowsOfLarge with the longest gaps (a 35,000-valve field had printed 35,000 lines).
constexpr std::size_t kTableRows = 300;
constexpr std::size_t kTableRowsOfLarge = 40;

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

// No scan could have seen a leak at the valve: its wait is only the time left to the end. Without
// an estimate (no onset yet: a mission stopped in its first tenth) it is not called unseen.
bool UnseenByScans(const ValveMetrics& v) { return !v.seen_by_scans && !std::isnan(v.expected_detection_by_scans_s); }

bool AnySensing(const std::vector<MissionMetrics>& runs) {
  return std::any_of(runs.begin(), runs.end(), [](const MissionMetrics& m) { return m.sensing; });
}

// A fleet figure that an unvisited valve makes a floor: ">= 60.0 s" (the valve counted as visited
// once, its leak as waiting to the end), else as Seconds.
std::string AtLeastIfUnvisited(const MissionMetrics& run, double seconds) {
  return run.unvisited_valves > 0 ? ">= " + Seconds(seconds) : Seconds(seconds);
}

// The valves a table lists, as indices into the first run's (matched: each run's valve for each of
// them, or null): every valve up to kTableRows, beyond the kTableRowsOfLarge with the longest gap
// in any run (with sensors the longest scan wait, the unseen first), longest first (ties in
// scenario order).
std::vector<std::size_t> ListedValves(const std::vector<std::vector<const ValveMetrics*>>& matched, bool by_scans) {
  const std::size_t m = matched.front().size();
  std::vector<std::size_t> listed(m);
  for (std::size_t i = 0; i < m; ++i) listed[i] = i;
  if (m <= kTableRows) return listed;
  // With sensors the valves a leak would have waited longest at (the unseen first): what the
  // scans, not the visits, say was watched least.
  const auto badness = [by_scans](const ValveMetrics& v) {
    if (!by_scans) return v.longest_unwatched_s;
    // NaN (no estimate): not counted.
    return UnseenByScans(v) ? std::numeric_limits<double>::infinity() : v.expected_detection_by_scans_s;
  };
  std::vector<double> worst(m, 0.0);
  for (const auto& run : matched) {
    for (std::size_t i = 0; i < m; ++i) {
      if (run[i] == nullptr) continue;
      const double b = badness(*run[i]);
      if (!std::isnan(b)) worst[i] = std::max(worst[i], b);
    }
  }
  std::stable_sort(listed.begin(), listed.end(), [&](std::size_t a, std::size_t b) { return worst[a] > worst[b]; });
  listed.resize(kTableRowsOfLarge);
  return listed;
}

// Each run's valve for each of the first run's, by name (runs of one scenario list the same
// valves; found through a hash map: a name search per valve was 1.2e9 compares at 35,000).
std::vector<std::vector<const ValveMetrics*>> MatchValves(const std::vector<MissionMetrics>& runs) {
  std::vector<std::vector<const ValveMetrics*>> matched;
  for (const MissionMetrics& run : runs) {
    std::unordered_map<std::string_view, const ValveMetrics*> by_name;
    for (const ValveMetrics& v : run.valves) by_name.emplace(v.name, &v);
    auto& row = matched.emplace_back();
    for (const ValveMetrics& v : runs.front().valves) {
      const auto it = by_name.find(v.name);
      row.push_back(it == by_name.end() ? nullptr : it->second);
    }
  }
  return matched;
}

// Which per-valve columns a table shows, and how far apart (FormatTable narrows it to fit). The
// intervals and the scans' waits are a sensing run's choice: a run without sensors always shows
// its intervals and has no waits.
struct TableLayout {
  bool gaps = true, intervals = true, scan_waits = true;
  std::size_t spacing = 2;
};

std::string BuildTable(const std::vector<MissionMetrics>& runs, const std::vector<std::vector<const ValveMetrics*>>& matched,
                       const std::vector<std::size_t>& listed, const TableLayout& layout) {
  const bool with_gaps = layout.gaps, with_intervals = layout.intervals, with_scan_waits = layout.scan_waits;
  const bool sensing = AnySensing(runs);
  const MissionMetrics& first = runs.front();
  const std::size_t rows = listed.size();
  // One Weight column if every run prints the same weights (the paper's case), else one per run.
  bool same_profile = true, same_weights = true;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    same_profile = same_profile && runs[r].profile == first.profile;
    for (const std::size_t i : listed) {
      const ValveMetrics* other = matched[r][i];
      same_weights = same_weights && other != nullptr &&
                     WeightText(other->weight) == WeightText(first.valves[i].weight);
    }
  }

  // What a fleet is judged by (metrics.json has them too) under the paper's three: a user had
  // found them only in the JSON.
  // With sensors two expected delays: from the visits (a leak seen the moment a vehicle is within
  // the visit radius) and from the scans (the leaks section's "from these scans"); a new user read
  // one line's 17.6 s against the other's 12.3 s as one figure disagreeing with itself.
  Block lead{"",
             {{"Valve", {}, true}},
             {"corr(visits, weight)", "ergodic metric", "time at boundary", "unvisited valves", "risk-weighted interval",
              sensing ? "exp. delay by visits" : "exp. detection delay"}};
  if (sensing) {
    lead.summary.push_back("exp. delay by scans");
    lead.summary.push_back("unseen by the scans");
  }
  for (const std::size_t i : listed) lead.columns[0].cells.push_back(first.valves[i].name);
  if (same_weights) {
    lead.columns.push_back({"Weight", {}});
    for (const std::size_t i : listed) lead.columns[1].cells.push_back(WeightText(first.valves[i].weight));
  }
  std::vector<Block> blocks = {lead};
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const MissionMetrics& run = runs[r];
    Block block;
    block.label = run.controller;
    if (!same_profile && !run.profile.empty()) block.label += " (" + run.profile + ")";
    Column weight{"weight", {}}, visits{"visits", {}}, interval{"interval", {}}, gap{"longest gap", {}},
        scan_wait{"scan wait", {}};
    for (const std::size_t i : listed) {
      const ValveMetrics* m = matched[r][i];
      weight.cells.push_back(m ? WeightText(m->weight) : "-");
      visits.cells.push_back(m ? fmt::format("{}", m->visits) : "-");
      interval.cells.push_back(m ? Seconds(m->mean_interval_s) : "-");
      gap.cells.push_back(m ? Seconds(m->longest_unwatched_s) : "-");
      scan_wait.cells.push_back(!m ? "-" : UnseenByScans(*m) ? "unseen" : Seconds(m->expected_detection_by_scans_s));
    }
    if (!same_weights) block.columns.push_back(weight);
    block.columns.push_back(visits);
    if (with_intervals || !run.sensing) block.columns.push_back(interval);
    if (with_gaps) block.columns.push_back(gap);
    // A camera inspects a valve from metres away: a vehicle that passes it on a leg, or turns to
    // it from the next one, watches it without a visit (within 0.3 m) to count. With sensors the
    // scans say how well each valve was watched (a valve of the look planner's with no visit had
    // its leak found sooner than under the tour).
    if (with_scan_waits && run.sensing) block.columns.push_back(scan_wait);
    const double vehicle_time = run.duration_s * run.vehicle_count;
    block.summary = {
        std::isnan(run.visit_weight_correlation) ? "undefined"
                                                 : fmt::format("{:+.2f}", run.visit_weight_correlation),
        std::isfinite(run.ergodic_metric) ? fmt::format("{:.2e}", run.ergodic_metric) : "---",
        vehicle_time > 0.0
            ? fmt::format("{:.1f} %", 100.0 * (run.time_outside_s + run.time_pinned_s) / vehicle_time)
            : "---",
        fmt::format("{} of {}", run.unvisited_valves, run.valves.size()),
        // A valve never visited counts as once in the mission, and its leak as waiting only to
        // the end: with any unvisited both figures are floors (a log with no visit had read 60 s).
        run.duration_s > 0.0 ? AtLeastIfUnvisited(run, run.risk_weighted_interval_s) : "---",
        run.duration_s > 0.0 ? AtLeastIfUnvisited(run, run.expected_detection_delay_s) : "---"};
    if (sensing) {
      block.summary.push_back(run.sensing ? Seconds(run.expected_detection_by_scans_s) : "---");
      const auto unseen = std::count_if(run.valves.begin(), run.valves.end(), UnseenByScans);
      block.summary.push_back(run.sensing ? fmt::format("{} of {}", unseen, run.valves.size()) : "---");
    }
    blocks.push_back(std::move(block));
  }
  std::string table = RenderTable(blocks, rows, layout.spacing);
  if (std::any_of(runs.begin(), runs.end(), [](const MissionMetrics& m) { return m.unvisited_valves > 0; })) {
    table += "(>=: some valve was never visited; it counts as visited once, its leak as waiting only to the end)\n";
  }
  // A vehicle that stays at its valve (a fleet of one vehicle a valve: the tours park) makes one
  // long visit: its interval reads as the mission's length while the valve was never unwatched (a
  // new user read a risk-weighted interval of 60 s beside a detection delay of 0 s as a contradiction).
  const auto kept_watch = [](const MissionMetrics& m) {
    return std::any_of(m.valves.begin(), m.valves.end(), [&](const ValveMetrics& v) {
      return m.duration_s > 0.0 && v.visits >= 1 && v.visits <= 2 && v.time_near_s >= 0.5 * m.duration_s;
    });
  };
  if (std::any_of(runs.begin(), runs.end(), kept_watch)) {
    table += "(a valve watched most of the mission in one or two long visits counts those visits alone: its interval, "
             "and so the risk-weighted interval, read long; its longest gap and the detection delay say how it was "
             "watched)\n";
  }
  if (rows < first.valves.size()) {
    table += sensing ? fmt::format("({} of {} valves listed: the longest scan waits; every valve is in metrics.json)\n",
                                   rows, first.valves.size())
                     : fmt::format("({} of {} valves listed: the longest gaps; every valve is in metrics.json, \"valves\")\n",
                                   rows, first.valves.size());
  }
  // Under the Bayesian loop the weights above are the profile's, the prior: what the vehicles
  // steered on moved with every scan (a leaking valve with a tenth of the risk drew the most visits,
  // and a new user read the table's weight and correlation as what they flew by).
  std::vector<std::string> dropped;
  if (!with_gaps) dropped.emplace_back("longest gap");
  if (sensing && !with_intervals) dropped.emplace_back("interval");
  if (sensing && !with_scan_waits) dropped.emplace_back("scan wait");
  if (!dropped.empty()) {
    std::string names;
    for (const std::string& name : dropped) names += (names.empty() ? "" : ", ") + name;
    table += fmt::format("(not shown, to fit {} columns: {}; metrics.json has every figure)\n", kTableWidth, names);
  }
  if (with_scan_waits && sensing) {
    table += "(scan wait: the mean time a leak starting at the valve (onsets spread over 0.1 to 0.9\n"
             " of the mission) would have waited for a scan to see it, from this mission's scans and\n"
             " the sensors' model; unseen: no scan could have seen it, its wait only the time left to\n"
             " the end. A visit, within the visit radius, need not be a look (the camera may face\n"
             " away), and a sensor watches a valve from metres off with no visit counted)\n";
  }
  if (std::any_of(runs.begin(), runs.end(), [](const MissionMetrics& m) { return m.steered_on_posterior; })) {
    // The column is the weight averaged over the mission: an operator's risk set moves it too
    // (a new user read 0.20 for a valve set to 10 as the profile's number).
    table += "(weight: each valve's risk weight averaged over the mission, the profile's with any\n"
             " operator's changes: the prior; the ergodic vehicles steered on the posterior, which\n"
             " the scans move: a detection raises its valve at once; see leaks below and risk.ot)\n";
  }
  return table;
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
  // To fit the terminal: with sensors first the intervals between visits (the scans' waits say
  // better how a valve was watched), then the longest gaps, then the columns' spacing, and the
  // waits last; the table says what it left out (metrics.json has every figure).
  const std::vector<std::vector<const ValveMetrics*>> matched = MatchValves(runs);
  const std::vector<std::size_t> listed =
      ListedValves(matched, AnySensing(runs));
  std::string table;
  for (const TableLayout& l : {TableLayout{true, true, true, 2}, TableLayout{true, false, true, 2},
                               TableLayout{false, false, true, 2}, TableLayout{false, false, true, 1},
                               TableLayout{false, false, false, 1}}) {
    table = BuildTable(runs, matched, listed, l);
    if (widest_line(table) <= static_cast<std::size_t>(kTableWidth)) break;
  }
  return table + FormatLeaks(runs);
}

namespace {

// `line` (no newline) onto out, broken at its last "; " (else ", ", else before " (") that keeps
// the first part within the terminal's width, the rest on a line of its own indented four (a
// leak's line with its visits after detection had run to 136 columns).
void AppendWrapped(std::string& out, const std::string& line) {
  const auto width = static_cast<std::size_t>(kTableWidth);
  if (line.size() <= width) {
    out += line + "\n";
    return;
  }
  std::size_t at = std::string::npos;
  for (const std::string_view mark : {"; ", ", ", " ("}) {  // the first kind of break that fits, the latest of it
    // A comma stays on the first line, so it must end within the width too.
    const std::size_t found = line.rfind(mark, mark == ", " ? width - 1 : width);
    // Past the indent and a few words: a break at the start would only move the line along.
    if (found != std::string::npos && found >= 12) {
      at = found;
      break;
    }
  }
  if (at == std::string::npos) {
    out += line + "\n";
    return;
  }
  const std::size_t rest = line[at] == ' ' ? at + 1 : at + 2;
  out += line.substr(0, line[at] == ',' ? at + 1 : at) + "\n";  // a comma stays where it was; a "; " goes
  AppendWrapped(out, "    " + line.substr(rest));
}

}  // namespace

std::string FormatLeaks(const std::vector<MissionMetrics>& runs) {
  std::string out;
  const auto after = [](double t, double start) {
    return std::isfinite(t) ? fmt::format("{:.1f} s (+{:.1f} s)", t, t - start) : std::string("never");
  };
  for (const MissionMetrics& run : runs) {
    if (!run.sensing && run.leaks.empty()) continue;
    // Under --steer prior the scans are fused and scored but steer nothing: said, as the profile
    // alone is then what the vehicles flew on.
    std::string steered;
    if (run.sensing && run.controller == "astar") {
      steered = run.tours_on_scans ? ", the next valves chosen on the scans" : ", the tours blind to the scans";
    } else if (run.sensing) {
      steered = run.steered_on_posterior ? ", steered on the posterior" : ", scored only: steered on the profile";
    }
    out += fmt::format("leaks ({}{}{}):{}\n", run.controller, run.profile.empty() ? "" : ", " + run.profile, steered,
                       run.leaks.empty() ? " none hidden" : "");
    std::size_t where_width = 0;  // the run's leaks' places in one column, as wide as the widest
    for (const LeakMetrics& leak : run.leaks) where_width = std::max(where_width, leak.where.size());
    for (const LeakMetrics& leak : run.leaks) {
      std::string line = fmt::format("  {:<{}} from {:6.1f} s: detected {}, confirmed {}, {} detection{}", leak.where,
                                     where_width, leak.start_s, after(leak.detected_s, leak.start_s),
                                     after(leak.confirmed_s, leak.start_s), leak.detections, leak.detections == 1 ? "" : "s");
      if (std::isfinite(leak.visits_per_min_after_detection)) {
        line += fmt::format("; then {:.1f} visits/min to it", leak.visits_per_min_after_detection);
      }
      AppendWrapped(out, line);
    }
    if (run.sensing) {
      const FalseAlarmMetrics& fa = run.false_alarms;
      AppendWrapped(out, fmt::format("  false alarms: {} raised, {} cleared{}, {} confirmed ({} false detection{} in {} scans)",
                                     fa.raised, fa.cleared,
                                     fa.cleared > 0 ? fmt::format(" (mean {:.1f} s, at most {:.1f} s)",
                                                                  fa.mean_time_to_clear_s, fa.max_time_to_clear_s)
                                                    : "",
                                     fa.confirmed, fa.detections, fa.detections == 1 ? "" : "s", run.scans));
      // What sage bench leaks measures over seeds, from this mission's scans alone: the table's
      // scan waits, weighted by the valves' risk.
      if (std::isfinite(run.expected_detection_by_scans_s)) {
        out += fmt::format("  expected time to detect a leak, from these scans: {:.1f} s (the scan waits above,\n"
                           "    risk-weighted: a leak at a valve drawn by its risk, starting in [{:.0f}, {:.0f}] s)\n",
                           run.expected_detection_by_scans_s, run.leak_onsets_from_s, run.leak_onsets_to_s);
      }
    }
  }
  return out;
}

std::string MetricsJson(const MissionMetrics& metrics, const RunInfo* info) {
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
                      {"longest_unwatched_s", number(v.longest_unwatched_s)},
                      {"visit_times_s", times}});
    if (metrics.sensing) {
      valves.back()["expected_detection_by_scans_s"] = number(v.expected_detection_by_scans_s);
      valves.back()["seen_by_scans"] = v.seen_by_scans;
    }
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
  Json json = {{"controller", metrics.controller},
                     {"profile", metrics.profile},
                     {"duration_s", number(metrics.duration_s)},
                     {"vehicle_count", metrics.vehicle_count},
                     {"visit_weight_correlation", number(metrics.visit_weight_correlation)},
                     {"ergodic_metric", number(metrics.ergodic_metric)},
                     {"time_outside_s", number(metrics.time_outside_s)},
                     {"time_pinned_s", number(metrics.time_pinned_s)},
                     {"metric_over_time", over_time},
                     {"valves", valves},
                     {"events", events},
                     {"expected_detection_delay_s", number(metrics.expected_detection_delay_s)},
                     {"risk_weighted_interval_s", number(metrics.risk_weighted_interval_s)},
                     {"dominant_interval_s", number(metrics.dominant_interval_s)},
                     {"unvisited_valves", metrics.unvisited_valves},
                     {"longest_gap_s", {{"median", number(metrics.longest_gap_median_s)},
                                        {"p90", number(metrics.longest_gap_p90_s)},
                                        {"max", number(metrics.longest_gap_max_s)}}}};
  // Leak sensing (issue 9): every hidden leak, and (with sensors) the false alarms.
  Json leaks = Json::array();
  for (const LeakMetrics& l : metrics.leaks) {
    leaks.push_back({{"where", l.where},
                     {"position_m", {l.position_m.x(), l.position_m.y()}},
                     {"valve", l.valve >= 0 ? Json(l.where) : Json(nullptr)},
                     {"start_s", number(l.start_s)},
                     {"strength", number(l.strength)},
                     {"detected_s", number(l.detected_s)},
                     {"confirmed_s", number(l.confirmed_s)},
                     {"time_to_detection_s", number(l.detected_s - l.start_s)},
                     {"time_to_confirmation_s", number(l.confirmed_s - l.start_s)},
                     {"detections", l.detections},
                     {"visits_per_min_after_detection", number(l.visits_per_min_after_detection)}});
  }
  json["leaks"] = leaks;
  if (metrics.sensing) {
    const FalseAlarmMetrics& fa = metrics.false_alarms;
    json["false_alarms"] = {{"raised", fa.raised},
                            {"cleared", fa.cleared},
                            {"confirmed", fa.confirmed},
                            {"mean_time_to_clear_s", number(fa.mean_time_to_clear_s)},
                            {"max_time_to_clear_s", number(fa.max_time_to_clear_s)},
                            {"detections", fa.detections}};
    json["scans"] = metrics.scans;
    json["steer"] = metrics.steered_on_posterior ? "posterior" : "prior";
    if (metrics.controller == "astar") json["astar_order"] = metrics.tours_on_scans ? "looks" : "shortest";
    json["expected_detection_by_scans_s"] = number(metrics.expected_detection_by_scans_s);
    json["leak_onsets_s"] = {number(metrics.leak_onsets_from_s), number(metrics.leak_onsets_to_s)};
  }
  if (info != nullptr) {
    json["complete"] = info->complete;
    json["planned_duration_s"] = number(info->planned_duration_s);
    json["stopped_early"] = info->stopped_early;
    json["rejected_samples"] = info->rejected_samples;
    json["rejected_by_kind"] = info->rejected_by_kind;
    json["rejected_by_sender"] = info->rejected_by_sender;
    json["transport"] = info->transport;
    json["resumes"] = info->resumes;
    json["rate_limited"] = {{"risk_updates", info->rate_limited_risk_updates},
                            {"by_sender", info->rate_limited_by_sender}};
  }
  return json.dump(2) + "\n";
}

void WriteMetricsJson(const std::string& path, const MissionMetrics& metrics) {
  WriteAtomically(path, MetricsJson(metrics));
}

}  // namespace sage::server
