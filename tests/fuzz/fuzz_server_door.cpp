// Fuzzing the server's door: every sample a server takes over DDS (vehicle states and coverage,
// operators' risk updates and fleet commands), decoded from CDR by Cyclone as a reader does and
// handed to the door the server node uses (server/node/server_door.h), on a fresh mission core
// of two_xt with four vehicles per input (fuzz_missions.h), with server cycles in between.
// Beyond crashes and sanitizer reports, nothing that is not finite may leave the server: every
// snapshot and assignment it sends is checked, and so is the fleet a door lets in (the
// workspace's room).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/mission_core.h"
#include "server/node/server_door.h"
#include "tests/fuzz/dds_records.h"
#include "tests/fuzz/fuzz_missions.h"

namespace sage::fuzz {
namespace {

void CheckFinite(const server::CycleOutput& out) {
  const agents::FleetSnapshot& s = out.snapshot;
  if (!s.phi.allFinite() || !s.coverage.sums.allFinite() || !std::isfinite(s.coverage.time_s) ||
      !std::isfinite(s.coverage.kernel_time_s) || !s.valve_weights.allFinite()) {
    Broken("the server sent a fleet snapshot that is not finite");
  }
  for (const agents::Assignment& a : out.assignments) {
    if (!a.phi.allFinite() || !a.tour_weights.allFinite() || !a.region_origin_m.allFinite() ||
        !a.region_size_m.allFinite()) {
      Broken("the server sent an assignment that is not finite");
    }
  }
}

}  // namespace
}  // namespace sage::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  sage::fuzz::ServerVariants();
  sage::fuzz::PrintCountsAtExit("sage_fuzz_server_door");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sage;
  using namespace sage::fuzz;
  if (size < 1) return 0;
  ServerVariant& v = ServerVariants()[data[0] % ServerVariants().size()];
  server::MissionCore core(*v.world, v.scenario, "", v.controller);
  server::ServerDoor door(core, kInstance, v.scenario.control_rate_hz);
  const double area_m2 = v.scenario.workspace.width_m * v.scenario.workspace.height_m;
  const std::size_t room = static_cast<std::size_t>(std::floor(area_m2 / maps::kMinAreaPerBlueRov2_m2));
  std::int64_t cycle = 0;
  for (const Record& r : SplitRecords(data + 1, size - 1)) {
    switch (static_cast<ServerOp>(r.op % kServerOps)) {
      case kState: {
        Decoded<proto::VehicleState> m(r.payload);
        if (!m.ok()) break;
        if (r.stamp_instance()) m.get().server_instance = kInstance;
        if (r.valid_data()) door.TakeState(m.get(), r.writer());
        if (r.instance_state() != 0) core.OnVehicleGone(static_cast<int>(m.get().vehicle_id), r.instance_state() == 2);
        break;
      }
      case kCoverage: {
        Decoded<proto::VehicleCoverage> m(r.payload);
        if (m.ok() && r.valid_data()) door.TakeCoverage(m.get(), r.writer());
        break;
      }
      case kRiskUpdate: {
        Decoded<proto::RiskUpdate> m(r.payload);
        if (m.ok() && r.valid_data()) {
          const std::optional<server::OperatorAnswer> a = door.TakeRiskUpdate(m.get(), r.writer());
          if (a && a->accepted && !std::isfinite(a->new_share)) Broken("a risk update gave a share that is not finite");
        }
        break;
      }
      case kCommand: {
        Decoded<proto::FleetCommand> m(r.payload);
        if (m.ok() && r.valid_data()) door.TakeCommand(m.get());
        break;
      }
      case kCycle: {
        core.SetClock(static_cast<double>(cycle) / v.scenario.control_rate_hz);
        CheckFinite(core.Cycle(cycle++));
        break;
      }
      case kGone: {
        std::uint32_t id = 0;
        std::memcpy(&id, r.payload.data(), std::min<std::size_t>(r.payload.size(), sizeof id));
        core.OnVehicleGone(static_cast<int>(id), (r.flags & 1) != 0);
        break;
      }
      case kServerOps:
        break;
    }
    if (core.roster().alive_count() > room) Broken("the door let in more vehicles than the workspace holds");
  }
  if (cycle > 0) {
    const server::MissionMetrics m = core.Metrics(std::max(core.time_s(), 1.0 / v.scenario.control_rate_hz));
    for (const server::ValveMetrics& valve : m.valves) {
      if (!std::isfinite(valve.weight) || !std::isfinite(valve.time_near_s)) Broken("metrics of a valve not finite");
    }
  }
  return 0;
}
