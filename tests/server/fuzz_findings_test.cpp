// What the fuzz harnesses found (tests/fuzz/regressions), as tests of the normal build: each input
// that broke something, through the same public path, with the property it broke. The fuzz build
// replays the same inputs under ASan and UBSan (ctest -L fuzz).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "maps/scenario/field_generator.h"
#include "maps/scenario/scenario.h"
#include "server/mission.h"
#include "server/report/report.h"

namespace sage::server {
namespace {

std::string Regression(const std::string& harness, const std::string& file) {
  std::ifstream in(std::string(SAGE_SOURCE_DIR) + "/tests/fuzz/regressions/" + harness + "/" + file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool Printable(const std::string& message) {
  for (const char c : message)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  return true;
}

// A map key holding a control character (GS) reached the error line as it was.
TEST(FuzzFindings, ScenarioErrorsShowNoControlCharacters) {
  const std::string text = Regression("scenario", "control_character_in_a_key.yaml");
  ASSERT_FALSE(text.empty());
  try {
    maps::ParseScenario(text, "fuzz.yaml");
    FAIL() << "the input loaded";
  } catch (const maps::ScenarioError& e) {
    EXPECT_TRUE(Printable(e.what())) << e.what();
    EXPECT_NE(std::string(e.what()).find("weights.P10:?1 = null: must be a number"), std::string::npos) << e.what();
  }
}

// A number field holding a control character reached the error line as it was.
TEST(FuzzFindings, CsvErrorsShowNoControlCharacters) {
  std::istringstream in(Regression("evaluate_csv", "control_character_in_a_number.csv"));
  try {
    ParseTrajectoryCsv(in, "fuzz.csv");
    FAIL() << "the input read";
  } catch (const maps::ScenarioError& e) {
    EXPECT_TRUE(Printable(e.what())) << e.what();
    EXPECT_NE(std::string(e.what()).find("column 'x'"), std::string::npos) << e.what();
  }
}

// The smallest generated field flown as a fleet of tours: the planner's nearest-medoid search
// stopped at 4 um when all medoids sat at one point (one vehicle, one tour) and indexed at -1,
// which only the sanitizers saw; the one tour holds both valves and both are visited.
TEST(FuzzFindings, OneTourOfTheSmallestFieldHoldsEveryValve) {
  maps::FieldOptions options;
  options.xts = 1;
  options.valves = 2;
  options.vehicles = 1;
  options.seed = 1;
  Mission mission(maps::WithDuration(maps::GenerateField(options), 60.0), ControllerKind::kAstar);
  const MissionResult result = mission.Run();
  ASSERT_EQ(result.metrics.valves.size(), 2u);
  for (const ValveMetrics& v : result.metrics.valves) EXPECT_GE(v.visits, 3) << v.name;
}

}  // namespace
}  // namespace sage::server
