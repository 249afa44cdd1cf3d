// sage view's replay of a recorded mission: a real in-process mission (joins, a loss, an
// operator's risk change) written to a run directory by the mission's own record, read back
// read-only, shows at any time what the mission was then: who was in it and where, who was lost,
// the risk as the operator had set it, and the visits metrics.json counts. A record still being
// written (a last line cut) reads; a bad row stops the read with its file and line.
#include "server/live/replay.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/mission.h"
#include "server/report/run_directory.h"
#include "tests/support/missions.h"

namespace sage::live {
namespace {

namespace fs = std::filesystem;
using testing::EventfulTwoXt;
std::string Read(const fs::path& path) { return testing::ReadText(path); }

class ReplayTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("sage_replay_test_" + std::to_string(getpid())));
    fs::remove_all(*dir_);
    const maps::Scenario s = EventfulTwoXt();
    server::RunDirectory run(dir_->string(), s);
    server::Mission mission(s, server::MissionOptions{"", server::ControllerKind::kErgodic, &run, false});
    while (mission.Step()) {
      if (std::abs(mission.time_s() - 20.0) < 1e-9) mission.SetRisk("P4", 6.0, "operator");
      run.Tick(mission.core());
    }
    run.Finish(mission.core(), mission.world(), 60.0, false);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static fs::path* dir_;
};
fs::path* ReplayTest::dir_ = nullptr;

const VehicleView* Find(const LiveFrame& frame, const std::string& name) {
  for (const VehicleView& v : frame.vehicles)
    if (v.name == name) return &v;
  return nullptr;
}

TEST_F(ReplayTest, ShowsWhoWasInTheMissionAndWhere) {
  Replay replay(server::ReadRunRecord(dir_->string()));
  EXPECT_TRUE(replay.record().complete);
  EXPECT_DOUBLE_EQ(replay.record().end_s, 60.0);
  EXPECT_EQ(replay.record().vehicle_names.size(), 4u);

  const LiveFrame at30 = replay.FrameAt(30.0);
  EXPECT_EQ(at30.vehicles.size(), 3u);  // "late" has not joined yet
  EXPECT_EQ(Find(at30, "late"), nullptr);
  for (const VehicleView& v : at30.vehicles) EXPECT_EQ(v.status, VehicleStatus::kAlive) << v.name;
  // Where the record has rov1 at t = 30 (a kept pose: every 0.2 s).
  const std::string csv = Read(*dir_ / "trajectory.csv");
  const std::size_t row = csv.find("\n30,rov1,");
  ASSERT_NE(row, std::string::npos);
  std::stringstream fields(csv.substr(row + 1, csv.find('\n', row + 1) - row - 1));
  std::string t, name, x, y, heading;
  std::getline(fields, t, ',');
  std::getline(fields, name, ',');
  std::getline(fields, x, ',');
  std::getline(fields, y, ',');
  std::getline(fields, heading, ',');
  EXPECT_NEAR(Find(at30, "rov1")->x_m, std::stod(x), 1e-5);
  EXPECT_NEAR(Find(at30, "rov1")->y_m, std::stod(y), 1e-5);
  EXPECT_NEAR(Find(at30, "rov1")->heading_rad, std::stod(heading), 1e-5);
  EXPECT_FALSE(at30.trails[0].empty());
  EXPECT_LE(at30.trails[0].size(), 16u);  // at most 8 points

  const LiveFrame at55 = replay.FrameAt(55.0);
  EXPECT_EQ(at55.vehicles.size(), 4u);
  ASSERT_NE(Find(at55, "rov2"), nullptr);
  EXPECT_EQ(Find(at55, "rov2")->status, VehicleStatus::kLost);  // greyed where it was lost, not dropped
  EXPECT_EQ(Find(at55, "late")->status, VehicleStatus::kAlive);
  EXPECT_EQ(Find(at55, "late")->id, 3);
}

TEST_F(ReplayTest, RiskAndVisitsAsTheMissionHadThem) {
  Replay replay(server::ReadRunRecord(dir_->string()));
  const maps::Scenario s = EventfulTwoXt();
  const Eigen::VectorXd profile = s.ProfileWeights(s.ProfileOrThrow(""));
  EXPECT_DOUBLE_EQ(replay.FrameAt(10.0).valves[3].raw_weight, profile[3]);
  const LiveFrame later = replay.FrameAt(40.0);
  EXPECT_DOUBLE_EQ(later.valves[3].raw_weight, 6.0);
  EXPECT_NEAR(later.valves[3].share, 6.0 / (profile.sum() - profile[3] + 6.0), 1e-12);
  // At the end, each valve's visits are those metrics.json counts (the mission's own metrics).
  const nlohmann::json metrics = nlohmann::json::parse(Read(*dir_ / "metrics.json"));
  const LiveFrame end = replay.FrameAt(60.0);
  ASSERT_EQ(metrics["valves"].size(), end.valves.size());
  int visits = 0;
  for (std::size_t i = 0; i < end.valves.size(); ++i) {
    EXPECT_EQ(end.valves[i].visits, metrics["valves"][i]["visits"].get<int>()) << i;
    visits += end.valves[i].visits;
    const auto& times = metrics["valves"][i]["visit_times_s"];
    if (!times.empty()) {
      EXPECT_NEAR(end.valves[i].last_visit_s, times.back().get<double>(), 1e-9) << i;
    }
  }
  EXPECT_GT(visits, 5);
  EXPECT_TRUE(end.finished);
  // The frame's log: the joins, the loss and the risk change, up to its time.
  const nlohmann::json frame = nlohmann::json::parse(replay.FrameJson(55.0));
  std::string log;
  for (const auto& e : frame["events"]) log += e[3].get<std::string>() + "\n";
  EXPECT_NE(log.find("late (id 3) joined"), std::string::npos) << log;
  EXPECT_NE(log.find("rov2 (id 1) lost"), std::string::npos) << log;
  EXPECT_NE(log.find("P4: risk 6 from operator"), std::string::npos) << log;
}

TEST_F(ReplayTest, APartialRecordReadsAndABadRowIsNamed) {
  const fs::path partial = *dir_ / "partial";
  fs::create_directories(partial);
  for (const char* name : {"scenario.yaml", "trajectory.csv", "fleet_events.csv", "risk_events.csv"}) {
    fs::copy_file(*dir_ / name, partial / name, fs::copy_options::overwrite_existing);
  }
  const std::size_t rows = server::ReadRunRecord(dir_->string()).rows;
  {
    std::ofstream out(partial / "trajectory.csv", std::ios::app);
    out << "60.1,rov1,1.0,2.0,0";  // a row still being written: no newline yet
  }
  const server::RunRecord cut = server::ReadRunRecord(partial.string());
  EXPECT_TRUE(cut.cut_line);
  EXPECT_EQ(cut.rows, rows);
  EXPECT_FALSE(cut.complete);  // no metrics.json: not known to be complete
  {
    std::ofstream out(partial / "trajectory.csv", std::ios::app);
    out << ",0,0,0,0\n60.2,rov1,nope,2.0,0,0,0,0,0\n";
  }
  try {
    server::ReadRunRecord(partial.string());
    FAIL() << "a bad row was read";
  } catch (const maps::ScenarioError& e) {
    const std::string line = "trajectory.csv:" + std::to_string(rows + 3) + ": 'nope' is not a number";
    EXPECT_NE(std::string(e.what()).find(line), std::string::npos) << e.what();
  }
  std::ofstream(partial / "risk_events.csv", std::ios::app) << "12,P99,1,0.5,\"x\"\n";
  std::ofstream(partial / "trajectory.csv", std::ios::trunc) << "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n";
  try {
    server::ReadRunRecord(partial.string());
    FAIL() << "an unknown valve was read";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("valve = 'P99': not in the run's scenario"), std::string::npos) << e.what();
  }
}

// Nothing can be acted on in a replay.
TEST_F(ReplayTest, RefusesActions) {
  Replay replay(server::ReadRunRecord(dir_->string()));
  const ActionAnswer a = replay.Act({"stop", "", 0.0, 0, -1});
  EXPECT_FALSE(a.accepted);
  EXPECT_NE(a.line.find("nothing to act on"), std::string::npos);
}

}  // namespace
}  // namespace sage::live
