// Writes the fuzzers' seed corpus into DIR (one folder per harness), from the project's own
// missions so that mutation starts from what a mission really sends:
//   scenario/      generated fields of several sizes and seeds (maps/scenario/field_generator.h)
//                  and the shipped scenarios at other fleet sizes, as EmitScenario writes them
//                  (the shipped files themselves are a corpus folder of their own)
//   evaluate_csv/  trajectory.csv of short in-process missions (vehicle ids, and names)
//   server_door/   the samples a server takes in its mission's first cycles (fuzz_missions.h),
//                  under each variant of the harness, with risk updates and commands
//   agent_door/    the samples a host of three vehicles takes: the server's status, targets,
//                  snapshots, a fourth vehicle's states as a neighbour, a retire order
// Usage: sage_fuzz_seeds DIR
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "agents/agent_mission.h"
#include "agents/node/wire.h"
#include "maps/scenario/field_generator.h"
#include "server/mission.h"
#include "server/report/report.h"
#include "tests/fuzz/dds_records.h"
#include "tests/fuzz/fuzz_missions.h"

namespace sage::fuzz {
namespace {

namespace fs = std::filesystem;

void Write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}
void Write(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  Write(path, std::string(bytes.begin(), bytes.end()));
}

void ScenarioSeeds(const fs::path& dir) {
  struct Size {
    int xts, valves, vehicles;
  };
  const Size sizes[] = {{1, 2, 1}, {2, 5, 1}, {3, 9, 2}, {5, 14, 3}, {8, 20, 4}};
  std::uint64_t seed = 1;
  for (const Size& size : sizes) {
    maps::FieldOptions options;
    options.xts = size.xts;
    options.valves = size.valves;
    options.vehicles = size.vehicles;
    options.seed = seed++;
    Write(dir / ("field_" + std::to_string(size.xts) + "xt.yaml"), maps::EmitScenario(maps::GenerateField(options)));
  }
  for (const char* name : {"two_xt.yaml", "fleet_field.yaml"}) {
    const maps::Scenario s = maps::LoadScenario(ScenarioPath(name));
    Write(dir / (std::string("emitted_") + name), maps::EmitScenario(s));
    Write(dir / (std::string("three_") + name), maps::EmitScenario(maps::WithVehicleCount(s, 3)));
  }
}

void CsvSeeds(const fs::path& dir) {
  for (const char* name : {"two_xt.yaml", "fleet_field.yaml"}) {
    server::Mission mission(maps::WithDuration(maps::LoadScenario(ScenarioPath(name)), 6.0),
                            server::ControllerKind::kErgodic);
    server::Trajectory trajectory = mission.Run().trajectory;
    server::WriteTrajectoryCsv((dir / (std::string(name) + ".csv")).string(), trajectory);
    trajectory.vehicle_names.clear();
    for (std::size_t i = 0; i < mission.scenario().vehicles.size(); ++i)
      trajectory.vehicle_names.push_back(mission.scenario().vehicles[i].name);
    server::WriteTrajectoryCsv((dir / (std::string(name) + ".names.csv")).string(), trajectory);
  }
  Write(dir / "quoted_bom.csv", std::string("\xEF\xBB\xBF" "vehicle,t,y,x\n\"rov 1\",0,1.0,2.0\n\"rov 1\",0.5,1.1,2.0\n"));
}

// A record flag: writer 1, the mission's instance stamped.
constexpr std::uint8_t kStamped = 0x11;

void ServerDoorSeeds(const fs::path& dir) {
  for (std::size_t vi = 0; vi < ServerVariants().size(); ++vi) {
    ServerVariant& v = ServerVariants()[vi];
    server::MissionCore core(*v.world, v.scenario, "", v.controller);
    agents::AgentMission host(*v.world, v.scenario,
                              v.controller == server::ControllerKind::kAstar ? agents::Guidance::kAstar
                                                                             : agents::Guidance::kErgodic);
    for (std::size_t id = 0; id < v.scenario.vehicles.size(); ++id)
      host.AddVehicle(static_cast<agents::VehicleId>(id), v.scenario.vehicles[id]);
    std::vector<std::uint8_t> input{static_cast<std::uint8_t>(vi)};
    for (std::int64_t k = 0; k < 12; ++k) {
      const agents::AgentMission::CycleOutput out = host.Step(k);
      for (const agents::CoverageMessage& c : out.coverage) {
        core.OnCoverage(c);
        AppendRecord(input, kCoverage, kStamped, Encode(agents::wire::ToWire(c, 0)));
      }
      for (const agents::StateReport& s : out.states) {
        core.OnState(s);
        AppendRecord(input, kState, kStamped, Encode(agents::wire::ToWire(s, kInstance, 0)));
      }
      if (k == 4) {
        std::string valve = v.scenario.AllValves().front().name, source = "operator";
        proto::RiskUpdate r{};
        r.valve = proto::BorrowString(valve);
        r.weight = 4.0;
        r.source = proto::BorrowString(source);
        AppendRecord(input, kRiskUpdate, 0x02, Encode(r));
        for (const char* verb : {"reserve", "remove"}) {
          std::string text = verb;
          proto::FleetCommand c{};
          c.stamp_ns = 1000 + k;
          c.verb = proto::BorrowString(text);
          c.count = 2;
          c.vehicle_id = 1;
          AppendRecord(input, kCommand, 0x03, Encode(c));
        }
      }
      core.SetClock(static_cast<double>(k) / v.scenario.control_rate_hz);
      const server::CycleOutput cycle = core.Cycle(k);
      AppendRecord(input, kCycle, 0);
      host.OnFleetSnapshot(cycle.snapshot);
      for (const agents::Assignment& a : cycle.assignments) host.OnAssignment(a);
    }
    Write(dir / ("server_variant" + std::to_string(vi)), input);
  }
}

void AgentDoorSeeds(const fs::path& dir) {
  for (std::size_t vi = 0; vi < HostVariants().size(); ++vi) {
    HostVariant& v = HostVariants()[vi];
    server::MissionCore core(*v.world, v.scenario, "",
                             v.guidance == agents::Guidance::kAstar ? server::ControllerKind::kAstar
                                                                    : server::ControllerKind::kErgodic);
    // The fleet's first four vehicles: the harness's host simulates 0..2, the fourth is a neighbour.
    agents::AgentMission fleet(*v.world, v.scenario, v.guidance);
    for (int id = 0; id <= kHostVehicles; ++id) fleet.AddVehicle(id, v.scenario.vehicles[id]);
    std::vector<std::uint8_t> input{static_cast<std::uint8_t>(vi)};
    proto::MissionStatus status{};
    status.server_instance = kInstance;
    status.start_ns = 1'700'000'000'000'000'000;
    status.time_scale = 1.0;
    status.duration_s = v.scenario.duration_s;
    status.vehicle_fingerprint = v.fingerprint();
    AppendRecord(input, kStatus, 0, Encode(status));
    for (std::int64_t k = 0; k < 8; ++k) {
      AppendRecord(input, kStep, 0);
      const agents::AgentMission::CycleOutput out = fleet.Step(k);
      for (const agents::StateReport& s : out.states) {
        core.OnState(s);
        if (s.id == kHostVehicles) AppendRecord(input, kNeighbour, 0x01, Encode(agents::wire::ToWire(s, kInstance, 0)));
      }
      for (const agents::CoverageMessage& c : out.coverage) core.OnCoverage(c);
      core.SetClock(static_cast<double>(k) / v.scenario.control_rate_hz);
      const server::CycleOutput cycle = core.Cycle(k);
      // The first cycle's targets alone, the later ones in a batch, as the server node sends them.
      std::vector<proto::ErgodicTarget> batch;
      for (const agents::Assignment& a : cycle.assignments) {
        fleet.OnAssignment(a);
        if (k == 0) {
          AppendRecord(input, kTarget, 0, Encode(agents::wire::ToWire(a, kInstance, 0, 0)));
        } else {
          batch.push_back(agents::wire::ToWire(a, kInstance, 0, 0));
        }
      }
      if (!batch.empty()) {
        AppendRecord(input, kTargets, 0, Encode(agents::wire::ToWire(batch, kInstance, static_cast<std::uint64_t>(k), 0)));
      }
      fleet.OnFleetSnapshot(cycle.snapshot);
      std::vector<std::uint32_t> ids;
      std::vector<std::uint64_t> seqs;
      AppendRecord(input, kSnapshot, 0,
                   Encode(agents::wire::ToWire(cycle.snapshot, kInstance,
                                               static_cast<std::uint32_t>(v.scenario.ergodic.basis_order), 0, ids, seqs)));
    }
    std::string verb = "retire";
    proto::FleetCommand retire{};
    retire.server_instance = kInstance;
    retire.verb = proto::BorrowString(verb);
    retire.vehicle_id = 2;
    AppendRecord(input, kRetire, 0, Encode(retire));
    AppendRecord(input, kStep, 0);
    Write(dir / ("host_variant" + std::to_string(vi)), input);
  }
}

}  // namespace
}  // namespace sage::fuzz

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc != 2) {
    std::cerr << "usage: sage_fuzz_seeds DIR\n";
    return 2;
  }
  const fs::path dir = argv[1];
  try {
    for (const char* harness : {"scenario", "evaluate_csv", "server_door", "agent_door"}) {
      fs::remove_all(dir / harness);
      fs::create_directories(dir / harness);
    }
    sage::fuzz::ScenarioSeeds(dir / "scenario");
    sage::fuzz::CsvSeeds(dir / "evaluate_csv");
    sage::fuzz::ServerDoorSeeds(dir / "server_door");
    sage::fuzz::AgentDoorSeeds(dir / "agent_door");
  } catch (const std::exception& e) {
    std::cerr << "sage_fuzz_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
