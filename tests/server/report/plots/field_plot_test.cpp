// The charts of a run, checked on fleet_field (the field whose old plot had P15 on XT-E's label)
// flown for 600 s under the 'leak' profile: a risk change at P9 (300 s), rov5 joining (200 s),
// rov2 lost (400 s). What is checked is what a reader sees: labels apart from each other and
// from the structures (in the SVG's geometry and in librsvg's drawing of it), nice ticks, the
// run table's weights, the events where they happened, the density mode with its count, and
// PNGs that decode with the XTs in their colour.
#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "maps/scenario/field_generator.h"
#include "maps/scenario/perception.h"
#include "maps/scenario/scenario.h"
#include "server/mission.h"
#include "server/mission_core.h"
#include "server/report/plots/mission_plots.h"
#include "server/report/plots/plot_record.h"
#include "server/report/plots/render.h"
#include "server/report/plots/weight_text.h"
#include "server/report/report.h"
#include "server/roster.h"

namespace sage::server::plots {
namespace {

const std::string kFleetField = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";

// Streams the mission's record into a PlotRecord, as RunDirectory does.
class PlotRecorder final : public MissionRecorder {
 public:
  explicit PlotRecorder(PlotRecord& record) : record_(record) {}
  void OnSample(const TrajectorySample& s, const std::string& name) override { record_.OnSample(s, name); }
  void OnFleetEvent(const FleetEventRecord& e) override { record_.OnFleetEvent(e); }
  void OnRiskEvent(const RiskEventRecord& e) override { record_.OnRiskEvent(e); }

 private:
  PlotRecord& record_;
};

struct FleetFieldRun {
  maps::Scenario scenario;
  std::unique_ptr<PlotRecord> record;
  MissionMetrics metrics;
  Trajectory first_and_last;  // every vehicle's first and last sample, from the full record
  MissionPlotInput Input() const {
    return {&scenario, &metrics, &record->trajectory(), record->Events(), record->events_not_kept(), "fleet_field, leak"};
  }
};

const FleetFieldRun& FleetField() {
  static const FleetFieldRun run = [] {
    FleetFieldRun r;
    r.scenario = maps::LoadScenario(kFleetField);
    r.record = std::make_unique<PlotRecord>(r.scenario);
    PlotRecorder recorder(*r.record);
    Mission mission(r.scenario, MissionOptions{"leak", ControllerKind::kErgodic, &recorder, true});
    MissionResult result = mission.Run();
    r.metrics = result.metrics;
    std::map<int, TrajectorySample> first, last;
    for (const TrajectorySample& s : result.trajectory.samples) {
      first.try_emplace(s.vehicle, s);
      last[s.vehicle] = s;
    }
    for (const auto& [v, s] : first) r.first_and_last.samples.push_back(s);
    for (const auto& [v, s] : last) r.first_and_last.samples.push_back(s);
    r.first_and_last.vehicle_names = result.trajectory.vehicle_names;
    return r;
  }();
  return run;
}

double Attribute(const std::string& svg, const std::string& name) {
  std::smatch m;
  const std::regex re(" " + name + "=\"([0-9.]+)\"");
  if (!std::regex_search(svg, m, re)) return -1.0;
  return std::stod(m[1]);
}

int Count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// No two labels overlap and none covers a structure or a valve's dot; an XT's name written
// inside its own footprint stays inside it. The same holds for the ink librsvg draws (each
// label's drawn box within its placed box and the white outline around its letters, 1.5 px).
// Every XT and valve is named.
TEST(FieldPlot, LabelsDoNotCollideOnFleetField) {
  constexpr double kOutline = 1.5;  // stroke-width 3, half of it outside the glyphs; the placer keeps 1.5 px between labels
  FieldPlotLayout layout;
  const std::string svg = FieldPlotSvg(FleetField().Input(), &layout);
  ASSERT_FALSE(layout.labels.empty());
  int valve_labels = 0, xt_labels = 0;
  for (std::size_t i = 0; i < layout.labels.size(); ++i) {
    const FieldPlotLayout::Label& a = layout.labels[i];
    SCOPED_TRACE(a.text);
    EXPECT_TRUE(layout.map.Contains(a.box));
    for (std::size_t j = i + 1; j < layout.labels.size(); ++j) {
      EXPECT_FALSE(a.box.Overlaps(layout.labels[j].box)) << "overlaps " << layout.labels[j].text;
    }
    for (std::size_t k = 0; k < layout.structures.size(); ++k) {
      const bool own = a.inside_owner && a.owner == FleetField().scenario.structures[k].name;
      if (own) {
        EXPECT_TRUE(layout.structures[k].Contains(a.box)) << "written inside its XT but not within it";
      } else {
        EXPECT_FALSE(a.box.Overlaps(layout.structures[k])) << "covers " << FleetField().scenario.structures[k].name;
      }
    }
    for (const Box& dot : layout.valve_markers) EXPECT_FALSE(a.box.Overlaps(dot));
    const std::optional<Box> ink = RenderedBox(svg, a.id);
    ASSERT_TRUE(ink) << a.id;
    EXPECT_TRUE(a.box.Grown(kOutline).Contains(*ink)) << "drawn at " << ink->x0 << "," << ink->y0 << " - " << ink->x1 << ","
                                                  << ink->y1 << ", placed at " << a.box.x0 << "," << a.box.y0 << " - "
                                                  << a.box.x1 << "," << a.box.y1;
    if (a.owner.rfind("XT-", 0) == 0) ++xt_labels;
    if (a.owner.size() >= 2 && a.owner[0] == 'P' && a.text.find(' ') != std::string::npos && a.text.find(':') == std::string::npos) {
      ++valve_labels;
    }
  }
  EXPECT_EQ(xt_labels, 6);
  EXPECT_EQ(valve_labels, 20);
}

// Axes in metres with nice ticks covering the 12 x 9.5 m workspace, a scale bar of a nice
// length, a colour bar, and the workspace drawn at the same scale along both axes.
TEST(FieldPlot, AxesScaleBarAndColourBar) {
  FieldPlotLayout layout;
  const std::string svg = FieldPlotSvg(FleetField().Input(), &layout);
  EXPECT_EQ(layout.x_ticks_m, (std::vector<double>{0, 2, 4, 6, 8, 10, 12}));
  ASSERT_GE(layout.y_ticks_m.size(), 3u);
  EXPECT_EQ(layout.y_ticks_m.front(), 0.0);
  EXPECT_GT(layout.y_ticks_m.back(), 9.5 - (layout.y_ticks_m[1] - layout.y_ticks_m[0]));
  EXPECT_NEAR(layout.map.width() / 12.0, layout.map.height() / 9.5, 1e-6);
  EXPECT_EQ(layout.scale_bar_m, 2.0);
  EXPECT_EQ(Count(svg, ">2 m<"), 1);
  EXPECT_EQ(Count(svg, ">x (m)<"), 1);
  EXPECT_EQ(Count(svg, ">y (m)<"), 1);
  EXPECT_EQ(Count(svg, "risk density (share per m\u00b2)"), 1);
}

// The valve labels carry the run table's Weight column (mission averages), not the final
// weights: P9 ends at 20/39 = 0.51 of the risk after the leak at 300 s, and averages ~0.28.
TEST(FieldPlot, ValveWeightsAreTheRunTables) {
  FieldPlotLayout layout;
  FieldPlotSvg(FleetField().Input(), &layout);
  const std::string table = FormatTable({FleetField().metrics});
  std::map<std::string, std::string> table_weight;
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string name, weight;
    if (words >> name >> weight && name.size() >= 2 && name[0] == 'P' && std::isdigit(name[1])) table_weight[name] = weight;
  }
  ASSERT_EQ(table_weight.size(), 20u) << table;
  int checked = 0;
  for (const FieldPlotLayout::Label& l : layout.labels) {
    const auto it = table_weight.find(l.owner);
    if (it == table_weight.end() || l.text.find(':') != std::string::npos) continue;
    EXPECT_EQ(l.text, l.owner + " " + it->second);
    ++checked;
  }
  EXPECT_EQ(checked, 20);
  EXPECT_NE(table_weight.at("P9"), "0.51");
  EXPECT_NEAR(std::stod(table_weight.at("P9")), 0.28, 0.03);
  EXPECT_NE(layout.caption[0].find("averaged over the mission"), std::string::npos);
}

// The events are where and when they happened: the risk change at P9 at 300 s, rov5 joining
// at 200 s where it was first seen, rov2 lost at 400 s where it was last seen; each marked and
// counted in the legend, and on the metric chart's time axis.
TEST(FieldPlot, EventsMarkedWhereAndWhenTheyHappened) {
  const std::vector<EventMarker> events = FleetField().record->Events();
  const auto find = [&](EventMarker::Kind kind, const std::string& who) -> const EventMarker* {
    for (const EventMarker& e : events)
      if (e.kind == kind && e.who == who) return &e;
    return nullptr;
  };
  const auto sample_of = [&](const std::string& name, bool last) {
    const Trajectory& t = FleetField().first_and_last;
    const std::size_t half = t.samples.size() / 2;
    for (std::size_t k = last ? half : 0; k < (last ? t.samples.size() : half); ++k)
      if (t.vehicle_names[t.samples[k].vehicle] == name) return t.samples[k];
    ADD_FAILURE() << "no sample of " << name;
    return TrajectorySample{};
  };
  const EventMarker* risk = find(EventMarker::Kind::kRisk, "P9");
  ASSERT_NE(risk, nullptr);
  EXPECT_NEAR(risk->time_s, 300.0, 0.11);
  EXPECT_NEAR(risk->share, 20.0 / 39.0, 1e-9);
  EXPECT_TRUE(risk->position_m.isApprox(FleetField().scenario.AllValves()[FleetField().scenario.ValveIndex("P9")].position_m));
  const EventMarker* join = find(EventMarker::Kind::kJoin, "rov5");
  ASSERT_NE(join, nullptr);
  EXPECT_NEAR(join->time_s, 200.0, 0.11);
  EXPECT_NEAR((join->position_m - sample_of("rov5", false).position_m).norm(), 0.0, 1e-9);
  const EventMarker* loss = find(EventMarker::Kind::kLoss, "rov2");
  ASSERT_NE(loss, nullptr);
  EXPECT_NEAR((loss->position_m - sample_of("rov2", true).position_m).norm(), 0.0, 1e-9);
  EXPECT_EQ(find(EventMarker::Kind::kJoin, "rov1"), nullptr) << "the initial fleet's joins are its starts";

  const std::string svg = FieldPlotSvg(FleetField().Input());
  EXPECT_EQ(Count(svg, ">risk change (1)<"), 1);
  EXPECT_EQ(Count(svg, ">vehicle joined (1)<"), 1);
  EXPECT_EQ(Count(svg, ">vehicle lost (1)<"), 1);
  const std::string metric = MetricChartSvg(FleetField().Input());
  EXPECT_EQ(Count(metric, "stroke-dasharray=\"4 3\""), 3);
  EXPECT_EQ(Count(metric, "P9 \u2192 0.51"), 1);
  EXPECT_EQ(Count(metric, "class=\"resumed\""), 0);
  // A resumed mission's chart marks where it resumed (a record's "resumed" event, as the plot
  // record keeps it), and says what the line is.
  PlotRecord record(FleetField().scenario);
  record.OnFleetEvent({412.5, "outage", -1, "", "no server for 3.0 s of wall time"});
  record.OnFleetEvent({412.5, "resumed", -1, "", "from the checkpoint at t = 412.5 s"});
  ASSERT_EQ(record.resumed_at_s(), std::vector<double>{412.5});
  EXPECT_TRUE(record.Events().empty()) << "a resume is a time, not a place on the field";
  MissionPlotInput resumed = FleetField().Input();
  resumed.resumed_at_s = record.resumed_at_s();
  const std::string chart = MetricChartSvg(resumed);
  EXPECT_EQ(Count(chart, "class=\"resumed\""), 1);
  EXPECT_EQ(Count(chart, ">resumed at 412.5 s<"), 1);
  EXPECT_NE(chart.find("Solid purple line: the mission resumed from its checkpoint"), std::string::npos);
}

// Up to 12 vehicles every track has its legend entry; above, the fleet's time as density,
// three highlighted tracks and the count. 1,000 vehicles make a figure of the same size.
TEST(FieldPlot, DensityAboveTwelveVehiclesWithTheCount) {
  const auto fleet = [&](int vehicles) {
    Trajectory t;
    for (int v = 0; v < vehicles; ++v) {
      t.vehicle_names.push_back(fmt::format("rov{}", v + 1));
      for (int k = 0; k < 20; ++k) {
        const double a = 0.3 * k + v;
        t.samples.push_back({k * 1.0, v, Eigen::Vector2d(6.0 + 4.0 * std::cos(a), 4.75 + 3.5 * std::sin(a))});
      }
    }
    return t;
  };
  const auto draw = [&](int vehicles, FieldPlotLayout& layout) {
    const Trajectory t = fleet(vehicles);
    MissionPlotInput input = FleetField().Input();
    input.trajectory = &t;
    return FieldPlotSvg(input, &layout);
  };
  FieldPlotLayout twelve, thirteen, thousand;
  const std::string svg12 = draw(12, twelve);
  EXPECT_FALSE(twelve.density);
  EXPECT_EQ(twelve.highlighted.size(), 12u);
  EXPECT_EQ(Count(svg12, ">rov12</text>"), 1);  // its legend entry
  draw(13, thirteen);
  EXPECT_TRUE(thirteen.density);
  const std::string svg = draw(1000, thousand);
  EXPECT_TRUE(thousand.density);
  EXPECT_EQ(thousand.vehicles, 1000);
  EXPECT_EQ(thousand.highlighted.size(), 3u);
  EXPECT_EQ(Count(svg, "1,000 vehicles; 3 tracks shown"), 1);
  EXPECT_EQ(Count(svg, "</polyline>"), 3);  // the three tracks, each on a white halo, in none of the density's blues
  EXPECT_EQ(Count(svg, "<polyline fill=\"none\" stroke=\"white\" stroke-width=\"3.6\""), 3);
  EXPECT_EQ(Count(svg, "stroke=\"#1f77b4\""), 0);
  EXPECT_EQ(Count(svg12, "stroke=\"white\" stroke-width=\"3.6\""), 0);  // twelve tracks, no density: no halo
  EXPECT_EQ(Count(svg, "fleet time (vehicle-s per m\u00b2)"), 1);
  EXPECT_LE(Attribute(svg, "height"), Attribute(svg12, "height") + 20.0);
  EXPECT_LE(Attribute(svg, "width"), 1000.0);
}

// Fields of any shape give figures of sane size: 500 m wide or 300 m tall, at most ~1,000 px.
TEST(FieldPlot, SizesStaySaneForAnyField) {
  for (const auto& [w, h] : {std::pair{500.0, 9.5}, std::pair{12.0, 300.0}, std::pair{2000.0, 2000.0}}) {
    maps::Scenario s = FleetField().scenario;
    s.workspace = {w, h};
    MissionPlotInput input = FleetField().Input();
    input.scenario = &s;
    const std::string svg = FieldPlotSvg(input);
    EXPECT_LE(Attribute(svg, "width"), 1000.0) << w << " x " << h;
    EXPECT_LE(Attribute(svg, "height"), 1100.0) << w << " x " << h;
    EXPECT_GE(Attribute(svg, "width"), 600.0) << w << " x " << h;
  }
}

// The six files: each PNG decodes at its SVG's size; in plot.png the pixels inside an XT's
// footprint (clear of its name) have the footprint's colour, #404040.
TEST(FieldPlot, PngsDecodeWithTheXtsInTheirColour) {
  const std::vector<PlotFile> files = MissionPlotFiles(FleetField().Input());
  ASSERT_EQ(files.size(), 6u);
  std::map<std::string, std::string> by_name;
  for (const PlotFile& f : files) by_name[f.name] = f.bytes;
  for (const char* chart : {"plot", "metric", "revisits"}) {
    const std::string& svg = by_name.at(std::string(chart) + ".svg");
    const std::string& png = by_name.at(std::string(chart) + ".png");
    ASSERT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << chart;
    const RgbaImage image = DecodePng(png);
    EXPECT_EQ(image.width, static_cast<int>(std::lround(Attribute(svg, "width")))) << chart;
    EXPECT_EQ(image.height, static_cast<int>(std::lround(Attribute(svg, "height")))) << chart;
  }
  FieldPlotLayout layout;
  FieldPlotSvg(FleetField().Input(), &layout);
  const RgbaImage plot = DecodePng(by_name.at("plot.png"));
  for (const Box& xt : layout.structures) {
    for (const auto& [x, y] : {std::pair{xt.x0 + 3.0, xt.y0 + 3.0}, std::pair{xt.x1 - 3.0, xt.y1 - 3.0}}) {
      const std::uint8_t* p = plot.At(static_cast<int>(x), static_cast<int>(y));
      EXPECT_EQ(fmt::format("#{:02x}{:02x}{:02x}", p[0], p[1], p[2]), "#404040") << x << "," << y;
    }
  }
}

// revisits.svg: valves sorted by longest gap, each with the run table's weight as the table prints
// it (a light valve's 0.0028 had read 0.00 on every label of a 350-valve field).
TEST(FieldPlot, RevisitChartSortedByLongestGap) {
  MissionMetrics metrics = FleetField().metrics;
  metrics.valves.front().weight = 0.0028;
  MissionPlotInput input = FleetField().Input();
  input.metrics = &metrics;
  const std::string svg = RevisitChartSvg(input);
  EXPECT_NE(svg.find(" 0.0028<"), std::string::npos);
  EXPECT_NE(FormatTable({metrics}).find(" 0.0028 "), std::string::npos) << "the table prints it so too";
  std::vector<const ValveMetrics*> sorted;
  for (const ValveMetrics& v : metrics.valves) sorted.push_back(&v);
  std::stable_sort(sorted.begin(), sorted.end(), [](auto* a, auto* b) { return a->longest_unwatched_s > b->longest_unwatched_s; });
  std::size_t at = 0;
  for (std::size_t r = 0; r < sorted.size(); ++r) {
    const std::string text = fmt::format(">{} {}<", sorted[r]->name, WeightText(sorted[r]->weight));
    const std::size_t found = svg.find(fmt::format("id=\"valve-{}\"", r));
    ASSERT_NE(found, std::string::npos) << r;
    EXPECT_EQ(svg.find(text, found), svg.find('>', found)) << text;
    EXPECT_GT(found, at);
    at = found;
  }
}

// A crowded field (a generated 100-XT, 350-valve field): only the 40 heaviest valves are tried,
// first; an XT is named only inside its footprint (none beside it with a leader line); the
// labels still keep clear of each other, the XTs and the valve dots; the caption says so.
TEST(FieldPlot, CrowdedFieldLabelsTheHeaviestValves) {
  maps::FieldOptions options;
  options.xts = 100;
  options.valves = 350;
  options.vehicles = 4;
  const maps::Scenario field = maps::GenerateField(options);
  const std::vector<maps::Valve> valves = field.AllValves();
  MissionMetrics metrics;
  Trajectory trajectory;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    ValveMetrics v;
    v.name = valves[i].name;
    v.weight = 0.001 + 1e-5 * static_cast<double>((i * 37) % 350);  // distinct, in no order of the index
    metrics.valves.push_back(v);
  }
  for (int v = 0; v < 4; ++v) {
    trajectory.vehicle_names.push_back(fmt::format("rov{}", v + 1));
    trajectory.samples.push_back({0.0, v, field.vehicles[v].start_m});
  }
  std::vector<std::pair<double, std::string>> by_weight;
  for (const ValveMetrics& v : metrics.valves) by_weight.emplace_back(-v.weight, v.name);
  std::sort(by_weight.begin(), by_weight.end());
  std::set<std::string> heaviest;
  for (std::size_t k = 0; k < 40; ++k) heaviest.insert(by_weight[k].second);

  FieldPlotLayout layout;
  const std::string svg = FieldPlotSvg({&field, &metrics, &trajectory, {}, 0, "crowded"}, &layout);
  int valve_labels = 0;
  for (std::size_t i = 0; i < layout.labels.size(); ++i) {
    const FieldPlotLayout::Label& a = layout.labels[i];
    if (a.owner.rfind("XT-", 0) == 0) {
      EXPECT_TRUE(a.inside_owner) << a.text;
    } else {
      EXPECT_TRUE(heaviest.count(a.owner)) << a.text;
      ++valve_labels;
    }
    for (std::size_t j = i + 1; j < layout.labels.size(); ++j) EXPECT_FALSE(a.box.Overlaps(layout.labels[j].box));
    for (const Box& dot : layout.valve_markers) EXPECT_FALSE(a.box.Overlaps(dot));
    if (!a.inside_owner) {
      for (const Box& xt : layout.structures) EXPECT_FALSE(a.box.Overlaps(xt)) << a.text;
    }
  }
  EXPECT_GT(valve_labels, 10);
  EXPECT_EQ(Count(svg, "Of 350 valves, the 40 of highest weight are labelled"), 1);
}

// The scenario's hidden leaks (which the server never knew) are drawn as red crosses with their
// onsets, in the legend and the caption; the onset labels keep clear of the others like any
// label; in plot.png the cross's centre is the leak's red.
TEST(FieldPlot, HiddenLeaksAsRedCrossesWithTheirOnsets) {
  maps::Scenario s = FleetField().scenario;
  maps::LeakSpec at_valve, on_seabed;
  at_valve.valve = "P9";
  at_valve.start_s = 300.0;
  on_seabed.point_m = {4.2, 3.0};
  on_seabed.start_s = 150.0;
  s.leaks = {on_seabed, at_valve};
  MissionPlotInput input = FleetField().Input();
  input.scenario = &s;
  FieldPlotLayout layout;
  const std::string svg = FieldPlotSvg(input, &layout);
  EXPECT_EQ(Count(svg, "stroke=\"#dd0000\" stroke-width=\"3\""), 3);  // two crosses and the legend's
  EXPECT_EQ(Count(svg, ">hidden leak (onset)<"), 1);
  EXPECT_EQ(Count(svg, "2 hidden leaks with their onsets"), 1);
  int onsets = 0;
  for (std::size_t i = 0; i < layout.labels.size(); ++i) {
    const FieldPlotLayout::Label& a = layout.labels[i];
    if (a.text == "leak from 150 s" || a.text == "leak from 300 s") ++onsets;
    for (std::size_t j = i + 1; j < layout.labels.size(); ++j) EXPECT_FALSE(a.box.Overlaps(layout.labels[j].box)) << a.text;
  }
  EXPECT_EQ(onsets, 2);
  const RgbaImage png = DecodePng(SvgToPng(svg));
  const double x = layout.map.x0 + 4.2 * layout.px_per_m, y = layout.map.y1 - 3.0 * layout.px_per_m;
  const std::uint8_t* p = png.At(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)));
  EXPECT_GT(p[0], 180) << int(p[0]) << "," << int(p[1]) << "," << int(p[2]);
  EXPECT_LT(p[1], 80);
  EXPECT_LT(p[2], 80);
}

// The record's copy stays within its budget however many vehicles and cycles: 10,000 vehicles
// for 100 cycles into 20,000 samples, thinned evenly (every vehicle kept at the same cycles).
TEST(PlotRecord, StaysWithinItsBudget) {
  maps::Scenario s = FleetField().scenario;
  PlotRecord record(s, 20000, 10);
  for (int cycle = 0; cycle < 100; ++cycle) {
    for (int v = 0; v < 10000; ++v) record.OnSample({cycle / s.control_rate_hz, v, Eigen::Vector2d(1, 1)}, fmt::format("v{}", v));
  }
  EXPECT_LE(record.trajectory().samples.size(), 20000u);
  EXPECT_GE(record.trajectory().samples.size(), 10000u);
  std::map<double, int> per_time;
  for (const TrajectorySample& t : record.trajectory().samples) ++per_time[t.time_s];
  for (const auto& [t, n] : per_time) EXPECT_EQ(n, 10000) << t;
  for (int k = 0; k < 15; ++k) record.OnRiskEvent({1.0 * k, "P1", 2.0, 0.1, "operator"});
  EXPECT_EQ(record.Events().size(), 10u);
  EXPECT_EQ(record.events_not_kept(), 5u);
}

}  // namespace
}  // namespace sage::server::plots
