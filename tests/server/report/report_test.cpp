#include "server/report/report.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace sage::server {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test for the files written.
class ReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "sage_report_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string WriteText(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name)) << text;
    return Path(name);
  }
  static std::string ReadText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
  }
  // The ScenarioError message of reading `text` as a CSV (empty if it reads fine).
  std::string ReadError(const std::string& text) const {
    const std::string path = WriteText("bad.csv", text);
    try {
      ReadTrajectoryCsv(path);
    } catch (const maps::ScenarioError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

Trajectory TwoVehicleTrajectory() {
  Trajectory trajectory;
  trajectory.vehicle_names = {"rov1", "rov2"};
  for (int k = 0; k < 50; ++k) {
    for (int v = 0; v < 2; ++v) {
      TrajectorySample s;
      s.time_s = k / 3.0;
      s.vehicle = v;
      s.position_m = {std::sin(k * 0.1) * 3.0 + 6.0, 1e-7 * k + v};
      s.heading_rad = -k / 7.0;
      s.velocity_mps = {1.0 / (k + 1), -2e-300};
      s.command_mps = {0.1 * v, 1.0 / 3.0};
      trajectory.samples.push_back(s);
    }
  }
  return trajectory;
}

void ExpectSameSamples(const Trajectory& a, const Trajectory& b) {
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    const TrajectorySample &x = a.samples[i], &y = b.samples[i];
    EXPECT_NEAR(x.time_s, y.time_s, 1e-9);
    EXPECT_EQ(x.vehicle, y.vehicle);
    EXPECT_LE((x.position_m - y.position_m).norm(), 1e-9);
    EXPECT_NEAR(x.heading_rad, y.heading_rad, 1e-9);
    EXPECT_LE((x.velocity_mps - y.velocity_mps).norm(), 1e-9);
    EXPECT_LE((x.command_mps - y.command_mps).norm(), 1e-9);
  }
}

// Write then read gives the same samples (within 1e-9) and names; without names, integer ids.
TEST_F(ReportTest, CsvRoundTrip) {
  Trajectory named = TwoVehicleTrajectory();
  WriteTrajectoryCsv(Path("named.csv"), named);
  EXPECT_EQ(ReadText(Path("named.csv")).substr(0, 40), "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n");
  const Trajectory named_back = ReadTrajectoryCsv(Path("named.csv"));
  ExpectSameSamples(named, named_back);
  EXPECT_EQ(named_back.vehicle_names, named.vehicle_names);

  Trajectory ids = named;
  ids.vehicle_names.clear();
  WriteTrajectoryCsv(Path("ids.csv"), ids);
  const Trajectory ids_back = ReadTrajectoryCsv(Path("ids.csv"));
  ExpectSameSamples(ids, ids_back);
  EXPECT_TRUE(ids_back.vehicle_names.empty());
  EXPECT_FALSE(fs::exists(Path("ids.csv.tmp")));
}

// Columns in any order, extra columns ignored, optional ones default to 0, names numbered in
// order of first appearance, vehicles interleaved and sorted by (time, vehicle); CRLF, a BOM and
// blank lines pass.
TEST_F(ReportTest, CsvColumnsInAnyOrderAndVehicleNames) {
  const std::string path = WriteText("log.csv",
                                     "\xEF\xBB\xBF" "depth,y,x,vehicle,t\r\n"
                                     "7,2.5,1.5,rov_b,0.1\r\n"
                                     "whatever,5,6,rov_b,0.2\r\n"
                                     "\r\n"
                                     "7,3.5,4.5,rov_a,0.1\r\n");
  const Trajectory t = ReadTrajectoryCsv(path);
  ASSERT_EQ(t.samples.size(), 3u);
  EXPECT_EQ(t.vehicle_names, (std::vector<std::string>{"rov_b", "rov_a"}));
  EXPECT_EQ(t.samples[0].time_s, 0.1);
  EXPECT_EQ(t.samples[0].vehicle, 0);
  EXPECT_EQ(t.samples[0].position_m, Eigen::Vector2d(1.5, 2.5));
  EXPECT_EQ(t.samples[1].vehicle, 1);
  EXPECT_EQ(t.samples[1].position_m, Eigen::Vector2d(4.5, 3.5));
  EXPECT_EQ(t.samples[2].time_s, 0.2);
  EXPECT_EQ(t.samples[2].position_m, Eigen::Vector2d(6, 5));
  EXPECT_EQ(t.samples[2].heading_rad, 0.0);
  EXPECT_EQ(t.samples[2].command_mps, Eigen::Vector2d::Zero());
}

// Each malformed file gives one line naming the file (and the line where there is one).
TEST_F(ReportTest, CsvErrorsAreOneLineNamingFileAndLine) {
  const std::string file = Path("bad.csv");
  const std::string header = "t,vehicle,x,y\n";
  EXPECT_EQ(ReadError(""), file + ": empty file (need a header with t, vehicle, x, y)");
  // A log with no header: its first row is not taken for column names (it had read as a
  // duplicate column '0').
  EXPECT_EQ(ReadError("0,0,1,2\n0.1,0,1.1,2\n"),
            file + ":1: no header: the first line holds numbers (need a header line naming the columns, e.g. "
                   "t,vehicle,x,y)");
  EXPECT_EQ(ReadError("t,vehicle,y\n0,0,1\n"),
            file + ": missing column 'x' (need t, vehicle, x, y, comma-separated; its header reads 3 column(s): t, "
                   "vehicle, y)");
  // Another separator: the header as read says so.
  EXPECT_EQ(ReadError("t;vehicle;x;y\n0;0;1;1\n"),
            file + ": missing column 't' (need t, vehicle, x, y, comma-separated; its header reads 1 column(s): "
                   "t;vehicle;x;y)");
  EXPECT_EQ(ReadError(header + "0,0,1,2\n0.1,0,abc,2\n"), file + ":3: column 'x' = 'abc': not a number");
  EXPECT_EQ(ReadError(header + "0,0,,2\n"), file + ":2: column 'x' = '': not a number");
  EXPECT_EQ(ReadError(header + "0,0,1\n"), file + ":2: 3 fields, the header has 4");
  EXPECT_EQ(ReadError(header + "0,0,1,2,3\n"), file + ":2: 5 fields, the header has 4");
  EXPECT_EQ(ReadError(header + "inf,0,1,2\n"), file + ":2: column 't' = 'inf': not finite");
  // Mission time starts at 0 (a log from t = -5 had been scored as a 1 s mission).
  EXPECT_EQ(ReadError(header + "-5,0,1,2\n0,0,1,2\n"),
            file + ":2: column 't' = '-5': must be >= 0 (mission seconds from the start)");
  EXPECT_EQ(ReadError(header + "0,0,nan,2\n"), file + ":2: column 'x' = 'nan': not finite");
  EXPECT_EQ(ReadError(header + "0,0,1e999,2\n"), file + ":2: column 'x' = '1e999': not finite");
  EXPECT_EQ(ReadError(header + "0,-1,1,2\n"), file + ":2: column 'vehicle' = '-1': must be an id in 0..65535 or a name");
  EXPECT_EQ(ReadError("t,x,x,y,vehicle\n"), file + ":1: duplicate column 'x'");
  EXPECT_EQ(ReadError(header + "0,0,1,2\n"), "");
  EXPECT_EQ(ReadError(header + "+0.5,0,1e-400,5e-324\n"), "");  // a sign, an underflow, a subnormal
  // A vehicle's samples go forward in time; vehicles may interleave.
  EXPECT_EQ(ReadError(header + "0,0,1,2\n0.2,1,1,2\n0.1,1,1,2\n"),
            file + ":4: t = 0.1 for vehicle 1 is not after its previous sample (t = 0.2 on line 3)");
  EXPECT_EQ(ReadError(header + "0.5,rov1,1,2\n0.5,rov1,1,2\n"),
            file + ":3: t = 0.5 for vehicle rov1 is not after its previous sample (t = 0.5 on line 2)");
  EXPECT_EQ(ReadError(header + "0.1,a,1,2\n0,b,1,2\n0.2,a,1,2\n"), "");
  try {
    ReadTrajectoryCsv(Path("missing.csv"));
    FAIL() << "no error for a missing file";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(Path("missing.csv") + ": cannot read:", 0), 0u) << e.what();
  }
}

// A last line with no newline after it that does not read as a row is a record a crash cut
// short (trajectory.csv is appended as a mission runs): left out and flagged, the rows before it
// read. The same line with its newline, or a bad line before the last, is still an error; a
// whole last row without a newline is a row.
TEST_F(ReportTest, CsvLeavesOutALastLineCutShort) {
  const std::string header = "t,vehicle,x,y,heading\n";
  const std::string rows = "0,0,1,2,0.5\n0.1,0,1.5,2,0.5\n";
  const Trajectory cut = ReadTrajectoryCsv(WriteText("cut.csv", header + rows + "0.2,0,1.7"));
  EXPECT_TRUE(cut.cut_line);
  ASSERT_EQ(cut.samples.size(), 2u);
  EXPECT_EQ(cut.samples[1].position_m, Eigen::Vector2d(1.5, 2));
  const Trajectory whole = ReadTrajectoryCsv(WriteText("whole.csv", header + rows + "0.2,0,1.7,2.1,0.4"));
  EXPECT_FALSE(whole.cut_line);
  ASSERT_EQ(whole.samples.size(), 3u);
  EXPECT_EQ(whole.samples[2].position_m, Eigen::Vector2d(1.7, 2.1));
  EXPECT_FALSE(ReadTrajectoryCsv(WriteText("clean.csv", header + rows)).cut_line);
  const std::string file = Path("bad.csv");
  EXPECT_EQ(ReadError(header + rows + "0.2,0,1.7\n"), file + ":4: 3 fields, the header has 5");
  EXPECT_EQ(ReadError(header + "0,0,1\n" + "0.1,0,1.5,2,0.5"), file + ":2: 3 fields, the header has 5");
}

MissionMetrics SampleMetrics() {
  MissionMetrics m;
  m.controller = "ergodic";
  m.profile = "one_extreme";
  m.duration_s = 300.0;
  m.vehicle_count = 2;
  m.ergodic_metric = 1.25e-3;
  m.time_outside_s = 3.5;
  m.time_pinned_s = 1.25;
  m.metric_over_time = {{1.0, 0.5}, {2.0, 0.25}};
  ValveMetrics p1{"P1", 0.55, 3, 6.5, 8.0, 1.5, {2.0, 7.0, 15.0}};
  ValveMetrics p3{"P3", 0.10, 0, std::numeric_limits<double>::quiet_NaN(), 300.0, 0.0, {}};
  m.valves = {p1, p3};
  EventResponse leak;
  leak.time_s = 150.0;
  leak.valve = "P1";
  leak.new_weight = 0.56;
  leak.heading_change_rad = 0.7;
  leak.time_to_next_visit_s = 3.2;
  leak.interval_before_s = 12.0;
  leak.interval_after_s = std::numeric_limits<double>::quiet_NaN();
  m.events = {leak};
  return m;  // visit_weight_correlation stays NaN
}

// metrics.json parses back with every documented key and value; NaN is written as null.
TEST_F(ReportTest, MetricsJsonHasEveryKey) {
  WriteMetricsJson(Path("metrics.json"), SampleMetrics());
  EXPECT_FALSE(fs::exists(Path("metrics.json.tmp")));
  const nlohmann::json j = nlohmann::json::parse(ReadText(Path("metrics.json")));
  EXPECT_EQ(j.size(), 17u);
  EXPECT_EQ(j.at("controller"), "ergodic");
  EXPECT_TRUE(j.at("leaks").is_array() && j.at("leaks").empty()) << "no leak hidden, no sensors: an empty list";
  EXPECT_FALSE(j.contains("false_alarms"));
  for (const char* key : {"expected_detection_delay_s", "risk_weighted_interval_s", "dominant_interval_s"}) {
    EXPECT_TRUE(j.at(key).is_number()) << key;
  }
  EXPECT_EQ(j.at("unvisited_valves"), 0);
  EXPECT_EQ(j.at("longest_gap_s").size(), 3u);
  EXPECT_EQ(j.at("profile"), "one_extreme");
  EXPECT_EQ(j.at("duration_s"), 300.0);
  EXPECT_EQ(j.at("vehicle_count"), 2);
  EXPECT_TRUE(j.at("visit_weight_correlation").is_null());
  EXPECT_EQ(j.at("ergodic_metric"), 1.25e-3);
  EXPECT_EQ(j.at("time_outside_s"), 3.5);
  EXPECT_EQ(j.at("time_pinned_s"), 1.25);
  ASSERT_EQ(j.at("metric_over_time").size(), 2u);
  EXPECT_EQ(j.at("metric_over_time")[1].at("t"), 2.0);
  EXPECT_EQ(j.at("metric_over_time")[1].at("ergodic_metric"), 0.25);
  ASSERT_EQ(j.at("valves").size(), 2u);
  const nlohmann::json& p1 = j.at("valves")[0];
  EXPECT_EQ(p1.size(), 8u);
  EXPECT_TRUE(p1.at("longest_unwatched_s").is_number());
  EXPECT_EQ(p1.at("name"), "P1");
  EXPECT_EQ(p1.at("weight"), 0.55);
  EXPECT_EQ(p1.at("visits"), 3);
  EXPECT_EQ(p1.at("mean_interval_s"), 6.5);
  EXPECT_EQ(p1.at("max_gap_s"), 8.0);
  EXPECT_EQ(p1.at("time_near_s"), 1.5);
  EXPECT_EQ(p1.at("visit_times_s"), nlohmann::json({2.0, 7.0, 15.0}));
  EXPECT_TRUE(j.at("valves")[1].at("mean_interval_s").is_null());
  EXPECT_TRUE(j.at("valves")[1].at("visit_times_s").empty());
  ASSERT_EQ(j.at("events").size(), 1u);
  const nlohmann::json& leak = j.at("events")[0];
  EXPECT_EQ(leak.size(), 7u);
  EXPECT_EQ(leak.at("valve"), "P1");
  EXPECT_EQ(leak.at("time_s"), 150.0);
  EXPECT_EQ(leak.at("heading_change_rad"), 0.7);
  EXPECT_EQ(leak.at("time_to_next_visit_s"), 3.2);
  EXPECT_TRUE(leak.at("interval_after_s").is_null());
}

// A path that cannot be written throws std::runtime_error naming it, and leaves no file behind.
TEST_F(ReportTest, UnwritablePathThrowsNamingIt) {
  const std::string path = Path("no_such_dir/metrics.json");
  try {
    WriteMetricsJson(path, SampleMetrics());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot write: No such file or directory");
  }
}

// A run directory is made (with its parents) and proven writable before a mission runs; a file
// in the way is one error naming the option and the path, and nothing is left behind.
TEST_F(ReportTest, RunDirectoryIsPreparedOrRefusedUpFront) {
  const std::string nested = Path("runs/a/b");
  PrepareRunDirectory(nested);
  EXPECT_TRUE(fs::is_directory(nested));
  EXPECT_TRUE(fs::is_empty(nested)) << "the write probe was left behind";
  const std::string blocked = WriteText("a_file", "x") + "/run";
  try {
    PrepareRunDirectory(blocked);
    FAIL() << "no error";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--out = " + blocked + ": cannot write there: ", 0), 0u) << e.what();
  }
  // The same said by the check every command makes before its work (evaluate had scored a record
  // first), naming the file in the way; a directory to be made under one that exists passes.
  try {
    CheckOutDirectory(blocked + "/deeper");
    FAIL() << "no error";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()), "--out = " + blocked + "/deeper: cannot write there: " +
                                         fs::absolute(Path("a_file")).lexically_normal().string() + " is not a directory");
  }
  EXPECT_NO_THROW(CheckOutDirectory(Path("runs/new/deeper")));
}

// An --out of the user's own files is refused before anything is written (a scenario run with
// `-o .` from its folder had been replaced by the run's copy); a new, empty or earlier run's
// directory takes the run.
TEST_F(ReportTest, OutDirectoryOfOtherFilesIsRefused) {
  EXPECT_NO_THROW(CheckOutDirectory(Path("absent/run")));
  fs::create_directories(Path("empty"));
  EXPECT_NO_THROW(CheckOutDirectory(Path("empty")));
  fs::create_directories(Path("earlier"));
  WriteText("earlier/scenario.yaml", "name: x\n");
  WriteText("earlier/metrics.json", "{}");
  EXPECT_NO_THROW(CheckOutDirectory(Path("earlier")));
  fs::create_directories(Path("compared/ergodic"));
  WriteText("compared/ergodic/metrics.json", "{}");
  EXPECT_NO_THROW(CheckOutDirectory(Path("compared")));
  fs::create_directories(Path("field"));
  WriteText("field/scenario.yaml", "name: mine\n");
  WriteText("field/bathymetry.xyz", "0 0 -100\n");
  try {
    CheckOutDirectory(Path("field"), "-o");
    FAIL() << "no error";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("-o = " + Path("field") + ": holds files that are not a run's (bathymetry.xyz "
                                          "and 1 more); ",
                                          0),
              0u)
        << e.what();
  }
  EXPECT_EQ(ReadText(Path("field/scenario.yaml")), "name: mine\n") << "the user's file was touched";
}

MissionMetrics AstarRun() {
  MissionMetrics m = SampleMetrics();
  m.controller = "astar";
  m.valves[0].visits = m.valves[1].visits = 37;
  m.valves[0].mean_interval_s = m.valves[1].mean_interval_s = 8.1;
  return m;
}

// Table 1: every valve, both runs, "---" for P3's undefined interval, the signed correlation,
// "undefined" for A*'s, and no line wider than 100 columns, even with three runs.
TEST(FormatTable, PaperLayout) {
  MissionMetrics ergodic = SampleMetrics();
  ergodic.visit_weight_correlation = 0.93;
  // What a fleet is judged by, under the paper's three lines.
  ergodic.unvisited_valves = 1;
  ergodic.risk_weighted_interval_s = 12.34;
  ergodic.expected_detection_delay_s = 4.56;
  const std::string table = FormatTable({AstarRun(), ergodic});
  for (const char* needle : {"unvisited valves", "risk-weighted interval", "exp. detection delay", "12.3 s", "4.6 s"}) {
    EXPECT_NE(table.find(needle), std::string::npos) << needle << " missing from\n" << table;
  }
  EXPECT_NE(table.find(fmt::format("1 of {}", ergodic.valves.size())), std::string::npos) << table;
  for (const char* needle : {"Valve", "Weight", "astar", "ergodic", "visits", "interval", "P1", "P3", "0.55",
                             "8.1 s", "6.5 s", "---", "+0.93", "undefined", "1.25e-03", "longest gap"}) {
    EXPECT_NE(table.find(needle), std::string::npos) << needle << " missing from\n" << table;
  }
  EXPECT_EQ(table.find("one_extreme"), std::string::npos);  // same profile: not in the labels
  const auto widest = [](const std::string& text) {
    std::size_t widest = 0, start = 0;
    for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
      widest = std::max(widest, end - start);
    }
    return widest;
  };
  EXPECT_LE(widest(table), 100u) << table;

  // Runs under different profiles: labels name the profile and each run shows its own weights.
  MissionMetrics graded = ergodic;
  graded.profile = "graded";
  graded.valves[0].weight = 0.40;
  const std::string three = FormatTable({AstarRun(), ergodic, graded});
  EXPECT_NE(three.find("ergodic (graded)"), std::string::npos) << three;
  EXPECT_NE(three.find("ergodic (one_extreme)"), std::string::npos) << three;
  EXPECT_NE(three.find("0.40"), std::string::npos) << three;
  EXPECT_LE(widest(three), 100u) << three;
}

// With sensors each valve's row says how long a leak there would have waited for a scan (a
// camera watches a valve from its legs, so a valve with no visit may be well watched): its own
// value in its own row, "unseen" where no scan could have seen a leak (its wait would only be the
// time left to the end), "---" where there is no estimate; no such column without sensors. The
// two expected delays are told apart (visits, scans). When runs are too wide for the terminal
// the intervals go first, then the gaps, and the table says what it left out.
TEST(FormatTable, ScanWaitsWithSensors) {
  const auto row_of = [](const std::string& table, const std::string& valve) {
    std::size_t start = 0;
    for (std::size_t end; (end = table.find('\n', start)) != std::string::npos; start = end + 1) {
      const std::string line = table.substr(start, end - start);
      if (line.rfind(valve + " ", 0) == 0) return line;
    }
    return std::string();
  };
  const auto widest = [](const std::string& text) {
    std::size_t widest = 0, start = 0;
    for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
      widest = std::max(widest, end - start);
    }
    return widest;
  };
  MissionMetrics m = SampleMetrics();
  const std::string blind = FormatTable({m});
  for (const char* absent : {"scan wait", "exp. delay by", "not shown"}) {
    EXPECT_EQ(blind.find(absent), std::string::npos) << absent << " in\n" << blind;
  }
  EXPECT_NE(blind.find("exp. detection delay"), std::string::npos) << blind;
  m.sensing = true;
  m.expected_detection_by_scans_s = 4.46;
  m.valves[0].expected_detection_by_scans_s = 3.44;
  m.valves[0].seen_by_scans = true;
  m.valves[1].expected_detection_by_scans_s = 6.71;  // P3: no visit, yet watched
  m.valves[1].seen_by_scans = true;
  const std::string table = FormatTable({m});
  for (const char* needle : {"scan wait", "(scan wait: the mean time a leak starting at the valve", "exp. delay by visits",
                             "exp. delay by scans"}) {
    EXPECT_NE(table.find(needle), std::string::npos) << needle << " missing from\n" << table;
  }
  EXPECT_NE(row_of(table, "exp. delay by scans").find(" 4.5 s"), std::string::npos) << table;
  EXPECT_EQ(table.find("not shown"), std::string::npos) << "one run fits whole:\n" << table;
  const std::string p1 = row_of(table, "P1"), p3 = row_of(table, "P3");
  ASSERT_FALSE(p1.empty()) << table;
  ASSERT_FALSE(p3.empty()) << table;
  EXPECT_TRUE(p1.ends_with(" 3.4 s")) << p1;
  EXPECT_TRUE(p3.ends_with(" 6.7 s")) << p3;
  EXPECT_NE(p3.find(" 0 "), std::string::npos) << "P3's visits stay 0: " << p3;
  m.valves[1].seen_by_scans = false;
  EXPECT_TRUE(row_of(FormatTable({m}), "P3").ends_with(" unseen")) << FormatTable({m});
  EXPECT_NE(row_of(FormatTable({m}), "unseen by the scans").find(" 1 of 2"), std::string::npos) << FormatTable({m});
  // No estimate (a mission stopped before the first onset): "---", seen or not.
  for (const bool seen : {true, false}) {
    m.valves[1].seen_by_scans = seen;
    m.valves[1].expected_detection_by_scans_s = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(row_of(FormatTable({m}), "P3").ends_with("---")) << FormatTable({m});
  }
  m.valves[1].seen_by_scans = true;

  // Two runs with sensors (sage compare): the intervals go, the longest gaps and the waits stay.
  MissionMetrics b = m, c = m;
  b.controller = "astar";
  c.controller = "looks";
  const std::string two = FormatTable({m, b});
  EXPECT_LE(widest(two), 100u) << two;
  EXPECT_NE(two.find("visits  longest gap  scan wait"), std::string::npos) << two;
  EXPECT_NE(two.find("(not shown, to fit 100 columns: interval; metrics.json has every figure)"), std::string::npos) << two;
  // Three: the gaps go too; the waits stay while the table fits.
  const std::string three = FormatTable({m, b, c});
  EXPECT_LE(widest(three), 100u) << three;
  EXPECT_NE(three.find("visits  scan wait"), std::string::npos) << three;
  EXPECT_NE(three.find("(not shown, to fit 100 columns: longest gap, interval;"), std::string::npos) << three;
  EXPECT_TRUE(row_of(three, "P1").ends_with(" 3.4 s")) << three;
}

// The leak lines fit the terminal as the table does: a long line is broken at its last "; ",
// else ", ", within 100 columns, the rest indented; nothing of it is lost.
TEST(FormatLeaks, LinesFitTheTerminal) {
  MissionMetrics m = SampleMetrics();
  m.sensing = true;
  m.scans = 91100;
  m.expected_detection_by_scans_s = 10.7;
  m.leak_onsets_from_s = 30.0;
  m.leak_onsets_to_s = 270.0;
  LeakMetrics leak;
  leak.where = "seabed (1104.25, 1033.5125)";  // 27 characters: the ", " before the detections at column 100
  leak.start_s = 1169.9;
  leak.detected_s = 1178.5;
  leak.confirmed_s = 1179.0;
  leak.detections = 10400;
  leak.visits_per_min_after_detection = 7.4;
  m.leaks = {leak};
  m.false_alarms.raised = 15;
  m.false_alarms.cleared = 12;
  m.false_alarms.confirmed = 3;
  m.false_alarms.detections = 16700;
  m.false_alarms.mean_time_to_clear_s = 32.1;
  m.false_alarms.max_time_to_clear_s = 38.1;
  const std::string text = FormatLeaks({m});
  std::string joined;  // the lines run together again, as one line would read
  std::size_t start = 0;
  for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string line = text.substr(start, end - start);
    EXPECT_LE(line.size(), 100u) << line;
    joined += line.rfind("    ", 0) == 0 ? (joined.ends_with(",") ? " " : "; ") + line.substr(4) : "\n" + line;
  }
  for (const char* needle : {"seabed (1104.25, 1033.5125) from 1169.9 s: detected 1178.5 s (+8.6 s), confirmed 1179.0 s (+9.1 s), 10400 detections; then 7.4 visits/min to it",
                             "15 raised, 12 cleared (mean 32.1 s, at most 38.1 s), 3 confirmed (16700 false detections in 91100 scans)",
                             "from these scans: 10.7 s"}) {
    EXPECT_NE(joined.find(needle), std::string::npos) << needle << " not in\n" << text;
  }
}

// The table's per-valve longest gap is the longest stretch with no vehicle within the visit radius,
// as metrics.json's longest_gap_s: a tour vehicle holding station on its valve made one visit in
// 118.6 s and read 118.6 s in the table, 4.3 s in the JSON (a new user's finding).
TEST(FormatTable, LongestGapIsTheStretchNobodyWatched) {
  MissionMetrics m = SampleMetrics();
  m.valves.front().max_gap_s = 118.6;
  m.valves.front().longest_unwatched_s = 4.3;
  const std::string table = FormatTable({m});
  EXPECT_NE(table.find("4.3 s"), std::string::npos) << table;
  EXPECT_EQ(table.find("118.6"), std::string::npos) << table;
}

// With a valve never visited, the risk-weighted interval and the expected detection delay are
// floors (the valve counted as visited once, its leak as waiting only to the end): the table
// marks them ">=" and says why (a log with no visit at all had read 60 s, as one visit a valve).
TEST(FormatTable, FiguresAnUnvisitedValveCutsShortAreMarked) {
  MissionMetrics m = SampleMetrics();
  m.unvisited_valves = 0;
  const std::string all_seen = FormatTable({m});
  EXPECT_EQ(all_seen.find(">="), std::string::npos) << all_seen;
  m.unvisited_valves = 1;
  const std::string table = FormatTable({m});
  EXPECT_NE(table.find(">= " + fmt::format("{:.1f} s", m.risk_weighted_interval_s)), std::string::npos) << table;
  EXPECT_NE(table.find(">= " + fmt::format("{:.1f} s", m.expected_detection_delay_s)), std::string::npos) << table;
  EXPECT_NE(table.find("(>=: some valve was never visited"), std::string::npos) << table;
}

// A valve watched most of the mission in one long visit (a vehicle parked at it) is footnoted:
// its interval reads as the mission's length while it was never unwatched.
TEST(FormatTable, AValveWatchedThroughoutIsFootnoted) {
  MissionMetrics m = SampleMetrics();
  const std::string plain = FormatTable({m});
  EXPECT_EQ(plain.find("watched most of the mission"), std::string::npos) << plain;
  m.valves.front().visits = 1;
  m.valves.front().time_near_s = 0.9 * m.duration_s;
  const std::string parked = FormatTable({m});
  EXPECT_NE(parked.find("(a valve watched most of the mission in one or two long visits"), std::string::npos) << parked;
}

// A large field's table lists the 40 valves with the longest gap in any run, longest first,
// and says where the others are; up to 300 valves it lists every one, in scenario order. Weights
// below 0.01 keep two significant digits.
TEST(FormatTable, LargeFieldListsLongestGaps) {
  const auto field = [](int valves, std::uint64_t salt) {
    MissionMetrics m = SampleMetrics();
    m.valves.clear();
    for (int i = 0; i < valves; ++i) {
      // A gap per valve from a scrambled order (no ties), different per run.
      const double gap = static_cast<double>((static_cast<std::uint64_t>(i) * 7919u + salt) % 100003u) / 100.0;
      // The longest stretch nobody watched ranks the valves (as metrics.json's longest_gap_s); the
      // longest between visit entries, here in the opposite order, does not.
      m.valves.push_back({fmt::format("P{}", i + 1), 1.0 / valves, 2, 10.0, 1100.0 - gap, 0.0, {}});
      m.valves.back().longest_unwatched_s = gap;
    }
    return m;
  };
  const auto rows_of = [](const std::string& table) {
    std::vector<std::string> names;
    std::size_t start = 0;
    for (std::size_t end; (end = table.find('\n', start)) != std::string::npos; start = end + 1) {
      const std::string line = table.substr(start, end - start);
      if (line.rfind("P", 0) == 0) names.push_back(line.substr(0, line.find(' ')));
    }
    return names;
  };
  const MissionMetrics a = field(2000, 11), b = field(2000, 5077);
  const std::string table = FormatTable({a, b});
  const std::vector<std::string> listed = rows_of(table);
  // Brute force: the 40 largest of max(gap in a, gap in b).
  std::vector<std::pair<double, int>> worst;
  for (int i = 0; i < 2000; ++i) {
    worst.push_back({std::max(a.valves[i].longest_unwatched_s, b.valves[i].longest_unwatched_s), i});
  }
  std::sort(worst.begin(), worst.end(),
            [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); });
  ASSERT_EQ(listed.size(), 40u) << table;
  for (int k = 0; k < 40; ++k) EXPECT_EQ(listed[k], a.valves[worst[k].second].name) << k;
  EXPECT_NE(table.find("(40 of 2000 valves listed: the longest gaps; every valve is in metrics.json"), std::string::npos);
  EXPECT_NE(table.find("0.0005 "), std::string::npos) << "a weight below 0.01 keeps two significant digits";

  // With sensors: the 40 a leak would have waited longest at, the never-seen first.
  MissionMetrics sensed = field(2000, 11);
  sensed.sensing = true;
  for (int i = 0; i < 2000; ++i) {
    ValveMetrics& v = sensed.valves[static_cast<std::size_t>(i)];
    v.seen_by_scans = i % 97 != 5;  // 21 never seen
    v.expected_detection_by_scans_s = static_cast<double>((static_cast<std::uint64_t>(i) * 6421u + 17u) % 100019u) / 1000.0;
  }
  const std::vector<std::string> by_scans = rows_of(FormatTable({sensed}));
  std::vector<std::pair<double, int>> waits;
  for (int i = 0; i < 2000; ++i) {
    const ValveMetrics& v = sensed.valves[static_cast<std::size_t>(i)];
    waits.push_back({v.seen_by_scans ? v.expected_detection_by_scans_s : std::numeric_limits<double>::infinity(), i});
  }
  std::sort(waits.begin(), waits.end(),
            [](const auto& x, const auto& y) { return x.first > y.first || (x.first == y.first && x.second < y.second); });
  ASSERT_EQ(by_scans.size(), 40u);
  for (int k = 0; k < 40; ++k) EXPECT_EQ(by_scans[k], sensed.valves[waits[k].second].name) << k;
  const std::string sensed_table = FormatTable({sensed});
  EXPECT_NE(sensed_table.find("(40 of 2000 valves listed: the longest scan waits; every valve is in metrics.json)"),
            std::string::npos)
      << sensed_table;
  EXPECT_NE(sensed_table.find("scan wait"), std::string::npos) << "the column the rows were chosen by is shown";
  std::size_t widest_sensed = 0, at = 0;
  for (std::size_t end; (end = sensed_table.find('\n', at)) != std::string::npos; at = end + 1) {
    widest_sensed = std::max(widest_sensed, end - at);
  }
  EXPECT_LE(widest_sensed, 100u) << sensed_table;

  const std::vector<std::string> all = rows_of(FormatTable({field(300, 11)}));
  ASSERT_EQ(all.size(), 300u);
  EXPECT_EQ(all.front(), "P1");
  EXPECT_EQ(all.back(), "P300");
}

}  // namespace
}  // namespace sage::server
