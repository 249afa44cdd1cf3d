// sage bench scale's measurement logic, without running a benchmark: the fleet sizes it accepts
// (and the command line refusing the others before anything runs), the field of a fleet of N,
// the server's summary line and the launcher's output read back, when every vehicle got under
// way, and a measured run turned into a row.
#include "server/app/bench_scale.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/app/cli.h"
#include "server/app/scale_measure.h"

namespace sage::server {
namespace {

// Whole numbers 1..10000, comma-separated, spaces around them allowed, returned in order.
TEST(ParseVehicleCounts, AcceptsFleetSizes) {
  EXPECT_EQ(ParseVehicleCounts("1,10,100,1000"), (std::vector<int>{1, 10, 100, 1000}));
  EXPECT_EQ(ParseVehicleCounts("10000, 1 ,100"), (std::vector<int>{1, 100, 10000}));
  EXPECT_EQ(ParseVehicleCounts("7"), (std::vector<int>{7}));
}

// Each bad list is one line naming the value and the rule.
TEST(ParseVehicleCounts, RefusesWithOneLine) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"0", "must be in 1..10000"},          {"10001", "must be in 1..10000"},
      {"99999999999999", "must be in 1..10000"}, {"-5", "not a whole number"},
      {"abc", "not a whole number"},         {"1.5", "not a whole number"},
      {"", "not a whole number"},            {"1,,2", "not a whole number"},
      {"10,10", "given twice"},
  };
  for (const auto& [text, rule] : bad) {
    try {
      ParseVehicleCounts(text);
      ADD_FAILURE() << "accepted --vehicles " << text;
    } catch (const maps::ScenarioError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("--vehicles = " + text + ":", 0), 0u) << what;
      EXPECT_NE(what.find(rule), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// The command line refuses bad input with status 2 before anything runs: no output directory
// appears.
TEST(BenchScaleCli, RefusesBadInputBeforeRunning) {
  const std::string out = (std::filesystem::temp_directory_path() / "sage_bench_scale_cli_test").string();
  std::filesystem::remove_all(out);
  const std::vector<std::vector<std::string>> bad = {
      {"--vehicles", "0"},       {"--vehicles", "ten"},   {"--vehicles", "20000"},
      {"--transport", "udp"},    {"--duration", "0"},     {"--duration", "soon"},
      {"--seed", "-3"},          {"--frobnicate"},        {"--repeat", "0"},
      {"--seed", "18446744073709551616"},  // one past 2^64 - 1: CLI11 alone would take 2^64 - 1
      {"--repeat", "11"},        {"--repeat", "twice"},
  };
  for (const std::vector<std::string>& options : bad) {
    std::vector<std::string> args = {"sage", "bench", "scale", "--out", out};
    args.insert(args.end(), options.begin(), options.end());
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    EXPECT_EQ(RunCli(static_cast<int>(argv.size()), argv.data()), 2) << options.front();
    EXPECT_FALSE(std::filesystem::exists(out)) << options.front();
  }
}

// Weak scaling: N XTs, 3.5 N valves rounded, N vehicles, the seed.
TEST(ScaleFieldOptions, GrowsWithTheFleet) {
  for (const auto& [n, valves] : std::vector<std::pair<int, int>>{{1, 4}, {10, 35}, {1000, 3500}, {3, 11}}) {
    const maps::FieldOptions o = ScaleFieldOptions(n, 7);
    EXPECT_EQ(o.xts, n);
    EXPECT_EQ(o.valves, valves) << n;
    EXPECT_GE(o.valves, 2 * n);
    EXPECT_LE(o.valves, 5 * n);
    EXPECT_EQ(o.vehicles, n);
    EXPECT_EQ(o.seed, 7u);
  }
}

// A line the server printed (a 10-vehicle launch), read field by field.
TEST(ParseServerSummary, ReadsTheServersLine) {
  const std::string line =
      "[info] server: 10 s of mission in 10.0 s wall (1.00x real time); 1000 messages in, 134 out (113/s); 0.120 MB "
      "in, 1.720 MB out at 0.182 MB/s; server cycle 0.56 ms mean, 5.35 ms p99, 23.41 ms max; peak RSS 22.9 MB; wrote "
      "/tmp/l10 in 0.0 s";
  const std::optional<ServerSummary> s = ParseServerSummary(line);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->mission_s, 10.0);
  EXPECT_EQ(s->wall_s, 10.0);
  EXPECT_EQ(s->real_time_factor, 1.0);
  EXPECT_EQ(s->messages_in, 1000u);
  EXPECT_EQ(s->messages_out, 134u);
  EXPECT_EQ(s->messages_per_s, 113.0);
  EXPECT_DOUBLE_EQ(s->mb_in, 0.12);
  EXPECT_DOUBLE_EQ(s->mb_out, 1.72);
  EXPECT_DOUBLE_EQ(s->mb_per_s, 0.182);
  EXPECT_DOUBLE_EQ(s->cycle_mean_ms, 0.56);
  EXPECT_DOUBLE_EQ(s->cycle_p99_ms, 5.35);
  EXPECT_DOUBLE_EQ(s->cycle_max_ms, 23.41);
  EXPECT_DOUBLE_EQ(s->peak_rss_mb, 22.9);
}

// The line of a server before bytes, p99 and peak RSS were added still reads, with those NaN;
// a cut or mangled line is no summary.
TEST(ParseServerSummary, OlderLineAndMalformedOnes) {
  const std::optional<ServerSummary> old = ParseServerSummary(
      "server: 30 s of mission in 30.0 s wall (1.00x real time); 310149 messages in, 1364 out (10380/s); server cycle "
      "9.79 ms mean, 49.30 ms max; wrote runs/x in 0.4 s");
  ASSERT_TRUE(old.has_value());
  EXPECT_EQ(old->messages_in, 310149u);
  EXPECT_DOUBLE_EQ(old->cycle_mean_ms, 9.79);
  EXPECT_DOUBLE_EQ(old->cycle_max_ms, 49.3);
  EXPECT_TRUE(std::isnan(old->cycle_p99_ms));
  EXPECT_TRUE(std::isnan(old->mb_in));
  EXPECT_TRUE(std::isnan(old->peak_rss_mb));
  for (const char* bad : {
           "server: 30 s of mission in 30.0 s wall (1.00x real time); 310149 messages in",
           "server: thirty s of mission in 30.0 s wall (1.00x real time); 1 messages in, 1 out (1/s); server cycle 1 ms "
           "mean, 2 ms max",
           "t =    30 / 60 s  vehicles 10 (lost 0)  ergodic metric 1.2e-04  server cycle 0.23 ms",
           "",
       }) {
    EXPECT_FALSE(ParseServerSummary(bad).has_value()) << bad;
  }
}

// In a launcher's whole output the last summary counts; progress is the last "t = x / y s" line;
// the host count comes from the launcher's start line.
TEST(LaunchOutput, SummaryProgressAndHosts) {
  const std::string output =
      "[info] launch: mission 'f' on DDS domain 82: server pid 1, 4 agent host(s) for 1000 vehicles; run dir d\n"
      "t =     0 / 60 s  vehicles 0 (lost 0)  ergodic metric nan  server cycle 0.00 ms\n"
      "t =    42 / 60 s  vehicles 1000 (lost 0)  ergodic metric 1.2e-04  server cycle 9.10 ms\n"
      "[info] server: 1 s of mission in 1.0 s wall (1.00x real time); 1 messages in, 1 out (2/s); server cycle 1.00 "
      "ms mean, 2.00 ms max\n"
      "[info] server: 60 s of mission in 60.1 s wall (1.00x real time); 9 messages in, 9 out (3/s); server cycle 4.00 "
      "ms mean, 5.00 ms p99, 6.00 ms max\n"
      "Valve  Weight | ergodic\n";
  ASSERT_TRUE(FindServerSummary(output).has_value());
  EXPECT_EQ(FindServerSummary(output)->mission_s, 60.0);
  EXPECT_DOUBLE_EQ(FindServerSummary(output)->cycle_p99_ms, 5.0);
  EXPECT_NEAR(*LaunchProgress(output), 0.7, 1e-12);
  EXPECT_EQ(LaunchHostCount(output), 4);
  EXPECT_FALSE(FindServerSummary("no summary here\n").has_value());
  EXPECT_FALSE(LaunchProgress("[info] launch: starting\n").has_value());
  EXPECT_EQ(LaunchHostCount(""), -1);
}

TrajectorySample At(double t, int vehicle, double x, double y) {
  TrajectorySample s;
  s.time_s = t;
  s.vehicle = vehicle;
  s.position_m = {x, y};
  return s;
}

// Moved means more than 5 cm from the first recorded position (4 cm is not); the fleet is under
// way when its last vehicle is; one that never moves leaves it undefined.
TEST(FirstMoveTracker, LastVehicleToMove) {
  FirstMoveTracker moves;
  moves.Add(At(0.0, 0, 1.0, 1.0));
  moves.Add(At(0.0, 3, 5.0, 5.0));
  moves.Add(At(0.1, 0, 1.04, 1.0));  // 4 cm: not yet
  moves.Add(At(0.2, 0, 1.0, 1.06));  // 6 cm
  moves.Add(At(0.2, 3, 5.0, 5.0));
  EXPECT_EQ(moves.vehicles(), 2);
  EXPECT_EQ(moves.never_moved(), 1);
  EXPECT_TRUE(std::isnan(moves.all_moved_s()));
  moves.Add(At(0.7, 3, 5.03, 4.95));  // 5.8 cm
  moves.Add(At(0.8, 0, 1.0, 1.0));    // back at its start: it has moved already
  EXPECT_EQ(moves.never_moved(), 0);
  EXPECT_DOUBLE_EQ(moves.all_moved_s(), 0.7);
  EXPECT_TRUE(std::isnan(FirstMoveTracker().all_moved_s()));
}

// The in-process row: real-time factor = mission s / loop wall s, the cycle's mean, nearest-rank
// p99 and max in ms, CPU per vehicle-second = CPU s / (N x mission s), quality from the metrics.
TEST(InprocRow, FiguresFromTheRun) {
  ScaleRow base;
  base.vehicles = 10;
  base.controller = "ergodic";
  InprocRun run;
  run.mission_s = 60.0;
  run.loop_wall_s = 20.0;
  run.cpu_s = 30.0;
  run.late_mission_s = 30.0;  // the second half: 30 mission s in 8 wall s on 12 CPU s
  run.late_wall_s = 8.0;
  run.late_cpu_s = 12.0;
  run.peak_rss_mb = 123.0;
  for (int i = 1; i <= 100; ++i) run.server_cycle_s.push_back(i * 1e-3);  // 1..100 ms
  run.all_moved_s = 0.4;
  run.metrics.unvisited_valves = 3;
  run.metrics.longest_gap_median_s = 20.0;
  run.metrics.longest_gap_p90_s = 40.0;
  run.metrics.longest_gap_max_s = 60.0;
  run.metrics.risk_weighted_interval_s = 12.0;
  run.metrics.expected_detection_delay_s = 5.0;
  run.metrics.dominant_interval_s = 7.5;
  run.metrics.visit_weight_correlation = 0.61;
  const ScaleRow row = InprocRow(base, run);
  EXPECT_EQ(row.transport, "inproc");
  EXPECT_EQ(row.vehicles, 10);
  EXPECT_DOUBLE_EQ(row.real_time_factor, 3.0);
  EXPECT_NEAR(row.server_cycle_mean_ms, 50.5, 1e-9);
  EXPECT_NEAR(row.server_cycle_p99_ms, 99.0, 1e-9);
  EXPECT_NEAR(row.server_cycle_max_ms, 100.0, 1e-9);
  EXPECT_DOUBLE_EQ(row.cpu_s_per_vehicle_s, 30.0 / 600.0);
  EXPECT_DOUBLE_EQ(row.real_time_factor_late, 30.0 / 8.0);
  EXPECT_DOUBLE_EQ(row.cpu_s_per_vehicle_s_late, 12.0 / 300.0);
  EXPECT_DOUBLE_EQ(row.peak_rss_mb, 123.0);
  EXPECT_DOUBLE_EQ(row.all_moved_after_s, 0.4);
  EXPECT_EQ(row.unvisited_valves, 3);
  EXPECT_DOUBLE_EQ(row.longest_gap_p90_s, 40.0);
  EXPECT_DOUBLE_EQ(row.risk_weighted_interval_s, 12.0);
  EXPECT_DOUBLE_EQ(row.expected_detection_delay_s, 5.0);
  EXPECT_DOUBLE_EQ(row.dominant_interval_s, 7.5);
  EXPECT_DOUBLE_EQ(row.visit_weight_correlation, 0.61);
  EXPECT_TRUE(std::isnan(row.dds_samples_per_s));  // no DDS in-process
}

// The DDS row takes the server's figures; bytes per second come from the totals over the wall.
TEST(DdsRow, FiguresFromTheServerAndTheLaunch) {
  ScaleRow base;
  base.vehicles = 100;
  DdsRun run;
  run.server = *ParseServerSummary(
      "server: 60 s of mission in 60.0 s wall (0.98x real time); 60000 messages in, 700 out (1012/s); 6.000 MB in, "
      "3.000 MB out at 0.150 MB/s; server cycle 1.50 ms mean, 8.00 ms p99, 20.00 ms max; peak RSS 50.0 MB");
  run.cpu_s = 120.0;
  run.largest_rss_mb = 60.0;
  run.agent_host_rss_mb = 55.0;
  run.agent_hosts = 1;
  const ScaleRow row = DdsRow(base, run);
  EXPECT_EQ(row.transport, "dds");
  EXPECT_DOUBLE_EQ(row.real_time_factor, 0.98);
  EXPECT_DOUBLE_EQ(row.server_cycle_p99_ms, 8.0);
  EXPECT_DOUBLE_EQ(row.dds_samples_per_s, 1012.0);
  EXPECT_DOUBLE_EQ(row.dds_bytes_per_s, 9e6 / 60.0);
  EXPECT_DOUBLE_EQ(row.cpu_s_per_vehicle_s, 120.0 / 6000.0);
  EXPECT_DOUBLE_EQ(row.server_peak_rss_mb, 50.0);
  EXPECT_DOUBLE_EQ(row.peak_rss_mb, 60.0);
  EXPECT_EQ(row.agent_hosts, 1);
}

}  // namespace
}  // namespace sage::server
