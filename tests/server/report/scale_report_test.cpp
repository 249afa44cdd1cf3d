// scale.json, scale.md and scale.svg of sage bench scale, and the figures read back from a run's
// metrics.json: the keys a reader relies on, null for what was not measured, a row that survives
// the trip through JSON (the in-process runs hand their rows back that way), one table row per
// run with ergodic before tours, and a plot with a line per controller and transport.
#include "server/report/scale_report.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/report/report.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

ScaleRow Row(int vehicles, const std::string& transport, const std::string& controller, double rtf, double cycle_ms) {
  ScaleRow r;
  r.vehicles = vehicles;
  r.transport = transport;
  r.controller = controller;
  r.assignment = controller == "astar" ? "tours" : "regions";
  r.real_time_factor = rtf;
  r.server_cycle_mean_ms = cycle_ms;
  r.server_cycle_p99_ms = 2 * cycle_ms;
  r.server_cycle_max_ms = 3 * cycle_ms;
  r.cpu_s_per_vehicle_s = 3e-4;
  if (transport == "inproc") {  // the second half is measured in-process only
    r.real_time_factor_late = 2.0 * rtf;
    r.cpu_s_per_vehicle_s_late = 2e-4;
  }
  r.peak_rss_mb = 40.0;
  r.unvisited_valves = 2;
  r.longest_gap_median_s = 20.0;
  r.longest_gap_p90_s = 30.0;
  r.longest_gap_max_s = 60.0;
  r.risk_weighted_interval_s = 14.0;
  r.expected_detection_delay_s = 6.0;
  r.dominant_interval_s = 10.0;
  r.visit_weight_correlation = 0.4;
  r.all_moved_after_s = 0.3;
  r.vehicles_never_moved = 0;
  if (transport == "dds") {
    r.dds_samples_per_s = 1500.0;
    r.dds_bytes_per_s = 2.1e6;
    r.server_peak_rss_mb = 49.0;
    r.agent_host_peak_rss_mb = 52.0;
    r.agent_hosts = 1;
  }
  return r;
}

// Every key the brief names is there, with its unit in its name; what was not measured is null.
TEST(ScaleJson, KeysAndNulls) {
  const nlohmann::json j = nlohmann::json::parse(ScaleJson({Row(100, "inproc", "ergodic", 109.4, 0.54)}));
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 1u);
  const nlohmann::json& r = j[0];
  for (const char* key :
       {"vehicles", "transport", "controller", "real_time_factor", "server_cycle_mean_ms", "server_cycle_p99_ms",
        "server_cycle_max_ms", "cpu_s_per_vehicle_s", "peak_rss_mb", "server_peak_rss_mb", "agent_host_peak_rss_mb",
        "dds_samples_per_s", "dds_bytes_per_s", "all_moved_after_s", "unvisited_valves", "longest_gap_median_s",
        "longest_gap_p90_s", "longest_gap_max_s", "risk_weighted_interval_s", "expected_detection_delay_s",
        "dominant_interval_s", "visit_weight_correlation"}) {
    EXPECT_TRUE(r.contains(key)) << key;
  }
  EXPECT_EQ(r["vehicles"], 100);
  EXPECT_EQ(r["transport"], "inproc");
  EXPECT_EQ(r["controller"], "ergodic");
  EXPECT_DOUBLE_EQ(r["real_time_factor"].get<double>(), 109.4);
  EXPECT_TRUE(r["dds_samples_per_s"].is_null());  // not measured in-process
  EXPECT_TRUE(r["agent_hosts"].is_null());
  EXPECT_EQ(r["vehicles_never_moved"], 0);  // zero is a count, not "not measured"
}

// A row comes back from its JSON exactly (doubles print round-trip), NaN as NaN, -1 as -1.
TEST(ScaleRowJson, RoundTrips) {
  ScaleRow row = Row(1000, "dds", "astar", 0.987654321, 29.17);
  row.note = "the launch exited with status 3 (see \"x.log\")";
  row.cpu_s = 1.0 / 3.0;
  const ScaleRow back = ParseScaleRowJson(ScaleRowJson(row));
  EXPECT_EQ(ScaleRowJson(back), ScaleRowJson(row));
  EXPECT_EQ(back.real_time_factor, row.real_time_factor);
  EXPECT_EQ(back.cpu_s, 1.0 / 3.0);
  EXPECT_EQ(back.note, row.note);
  EXPECT_TRUE(std::isnan(back.setup_wall_s));
  EXPECT_EQ(ScaleRowJson(ParseScaleRowJson(ScaleRowJson(ScaleRow{}))), ScaleRowJson(ScaleRow{}));
  EXPECT_EQ(ParseScaleRowJson(ScaleRowJson(ScaleRow{})).agent_hosts, -1);
  EXPECT_THROW(ParseScaleRowJson("error: out of memory"), maps::ScenarioError);
  EXPECT_THROW(ParseScaleRowJson("{\"vehicles\": 3}"), maps::ScenarioError);  // keys missing
}

// One table row per run, sorted by N, in-process before DDS, ergodic right above the tours of
// the same N and transport; unmeasured cells are "-".
TEST(ScaleTable, OneRowPerRunErgodicNextToTours) {
  const std::vector<ScaleRow> rows = {Row(10, "dds", "astar", 1.0, 0.24),    Row(1, "inproc", "astar", 4756, 0.009),
                                      Row(10, "inproc", "ergodic", 1315, 0.045), Row(10, "dds", "ergodic", 1.0, 0.26),
                                      Row(1, "inproc", "ergodic", 15308, 0.001), Row(10, "inproc", "astar", 1318, 0.04)};
  const std::string table = ScaleTable(rows);
  std::vector<std::string> lines;  // the table's (the terminal's text goes on with the CPU against N = 1)
  std::istringstream in(table);
  for (std::string line; std::getline(in, line) && line.rfind("|", 0) == 0;) lines.push_back(line);
  ASSERT_EQ(lines.size(), 2 + rows.size());
  const std::vector<std::string> expected = {"| 1 | inproc | ergodic",  "| 1 | inproc | A* tours", "| 10 | inproc | ergodic",
                                             "| 10 | inproc | A* tours", "| 10 | dds | ergodic",    "| 10 | dds | A* tours"};
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(lines[2 + i].rfind(expected[i], 0), 0u) << lines[2 + i];
  const auto columns = [](const std::string& line) { return std::count(line.begin(), line.end(), '|'); };
  for (const std::string& line : lines) EXPECT_EQ(columns(line), columns(lines[0])) << line;
  EXPECT_NE(lines[2].find("| - |"), std::string::npos);  // in-process: no DDS column
  EXPECT_NE(lines[6].find("1,500/s, 2.10 MB/s"), std::string::npos) << lines[6];
  EXPECT_NE(lines[2].find("| 15308x (30616x) |"), std::string::npos) << lines[2];  // the second half in brackets
  EXPECT_NE(lines[2].find("| 0.300 ms (0.200 ms) |"), std::string::npos) << lines[2];
  EXPECT_NE(lines[6].find("| 1.00x |"), std::string::npos) << lines[6];  // over DDS: none
  // Two valves never visited: the risk-weighted interval is a floor, marked and explained as in
  // sage run's table; with every valve visited it is not.
  EXPECT_NE(lines[2].find("| >= 14.0 s |"), std::string::npos) << lines[2];
  EXPECT_NE(table.find("\n(>=: some valve was never visited;"), std::string::npos) << table;
  std::vector<ScaleRow> all_seen = rows;
  for (ScaleRow& r : all_seen) r.unvisited_valves = 0;
  EXPECT_EQ(ScaleTable(all_seen).find(">="), std::string::npos);
  // A mean above the p99 (one long first cycle) is explained under the table, only then.
  EXPECT_EQ(table.find("mean above its p99"), std::string::npos) << table;
  std::vector<ScaleRow> long_first = rows;
  long_first[0].server_cycle_mean_ms = 0.124;
  long_first[0].server_cycle_p99_ms = 0.036;
  long_first[0].server_cycle_max_ms = 35.0;
  EXPECT_NE(ScaleTable(long_first).find("\nA server cycle's mean above its p99 is a few long cycles carrying the mean"),
            std::string::npos);
  long_first[0].server_cycle_mean_ms = 0.0362;  // shown as 0.036, as the p99
  EXPECT_EQ(ScaleTable(long_first).find("mean above its p99"), std::string::npos);
  const std::string md = ScaleMarkdown(rows, "Command: `sage bench scale`.");
  EXPECT_NE(md.find("Command: `sage bench scale`."), std::string::npos);
  EXPECT_NE(md.find(table), std::string::npos);
}

// Repetitions: the table keeps one row per N, transport and controller, the run with the median
// real-time factor (a failed run counting as slowest; of two, the slower); every run is listed in
// run order; and the CPU per vehicle-second against the smallest fleet is the ratio of the runs'
// medians, computed here by hand.
TEST(ScaleSpread, MedianRunInTheTableEveryRunListed) {
  std::vector<ScaleRow> rows;
  const auto add = [&](int n, const std::string& controller, int run, double rtf, double cpu_ms) {
    ScaleRow r = Row(n, "inproc", controller, rtf, 1.0);
    r.run = run;
    r.cpu_s_per_vehicle_s = cpu_ms * 1e-3;
    rows.push_back(r);
  };
  // Round by round, as the bench runs them.
  add(100, "ergodic", 1, 180.0, 0.061);
  add(10000, "ergodic", 1, 1.84, 0.097);
  add(10000, "astar", 1, 2.65, 0.065);
  add(100, "ergodic", 2, 150.0, 0.055);
  add(10000, "ergodic", 2, ScaleRow::kNaN, 0.120);  // failed
  add(10000, "astar", 2, 2.40, 0.070);
  add(100, "ergodic", 3, 200.0, 0.058);
  add(10000, "ergodic", 3, 2.21, 0.080);

  const std::vector<ScaleRow> median = MedianRuns(rows);
  ASSERT_EQ(median.size(), 3u);
  EXPECT_EQ(median[0].vehicles, 100);
  EXPECT_EQ(median[0].run, 1);  // 150 < 180 < 200
  EXPECT_EQ(median[1].controller, "ergodic");
  EXPECT_EQ(median[1].run, 1);  // failed < 1.84 < 2.21
  EXPECT_EQ(median[2].controller, "astar");
  EXPECT_EQ(median[2].run, 2);  // two runs: the slower, 2.40
  EXPECT_EQ(MedianRuns({rows[1]}).front().run, 1);

  const std::string table = ScaleTable(rows);
  EXPECT_NE(table.find("| 10,000 | inproc | ergodic (regions) | 1.84x"), std::string::npos) << table;
  EXPECT_EQ(table.find("| 2.21x"), std::string::npos) << table;  // not the median: listed below only
  const std::string spread = ScaleSpread(rows);
  EXPECT_NE(spread.find("10,000 inproc, ergodic (regions): 3 runs, real-time factor 1.84x / - / 2.21x; CPU per "
                        "vehicle-s 0.097 / 0.120 / 0.080 ms"),
            std::string::npos)
      << spread;
  EXPECT_NE(spread.find("10,000 inproc, A* tours: 2 runs"), std::string::npos) << spread;
  // Medians by hand: ergodic 0.058 at 100 (0.055, 0.058, 0.061) and 0.097 at 10,000 (0.080, 0.097, 0.120).
  const std::string ratio = fmt::format("{:.2f}x that at 10,000", 0.097 / 0.058);
  EXPECT_NE(spread.find("- inproc, ergodic (regions): 0.058 ms at 100; " + ratio), std::string::npos) << spread;
  EXPECT_EQ(spread.find("- inproc, A* tours:"), std::string::npos) << spread;  // one size only: no ratio
  EXPECT_NE(ScaleMarkdown(rows).find(spread), std::string::npos);
  // One run of one size: nothing to say.
  EXPECT_EQ(ScaleSpread({rows[0]}), "");

  // The run survives JSON; rows written before --repeat read as run 1.
  EXPECT_EQ(ParseScaleRowJson(ScaleRowJson(rows[4])).run, 2);
  nlohmann::json old = nlohmann::json::parse(ScaleRowJson(rows[4]));
  old.erase("run");
  EXPECT_EQ(ParseScaleRowJson(old.dump()).run, 1);
}

// Four lines in each of the two panels (2 controllers x 2 transports), dashed over DDS, the
// decades of N labelled, the real-time line drawn; rows with no figure leave no point.
TEST(ScaleSvg, LinePerControllerAndTransport) {
  std::vector<ScaleRow> rows;
  for (int n : {1, 10, 100, 1000}) {
    rows.push_back(Row(n, "inproc", "ergodic", 15000.0 / n, 0.001 * n));
    rows.push_back(Row(n, "inproc", "astar", 5000.0 / n, 0.002 * n));
    rows.push_back(Row(n, "dds", "ergodic", 1.0, 0.2 * n));
    rows.push_back(Row(n, "dds", "astar", 1.0, 0.1 * n));
  }
  ScaleRow failed = Row(10000, "inproc", "ergodic", ScaleRow::kNaN, ScaleRow::kNaN);
  rows.push_back(failed);
  const std::string svg = ScaleSvg(rows);
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = svg.find(what); at != std::string::npos; at = svg.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(count("<polyline"), 8u);
  EXPECT_EQ(count("<polyline fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"2\" stroke-dasharray"), 2u);  // ergodic, DDS
  EXPECT_EQ(count("real time</text>"), 1u);
  for (const char* label : {">1<", ">10<", ">100<", ">1,000<", ">10,000<"}) EXPECT_GT(count(label), 0u) << label;
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(count("over DDS</text>"), 2u);
  EXPECT_EQ(count("in-process</text>"), 2u);
  // An in-process bench's legend names only its own lines.
  std::vector<ScaleRow> inproc;
  for (const ScaleRow& r : rows)
    if (r.transport == "inproc") inproc.push_back(r);
  const std::string only = ScaleSvg(inproc);
  EXPECT_EQ(only.find("over DDS</text>"), std::string::npos);
  EXPECT_NE(only.find("ergodic, in-process</text>"), std::string::npos);
  EXPECT_NE(only.find("A* tours, in-process</text>"), std::string::npos);
}

// ReadMetricsSummary reads back what MetricsJson writes; a file without the fleet figures is a
// one-line error naming it.
TEST(ReadMetricsSummary, ReadsWhatMetricsJsonWrites) {
  std::string pattern = (fs::temp_directory_path() / "sage_scale_report_test_XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const fs::path dir = pattern;
  MissionMetrics m;
  m.controller = "ergodic";
  m.profile = "graded";
  m.duration_s = 60.0;
  m.vehicle_count = 10;
  m.visit_weight_correlation = std::numeric_limits<double>::quiet_NaN();
  m.expected_detection_delay_s = 6.5;
  m.risk_weighted_interval_s = 14.25;
  m.dominant_interval_s = 8.5;
  m.unvisited_valves = 3;
  m.longest_gap_median_s = 21.0;
  m.longest_gap_p90_s = 29.5;
  m.longest_gap_max_s = 60.0;
  WriteMetricsJson((dir / "metrics.json").string(), m);
  const MissionMetrics back = ReadMetricsSummary((dir / "metrics.json").string());
  EXPECT_EQ(back.controller, "ergodic");
  EXPECT_EQ(back.vehicle_count, 10);
  EXPECT_TRUE(std::isnan(back.visit_weight_correlation));
  EXPECT_EQ(back.expected_detection_delay_s, 6.5);
  EXPECT_EQ(back.risk_weighted_interval_s, 14.25);
  EXPECT_EQ(back.dominant_interval_s, 8.5);
  EXPECT_EQ(back.unvisited_valves, 3);
  EXPECT_EQ(back.longest_gap_median_s, 21.0);
  EXPECT_EQ(back.longest_gap_p90_s, 29.5);
  EXPECT_EQ(back.longest_gap_max_s, 60.0);
  std::ofstream(dir / "old.json") << "{\"controller\": \"ergodic\"}";
  try {
    ReadMetricsSummary((dir / "old.json").string());
    ADD_FAILURE() << "read a metrics.json without its figures";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("old.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadMetricsSummary((dir / "missing.json").string()), maps::ScenarioError);
  fs::remove_all(dir);
}

// The three files are written where asked, scale.json parseable.
TEST(WriteScaleReport, WritesTheThreeFiles) {
  std::string pattern = (fs::temp_directory_path() / "sage_scale_report_test_XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const fs::path dir = pattern;
  WriteScaleReport(dir.string(), {Row(1, "inproc", "ergodic", 100.0, 0.1)}, "preamble");
  for (const char* name : {"scale.json", "scale.md", "scale.svg"}) EXPECT_TRUE(fs::exists(dir / name)) << name;
  std::ifstream in(dir / "scale.json");
  EXPECT_EQ(nlohmann::json::parse(in).size(), 1u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sage::server
