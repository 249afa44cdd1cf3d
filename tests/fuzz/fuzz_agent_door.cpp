// Fuzzing an agent host's door: every sample a host takes over DDS (the server's status, targets,
// fleet snapshots and retire orders, the other hosts' vehicle states), decoded from CDR by
// Cyclone as a reader does and handed to the door the agent node uses (agents/node/host_door.h),
// on a fresh host of three BlueROV2s of two_xt per input, stepped in between. Beyond crashes
// and sanitizer reports, whatever arrives must leave the vehicles' states, commands and coverage
// finite: a message that passes the door is one the vehicles can steer on.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "agents/agent_mission.h"
#include "agents/node/host_door.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "tests/fuzz/dds_records.h"
#include "tests/fuzz/fuzz_missions.h"

namespace sage::fuzz {
namespace {

void CheckFinite(const agents::AgentMission& mission, const agents::AgentMission::CycleOutput& out) {
  for (const agents::StateReport& s : out.states) {
    if (!s.state.position_m.allFinite() || !s.state.velocity_mps.allFinite() || !std::isfinite(s.state.heading_rad) ||
        !s.command_mps.allFinite()) {
      Broken("a vehicle's state or command is not finite after the messages it was sent");
    }
  }
  for (const agents::CoverageMessage& c : out.coverage) {
    if (!c.report.sums.allFinite() || !std::isfinite(c.report.kernel_time_s)) Broken("coverage not finite");
  }
  for (const agents::VehicleId id : mission.ids()) {
    if (!mission.host().State(id).position_m.allFinite()) Broken("a vehicle's position is not finite");
  }
}

}  // namespace
}  // namespace sage::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  sage::fuzz::HostVariants();
  sage::fuzz::PrintCountsAtExit("sage_fuzz_agent_door");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sage;
  using namespace sage::fuzz;
  if (size < 1) return 0;
  const HostVariant& v = HostVariants()[data[0] % HostVariants().size()];
  agents::AgentMission mission(*v.world, v.scenario, v.guidance);
  for (int id = 0; id < kHostVehicles; ++id) mission.AddVehicle(id, v.scenario.vehicles[id]);
  agents::HostDoor door(mission, v.fingerprint());
  std::int64_t k = 0;
  for (const Record& r : SplitRecords(data + 1, size - 1)) {
    switch (static_cast<HostOp>(r.op % kHostOps)) {
      case kStatus: {
        Decoded<proto::MissionStatus> m(r.payload);
        if (!m.ok() || !r.valid_data()) break;
        if (r.stamp_instance()) {
          m.get().server_instance = kInstance;
          m.get().vehicle_fingerprint = v.fingerprint();
        }
        door.TakeStatus(m.get());
        break;
      }
      case kTarget: {
        Decoded<proto::ErgodicTarget> m(r.payload);
        if (!m.ok() || !r.valid_data()) break;
        if (r.stamp_instance()) m.get().server_instance = door.clock().instance;
        door.TakeTarget(m.get(), k);
        break;
      }
      case kTargets: {
        Decoded<proto::ErgodicTargets> m(r.payload);
        if (!m.ok() || !r.valid_data()) break;
        if (r.stamp_instance()) {
          m.get().server_instance = door.clock().instance;
          for (std::uint32_t i = 0; i < m.get().targets._length; ++i) m.get().targets._buffer[i].server_instance = door.clock().instance;
        }
        door.TakeTargets(m.get(), k);
        break;
      }
      case kSnapshot: {
        Decoded<proto::FleetCoverage> m(r.payload);
        if (!m.ok() || !r.valid_data()) break;
        if (r.stamp_instance()) m.get().server_instance = door.clock().instance;
        door.TakeSnapshot(m.get(), k);
        break;
      }
      case kRetire: {
        Decoded<proto::FleetCommand> m(r.payload);
        if (!m.ok() || !r.valid_data()) break;
        if (r.stamp_instance()) m.get().server_instance = door.clock().instance;
        // The node retires a vehicle it is ordered to (and never its last: the host then ends).
        if (const auto id = door.TakeCommand(m.get()); id && mission.vehicle_count() > 1) mission.RemoveVehicle(*id);
        break;
      }
      case kNeighbour: {
        Decoded<proto::VehicleState> m(r.payload);
        if (!m.ok()) break;
        if (r.stamp_instance()) m.get().server_instance = door.clock().instance;
        door.TakeNeighbour(m.get(), r.valid_data(), r.instance_state() == 0);
        break;
      }
      case kStep: {
        mission.SetOtherVehicles(door.OthersAt(k - 1));
        CheckFinite(mission, mission.Step(k++));
        break;
      }
      case kHostOps:
        break;
    }
  }
  return 0;
}
