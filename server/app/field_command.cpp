#include "server/app/field_command.h"

#include <chrono>

#include <spdlog/spdlog.h>

#include "server/report/mission_file.h"

namespace sage::server {

int CmdFieldGenerate(const maps::FieldOptions& options, const std::string& out_path) {
  const auto start = std::chrono::steady_clock::now();
  const maps::Scenario field = maps::GenerateField(options);
  try {
    WriteScenarioTo(out_path, field);
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(std::string("--out: ") + e.what());
  }
  spdlog::info("wrote {}: {} XTs, {} valves, {} vehicles on {:.1f} x {:.1f} m (K = {}, A* grid {} m) in {:.2f} s; run it "
               "with sage run {} or sage launch {}",
               out_path, field.structures.size(), field.ValveCount(), field.vehicles.size(),
               field.workspace.width_m, field.workspace.height_m, field.ergodic.basis_order,
               field.astar.grid_resolution_m,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), out_path, out_path);
  return 0;
}

}  // namespace sage::server
