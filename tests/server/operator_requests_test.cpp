// An operator's request, checked before it reaches the server and answered in one line: the
// same for the commands and the live view's buttons.
#include "server/operator_requests.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "maps/scenario/field_generator.h"

namespace sage::server {
namespace {

const std::string kTwoXt = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";

std::string Refusal(const maps::Scenario& s, const std::string& valve, double weight) {
  try {
    CheckRiskRequest(s, valve, weight);
  } catch (const maps::ScenarioError& e) {
    return e.what();
  }
  return "";
}

TEST(OperatorRequests, RiskRequestsCheckedAtTheDoor) {
  const maps::Scenario s = maps::LoadScenario(kTwoXt);
  EXPECT_EQ(Refusal(s, "P1", 0.9), "");
  EXPECT_EQ(Refusal(s, "P1", -1), "weight = -1: must be a number in [0, 1e12] (weights are relative)");
  EXPECT_NE(Refusal(s, "P1", std::nan("")).find("must be a number"), std::string::npos);
  EXPECT_EQ(Refusal(s, "P9", 1), "valve = P9: not in this mission (valves: P1, P2, P3, P4, P5)");
  maps::FieldOptions big;
  big.xts = 20;
  big.valves = 70;
  big.vehicles = 2;
  const std::string many = Refusal(maps::GenerateField(big), "nope", 1);
  EXPECT_NE(many.find(", ... (70 in all))"), std::string::npos) << many;
  EXPECT_THROW(CheckAddCount(0), maps::ScenarioError);
  EXPECT_THROW(CheckAddCount(10001), maps::ScenarioError);
  EXPECT_NO_THROW(CheckAddCount(10000));
  EXPECT_THROW(CheckVehicleId(-1), maps::ScenarioError);
}

TEST(OperatorRequests, OneLineAnswers) {
  EXPECT_EQ(RiskAppliedLine("P9", 20, 31.25, 0.4172), "P9: risk 20 applied at t = 31.2 s; now 41.7 % of the field's risk");
  EXPECT_EQ(RiskRefusedLine("rate limit"), "the mission did not apply it: rate limit");
  EXPECT_EQ(HostStartedLine(4242, 2, 8, "r/agents-add-8.log"),
            "started agent host pid 4242 with 2 vehicles: rov9..rov10, ids 8..9 (log: r/agents-add-8.log)");
  EXPECT_EQ(HostStartedLine(4243, 1, 2, "r/agents-add-2.log"),
            "started agent host pid 4243 with 1 vehicle: rov3, id 2 (log: r/agents-add-2.log)");
  EXPECT_EQ(VehicleLeftLine(3, "rov4", 12.0), "rov4 (id 3) left the mission (told to at t = 12.0 s)");
  EXPECT_EQ(VehicleLeftLine(3, "", 12.0), "vehicle 3 left the mission (told to at t = 12.0 s)");
  EXPECT_EQ(VehicleNotLeftLine(3, "rov4", 12.0, 5.0), "rov4 (id 3) was told to leave at t = 12.0 s but had not left within 5 s");
  EXPECT_EQ(VehicleNotLeftLine(3, "", 12.0, 5.0), "vehicle 3 was told to leave at t = 12.0 s but had not left within 5 s");
  EXPECT_EQ(StopLine(40.06, "/runs/x"), "the mission stops at t = 40.1 s; its server writes /runs/x");
}

// sage status believes a vehicle's state only inside what the mission allows, and says why not.
TEST(OperatorRequests, HeardStatesCheckedAtTheDoor) {
  maps::Scenario scenario;
  scenario.workspace = {20.0, 10.0};
  scenario.vehicles.resize(1);
  scenario.vehicles[0].transit_speed_mps = 5.0;  // a fast scenario: up to 15 m/s believed
  constexpr std::int64_t kMaxId = 1000;
  const Eigen::Vector2d in(3.0, 4.0), slow(0.5, 0.2);
  const auto problem = [&](std::uint64_t id, const std::string& name, double t, const Eigen::Vector2d& x,
                           const Eigen::Vector2d& v) { return HeardStateProblem(id, name, t, x, v, scenario, kMaxId); };
  EXPECT_EQ(problem(0, "rov1", 12.3, in, slow), "");
  EXPECT_EQ(problem(1000, "røv1", 0.0, in, slow), "");  // UTF-8, as a scenario allows; the last id
  EXPECT_NE(problem(1001, "rov1", 0.0, in, slow).find("id 1001: not one a mission issues (0..1000)"), std::string::npos);
  // A crowded fleet pushes hulls out of the box: as far as the server takes (20 m here), not further.
  EXPECT_EQ(problem(0, "rov1", 0.0, Eigen::Vector2d(-0.9, 10.9), slow), "");
  EXPECT_EQ(problem(0, "rov1", 0.0, Eigen::Vector2d(39.9, -19.9), slow), "");
  EXPECT_NE(problem(0, "rov1", 1.0, Eigen::Vector2d(40.5, 4.0), slow).find("(40.5, 4) m is far outside the 20 x 10 m"),
            std::string::npos);
  EXPECT_NE(problem(0, "rov1", 1.0, Eigen::Vector2d(3.0, -20.5), slow), "");
  EXPECT_NE(problem(0, "rov1", 1.0, Eigen::Vector2d(NAN, 4.0), slow).find("position"), std::string::npos);
  EXPECT_NE(problem(0, "", 1.0, in, slow).find("name"), std::string::npos);
  EXPECT_NE(problem(0, std::string(65, 'r'), 1.0, in, slow).find("name"), std::string::npos);
  EXPECT_NE(problem(0, "rov\n1", 1.0, in, slow).find("control characters"), std::string::npos);
  EXPECT_NE(problem(0, "rov1", -0.1, in, slow).find("mission time"), std::string::npos);
  EXPECT_NE(problem(0, "rov1", NAN, in, slow).find("mission time"), std::string::npos);
  EXPECT_EQ(problem(0, "rov1", 1.0, in, Eigen::Vector2d(14.0, 0.0)), "");
  EXPECT_NE(problem(0, "rov1", 1.0, in, Eigen::Vector2d(12.0, 9.5)).find("not a speed within 15 m/s"), std::string::npos);
  EXPECT_NE(problem(0, "rov1", 1.0, in, Eigen::Vector2d(INFINITY, 0.0)).find("velocity"), std::string::npos);
  // A huge number is said in a few digits, not hundreds.
  EXPECT_LT(problem(0, "rov1", 1.0, Eigen::Vector2d(1e300, 4.0), slow).size(), 100u);

  HeardStatus status;
  status.time_s = 42.0;
  status.duration_s = 600.0;
  EXPECT_EQ(HeardStatusProblem(status, kMaxId, 1e-3, 1e3), "");  // no metric yet (NaN) is allowed
  for (auto spoil : std::vector<void (*)(HeardStatus&)>{
           [](HeardStatus& s) { s.time_s = -1.0; }, [](HeardStatus& s) { s.time_s = 602.0; },
           [](HeardStatus& s) { s.duration_s = 0.0; }, [](HeardStatus& s) { s.time_scale = 0.0; },
           [](HeardStatus& s) { s.time_scale = 1e300; }, [](HeardStatus& s) { s.cycle_ms = NAN; },
           [](HeardStatus& s) { s.cycle_ms = 1e300; }, [](HeardStatus& s) { s.ergodic_metric = -0.5; },
           [](HeardStatus& s) { s.ergodic_metric = INFINITY; }, [](HeardStatus& s) { s.lost = -1; },
           [](HeardStatus& s) { s.alive = 1002; }}) {
    HeardStatus bad = status;
    spoil(bad);
    EXPECT_NE(HeardStatusProblem(bad, kMaxId, 1e-3, 1e3), "");
    EXPECT_LT(HeardStatusProblem(bad, kMaxId, 1e-3, 1e3).size(), 120u) << HeardStatusProblem(bad, kMaxId, 1e-3, 1e3);
  }
}

// The report: the mission's progress at its measured pace, one row a vehicle (the first max_rows,
// then how many more), and the samples refused; a finished mission says so instead of its pace.
TEST(OperatorRequests, StatusReportListsWhatWasHeard) {
  HeardStatus heard;
  heard.has_status = true;
  heard.time_s = 150.04;
  heard.duration_s = 600.0;
  heard.time_scale = 2.0;
  heard.measured_rate = 1.734;
  heard.cycle_ms = 0.4149;
  heard.ergodic_metric = 0.012345;
  heard.alive = 4;
  heard.lost = 1;
  heard.listened_s = 1.04;
  for (int id : {0, 1, 4}) {
    heard.vehicles.push_back({id, "rov" + std::to_string(id + 1), 149.9, Eigen::Vector2d(1.0 + id, -2.5), 0.7});
  }
  heard.vehicles.push_back({7, std::string(40, 'x'), 149.9, Eigen::Vector2d(1.0, 2.5), 0.7});
  heard.refused = 2;
  heard.last_refusal = "rov9: position (nan, 1) m is far outside the 12 x 10 m workspace";
  heard.left = 2;
  heard.plan_time_s = 100.5;
  heard.plan = "regions: 3 regions for 4 vehicles; 1 vehicle(s) held in reserve";
  const std::string report = StatusReport(heard, "fleet_field", "runs/fleet_field_launch", 2);
  EXPECT_NE(report.find("fleet_field: t = 150.0 of 600.0 s (25 %), running at 1.73x real time (asked 2x)\n"
                        "run directory runs/fleet_field_launch\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("server cycle 0.41 ms; ergodic metric 0.01235; 4 vehicles flying, 1 lost, 2 left\n"),
            std::string::npos)
      << report;
  // The record's latest plan, which says how many are held in reserve (they hold, at no speed).
  EXPECT_NE(report.find("the plan flown, of t = 100.5 s:\n  regions: 3 regions for 4 vehicles; 1 vehicle(s) held in "
                        "reserve\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("vehicles heard in 1.0 s (4 of 4 flying):"), std::string::npos) << report;
  EXPECT_NE(report.find("       0  rov1      1.00     -2.50        0.70     149.9\n"), std::string::npos) << report;
  EXPECT_NE(report.find("rov2"), std::string::npos);
  EXPECT_EQ(report.find("rov5"), std::string::npos) << "past max_rows";
  EXPECT_NE(report.find("(and 2 more: 4 heard; the first 2 by id are shown"), std::string::npos) << report;
  EXPECT_NE(report.find("2 samples refused at the door; the last:\n  rov9: position"), std::string::npos) << report;
  // Every line but the refusal's own words within 100 columns, a 40-character name cut to 24.
  const std::string every = StatusReport(heard, std::string(64, 'm'), "r", 10);
  EXPECT_NE(every.find(std::string(24, 'x') + "..."), std::string::npos) << every;
  EXPECT_EQ(every.find(std::string(25, 'x')), std::string::npos) << every;
  for (const std::string* text : {&report, &every}) {
    for (std::size_t at = 0; at < text->size();) {
      const std::size_t end = text->find('\n', at);
      if (text->compare(at, 2, "  ") != 0) EXPECT_LE(end - at, 100u) << text->substr(at, end - at);
      at = end + 1;
    }
  }

  heard.finished = true;
  heard.left = -1;  // no record read: nothing said of it
  heard.plan.clear();
  heard.time_s = 600.0;
  heard.ergodic_metric = NAN;
  heard.refused = 0;
  heard.vehicles.clear();
  const std::string done = StatusReport(heard, "m", "r");
  EXPECT_NE(done.find("t = 600.0 of 600.0 s (100 %), finished\n"), std::string::npos) << done;
  EXPECT_NE(done.find("ergodic metric not yet"), std::string::npos) << done;
  EXPECT_NE(done.find("no vehicle heard in 1.0 s"), std::string::npos) << done;
  EXPECT_EQ(done.find("refused"), std::string::npos) << done;
  EXPECT_EQ(done.find("left"), std::string::npos) << done;
  EXPECT_EQ(done.find("plan"), std::string::npos) << done;
  heard.finished = false;
  heard.measured_rate = NAN;  // one status heard: the pace asked
  EXPECT_NE(StatusReport(heard, "m", "r").find("running, asked 2x real time"), std::string::npos);
}

}  // namespace
}  // namespace sage::server
