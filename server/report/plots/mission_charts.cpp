// metric.svg and revisits.svg, and the six plot files of a run directory (see mission_plots.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "server/report/plots/mission_plots.h"
#include "server/report/plots/nice_scale.h"
#include "server/report/plots/render.h"
#include "server/report/plots/svg_writer.h"
#include "server/report/plots/weight_text.h"

namespace sage::server::plots {
namespace {

constexpr double kChartWidth = 760.0, kLeft = 84.0, kRight = 40.0, kCaptionFont = 11.0;

const char* MarkerColour(EventMarker::Kind kind) {
  switch (kind) {
    case EventMarker::Kind::kRisk: return "#e6550d";
    case EventMarker::Kind::kJoin: return "#2ca02c";
    case EventMarker::Kind::kLoss: return "#111111";
    case EventMarker::Kind::kLeave: return "#555555";
  }
  return "#555555";
}

void Caption(SvgDocument& svg, const std::vector<std::string>& lines, double top) {
  for (std::size_t k = 0; k < lines.size(); ++k) svg.Text(kLeft, top + 15.0 * k, lines[k], kCaptionFont, "start", "fill=\"#444\"");
}

std::vector<std::string> Wrapped(const std::vector<std::string>& paragraphs) {
  std::vector<std::string> lines;
  for (const std::string& p : paragraphs)
    for (std::string& line : WrapText(p, kChartWidth - kLeft - 20.0, kCaptionFont)) lines.push_back(std::move(line));
  return lines;
}

void Require(const MissionPlotInput& input, const char* what) {
  if (input.scenario == nullptr || input.metrics == nullptr) {
    throw std::invalid_argument(fmt::format("{}: scenario and metrics are required", what));
  }
}

}  // namespace

std::string MetricChartSvg(const MissionPlotInput& input) {
  Require(input, "MetricChartSvg");
  const MissionMetrics& m = *input.metrics;
  const double duration = m.duration_s > 0.0 ? m.duration_s : 1.0;
  constexpr double kTop = 70.0, kHeight = 240.0;
  const double x0 = kLeft, x1 = kChartWidth - kRight, y0 = kTop, y1 = kTop + kHeight;
  std::vector<MetricSample> samples;
  for (const MetricSample& s : m.metric_over_time)
    if (std::isfinite(s.ergodic_metric) && s.ergodic_metric > 0.0 && s.time_s >= 0.0) samples.push_back(s);
  double lo = 1e-6, hi = 1.0;
  if (!samples.empty()) {
    lo = hi = samples.front().ergodic_metric;
    for (const MetricSample& s : samples) lo = std::min(lo, s.ergodic_metric), hi = std::max(hi, s.ergodic_metric);
    // Whole decades around the data, so the axis has ticks at powers of ten.
    lo = std::pow(10.0, std::floor(std::log10(lo)));
    hi = std::pow(10.0, std::ceil(std::log10(hi)));
    if (!(hi > lo)) hi = lo * 10.0;
  }
  const auto tx = [&](double t) { return x0 + t / duration * (x1 - x0); };
  const auto vy = [&](double v) { return y1 - std::log(v / lo) / std::log(hi / lo) * (y1 - y0); };

  std::vector<std::string> caption = {
      "The ergodic metric \u03a3\u2096 \u039b\u2096 (c\u2096 \u2212 \u03c6\u2096)\u00b2 of the whole fleet's time-averaged path "
      "against the risk field in force at each moment (lower: the fleet's time matches the risk better); log scale.",
      std::isfinite(m.ergodic_metric) ? fmt::format("At the end: {:.2e} (the run table's ergodic metric).", m.ergodic_metric)
                                      : std::string("At the end: undefined.")};
  if (!input.events.empty()) caption.push_back("Vertical lines: risk changes, vehicles joining, lost or leaving, at their times.");
  if (!input.resumed_at_s.empty()) {
    caption.push_back(fmt::format("Solid purple line{}: the mission resumed from its checkpoint after its server stopped "
                                  "(fleet_events.csv: outage, resumed).",
                                  input.resumed_at_s.size() == 1 ? "" : "s"));
  }
  if (samples.empty()) caption.push_back("No metric samples were recorded.");
  const std::vector<std::string> lines = Wrapped(caption);
  const double caption_top = y1 + 62.0;
  SvgDocument svg(kChartWidth, caption_top + 15.0 * lines.size() + 6.0);
  svg.Text(kLeft, 26.0, input.title.empty() ? "ergodic metric over time" : input.title + ": ergodic metric over time", 15.0);

  // Events first (under the curve): a line at each time and its marker in the strip above.
  LabelPlacer strip({x0 - 30.0, 34.0, x1 + 30.0, y0 - 4.0}, 1.0);
  int shown = 0;
  for (const EventMarker& e : input.events) {
    if (!(e.time_s >= 0.0 && e.time_s <= duration)) continue;
    const double x = tx(e.time_s);
    svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"{3}\" stroke-width=\"1\" "
            "stroke-dasharray=\"4 3\"/>\n", x, y0, y1, MarkerColour(e.kind));
    if (shown++ >= 40) continue;  // lines for all, labels for the first 40
    const std::string text = e.kind == EventMarker::Kind::kRisk ? fmt::format("{} \u2192 {:.2f}", e.who, e.share)
                                                                : fmt::format("{} {}", e.who, ToString(e.kind));
    const double w = TextWidth(text, 10.0), h = (kAscentEm + kDescentEm) * 10.0;
    const auto at = strip.Place(Box{x - 0.5, y0 - 1.0, x + 0.5, y0}, w, h, 2.0);
    if (at) svg.Text(at->box.x0, at->box.y0 + kAscentEm * 10.0, text, 10.0, "start", fmt::format("fill=\"{}\"", MarkerColour(e.kind)));
  }
  // A resume: a solid line, labelled.
  for (const double t : input.resumed_at_s) {
    if (!(t >= 0.0 && t <= duration)) continue;
    const double x = tx(t);
    svg.Put("<line class=\"resumed\" x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#7b3294\" "
            "stroke-width=\"1.5\"/>\n", x, y0, y1);
    // Inside the plot, at the line's top (the strip above is the place events' and may be full).
    const std::string text = fmt::format("resumed at {:.1f} s", t);
    const bool left = x + 4.0 + TextWidth(text, 10.0) > x1;
    svg.Text(left ? x - 4.0 : x + 4.0, y0 + 14.0, text, 10.0, left ? "end" : "start", "fill=\"#7b3294\"");
  }
  svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#222\"/>\n", x0, y0, x1 - x0,
          y1 - y0);
  const Ticks t_ticks = LinearTicks(0.0, duration, 10);
  DrawAxis(svg, {AxisSpec::Side::kBottom, x0, y0, x1, y1, t_ticks.values, tx,
                 [&](double v) { return TickLabel(v, t_ticks.step); }, "mission time (s)", true});
  DrawAxis(svg, {AxisSpec::Side::kLeft, x0, y0, x1, y1, LogTicks(lo, hi), vy, [](double v) { return fmt::format("{:.0e}", v); },
                 "ergodic metric", true});
  if (!samples.empty()) {
    // At most ~2,000 points: a week-long mission's per-second samples thinned evenly.
    const std::size_t stride = std::max<std::size_t>(1, samples.size() / 2000);
    svg.Put("<polyline id=\"metric\" fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.8\" points=\"");
    for (std::size_t k = 0; k < samples.size(); k += stride) svg.Put("{:.1f},{:.1f} ", tx(samples[k].time_s), vy(samples[k].ergodic_metric));
    svg.Put("{:.1f},{:.1f}\"/>\n", tx(samples.back().time_s), vy(samples.back().ergodic_metric));
  }
  Caption(svg, lines, caption_top);
  return svg.Finish();
}

std::string RevisitChartSvg(const MissionPlotInput& input) {
  Require(input, "RevisitChartSvg");
  const MissionMetrics& m = *input.metrics;
  constexpr std::size_t kMaxRows = 40;
  constexpr double kTop = 58.0, kRow = 17.0, kFont = 11.0;
  std::vector<const ValveMetrics*> rows;
  for (const ValveMetrics& v : m.valves) rows.push_back(&v);
  std::stable_sort(rows.begin(), rows.end(), [](const ValveMetrics* a, const ValveMetrics* b) { return a->longest_unwatched_s > b->longest_unwatched_s; });
  const std::size_t total = rows.size();
  if (rows.size() > kMaxRows) rows.resize(kMaxRows);
  double max_weight = 0.0, longest = 0.0, widest_name = 0.0;
  for (const ValveMetrics* v : rows) {
    max_weight = std::max(max_weight, v->weight);
    longest = std::max({longest, v->longest_unwatched_s, std::isfinite(v->mean_interval_s) ? v->mean_interval_s : 0.0});
    widest_name = std::max(widest_name, TextWidth(v->name + " " + WeightText(v->weight), kFont));
  }
  if (!(longest > 0.0)) longest = m.duration_s > 0.0 ? m.duration_s : 1.0;
  // The axis ends at a tick: the longest bar ends inside it, and its length reads off the ticks.
  longest = std::ceil(longest / LinearTicks(0.0, longest, 8).step - 1e-9) * LinearTicks(0.0, longest, 8).step;
  const double x0 = std::max(kLeft, widest_name + 24.0), x1 = kChartWidth - kRight - 50.0;
  const double y0 = kTop, y1 = kTop + kRow * std::max<std::size_t>(rows.size(), 1);
  const auto tx = [&](double s) { return x0 + s / longest * (x1 - x0); };

  std::vector<std::string> caption = {
      "Bars: each valve's longest gap, the longest stretch with no vehicle within the visit radius (from the start, between visits, to the end; a vehicle holding station watches its valve), as the "
      "run table's longest gap; black ticks: the mean interval between visits; right: visits. Valves sorted by longest gap.",
      "Labels: name and weight averaged over the mission (the run table's Weight); bar shade: the same weight."};
  if (total > rows.size()) {
    caption.push_back(fmt::format("The {} valves with the longest gaps of {}.", rows.size(), Grouped(static_cast<long long>(total))));
  }
  if (m.unvisited_valves > 0) caption.push_back(fmt::format("{} valves never visited: their gap is the whole mission.", m.unvisited_valves));
  const std::vector<std::string> lines = Wrapped(caption);
  const double caption_top = y1 + 60.0;
  SvgDocument svg(kChartWidth, caption_top + 15.0 * lines.size() + 6.0);
  svg.Text(kLeft, 26.0, input.title.empty() ? "revisits per valve" : input.title + ": revisits per valve", 15.0);
  svg.Text(x1 + 8.0, kTop - 6.0, "visits", 10.0, "start", "fill=\"#444\"");
  const Ticks ticks = LinearTicks(0.0, longest, 8);
  DrawAxis(svg, {AxisSpec::Side::kBottom, x0, y0, x1, y1, ticks.values, tx, [&](double v) { return TickLabel(v, ticks.step); },
                 "seconds", true});
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const ValveMetrics& v = *rows[r];
    const double y = y0 + r * kRow;
    const Rgb shade = Reds(max_weight > 0.0 ? 0.15 + 0.85 * v.weight / max_weight : 0.5);
    svg.Put("<rect id=\"gap-{}\" x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\" stroke=\"#666\" "
            "stroke-width=\"0.5\"/>\n", r, x0, y + 2.0, std::max(0.0, tx(v.longest_unwatched_s) - x0), kRow - 4.0, Hex(shade));
    if (std::isfinite(v.mean_interval_s)) {
      const double x = tx(v.mean_interval_s);
      svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"black\" stroke-width=\"2.5\"/>\n", x, y + 0.5,
              y + kRow - 0.5);
    }
    svg.Text(x0 - 8.0, y + kRow - 4.5, v.name + " " + WeightText(v.weight), kFont, "end", fmt::format("id=\"valve-{}\"", r));
    svg.Text(x1 + 8.0, y + kRow - 4.5, std::to_string(v.visits), kFont, "start", "fill=\"#444\"");
  }
  svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#222\"/>\n", x0, y0, x1 - x0,
          y1 - y0);
  Caption(svg, lines, caption_top);
  return svg.Finish();
}

std::vector<PlotFile> MissionPlotFiles(const MissionPlotInput& input) {
  std::vector<PlotFile> files;
  const std::pair<const char*, std::string> charts[] = {
      {"plot", FieldPlotSvg(input)}, {"metric", MetricChartSvg(input)}, {"revisits", RevisitChartSvg(input)}};
  for (const auto& [name, svg] : charts) {
    files.push_back({std::string(name) + ".svg", svg});
    files.push_back({std::string(name) + ".png", SvgToPng(svg)});
  }
  return files;
}

}  // namespace sage::server::plots
