// An operator's request, checked before it reaches the server and answered in one line: the
// same for the commands and the live view's buttons.
#include "server/operator_requests.h"

#include <cmath>

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

}  // namespace
}  // namespace sage::server
