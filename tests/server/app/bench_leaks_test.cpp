// The leak sensing's command line: --random-leaks and --leak-sites draw the hidden leaks from the
// effective seed, --steer chooses the loop; sage bench leaks flies every configuration on the
// same leaks and writes its three files; a scenario without sensors is refused before anything runs.
#include "server/app/bench_leaks.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/app/cli_scenario.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";
const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

TEST(LeakOverrides, RandomLeaksFromTheEffectiveSeedAndSteer) {
  ScenarioOverrides o;
  o.scenario_path = kTwoXtLeaks;
  o.random_leaks = 3;
  o.seed = 9;
  o.duration_s = 100.0;
  o.steer = "prior";
  const maps::Scenario a = LoadWithOverrides(o);
  ASSERT_EQ(a.leaks.size(), 3u);
  EXPECT_FALSE(a.fusion.steer);
  for (const maps::LeakSpec& leak : a.leaks) {
    EXPECT_FALSE(leak.valve.empty());
    EXPECT_GE(leak.start_s, 10.0);
    EXPECT_LE(leak.start_s, 90.0) << "drawn over the effective duration";
  }
  EXPECT_EQ(maps::EmitScenario(LoadWithOverrides(o)), maps::EmitScenario(a));
  o.leak_sites = "seabed";
  for (const maps::LeakSpec& leak : LoadWithOverrides(o).leaks) EXPECT_TRUE(leak.valve.empty());
  o.steer = "maybe";
  EXPECT_THROW(LoadWithOverrides(o), maps::ScenarioError);
  o.steer.reset();
  o.random_leaks.reset();
  EXPECT_THROW(LoadWithOverrides(o), maps::ScenarioError) << "--leak-sites without --random-leaks";
}

TEST(BenchLeaks, EveryConfigurationMeetsTheSameLeaks) {
  const fs::path dir = fs::temp_directory_path() / "sage_bench_leaks_test";
  fs::remove_all(dir);
  BenchLeaksCommand c;
  c.scenario.scenario_path = kTwoXtLeaks;
  c.scenario.duration_s = 60.0;
  c.runs = 2;
  c.configs = "bayes,astar";
  c.out_dir = dir.string();
  c.jobs = 2;
  ASSERT_EQ(CmdBenchLeaks(c), 0);
  for (const char* f : {"leaks.json", "leaks.md", "leaks.svg"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  std::ifstream in(dir / "leaks.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j.at("runs").size(), 4u);
  ASSERT_EQ(j.at("summaries").size(), 2u);
  EXPECT_EQ(j["summaries"][0]["config"], "bayes");
  EXPECT_EQ(j["summaries"][1]["config"], "astar");
  // Run r of each configuration: the same seed, the same leak.
  for (int run = 0; run < 2; ++run) {
    std::vector<nlohmann::json> rows;
    for (const nlohmann::json& r : j.at("runs"))
      if (r.at("run") == run) rows.push_back(r);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].at("seed"), rows[1].at("seed"));
    EXPECT_EQ(rows[0].at("where"), rows[1].at("where"));
    EXPECT_EQ(rows[0].at("start_s"), rows[1].at("start_s"));
  }
  fs::remove_all(dir);
  c.scenario.scenario_path = kTwoXt;
  try {
    CmdBenchLeaks(c);
    ADD_FAILURE() << "a scenario without sensors was benched";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("sensors: none"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir)) << "refused before anything was written";
  // Flowline sites on a field without flowlines: refused before anything is written, too.
  c.scenario.scenario_path = kTwoXtLeaks;
  c.sites = "flowlines";
  try {
    CmdBenchLeaks(c);
    ADD_FAILURE() << "flowline leaks benched on a field without flowlines";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("has no flowlines"), std::string::npos) << e.what();
    // In the bench's own words: its options are --leaks and --sites (sage run's --random-leaks is not one).
    EXPECT_EQ(std::string(e.what()).rfind("--sites = flowlines: ", 0), 0u) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir));
  c.sites = "valves";
  c.leaks = 6;  // five valves
  try {
    CmdBenchLeaks(c);
    ADD_FAILURE() << "six valve leaks benched on five valves";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--leaks = 6: at most one leak a valve", 0), 0u) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir));
  c.leaks = 1;
  c.scenario.scenario_path = kTwoXtLeaks;
  c.configs = "bayes,tours";
  EXPECT_THROW(CmdBenchLeaks(c), maps::ScenarioError);
}

}  // namespace
}  // namespace sage::server
