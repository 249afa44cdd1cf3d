// RunDirectory: a mission's record as it runs. The appended files hold what happened up to the
// last flush, metrics.json says "complete": false until the end, the checkpoint decodes, the
// final set appears whole or not at all, and a resumed record continues the cut one.
#include "server/report/run_directory.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "maps/risk_layer.h"
#include "maps/risk_octree.h"
#include "maps/world.h"
#include "server/mission.h"
#include "server/mission_core.h"
#include "server/report/checkpoint.h"
#include "server/report/mission_file.h"
#include "tests/support/missions.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;
const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

std::string Read(const fs::path& path) { return testing::ReadText(path); }

class RunDirectoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("sage_run_dir_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Steps the mission to mission time t_s, its record ticking each cycle, and checkpoints there.
  static void FlyToCheckpoint(Mission& mission, RunDirectory& run, double t_s) {
    while (mission.time_s() < t_s) {
      mission.Step();
      run.Tick(mission.core());
    }
    run.Checkpoint(mission.core());
  }
  fs::path dir_;
};

// Flushed and checkpointed every cycle (periods 0): halfway through, trajectory.csv ends at the
// last cycle, metrics.json is partial, the checkpoint is of that time; at the end the final set
// is there, complete, and the checkpoint is gone.
TEST_F(RunDirectoryTest, PartialWhileRunningCompleteAtTheEnd) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 20.0);
  RunDirectoryOptions options;
  options.flush_period_s = 0.0;
  options.checkpoint_period_s = 0.0;
  RunDirectory run(dir_.string(), s, options);
  Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
  FlyToCheckpoint(mission, run, 10.0);
  const RecordSummary partial = ReadRecordSummary(dir_.string());
  EXPECT_FALSE(partial.complete);
  EXPECT_DOUBLE_EQ(partial.recorded_until_s, mission.core().time_s());
  EXPECT_TRUE(partial.has_checkpoint);
  EXPECT_NEAR(ReadCheckpoint(dir_.string()).time_s, mission.core().time_s(), 0.1 + 1e-9);
  EXPECT_FALSE(fs::exists(dir_ / "plot.svg"));
  const nlohmann::json metrics = nlohmann::json::parse(Read(dir_ / "metrics.json"));
  EXPECT_FALSE(metrics.at("complete").get<bool>());
  EXPECT_EQ(metrics.at("planned_duration_s").get<double>(), 20.0);
  EXPECT_EQ(metrics.at("transport").get<std::string>(), "in-process");

  while (mission.Step()) run.Tick(mission.core());
  run.Finish(mission.core(), mission.world(), 20.0, false);
  const RecordSummary done = ReadRecordSummary(dir_.string());
  EXPECT_TRUE(done.complete);
  EXPECT_DOUBLE_EQ(done.recorded_until_s, 20.0);
  EXPECT_FALSE(done.has_checkpoint);
  for (const char* name : {"plot.svg", "plot.png", "metric.svg", "metric.png", "revisits.svg", "revisits.png", "seabed.bt", "risk.ot", "scenario.yaml", "metrics.json", "trajectory.csv",
                           "fleet_events.csv", "risk_events.csv"}) {
    EXPECT_TRUE(fs::exists(dir_ / name)) << name;
    EXPECT_FALSE(fs::exists(dir_ / (std::string(name) + ".tmp"))) << name;
  }
  // One row per vehicle and cycle, both ends included.
  const std::string csv = Read(dir_ / "trajectory.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 201);
}

// A record nothing resumes (sage run's) keeps its partial metrics.json as it runs, with no
// checkpoint.bin beside it; the periodic ones as the explicit ones.
TEST_F(RunDirectoryTest, ARecordNothingResumesWritesPartialMetricsOnly) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 6.0);
  RunDirectoryOptions options;
  options.checkpoint_period_s = 0.0;
  options.resumable = false;
  RunDirectory run(dir_.string(), s, options);
  Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
  FlyToCheckpoint(mission, run, 3.0);
  const RecordSummary partial = ReadRecordSummary(dir_.string());
  EXPECT_FALSE(partial.complete);
  EXPECT_DOUBLE_EQ(partial.recorded_until_s, mission.core().time_s());
  EXPECT_FALSE(partial.has_checkpoint);
  EXPECT_FALSE(fs::exists(dir_ / "checkpoint.bin"));
  const nlohmann::json metrics = nlohmann::json::parse(Read(dir_ / "metrics.json"));
  EXPECT_FALSE(metrics.at("complete").get<bool>());
  EXPECT_NEAR(metrics.at("duration_s").get<double>(), mission.core().time_s(), 1e-9);
  while (mission.Step()) run.Tick(mission.core());
  run.Finish(mission.core(), mission.world(), 6.0, false);
  EXPECT_TRUE(ReadRecordSummary(dir_.string()).complete);
}

// The run directory's copy of the seabed map is taken as the mission starts and is the map it
// flew: the source deleted mid-mission does not keep the final set from being written (the end had
// copied the map again), a copy another mission left there under another extension is removed.
TEST_F(RunDirectoryTest, TheSeabedMapIsKeptAsTheMissionStarts) {
  const fs::path source = dir_.string() + "_source";
  fs::remove_all(source);
  fs::create_directories(source);
  const std::string scenarios = std::string(SAGE_SOURCE_DIR) + "/scenarios/";
  fs::copy_file(scenarios + "manifold_slope.xyz", source / "manifold_slope.xyz");
  fs::copy_file(scenarios + "manifold_slope.yaml", source / "manifold_slope.yaml");
  fs::create_directories(dir_);
  std::ofstream(dir_ / "seabed_map.csv") << "x,y,z\n";  // an earlier mission's
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario((source / "manifold_slope.yaml").string()), 2.0);
  RunDirectory run(dir_.string(), s);
  EXPECT_FALSE(fs::exists(dir_ / "seabed_map.csv"));
  EXPECT_EQ(Read(dir_ / "seabed_map.xyz"), Read(scenarios + "manifold_slope.xyz"));
  Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
  fs::remove_all(source);
  while (mission.Step()) run.Tick(mission.core());
  ASSERT_NO_THROW(run.Finish(mission.core(), mission.world(), 2.0, false));
  EXPECT_TRUE(ReadRecordSummary(dir_.string()).complete);
  EXPECT_EQ(Read(dir_ / "seabed_map.xyz"), Read(scenarios + "manifold_slope.xyz"));
  const maps::Scenario kept = maps::LoadScenario((dir_ / "scenario.yaml").string());
  ASSERT_TRUE(kept.seabed.has_value());
  EXPECT_EQ(fs::path(kept.seabed->map), dir_ / "seabed_map.xyz");
  EXPECT_EQ(kept.seabed->map_fnv1a, s.seabed->map_fnv1a);
  EXPECT_EQ(maps::ScenarioHash(kept), maps::ScenarioHash(s));
}

// If one file of the final set cannot be written, none of it appears: metrics.json stays the
// partial one (complete: false), no plot, no temporaries, and the error names the file.
TEST_F(RunDirectoryTest, FinalSetIsAllOrNothing) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 5.0);
  RunDirectoryOptions options;
  options.checkpoint_period_s = 0.0;
  RunDirectory run(dir_.string(), s, options);
  Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
  while (mission.Step()) run.Tick(mission.core());
  run.Checkpoint(mission.core());
  fs::create_directories(dir_ / "seabed.bt.tmp");  // a directory where a file must go: the write fails
  try {
    run.Finish(mission.core(), mission.world(), 5.0, false);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("seabed.bt"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(ReadRecordSummary(dir_.string()).complete);
  EXPECT_FALSE(fs::exists(dir_ / "plot.svg"));
  EXPECT_FALSE(fs::exists(dir_ / "plot.svg.tmp"));
  EXPECT_FALSE(fs::exists(dir_ / "plot.png"));
  EXPECT_FALSE(fs::exists(dir_ / "plot.png.tmp"));
  EXPECT_FALSE(fs::exists(dir_ / "metrics.json.tmp"));
}

// risk.ot in the run directory loads back as the risk layer's tree type: without a layer it is
// the prior layer (no leaf; a layer loading it has the valves' phi_k exactly); with one, every
// leaf's excess comes back bit for bit and a layer loading it has the same phi_k (1e-12 relative).
TEST_F(RunDirectoryTest, RiskOtLoadsBackAsTheRiskTree) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 2.0);
  for (const bool with_layer : {false, true}) {
    fs::remove_all(dir_);
    RunDirectory run(dir_.string(), s);
    Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
    while (mission.Step()) run.Tick(mission.core());
    maps::RiskLayer layer = maps::RiskLayer::ForWorld(mission.world());
    layer.Raise(s.AllValves()[1].position_m, 0.8, 1.5);
    layer.SetExcess({0.1, 0.1}, -0.25);
    run.Finish(mission.core(), mission.world(), 2.0, false, with_layer ? &layer : nullptr);

    std::ifstream in(dir_ / "risk.ot", std::ios::binary);
    ASSERT_TRUE(in) << "no risk.ot";
    const std::unique_ptr<maps::RiskOcTree> tree = maps::ReadRiskOcTree(in, (dir_ / "risk.ot").string());
    EXPECT_EQ(tree->getTreeType(), "SageRiskOcTree");
    EXPECT_EQ(tree->getResolution(), layer.resolution_m());
    EXPECT_EQ(static_cast<std::int64_t>(tree->getNumLeafNodes()), with_layer ? layer.leaf_count() : 0);
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
      const Eigen::Vector2d inside(it.getX() - 0.25 * it.getSize(), it.getY() - 0.25 * it.getSize());
      EXPECT_EQ(it->risk(), static_cast<float>(layer.Excess(inside)));
    }
    maps::RiskLayer loaded = maps::RiskLayer::ForWorld(mission.world());
    std::ifstream again(dir_ / "risk.ot", std::ios::binary);
    loaded.LoadExcess(again, "risk.ot");
    const Eigen::VectorXd& expected = with_layer ? layer.coefficients() : mission.world().risk().coefficients();
    EXPECT_LE((loaded.coefficients() - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
        << (with_layer ? "with" : "without") << " a layer";
  }
}

// A resumed record is cut back to its last complete line (a crash can leave half a line) and
// continues after it; a new mission in the same directory starts the files afresh.
TEST_F(RunDirectoryTest, ResumeContinuesACutRecord) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  {
    RunDirectory run(dir_.string(), s);
    run.OnSample({0.1, 0, {1.0, 2.0}, 0.0, {0, 0}, {0, 0}}, "rov1");
  }
  {
    std::ofstream cut(dir_ / "trajectory.csv", std::ios::app);
    cut << "0.2,rov1,1.5";  // half a row
  }
  RunDirectoryOptions resume;
  resume.resume = true;
  {
    RunDirectory run(dir_.string(), s, resume);
    run.OnSample({0.3, 0, {1.0, 2.5}, 0.0, {0, 0}, {0, 0}}, "rov1");
  }
  EXPECT_EQ(Read(dir_ / "trajectory.csv"),
            "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n0.1,rov1,1,2,0,0,0,0,0\n0.3,rov1,1,2.5,0,0,0,0,0\n");
  const RecordTail tail = ReadRecordTail(dir_.string(), 0.1);
  ASSERT_EQ(tail.samples.size(), 1u);
  EXPECT_EQ(tail.samples[0].first.time_s, 0.3);
  EXPECT_EQ(tail.samples[0].second, "rov1");
  { RunDirectory fresh(dir_.string(), s); }
  EXPECT_EQ(Read(dir_ / "trajectory.csv"), "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n");
}

// A resumed mission draws its whole record, not only what came after the resume: a record left
// by a crash at its end (everything flushed, nothing finished), restored into the plot of a new
// RunDirectory and finished, draws plot.svg byte for byte as the mission that never stopped —
// fleet_field under 'leak' to 450 s: P9's risk change at 300 s, rov5's join at 200 s and rov2's
// loss at 400 s, five vehicles' tracks.
TEST_F(RunDirectoryTest, ResumedPlotDrawsTheWholeRecord) {
  const maps::Scenario s =
      maps::WithDuration(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml"), 450.0);
  const fs::path whole = dir_.string() + "_whole";
  fs::remove_all(whole);
  {
    RunDirectory run(whole.string(), s);
    Mission mission(s, MissionOptions{"leak", ControllerKind::kErgodic, &run, false});
    while (mission.Step()) run.Tick(mission.core());
    run.Finish(mission.core(), mission.world(), 450.0, false);
  }
  RunDirectoryOptions options;
  options.flush_period_s = 0.0;
  Mission mission(s, MissionOptions{"leak", ControllerKind::kErgodic, nullptr, false});
  {
    RunDirectory run(dir_.string(), s, options);
    Mission recorded(s, MissionOptions{"leak", ControllerKind::kErgodic, &run, false});
    while (recorded.Step()) run.Tick(recorded.core());
  }  // the crash: everything flushed, nothing finished
  while (mission.Step()) {
  }
  ASSERT_NE(Read(dir_ / "risk_events.csv").find("300,P9"), std::string::npos) << Read(dir_ / "risk_events.csv");
  ASSERT_NE(Read(dir_ / "fleet_events.csv").find(",joined,4,rov5"), std::string::npos);
  RunDirectoryOptions resume = options;
  resume.resume = true;
  RunDirectory run(dir_.string(), s, resume);
  std::map<int, int> index_of_id;
  for (const auto& [id, member] : mission.core().roster().members()) index_of_id[id] = member.index;
  run.RestorePlot(index_of_id);
  run.Finish(mission.core(), mission.world(), 450.0, false);
  const std::string drawn = Read(dir_ / "plot.svg");
  EXPECT_NE(drawn.find("rov5 joined"), std::string::npos);
  EXPECT_EQ(drawn, Read(whole / "plot.svg"));
  // Without the restore, the resumed plot had no track and no mark at all.
  fs::remove_all(whole);
}

// A large fleet's cycles (rows formatted off the cycle) land in trajectory.csv in order and
// byte for byte as one sample at a time writes them, with small cycles and single samples in
// between, and a flush in the middle holds every row given before it.
TEST_F(RunDirectoryTest, LargeCyclesWriteTheSameRowsInOrder) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  std::vector<std::string> names;
  std::vector<const std::string*> name_of;
  for (int v = 0; v < 900; ++v) names.push_back(fmt::format("rov{}", v));
  for (const std::string& n : names) name_of.push_back(&n);
  const auto cycle = [](int c, int vehicles) {
    std::vector<TrajectorySample> samples;
    for (int v = 0; v < vehicles; ++v) {
      samples.push_back({0.1 * c, v, {0.01 * v + c / 3.0, 7.0 / (v + 1)}, 0.001 * v, {1.0 / 3, -0.25}, {0, 1e-9 * v}});
    }
    return samples;
  };
  const std::vector<int> sizes = {900, 3, 700, 900, 1};
  const fs::path one_by_one = dir_.string() + "_one_by_one";
  {
    RunDirectory run(one_by_one.string(), s);
    for (std::size_t c = 0; c < sizes.size(); ++c)
      for (const TrajectorySample& x : cycle(static_cast<int>(c), sizes[c])) run.OnSample(x, names[x.vehicle]);
  }
  RunDirectoryOptions options;
  options.flush_period_s = 0.0;
  {
    RunDirectory run(dir_.string(), s, options);
    Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, nullptr, false});
    for (std::size_t c = 0; c < sizes.size(); ++c) {
      run.OnSamples(cycle(static_cast<int>(c), sizes[c]), name_of);
      if (c == 2) {
        run.Tick(mission.core());  // flush period 0: everything so far is on disk
        EXPECT_EQ(run.flushed_until_s(), 0.2);
        const std::string so_far = Read(dir_ / "trajectory.csv");
        EXPECT_EQ(std::count(so_far.begin(), so_far.end(), '\n'), 1 + 900 + 3 + 700);
      }
    }
  }
  const std::string expected = Read(one_by_one / "trajectory.csv");
  fs::remove_all(one_by_one);
  EXPECT_EQ(std::count(expected.begin(), expected.end(), '\n'), 1 + 900 + 3 + 700 + 900 + 1);
  EXPECT_EQ(Read(dir_ / "trajectory.csv"), expected);
}

// trajectory_rate_hz thins trajectory.csv, not the mission: at 2 Hz (every 5th cycle at 10 Hz) the
// file holds exactly the full record's rows of those cycles and of the last (30.3 s, off the
// rate: the record ends where the mission did), byte for byte, and metrics.json the same figures
// (they count every cycle). A large batch (rows formatted off the cycle) is split by each
// sample's own time, as a batch over DDS may hold late states of the cycle before.
TEST_F(RunDirectoryTest, TrajectoryRateThinsTheRecordNotTheMetrics) {
  const maps::Scenario full =
      maps::WithDuration(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml"), 30.3);
  maps::Scenario thinned = full;
  thinned.trajectory_rate_hz = 2.0;
  thinned.Validate();
  ASSERT_EQ(thinned.TrajectoryEvery(), 5);
  const fs::path whole = dir_.string() + "_whole";
  fs::remove_all(whole);
  const auto fly = [](const fs::path& dir, const maps::Scenario& s) {
    RunDirectory run(dir.string(), s);
    Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
    while (mission.Step()) run.Tick(mission.core());
    run.Finish(mission.core(), mission.world(), s.duration_s, false);
  };
  fly(whole, full);
  fly(dir_, thinned);
  std::istringstream all(Read(whole / "trajectory.csv"));
  std::string line, expected;
  std::getline(all, line);
  expected = line + "\n";
  int rows = 0;
  while (std::getline(all, line)) {
    const long cycle = std::lround(std::stod(line.substr(0, line.find(','))) * full.control_rate_hz);
    if (cycle % 5 == 0 || cycle == 303) expected += line + "\n", ++rows;
  }
  EXPECT_EQ(rows, 4 * (300 / 5 + 1 + 1));  // four vehicles, t = 0, 0.5, ..., 30 and 30.3
  EXPECT_EQ(Read(dir_ / "trajectory.csv"), expected);
  const nlohmann::json a = nlohmann::json::parse(Read(whole / "metrics.json"));
  const nlohmann::json b = nlohmann::json::parse(Read(dir_ / "metrics.json"));
  for (const char* key : {"valves", "ergodic_metric", "risk_weighted_interval_s", "longest_gap_s", "metric_over_time"}) {
    EXPECT_EQ(a.at(key), b.at(key)) << key;
  }
  fs::remove_all(whole);

  // Large batches: one off the rate (c = 3) leaves no row; one holding cycles 9 and 10 (the first
  // half late states of cycle 9) leaves cycle 10's 300 rows alone.
  const fs::path large = dir_.string() + "_large";
  fs::remove_all(large);
  std::vector<std::string> names;
  std::vector<const std::string*> name_of;
  for (int v = 0; v < 600; ++v) names.push_back(fmt::format("rov{}", v));
  for (const std::string& n : names) name_of.push_back(&n);
  {
    RunDirectory run(large.string(), thinned);
    std::vector<TrajectorySample> off, mixed;
    for (int v = 0; v < 600; ++v) off.push_back({0.3, v, {0.01 * v, 1.0}, 0.0, {0, 0}, {0, 0}});
    for (int v = 0; v < 600; ++v) mixed.push_back({v < 300 ? 0.9 : 1.0, v, {0.01 * v, 1.0}, 0.0, {0, 0}, {0, 0}});
    run.OnSamples(off, name_of);
    run.OnSamples(mixed, name_of);
  }
  const std::string rows_large = Read(large / "trajectory.csv");
  EXPECT_EQ(std::count(rows_large.begin(), rows_large.end(), '\n'), 1 + 300);
  EXPECT_NE(rows_large.find("\n1,rov300,"), std::string::npos);
  EXPECT_EQ(rows_large.find("\n0.3,"), std::string::npos);
  EXPECT_EQ(rows_large.find("\n0.9,"), std::string::npos);
  fs::remove_all(large);
}

// Free text in the event files cannot break a row: a detail with commas, quotes and a newline
// reads back as it was (control characters as spaces).
TEST_F(RunDirectoryTest, EventTextStaysInItsField) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  {
    RunDirectory run(dir_.string(), s);
    run.OnFleetEvent({1.5, "outage", -1, "", "down, for \"12\" s\nthen back"});
    run.OnRiskEvent({2.0, "P1", 3.0, 0.5, "sonar, \"port\""});
  }
  const RecordTail tail = ReadRecordTail(dir_.string(), 0.0);
  ASSERT_EQ(tail.fleet_events.size(), 1u);
  EXPECT_EQ(tail.fleet_events[0].detail, "down, for \"12\" s then back");
  EXPECT_EQ(tail.fleet_events[0].vehicle_id, -1);
  ASSERT_EQ(tail.risk_events.size(), 1u);
  EXPECT_EQ(tail.risk_events[0].source, "sonar, \"port\"");
  EXPECT_EQ(tail.risk_events[0].new_share, 0.5);
}

// Rows are written once they pass flush_bytes, at the end of a cycle, however long the wall-clock
// flush period: what waits in memory stays within flush_bytes and one cycle's rows (a mission
// simulated at thousands of times real time had held an hour of rows), what is on disk mid-run
// ends in a whole line, and the finished file is byte for byte a default run's.
TEST_F(RunDirectoryTest, RowsAreWrittenOnceTheyPassFlushBytes) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 60.0);
  const auto run_with = [&](const fs::path& dir, RunDirectoryOptions options, bool check) {
    RunDirectory run(dir.string(), s, options);
    Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
    std::size_t most = 0;
    while (mission.Step()) {
      run.Tick(mission.core());
      most = std::max(most, run.buffered_bytes());
    }
    if (check) {
      EXPECT_LE(most, options.flush_bytes + 1024) << "waiting in memory";
      const std::string mid = Read(dir / "trajectory.csv");
      EXPECT_GE(mid.size(), 3 * options.flush_bytes) << "written while the mission ran";
      EXPECT_EQ(mid.back(), '\n');
    }
    run.Finish(mission.core(), mission.world(), 60.0, false);
  };
  RunDirectoryOptions small;
  small.flush_period_s = 1e9;
  small.checkpoint_period_s = 1e9;
  small.flush_bytes = 16 << 10;
  run_with(dir_, small, true);
  const fs::path other = dir_.string() + "_default";
  fs::remove_all(other);
  run_with(other, RunDirectoryOptions{}, false);
  EXPECT_EQ(Read(dir_ / "trajectory.csv"), Read(other / "trajectory.csv"));
  fs::remove_all(other);
}

// metrics.json says what was refused at the door and from whom: a state with a NaN position and
// one stamped 100 s ahead of the clock, from two vehicles, appear by kind and by sender and add up
// to rejected_samples.
TEST_F(RunDirectoryTest, MetricsJsonCountsRefusalsByKindAndSender) {
  const maps::Scenario s = maps::WithDuration(maps::LoadScenario(kTwoXt), 1.0);
  maps::World world(s);
  MissionCore core(world, s, "", ControllerKind::kErgodic);
  RunDirectory run(dir_.string(), s);
  agents::StateReport nan_state, future_state;
  nan_state.id = 4, nan_state.name = "a", nan_state.state.position_m = {std::nan(""), 1.0};
  future_state.id = 5, future_state.name = "b", future_state.time_s = 100.0, future_state.state.position_m = {1.0, 1.0};
  EXPECT_FALSE(core.OnState(nan_state));
  EXPECT_FALSE(core.OnState(future_state));
  EXPECT_FALSE(core.OnState(future_state));
  core.Cycle(0);
  run.Finish(core, world, 1.0, false);
  const nlohmann::json metrics = nlohmann::json::parse(Read(dir_ / "metrics.json"));
  EXPECT_EQ(metrics.at("rejected_samples").get<int>(), 3);
  EXPECT_EQ(metrics.at("rejected_by_kind").at("state not finite").get<int>(), 1);
  EXPECT_EQ(metrics.at("rejected_by_kind").at("state ahead of the clock").get<int>(), 2);
  EXPECT_EQ(metrics.at("rejected_by_sender").at("vehicle 4").get<int>(), 1);
  EXPECT_EQ(metrics.at("rejected_by_sender").at("vehicle 5").get<int>(), 2);
}

// regions.csv: one row per region of each split, its box, basis order and valves as the split
// made them (a regions mission on fleet_field: four vehicles, one split; the same mission kept in
// memory, a fixed seed, makes the same split).
TEST_F(RunDirectoryTest, RegionsAreRecordedAsSplit) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml");
  s.fleet_events.clear();
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  s = maps::WithDuration(s, 3.0);
  {
    RunDirectory run(dir_.string(), s);
    Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, &run, false});
    while (mission.Step()) run.Tick(mission.core());
    run.Finish(mission.core(), mission.world(), 3.0, false);
  }
  TrajectoryRecorder kept;
  Mission(s, MissionOptions{"", ControllerKind::kErgodic, &kept, false}).Run();
  ASSERT_EQ(kept.regions.size(), 1u);
  std::istringstream csv(Read(dir_ / "regions.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,vehicle_id,name,x_m,y_m,width_m,height_m,order,valves");
  std::size_t rows = 0;
  for (; std::getline(csv, line); ++rows) {
    ASSERT_LT(rows, kept.regions[0].second.size());
    const RegionRecord& r = kept.regions[0].second[rows];
    std::string valves;
    for (const std::string& v : r.valves) valves += (valves.empty() ? "" : " ") + v;
    EXPECT_EQ(line, fmt::format("{},{},{},{},{},{},{},{},\"{}\"", kept.regions[0].first, r.vehicle_id, r.name,
                                r.box.origin_m.x(), r.box.origin_m.y(), r.box.size_m.x(), r.box.size_m.y(),
                                r.box.order, valves));
  }
  EXPECT_EQ(rows, s.vehicles.size());
}

}  // namespace
}  // namespace sage::server
