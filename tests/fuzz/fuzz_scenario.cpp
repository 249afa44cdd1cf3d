// Fuzzing the scenario reader (maps/scenario): any text either loads as a scenario or is refused
// with one line (maps::ScenarioError, no control characters), and nothing else ever leaves the
// reader. One in four scenarios that load (by the input's hash) is written again (EmitScenario) and
// must load back to the same scenario (ScenarioHash), and one in four of the small ones (a grid of at most 40,000 A* cells,
// K <= 24, a few vehicles and valves) is built into its World and flown for a few cycles
// in-process under one controller, so that the bounds of every field that drives cost are tried
// for real.
#include <cstdint>
#include <string>

#include "maps/scenario/scenario.h"
#include "server/mission.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

bool SmallEnoughToFly(const sage::maps::Scenario& s) {
  const double cells = (s.workspace.width_m / s.astar.grid_resolution_m) * (s.workspace.height_m / s.astar.grid_resolution_m);
  return cells <= 40000.0 && s.ergodic.basis_order <= 24 && s.vehicles.size() <= 4 && s.ValveCount() <= 24 &&
         s.physics_rate_hz <= 200.0 && s.structures.size() <= 16;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sage;
  // The reader refuses files over 64 MB before parsing (tested in the unit tests); fuzz inputs
  // stay far below that.
  if (size > (1u << 20)) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  maps::Scenario scenario;
  try {
    scenario = maps::ParseScenario(text, "fuzz.yaml");
  } catch (const maps::ScenarioError& e) {
    if (!fuzz::PrintableLine(e.what())) fuzz::Broken(std::string("an error that is not one line: ") + e.what());
    return 0;
  }
  // One input in four that loads is written back and read again, and flown if it is small (its
  // world built, a few cycles of one controller, which the input's hash picks): a flight costs a
  // hundred parses, and the parse is most of an input's time.
  std::uint64_t hash = 14695981039346656037ull;  // FNV-1a of the input
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 1099511628211ull;
  if ((hash >> 7) % 4 != 0) return 0;
  // What it writes, it reads back the same.
  const std::string emitted = maps::EmitScenario(scenario);
  try {
    const maps::Scenario again = maps::ParseScenario(emitted, "emitted.yaml");
    if (maps::ScenarioHash(again) != maps::ScenarioHash(scenario)) fuzz::Broken("emitted scenario loads as another:\n" + emitted);
  } catch (const maps::ScenarioError& e) {
    fuzz::Broken(std::string("emitted scenario does not load: ") + e.what() + "\n" + emitted);
  }
  if (!SmallEnoughToFly(scenario)) return 0;
  {
    const auto controller = (hash >> 8) % 2 == 0 ? server::ControllerKind::kErgodic : server::ControllerKind::kAstar;
    server::MissionOptions options;
    options.controller = controller;
    options.threads = 1;
    options.keep_trajectory = false;
    try {
      server::Mission mission(scenario, options);
      for (int k = 0; k < 3 && mission.Step(); ++k) {
      }
    } catch (const maps::ScenarioError& e) {
      // A scenario may still be refused when its world is built (a start inside a structure).
      if (!fuzz::PrintableLine(e.what())) fuzz::Broken(std::string("an error that is not one line: ") + e.what());
    }
  }
  return 0;
}
