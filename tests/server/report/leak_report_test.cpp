// sage bench leaks' summaries against a hand count: means over the leaks detected, nearest-rank
// percentiles with a leak never detected later than any, revisits over valve leaks only, false
// alarms per run; the files are JSON that parses back, Markdown with the ratios, an SVG.
#include "server/report/leak_report.h"

#include <cmath>
#include <filesystem>
#include <fstream>
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
  const std::string md = LeakBenchMarkdown(s, "preamble here", "b");
  EXPECT_NE(md.find("preamble here"), std::string::npos);
  EXPECT_NE(md.find("| A | 2.50x | 4.50x | 2.67x |"), std::string::npos) << md;
  EXPECT_NE(md.find("never"), std::string::npos);
  const std::string svg = LeakBenchSvg(s, runs, "t <&> title");
  EXPECT_NE(svg.find("t &lt;&amp;&gt; title"), std::string::npos);
  EXPECT_EQ(svg.rfind("</svg>"), svg.size() - 7);
  EXPECT_NE(svg.find("A (9/10)"), std::string::npos);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_leak_report_test";
  std::filesystem::create_directories(dir);
  WriteLeakBench(dir.string(), s, runs, "p", "b", "title");
  for (const char* f : {"leaks.json", "leaks.md", "leaks.svg"}) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sage::server
