// sage bench leaks' summaries against a hand count: means over the leaks detected, nearest-rank
// percentiles with a leak never detected later than any, revisits over valve leaks only, false
// alarms per run; the files are JSON that parses back, Markdown with the ratios, an SVG.
#include "server/report/leak_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace sage::server {
namespace {

LeakRun Row(const std::string& config, int run, double start, double detected, bool valve = true, double visits = 6.0,
            int alarms = 0) {
  LeakRun r;
  r.config = config;
  r.run = run;
  r.where = valve ? "P1" : "seabed (1, 1)";
  r.at_valve = valve;
  r.start_s = start;
  r.detected_s = detected;
  r.confirmed_s = detected + 1.0;
  r.visits_per_min_after_detection = std::isnan(detected) ? std::nan("") : visits;
  r.false_alarms = alarms;
  return r;
}

TEST(LeakReport, SummariesMatchAHandCount) {
  const double never = std::nan("");
  // ten leaks of "a": delays 1..9 s and one never; "b": 2 s each.
  std::vector<LeakRun> runs;
  for (int k = 0; k < 9; ++k) runs.push_back(Row("a", k, 100.0, 100.0 + (k + 1), k % 2 == 0, 4.0 + k, k == 0 ? 3 : 0));
  runs.push_back(Row("a", 9, 100.0, never));
  for (int k = 0; k < 10; ++k) runs.push_back(Row("b", k, 50.0, 52.0, true, 3.0));
  const std::vector<LeakSummary> s = SummariseLeakRuns(runs, {"a", "b"}, {"A", "B"});
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].leaks, 10);
  EXPECT_EQ(s[0].detected, 9);
  EXPECT_EQ(s[0].runs, 10);
  EXPECT_DOUBLE_EQ(s[0].detection_mean_s, 5.0);  // (1 + ... + 9) / 9
  EXPECT_DOUBLE_EQ(s[0].detection_median_s, 5.0);  // the 5th of 10
  EXPECT_DOUBLE_EQ(s[0].detection_p90_s, 9.0);     // the 9th of 10
  EXPECT_TRUE(std::isnan(s[0].detection_max_s)) << "the 10th is the leak never detected";
  // Valve leaks detected: k = 0, 2, 4, 6, 8 -> visits 4, 6, 8, 10, 12.
  EXPECT_DOUBLE_EQ(s[0].visits_per_min_after_detection, 8.0);
  EXPECT_DOUBLE_EQ(s[0].false_alarms_per_run, 0.3);
  EXPECT_DOUBLE_EQ(s[1].detection_p90_s, 2.0);
  EXPECT_EQ(s[1].description, "B");

  const nlohmann::json j = nlohmann::json::parse(LeakBenchJson(s, runs));
  EXPECT_EQ(j.at("runs").size(), 20u);
  EXPECT_TRUE(j["summaries"][0]["time_to_detection_s"]["max"].is_null());
  EXPECT_EQ(j["summaries"][0]["time_to_detection_s"]["p90"], 9.0);
  EXPECT_TRUE(j["runs"][9]["detected_s"].is_null());
  const std::string md = LeakBenchMarkdown(s, runs, "preamble here", "b");
  EXPECT_NE(md.find("preamble here"), std::string::npos);
  // A's mean is over the 9 leaks it found: the ratio says so (a missed leak must not read as sooner).
  EXPECT_NE(md.find("| A | 2.50x (of 9 / 10 detected against 10 / 10) | 4.50x | 2.67x | "), std::string::npos) << md;
  EXPECT_NE(md.find("never"), std::string::npos);
  // The terminal's table: within 100 columns, a row per configuration by its name with its figures
  // (A: 10 leaks, 9 found, mean 5.0 s, p90 9.0 s, max never; B's description below).
  const std::string terminal = LeakBenchTerminalTable(s);
  for (std::size_t at = 0; at < terminal.size();) {
    const std::size_t end = terminal.find('\n', at);
    EXPECT_LE(end - at, 100u) << terminal.substr(at, end - at);
    at = end + 1;
  }
  EXPECT_NE(terminal.find("a             10     9    5.0    5.0    9.0  never"), std::string::npos) << terminal;
  EXPECT_NE(terminal.find("  b: B\n"), std::string::npos) << terminal;
  EXPECT_EQ(terminal.find('|'), std::string::npos) << terminal;
  const std::string svg = LeakBenchSvg(s, runs, "t <&> title");
  EXPECT_NE(svg.find("t &lt;&amp;&gt; title"), std::string::npos);
  EXPECT_EQ(svg.rfind("</svg>"), svg.size() - 7);
  EXPECT_NE(svg.find("A (9/10)"), std::string::npos);
  // The time axis ends at the first nice step at or past the longest delay: 9 s here (steps of 1 s),
  // 25 s for a longest 24.8 s (steps of 5 s; a round end of its own had drawn it to 50 s).
  EXPECT_NE(svg.find(">9</text>"), std::string::npos) << svg;
  EXPECT_EQ(svg.find(">10</text>"), std::string::npos) << svg;
  std::vector<LeakRun> longer = runs;
  longer.push_back(Row("b", 10, 50.0, 74.8));
  const std::string svg25 = LeakBenchSvg(SummariseLeakRuns(longer, {"a", "b"}, {"A", "B"}), longer, "t");
  EXPECT_NE(svg25.find(">25</text>"), std::string::npos) << svg25;
  EXPECT_EQ(svg25.find(">30</text>"), std::string::npos) << svg25;
  EXPECT_EQ(svg25.find(">50</text>"), std::string::npos) << svg25;

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_leak_report_test";
  std::filesystem::create_directories(dir);
  WriteLeakBench(dir.string(), s, runs, "p", "b", "title");
  for (const char* f : {"leaks.json", "leaks.md", "leaks.svg"}) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::filesystem::remove_all(dir);
}

// Leak by leak: the same leak (run, site, onset) under both configurations, against a direct
// computation of the differences; a shift common to every leak is known exactly however much the
// leaks themselves spread.
TEST(LeakReport, PairsEachLeakWithTheBaselinesSameLeak) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> spread(0.0, 12.0);
  std::normal_distribution<double> change(0.4, 1.0);
  std::vector<LeakRun> runs;
  std::vector<double> differences;
  for (int k = 0; k < 200; ++k) {
    const double start = 30.0 + k, base = spread(rng), mine = std::max(0.1, base + change(rng));
    runs.push_back(Row("astar", k, start, start + base));
    runs.push_back(Row("bayes", k, start, start + mine));
    differences.push_back(mine - base);
  }
  // A leak only one of them met (another run) has no partner; one detected by one only is counted apart.
  runs.push_back(Row("bayes", 500, 40.0, 45.0));
  runs.push_back(Row("astar", 201, 40.0, 41.0));
  runs.push_back(Row("bayes", 201, 40.0, std::nan("")));
  const LeakPairing p = PairDetections(runs, "bayes", "astar");
  EXPECT_EQ(p.pairs, 200);
  EXPECT_EQ(p.only_config, 0);
  EXPECT_EQ(p.only_baseline, 1);
  double sum = 0.0, sum_squares = 0.0;
  int sooner = 0;
  for (double d : differences) {
    sum += d;
    sum_squares += d * d;
    sooner += d < 0.0 ? 1 : 0;
  }
  const double n = 200.0, mean = sum / n;
  const double sd = std::sqrt((sum_squares - n * mean * mean) / (n - 1.0));  // the one-pass form, as a check
  EXPECT_NEAR(p.mean_difference_s, mean, 1e-9);
  EXPECT_NEAR(p.mean_half_width_s, 1.96 * sd / std::sqrt(n), 1e-9);
  EXPECT_NEAR(p.sooner_share, sooner / n, 1e-12);
  // Not every leak detected by both: no p90 interval.
  EXPECT_TRUE(std::isnan(p.p90_difference_s));
  EXPECT_NE(PairingText(p).find("detected under one only: 0 / 1"), std::string::npos) << PairingText(p);

  // Every leak 2 s later, over leaks that spread over 12 s: the difference and its interval are 2 s exactly.
  std::vector<LeakRun> shifted;
  for (int k = 0; k < 100; ++k) {
    const double base = spread(rng);
    shifted.push_back(Row("astar", k, 100.0, 100.0 + base));
    shifted.push_back(Row("late", k, 100.0, 100.0 + base + 2.0));
  }
  const LeakPairing q = PairDetections(shifted, "late", "astar");
  EXPECT_NEAR(q.mean_difference_s, 2.0, 1e-9);
  EXPECT_NEAR(q.mean_half_width_s, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(q.sooner_share, 0.0);
  EXPECT_DOUBLE_EQ(q.tied_share, 0.0);
  EXPECT_NEAR(q.p90_difference_s, 2.0, 1e-9);
  EXPECT_NEAR(q.p90_low_s, 2.0, 1e-9);
  EXPECT_NEAR(q.p90_high_s, 2.0, 1e-9);
  EXPECT_EQ(PairingText(q), "+2.0 s ± 0.0 s (95 %, 100 pairs), sooner in 0 %; p90 +2.0 s (+2.0 s .. +2.0 s)");

  // Ties are counted apart, not as half sooner: two of five sooner, one as soon, two later (a
  // new user had read "sooner in 50 %" for this).
  std::vector<LeakRun> five;
  for (int k = 0; k < 5; ++k) {
    five.push_back(Row("astar", k, 50.0, 55.0));
    five.push_back(Row("bayes", k, 50.0, 55.0 + (k < 2 ? -1.0 : (k == 2 ? 0.0 : 1.5))));
  }
  const LeakPairing t = PairDetections(five, "bayes", "astar");
  EXPECT_DOUBLE_EQ(t.sooner_share, 0.4);
  EXPECT_DOUBLE_EQ(t.tied_share, 0.2);
  EXPECT_NE(PairingText(t).find("sooner in 40 %, as soon in 20 %"), std::string::npos) << PairingText(t);

  // The bootstrap's interval holds the p90 difference of the leaks themselves and is not a point
  // when the leaks' changes differ.
  std::vector<LeakRun> noisy;
  for (int k = 0; k < 150; ++k) {
    const double base = spread(rng);
    noisy.push_back(Row("astar", k, 100.0, 100.0 + base));
    noisy.push_back(Row("bayes", k, 100.0, 100.0 + std::max(0.1, base + change(rng))));
  }
  const LeakPairing r = PairDetections(noisy, "bayes", "astar");
  ASSERT_TRUE(std::isfinite(r.p90_difference_s));
  EXPECT_LE(r.p90_low_s, r.p90_difference_s);
  EXPECT_GE(r.p90_high_s, r.p90_difference_s);
  EXPECT_LT(r.p90_low_s, r.p90_high_s);
  // Too few pairs for an interval.
  std::vector<LeakRun> few(noisy.begin(), noisy.begin() + 20);
  const LeakPairing f = PairDetections(few, "bayes", "astar");
  EXPECT_EQ(f.pairs, 10);
  EXPECT_TRUE(std::isnan(f.mean_half_width_s));
  EXPECT_NE(PairingText(f).find("too few for an interval"), std::string::npos);

  // In leaks.json, beside the summary of every configuration but the baseline.
  const std::vector<LeakSummary> s = SummariseLeakRuns(shifted, {"astar", "late"}, {"A", "L"});
  const nlohmann::json j = nlohmann::json::parse(LeakBenchJson(s, shifted, "astar"));
  EXPECT_FALSE(j["summaries"][0].contains("against_baseline"));
  EXPECT_EQ(j["summaries"][1]["against_baseline"]["pairs"], 100);
  EXPECT_NEAR(j["summaries"][1]["against_baseline"]["mean_difference_s"].get<double>(), 2.0, 1e-9);
}

}  // namespace
}  // namespace sage::server
