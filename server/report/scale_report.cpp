// scale.json, scale.md and scale.svg of `sage bench scale`, and the figures of a finished run's
// metrics.json that a row takes from a launch.
#include "server/report/scale_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string_view>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/atomic_write.h"

namespace sage::server {
// Internals in a named namespace: this file shares a unity batch with the other report writers.
namespace scale_report_internal {

using Json = nlohmann::ordered_json;

// Every member of a row once, with its JSON key, for writing and reading alike.
template <class Row, class Visit>
void VisitFields(Row& r, Visit&& v) {
  v("vehicles", r.vehicles);
  v("run", r.run);
  v("transport", r.transport);
  v("controller", r.controller);
  v("assignment", r.assignment);
  v("field", r.field);
  v("xts", r.xts);
  v("valves", r.valves);
  v("field_width_m", r.field_width_m);
  v("field_height_m", r.field_height_m);
  v("duration_s", r.duration_s);
  v("mission_s", r.mission_s);
  v("wall_s", r.wall_s);
  v("setup_wall_s", r.setup_wall_s);
  v("real_time_factor", r.real_time_factor);
  v("real_time_factor_late", r.real_time_factor_late);
  v("server_cycle_mean_ms", r.server_cycle_mean_ms);
  v("server_cycle_p99_ms", r.server_cycle_p99_ms);
  v("server_cycle_max_ms", r.server_cycle_max_ms);
  v("cpu_s", r.cpu_s);
  v("cpu_s_per_vehicle_s", r.cpu_s_per_vehicle_s);
  v("cpu_s_per_vehicle_s_late", r.cpu_s_per_vehicle_s_late);
  v("cpu_scope", r.cpu_scope);
  v("peak_rss_mb", r.peak_rss_mb);
  v("server_peak_rss_mb", r.server_peak_rss_mb);
  v("agent_host_peak_rss_mb", r.agent_host_peak_rss_mb);
  v("agent_hosts", r.agent_hosts);
  v("dds_samples_per_s", r.dds_samples_per_s);
  v("dds_bytes_per_s", r.dds_bytes_per_s);
  v("dds_bytes_in", r.dds_bytes_in);
  v("dds_bytes_out", r.dds_bytes_out);
  v("all_moved_after_s", r.all_moved_after_s);
  v("vehicles_never_moved", r.vehicles_never_moved);
  v("unvisited_valves", r.unvisited_valves);
  v("longest_gap_median_s", r.longest_gap_median_s);
  v("longest_gap_p90_s", r.longest_gap_p90_s);
  v("longest_gap_max_s", r.longest_gap_max_s);
  v("risk_weighted_interval_s", r.risk_weighted_interval_s);
  v("expected_detection_delay_s", r.expected_detection_delay_s);
  v("dominant_interval_s", r.dominant_interval_s);
  v("visit_weight_correlation", r.visit_weight_correlation);
  v("note", r.note);
}

// NaN and negative counts are "not measured": null.
Json ToJson(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
Json ToJson(int v) { return v >= 0 ? Json(v) : Json(nullptr); }
Json ToJson(const std::string& v) { return Json(v); }

Json RowToJson(const ScaleRow& row) {
  Json j = Json::object();
  VisitFields(row, [&](const char* key, const auto& value) { j[key] = ToJson(value); });
  return j;
}

void FromJson(const Json& j, double& v) { v = j.is_null() ? ScaleRow::kNaN : j.get<double>(); }
void FromJson(const Json& j, int& v) { v = j.is_null() ? -1 : j.get<int>(); }
void FromJson(const Json& j, std::string& v) { v = j.get<std::string>(); }

// ---- the table ----------------------------------------------------------------------------

std::string Ms(double ms) {
  if (!std::isfinite(ms)) return "-";
  return ms < 1.0 ? fmt::format("{:.3f}", ms) : ms < 10.0 ? fmt::format("{:.2f}", ms) : fmt::format("{:.1f}", ms);
}
std::string Secs(double s) { return std::isfinite(s) ? fmt::format("{:.1f} s", s) : "-"; }
std::string Mb(double mb) { return std::isfinite(mb) ? fmt::format("{:.0f} MB", mb) : "-"; }
std::string Factor(double x) {
  if (!std::isfinite(x)) return "-";
  return x < 100.0 ? fmt::format("{:.2f}x", x) : fmt::format("{:.0f}x", x);
}
std::string Thousands(double v) {
  std::string digits = fmt::format("{:.0f}", v);
  for (int i = static_cast<int>(digits.size()) - 3; i > 0; i -= 3) digits.insert(static_cast<std::size_t>(i), ",");
  return digits;
}

std::string ControllerLabel(const ScaleRow& r) {
  if (r.controller == "astar") return "A* tours";
  return r.assignment.empty() ? r.controller : fmt::format("{} ({})", r.controller, r.assignment);
}

std::vector<ScaleRow> Sorted(std::vector<ScaleRow> rows) {
  const auto key = [](const ScaleRow& r) {
    return std::tuple(r.vehicles, r.transport == "inproc" ? 0 : 1, r.controller == "ergodic" ? 0 : 1);
  };
  std::stable_sort(rows.begin(), rows.end(), [&](const ScaleRow& a, const ScaleRow& b) { return key(a) < key(b); });
  return rows;
}

// Rows of one vehicle count, transport and controller, in the order given.
std::vector<std::vector<ScaleRow>> Groups(const std::vector<ScaleRow>& rows) {
  std::vector<std::vector<ScaleRow>> groups;
  for (const ScaleRow& r : Sorted(rows)) {
    const bool same = !groups.empty() && groups.back().front().vehicles == r.vehicles &&
                      groups.back().front().transport == r.transport && groups.back().front().controller == r.controller;
    if (same) groups.back().push_back(r);
    else groups.push_back({r});
  }
  return groups;
}

double Median(std::vector<double> values) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  if (values.empty()) return ScaleRow::kNaN;
  std::sort(values.begin(), values.end());
  const std::size_t half = values.size() / 2;
  return values.size() % 2 == 1 ? values[half] : 0.5 * (values[half - 1] + values[half]);
}

std::string TableText(const std::vector<ScaleRow>& all_rows) {
  const std::vector<ScaleRow> rows = MedianRuns(all_rows);
  std::string out =
      "| vehicles | transport | controller | real-time factor (2nd half) | server cycle mean / p99 / max | CPU per vehicle-s "
      "(2nd half) | peak RSS | "
      "DDS at the server | all moved by | unvisited valves | longest gap median / p90 / max | risk-weighted interval | "
      "expected detection delay | dominant valve interval | corr(visits, weight) |\n"
      "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  // A whole-mission figure and, where measured, its second half's in brackets.
  const auto with_late = [](const std::string& whole, double late, const std::string& late_text) {
    return std::isfinite(late) ? fmt::format("{} ({})", whole, late_text) : whole;
  };
  const auto cpu_ms = [](double s) { return std::isfinite(s) ? fmt::format("{} ms", Ms(1e3 * s)) : std::string("-"); };
  for (const ScaleRow& r : Sorted(rows)) {
    std::string rss = Mb(r.peak_rss_mb);
    if (r.transport == "dds" && std::isfinite(r.server_peak_rss_mb)) {
      rss = fmt::format("server {:.0f}, host {} MB", r.server_peak_rss_mb,
                        std::isfinite(r.agent_host_peak_rss_mb) ? fmt::format("{:.0f}", r.agent_host_peak_rss_mb) : "-");
    }
    const std::string dds = std::isfinite(r.dds_samples_per_s)
                                ? fmt::format("{}/s, {:.2f} MB/s", Thousands(r.dds_samples_per_s), r.dds_bytes_per_s / 1e6)
                                : "-";
    const std::string moved = r.vehicles_never_moved > 0 ? fmt::format("{} never", r.vehicles_never_moved)
                                                         : Secs(r.all_moved_after_s);
    const std::string gaps =
        std::isfinite(r.longest_gap_max_s)
            ? fmt::format("{:.0f} / {:.0f} / {:.0f} s", r.longest_gap_median_s, r.longest_gap_p90_s, r.longest_gap_max_s)
            : "-";
    // A valve never visited makes these a floor (">=", as sage run's table marks them).
    const auto at_least = [](const ScaleRow& row, double seconds) {
      return row.unvisited_valves > 0 && std::isfinite(seconds) ? ">= " + Secs(seconds) : Secs(seconds);
    };
    const std::string corr = std::isfinite(r.visit_weight_correlation)
                                 ? fmt::format("{:+.2f}", r.visit_weight_correlation)
                                 : (r.unvisited_valves >= 0 ? "undefined" : "-");
    out += fmt::format("| {} | {} | {} | {} | {} / {} / {} ms | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                       Thousands(r.vehicles), r.transport, ControllerLabel(r),
                       with_late(Factor(r.real_time_factor), r.real_time_factor_late, Factor(r.real_time_factor_late)),
                       Ms(r.server_cycle_mean_ms), Ms(r.server_cycle_p99_ms), Ms(r.server_cycle_max_ms),
                       with_late(cpu_ms(r.cpu_s_per_vehicle_s), r.cpu_s_per_vehicle_s_late, cpu_ms(r.cpu_s_per_vehicle_s_late)),
                       rss, dds, moved, r.unvisited_valves >= 0 ? std::to_string(r.unvisited_valves) : "-", gaps,
                       at_least(r, r.risk_weighted_interval_s), at_least(r, r.expected_detection_delay_s),
                       Secs(r.dominant_interval_s), corr);
  }
  if (std::any_of(rows.begin(), rows.end(), [](const ScaleRow& r) { return r.unvisited_valves > 0; })) {
    out += "\n(>=: some valve was never visited; it counts as visited once, its leak as waiting only to the end)\n";
  }
  // Said under the table, where a reader meets it (a new user read 0.124 / 0.036 / 35.0 ms as wrong).
  // As shown: two cells that read alike are not called apart.
  const auto shown_above = [](const ScaleRow& r) {
    return std::isfinite(r.server_cycle_mean_ms) && std::isfinite(r.server_cycle_p99_ms) &&
           std::stod(Ms(r.server_cycle_mean_ms)) > std::stod(Ms(r.server_cycle_p99_ms));
  };
  if (std::any_of(rows.begin(), rows.end(), shown_above)) {
    out += "\nA server cycle's mean above its p99 is a few long cycles carrying the mean (the first plan of regions or "
           "tours); the p99 is the steady cycle, the max the longest.\n";
  }
  return out;
}

// ---- the plot -------------------------------------------------------------------------------

// One log10 axis over the data's decades.
struct LogAxis {
  int low = 0, high = 1;  // decades
  double pixel_low = 0.0, pixel_high = 1.0;
  static LogAxis Over(const std::vector<double>& values, double pixel_low, double pixel_high) {
    LogAxis axis{0, 1, pixel_low, pixel_high};
    bool any = false;
    double lo = 0.0, hi = 0.0;
    for (double v : values) {
      if (!(v > 0.0) || !std::isfinite(v)) continue;
      const double l = std::log10(v);
      lo = any ? std::min(lo, l) : l;
      hi = any ? std::max(hi, l) : l;
      any = true;
    }
    if (any) {
      axis.low = static_cast<int>(std::floor(lo + 1e-9));
      axis.high = std::max(axis.low + 1, static_cast<int>(std::ceil(hi - 1e-9)));
    }
    return axis;
  }
  double Pixel(double v) const {
    const double f = (std::log10(v) - low) / static_cast<double>(high - low);
    return pixel_low + f * (pixel_high - pixel_low);
  }
};

std::string DecadeLabel(int decade) {
  if (decade >= 0 && decade <= 6) return Thousands(std::pow(10.0, decade));
  if (decade < 0 && decade >= -3) return fmt::format("{:.{}f}", std::pow(10.0, decade), -decade);
  return fmt::format("1e{}", decade);
}

}  // namespace scale_report_internal

namespace internal = scale_report_internal;

std::vector<ScaleRow> MedianRuns(const std::vector<ScaleRow>& rows) {
  std::vector<ScaleRow> out;
  for (std::vector<ScaleRow>& group : internal::Groups(rows)) {
    const auto speed = [](const ScaleRow& r) { return std::isfinite(r.real_time_factor) ? r.real_time_factor : -1.0; };
    std::stable_sort(group.begin(), group.end(), [&](const ScaleRow& a, const ScaleRow& b) { return speed(a) < speed(b); });
    out.push_back(group[(group.size() - 1) / 2]);
  }
  return out;
}

std::string ScaleSpread(const std::vector<ScaleRow>& rows) {
  const std::vector<std::vector<ScaleRow>> groups = internal::Groups(rows);
  const auto label = [](const ScaleRow& r) {
    return fmt::format("{} {}, {}", internal::Thousands(r.vehicles), r.transport, internal::ControllerLabel(r));
  };
  const auto cpu_ms = [](double s) { return std::isfinite(s) ? internal::Ms(1e3 * s) : std::string("-"); };
  std::string runs;
  for (std::vector<ScaleRow> group : groups) {
    if (group.size() < 2) continue;
    std::stable_sort(group.begin(), group.end(), [](const ScaleRow& a, const ScaleRow& b) { return a.run < b.run; });
    std::string speeds, cpus;
    for (const ScaleRow& r : group) {
      speeds += (speeds.empty() ? "" : " / ") + internal::Factor(r.real_time_factor);
      cpus += (cpus.empty() ? "" : " / ") + cpu_ms(r.cpu_s_per_vehicle_s);
    }
    runs += fmt::format("- {}: {} runs, real-time factor {}; CPU per vehicle-s {} ms\n", label(group.front()),
                        group.size(), speeds, cpus);
  }
  // Per transport and controller: the median CPU per vehicle-second at each N against the smallest N's.
  // (A small fleet may fly another assignment than a large one: the label names it only if all agree.)
  std::map<std::pair<std::string, std::string>, std::vector<std::pair<int, double>>> by_kind;
  std::map<std::pair<std::string, std::string>, std::string> kind_label;
  for (const std::vector<ScaleRow>& group : groups) {
    std::vector<double> cpu;
    for (const ScaleRow& r : group) cpu.push_back(r.cpu_s_per_vehicle_s);
    const ScaleRow& first = group.front();
    const auto kind = std::pair(first.transport, first.controller);
    by_kind[kind].emplace_back(first.vehicles, internal::Median(cpu));
    const auto [at, added] = kind_label.emplace(kind, internal::ControllerLabel(first));
    if (!added && at->second != internal::ControllerLabel(first)) at->second = first.controller;
  }
  std::string flat;
  for (const auto& [kind, sizes] : by_kind) {
    if (sizes.size() < 2 || !std::isfinite(sizes.front().second) || !(sizes.front().second > 0.0)) continue;
    std::string ratios;
    for (std::size_t i = 1; i < sizes.size(); ++i) {
      ratios += fmt::format("{}{}{} at {}", ratios.empty() ? "" : ", ", internal::Factor(sizes[i].second / sizes.front().second),
                            ratios.empty() ? " that" : "", internal::Thousands(sizes[i].first));
    }
    flat += fmt::format("- {}, {}: {} ms at {}; {}\n", kind.first, kind_label.at(kind), cpu_ms(sizes.front().second),
                        internal::Thousands(sizes.front().first), ratios);
  }
  std::string out;
  if (!runs.empty()) {
    out += "Each configuration ran several times, round by round (so the machine's slower and faster spells fall on "
           "all of them); the table shows the run with the median real-time factor. Every run, in order:\n\n" +
           runs + "\n";
  }
  if (!flat.empty()) {
    out += "CPU per vehicle-second against the smallest fleet's (with --repeat, the median of each size's runs):\n\n" + flat;
  }
  return out;
}

std::string ScaleRowJson(const ScaleRow& row) { return internal::RowToJson(row).dump(); }

ScaleRow ParseScaleRowJson(const std::string& text) {
  ScaleRow row;
  try {
    const internal::Json j = internal::Json::parse(text);
    internal::VisitFields(row, [&](const char* key, auto& value) {
      if (std::string_view(key) == "run" && !j.contains(key)) return;  // rows written before --repeat: run 1
      internal::FromJson(j.at(key), value);
    });
  } catch (const nlohmann::json::exception& e) {
    throw maps::ScenarioError(std::string("not a scale row: ") + e.what());
  }
  return row;
}

std::string ScaleJson(const std::vector<ScaleRow>& rows) {
  internal::Json array = internal::Json::array();
  for (const ScaleRow& r : rows) array.push_back(internal::RowToJson(r));
  return array.dump(2) + "\n";
}

std::string ScaleTable(const std::vector<ScaleRow>& rows) {
  const std::string spread = ScaleSpread(rows);
  return internal::TableText(rows) + (spread.empty() ? "" : "\n" + spread);
}

std::string ScaleMarkdown(const std::vector<ScaleRow>& rows, const std::string& preamble) {
  std::string out = "# sage bench scale\n\n";
  if (!preamble.empty()) out += preamble + (preamble.back() == '\n' ? "\n" : "\n\n");
  out += internal::TableText(rows);
  const std::string spread = ScaleSpread(rows);
  if (!spread.empty()) out += "\n" + spread;
  out +=
      "\n- **real-time factor**: mission seconds per wall second of the mission loop (over DDS the server's loop, "
      "paced to real time, so at most 1.00x: below it the server fell behind). In brackets, in-process: the same "
      "over the mission's second half alone, the start-up plans (a large field's first split, the first paths into "
      "the regions or tours) behind it: what each further second of a long mission costs.\n"
      "- **server cycle**: in-process, the wall time of MissionCore::Cycle; over DDS, the server's whole cycle "
      "(taking every sample, the core's cycle, publishing, the record); mean, nearest-rank p99 and max (a "
      "mean above the p99 is a few long cycles: the first plan of regions or tours).\n"
      "- **CPU per vehicle-s**: user + system CPU seconds / (vehicles x mission seconds). In-process: the mission "
      "loop of the process that ran it (getrusage RUSAGE_SELF before and after; in brackets, from half way to the "
      "end). Over DDS: every process of the "
      "launch from start to exit (launcher, server, agent hosts; wait4 on the launcher), set-up and final writes "
      "included.\n"
      "- **peak RSS**: ru_maxrss. In-process: the process that ran the mission (forked from the benchmark, so its "
      "few MB are included). Over DDS: the server's own (its summary line) and the largest agent host's (VmHWM, read "
      "every 0.5 s while it ran); scale.json also has the largest process of the launch (wait4).\n"
      "- **DDS at the server**: samples the server took and wrote per wall second, and their serialised payload "
      "(XCDR1, proto/wire_size.h) per wall second; a sample written once counts once however many hosts read it.\n"
      "- **all moved by**: mission time by which every vehicle had been more than 5 cm from its first recorded "
      "position.\n"
      "- **quality** (the run's metrics): valves never visited; per valve the longest stretch with no vehicle within "
      "the visit radius, median / p90 / max over valves; the risk-weighted mean revisit interval sum w T / max(n, "
      "1); the expected time a leak goes unnoticed sum w sum g^2 / 2T; the dominant valve's T / max(n, 1); the "
      "Pearson correlation of visits with weight.\n";
  return out;
}

std::string ScaleSvg(const std::vector<ScaleRow>& all_rows) {
  const std::vector<ScaleRow> rows = MedianRuns(all_rows);
  constexpr double kPanelW = 360.0, kPanelH = 260.0, kLeft = 70.0, kTop = 60.0, kGap = 90.0;
  constexpr double kWidthPx = kLeft + 2.0 * kPanelW + kGap + 30.0;
  constexpr double kHeightPx = kTop + kPanelH + 100.0;
  // plot.svg's palette: a colour per controller, solid in-process, dashed over DDS.
  const std::map<std::string, const char*> kColour = {{"ergodic", "#1f77b4"}, {"astar", "#ff7f0e"}};

  std::vector<double> ns, rtfs, cycles;
  for (const ScaleRow& r : rows) {
    ns.push_back(r.vehicles);
    rtfs.push_back(r.real_time_factor);
    cycles.push_back(r.server_cycle_mean_ms);
  }
  rtfs.push_back(0.5);  // the real-time line is always in view, off the frame (DDS runs sit on it)

  fmt::memory_buffer out;
  const auto put = [&]<typename... A>(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(out), format, std::forward<A>(args)...);
  };
  put("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
      "font-family=\"sans-serif\">\n", kWidthPx, kHeightPx, kWidthPx, kHeightPx);
  put("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  put("<text x=\"{}\" y=\"28\" font-size=\"16\">sage bench scale: real-time factor and server cycle against fleet "
      "size</text>\n", kLeft);

  struct Panel {
    const char* title;
    const std::vector<double>* values;
    double ScaleRow::*member;
    bool real_time_line;
  };
  const Panel panels[] = {{"real-time factor (mission s per wall s)", &rtfs, &ScaleRow::real_time_factor, true},
                          {"server cycle, mean (ms)", &cycles, &ScaleRow::server_cycle_mean_ms, false}};
  for (int p = 0; p < 2; ++p) {
    const Panel& panel = panels[p];
    const double x0 = kLeft + p * (kPanelW + kGap), y0 = kTop;
    const internal::LogAxis x = internal::LogAxis::Over(ns, x0, x0 + kPanelW);
    const internal::LogAxis y = internal::LogAxis::Over(*panel.values, y0 + kPanelH, y0);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"13\">{}</text>\n", x0, y0 - 10.0, panel.title);
    // Decade grid lines and labels.
    for (int d = x.low; d <= x.high; ++d) {
      const double px = x.Pixel(std::pow(10.0, d));
      put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n", px, y0, px, y0 + kPanelH);
      put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"middle\">{}</text>\n", px, y0 + kPanelH + 16.0,
          internal::DecadeLabel(d));
    }
    for (int d = y.low; d <= y.high; ++d) {
      const double py = y.Pixel(std::pow(10.0, d));
      put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n", x0, py, x0 + kPanelW, py);
      put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"end\">{}</text>\n", x0 - 6.0, py + 4.0,
          internal::DecadeLabel(d));
    }
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" text-anchor=\"middle\">vehicles (log)</text>\n",
        x0 + 0.5 * kPanelW, y0 + kPanelH + 34.0);
    if (panel.real_time_line) {
      const double py = y.Pixel(1.0);
      put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#c00\" stroke-dasharray=\"2 3\"/>\n",
          x0, py, x0 + kPanelW, py);
      put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" fill=\"#c00\" text-anchor=\"end\">real time</text>\n",
          x0 + kPanelW - 4.0, py - 4.0);
    }
    // One polyline per controller and transport, through the rows sorted by N.
    for (const char* transport : {"inproc", "dds"}) {
      for (const auto& [controller, colour] : kColour) {
        std::vector<std::pair<double, double>> points;
        for (const ScaleRow& r : internal::Sorted(rows)) {
          const double v = r.*panel.member;
          if (r.transport != transport || r.controller != controller || !(v > 0.0) || !std::isfinite(v)) continue;
          points.emplace_back(x.Pixel(r.vehicles), y.Pixel(v));
        }
        if (points.empty()) continue;
        const bool dashed = std::string(transport) == "dds";
        put("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\"{} points=\"", colour,
            dashed ? " stroke-dasharray=\"6 4\"" : "");
        for (const auto& [px, py] : points) put("{:.1f},{:.1f} ", px, py);
        put("\"/>\n");
        for (const auto& [px, py] : points) {
          put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"{}\"/>\n", px, py, dashed ? "white" : colour);
          if (dashed) put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"none\" stroke=\"{}\"/>\n", px, py, colour);
        }
      }
    }
    put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"black\"/>\n", x0, y0,
        kPanelW, kPanelH);
  }

  // Legend: controller by colour, transport by dash.
  const double legend_y = kTop + kPanelH + 70.0;
  double lx = kLeft;
  for (const char* transport : {"inproc", "dds"}) {
    for (const auto& [controller, colour] : kColour) {
      // Only the lines drawn (an in-process bench's legend had listed "over DDS" lines it has not).
      const std::string& name = controller;  // a structured binding is not captured (clang)
      const bool drawn = std::any_of(rows.begin(), rows.end(), [&](const ScaleRow& r) {
        return r.transport == transport && r.controller == name;
      });
      if (!drawn) continue;
      const bool dashed = std::string(transport) == "dds";
      put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"2\"{}/>\n", lx,
          legend_y - 4.0, lx + 28.0, legend_y - 4.0, colour, dashed ? " stroke-dasharray=\"6 4\"" : "");
      put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">{}, {}</text>\n", lx + 34.0, legend_y,
          controller == "astar" ? "A* tours" : "ergodic", dashed ? "over DDS" : "in-process");
      lx += 185.0;
    }
  }
  put("</svg>\n");
  return std::string(out.data(), out.size());
}

void WriteScaleReport(const std::string& dir, const std::vector<ScaleRow>& rows, const std::string& preamble) {
  namespace fs = std::filesystem;
  detail::WriteAtomically((fs::path(dir) / "scale.json").string(), ScaleJson(rows));
  detail::WriteAtomically((fs::path(dir) / "scale.md").string(), ScaleMarkdown(rows, preamble));
  detail::WriteAtomically((fs::path(dir) / "scale.svg").string(), ScaleSvg(rows));
}

MissionMetrics ReadMetricsSummary(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw maps::ScenarioError(path + ": cannot read (no metrics.json: did the mission finish?)");
  MissionMetrics m;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    const auto number = [&](const nlohmann::json& v) {
      return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
    };
    m.controller = j.at("controller").get<std::string>();
    m.profile = j.at("profile").get<std::string>();
    m.duration_s = number(j.at("duration_s"));
    m.vehicle_count = j.at("vehicle_count").get<int>();
    m.visit_weight_correlation = number(j.at("visit_weight_correlation"));
    m.ergodic_metric = number(j.at("ergodic_metric"));
    m.expected_detection_delay_s = number(j.at("expected_detection_delay_s"));
    m.risk_weighted_interval_s = number(j.at("risk_weighted_interval_s"));
    m.dominant_interval_s = number(j.at("dominant_interval_s"));
    m.unvisited_valves = j.at("unvisited_valves").get<int>();
    const nlohmann::json& gaps = j.at("longest_gap_s");
    m.longest_gap_median_s = number(gaps.at("median"));
    m.longest_gap_p90_s = number(gaps.at("p90"));
    m.longest_gap_max_s = number(gaps.at("max"));
  } catch (const nlohmann::json::exception& e) {
    throw maps::ScenarioError(path + ": not a run's metrics: " + e.what());
  }
  return m;
}

}  // namespace sage::server
