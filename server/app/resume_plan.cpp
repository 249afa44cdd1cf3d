#include "server/app/resume_plan.h"

#include <map>

#include "server/mission_core.h"
#include "server/report/checkpoint.h"
#include "server/report/run_directory.h"

namespace sage::server {

std::vector<ResumedVehicle> VehiclesToResume(const maps::Scenario& scenario, const std::string& dir) {
  const MissionCheckpoint checkpoint = ReadCheckpoint(dir);
  const RecordTail tail = ReadRecordTail(dir, checkpoint.time_s);
  struct Known {
    std::string name;
    bool alive = false;
    agents::VehicleResume resume;
  };
  std::map<int, Known> known;
  for (const auto& [id, m] : checkpoint.roster.members) {
    Known& k = known[id];
    k.name = m.name;
    k.alive = m.status == Roster::Status::kAlive;
    k.resume.position_m = m.has_state ? m.last.state.position_m : SpecForVehicle(scenario, id, m.name).start_m;
    k.resume.heading_rad = m.last.state.heading_rad;
  }
  for (const auto& [id, v] : checkpoint.fleet.vehicles) {
    if (v.reported && known.count(id)) known[id].resume.coverage = v.report;
  }
  for (const FleetEventRecord& e : tail.fleet_events) {
    if (e.vehicle_id < 0) continue;
    Known& k = known[e.vehicle_id];
    k.name = e.name;
    k.alive = e.what == "joined" || e.what == "rejoined";
  }
  std::map<std::string, int> id_of;
  for (const auto& [id, k] : known) id_of[k.name] = id;
  for (const auto& [sample, name] : tail.samples) {
    const auto it = id_of.find(name);
    if (it == id_of.end()) continue;
    known[it->second].resume.position_m = sample.position_m;
    known[it->second].resume.heading_rad = sample.heading_rad;
  }
  std::vector<ResumedVehicle> out;
  for (const auto& [id, k] : known) {
    if (!k.alive) continue;
    ResumedVehicle v;
    v.id = id;
    v.spec = SpecForVehicle(scenario, id, k.name);
    v.spec.name = k.name;
    v.resume = k.resume;
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace sage::server
