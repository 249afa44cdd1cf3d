// Fuzzing the CSV reader of `sage evaluate` (server/report): any text either reads as a
// trajectory or is refused with one line (maps::ScenarioError), and a trajectory that reads is
// evaluated as `sage evaluate` does (against two_xt's leak_injection profile, with its timed
// event) without anything else leaving the code. Metrics of a trajectory read are finite where
// they are defined. The ergodic metric is sampled at most 2,000 times per input (evaluate's own
// bound is 100,000) so that an input stays within milliseconds.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "maps/scenario/scenario.h"
#include "server/report/report.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

const sage::maps::Scenario& TwoXt() {
  static const sage::maps::Scenario scenario =
      sage::maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  return scenario;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  TwoXt();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sage;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const server::Trajectory trajectory = server::ParseTrajectoryCsv(in, "fuzz.csv");
    const maps::Scenario& scenario = TwoXt();
    const server::MissionMetrics m = server::EvaluateRecorded(
        trajectory, scenario, scenario.ProfileOrThrow("leak_injection"), std::nullopt, "fuzz.csv", 2000.0);
    if (!std::isfinite(m.duration_s) || !std::isfinite(m.time_outside_s) || !std::isfinite(m.time_pinned_s) ||
        !std::isfinite(m.expected_detection_delay_s) || !std::isfinite(m.risk_weighted_interval_s)) {
      fuzz::Broken("a figure of a trajectory read is not finite");
    }
    for (const server::ValveMetrics& v : m.valves) {
      if (!std::isfinite(v.time_near_s) || !std::isfinite(v.max_gap_s) || !std::isfinite(v.longest_unwatched_s)) {
        fuzz::Broken("a valve's figure is not finite");
      }
    }
  } catch (const maps::ScenarioError& e) {
    if (!fuzz::PrintableLine(e.what())) fuzz::Broken(std::string("an error that is not one line: ") + e.what());
  }
  return 0;
}
