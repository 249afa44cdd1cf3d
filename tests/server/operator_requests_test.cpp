// An operator's request, checked before it reaches the server and answered in one line: the
// same for the commands and the live view's buttons.
#include "server/operator_requests.h"

#include <cmath>
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
  EXPECT_EQ(VehicleLeftLine(3, 12.0), "vehicle 3 left the mission (told to at t = 12.0 s)");
  EXPECT_EQ(VehicleNotLeftLine(3, 12.0, 5.0), "vehicle 3 was told to leave at t = 12.0 s but had not left within 5 s");
  EXPECT_EQ(StopLine(40.06, "/runs/x"), "the mission stops at t = 40.1 s; its server writes /runs/x");
}

// sage status believes a vehicle's state only inside what the mission allows, and says why not.
TEST(OperatorRequests, HeardStatesCheckedAtTheDoor) {
  const maps::Workspace field{20.0, 10.0};
  const Eigen::Vector2d in(3.0, 4.0), slow(0.5, 0.2);
  EXPECT_EQ(HeardStateProblem("rov1", 12.3, in, slow, field), "");
  EXPECT_EQ(HeardStateProblem("rov1", 0.0, Eigen::Vector2d(-0.9, 10.9), slow, field), "");  // within the 1 m margin
  EXPECT_NE(HeardStateProblem("", 1.0, in, slow, field).find("name"), std::string::npos);
  EXPECT_NE(HeardStateProblem(std::string(65, 'r'), 1.0, in, slow, field).find("name"), std::string::npos);
  EXPECT_NE(HeardStateProblem("rov\n1", 1.0, in, slow, field).find("control characters"), std::string::npos);
  EXPECT_EQ(HeardStateProblem("røv1", 1.0, in, slow, field), "");  // UTF-8, as a scenario allows
  EXPECT_NE(HeardStateProblem("rov1", -0.1, in, slow, field).find("mission time"), std::string::npos);
  EXPECT_NE(HeardStateProblem("rov1", NAN, in, slow, field).find("mission time"), std::string::npos);
  EXPECT_NE(HeardStateProblem("rov1", 1.0, Eigen::Vector2d(21.5, 4.0), slow, field).find("not within the 20 x 10 m"),
            std::string::npos);
  EXPECT_NE(HeardStateProblem("rov1", 1.0, Eigen::Vector2d(NAN, 4.0), slow, field).find("position"), std::string::npos);
  EXPECT_NE(HeardStateProblem("rov1", 1.0, in, Eigen::Vector2d(8.0, 7.0), field).find("speed under 10"), std::string::npos);
  EXPECT_NE(HeardStateProblem("rov1", 1.0, in, Eigen::Vector2d(INFINITY, 0.0), field).find("velocity"), std::string::npos);

  HeardStatus status;
  status.time_s = 42.0;
  status.duration_s = 600.0;
  EXPECT_EQ(HeardStatusProblem(status), "");  // no metric yet (NaN) is allowed
  for (auto spoil : std::vector<void (*)(HeardStatus&)>{
           [](HeardStatus& s) { s.time_s = -1.0; }, [](HeardStatus& s) { s.duration_s = 0.0; },
           [](HeardStatus& s) { s.time_scale = 0.0; }, [](HeardStatus& s) { s.cycle_ms = NAN; },
           [](HeardStatus& s) { s.ergodic_metric = -0.5; }, [](HeardStatus& s) { s.ergodic_metric = INFINITY; },
           [](HeardStatus& s) { s.lost = -1; }}) {
    HeardStatus bad = status;
    spoil(bad);
    EXPECT_NE(HeardStatusProblem(bad), "");
  }
}

// The report: the mission's progress, one row a vehicle (the first max_rows, then how many more),
// and the samples refused; a finished mission says so instead of its speed.
TEST(OperatorRequests, StatusReportListsWhatWasHeard) {
  HeardStatus heard;
  heard.has_status = true;
  heard.time_s = 150.04;
  heard.duration_s = 600.0;
  heard.time_scale = 2.0;
  heard.cycle_ms = 0.4149;
  heard.ergodic_metric = 0.012345;
  heard.alive = 3;
  heard.lost = 1;
  heard.listened_s = 1.04;
  for (int id : {0, 1, 4}) {
    heard.vehicles.push_back({id, "rov" + std::to_string(id + 1), 149.9, Eigen::Vector2d(1.0 + id, 2.5), 0.7});
  }
  heard.refused = 2;
  heard.last_refusal = "rov9: position (nan, 1) m is not within the 12 x 10 m workspace";
  const std::string report = StatusReport(heard, "fleet_field (runs/fleet_field_launch)", 2);
  EXPECT_NE(report.find("fleet_field (runs/fleet_field_launch): t = 150.0 of 600.0 s (25 %), running at 2.00x real time\n"),
            std::string::npos)
      << report;
  EXPECT_NE(report.find("server cycle 0.41 ms; ergodic metric 0.01235; 3 vehicles flying, 1 lost\n"), std::string::npos)
      << report;
  EXPECT_NE(report.find("vehicles heard in 1.0 s:"), std::string::npos) << report;
  EXPECT_NE(report.find("rov1"), std::string::npos);
  EXPECT_NE(report.find("rov2"), std::string::npos);
  EXPECT_EQ(report.find("rov5"), std::string::npos) << "past max_rows";
  EXPECT_NE(report.find("(and 1 more: 3 heard; the first 2 by id are shown"), std::string::npos) << report;
  EXPECT_NE(report.find("2 samples refused at the door; the last:\n  rov9: position"), std::string::npos) << report;
  // Every line but the refusal's own words within 100 columns.
  std::size_t at = 0;
  while (at < report.size()) {
    const std::size_t end = report.find('\n', at);
    if (report.compare(at, 2, "  ") != 0) EXPECT_LE(end - at, 100u) << report.substr(at, end - at);
    at = end + 1;
  }

  heard.finished = true;
  heard.time_s = 600.0;
  heard.ergodic_metric = NAN;
  heard.refused = 0;
  heard.vehicles.clear();
  const std::string done = StatusReport(heard, "m (r)");
  EXPECT_NE(done.find("t = 600.0 of 600.0 s (100 %), finished\n"), std::string::npos) << done;
  EXPECT_NE(done.find("ergodic metric not yet"), std::string::npos) << done;
  EXPECT_NE(done.find("no vehicle heard in 1.0 s"), std::string::npos) << done;
  EXPECT_EQ(done.find("refused"), std::string::npos) << done;
}

}  // namespace
}  // namespace sage::server
