// Scenario YAML writing: EmitScenario, the inverse of ParseScenario.
#include "maps/scenario/scenario.h"

#include <yaml-cpp/yaml.h>

#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::EventKey;
using detail::FormatNumber;

}  // namespace

std::string EmitScenario(const Scenario& s) {
  // Numbers go out as shortest round-trip text so ParseScenario(EmitScenario(s)) == s exactly;
  // the covariance is always written in full.
  YAML::Emitter out;
  const auto key = [&](const std::string& name) -> YAML::Emitter& { return out << YAML::Key << name << YAML::Value; };
  const auto number = [&](const std::string& name, double v) { key(name) << FormatNumber(v); };
  const auto vector = [&](const Eigen::Vector2d& v) {
    out << YAML::Flow << YAML::BeginSeq << FormatNumber(v.x()) << FormatNumber(v.y()) << YAML::EndSeq;
  };
  const auto vehicle_map = [&](const VehicleSpec& vehicle) {
    out << YAML::Flow << YAML::BeginMap;
    key("name") << vehicle.name;
    key("start_m"); vector(vehicle.start_m);
    number("start_heading_rad", vehicle.start_heading_rad);
    key("model") << ToString(vehicle.model);
    number("transit_speed_mps", vehicle.transit_speed_mps);
    out << YAML::EndMap;
  };
  out << YAML::Comment(std::string(kEmittedScenarioHeader).substr(2));  // YAML::Comment writes the "# "
  out << YAML::BeginMap;
  key("name") << s.name;
  key("workspace") << YAML::Flow << YAML::BeginMap;
  number("width_m", s.workspace.width_m);
  number("height_m", s.workspace.height_m);
  out << YAML::EndMap;
  number("duration_s", s.duration_s);
  number("control_rate_hz", s.control_rate_hz);
  number("physics_rate_hz", s.physics_rate_hz);
  if (s.trajectory_rate_hz > 0.0) number("trajectory_rate_hz", s.trajectory_rate_hz);
  number("visit_radius_m", s.visit_radius_m);
  number("rearm_radius_m", s.rearm_radius_m);
  key("seed") << std::to_string(s.seed);
  number("start_jitter_m", s.start_jitter_m);
  key("ergodic") << YAML::Flow << YAML::BeginMap;
  key("basis_order") << std::to_string(s.ergodic.basis_order);
  number("forgetting_time_s", s.ergodic.forgetting_time_s);
  number("min_turn_radius_m", s.ergodic.min_turn_radius_m);
  number("weight_exponent", s.ergodic.weight_exponent);
  if (s.ergodic.final_approach_m > 0.0) number("final_approach_m", s.ergodic.final_approach_m);
  out << YAML::EndMap;
  key("guard") << YAML::Flow << YAML::BeginMap;
  key("enabled") << s.guard.enabled;
  number("weight_floor", s.guard.weight_floor);
  number("revisit_bound_s", s.guard.revisit_bound_s);
  out << YAML::EndMap;
  key("astar") << YAML::Flow << YAML::BeginMap;
  number("grid_resolution_m", s.astar.grid_resolution_m);
  number("clearance_m", s.astar.clearance_m);
  number("wait_per_lap_s", s.astar.wait_per_lap_s);
  number("weight_exponent", s.astar.weight_exponent);
  number("replan_delay_s", s.astar.replan_delay_s);
  if (s.astar.order == AstarSettings::Order::kLooks) key("order") << "looks";
  if (s.astar.look_exponent != AstarSettings{}.look_exponent) number("look_exponent", s.astar.look_exponent);
  if (s.astar.look_leak_weight != AstarSettings{}.look_leak_weight) number("look_leak_weight", s.astar.look_leak_weight);
  out << YAML::EndMap;
  key("structures") << YAML::BeginSeq;
  for (const ChristmasTree& tree : s.structures) {
    out << YAML::BeginMap;
    key("name") << tree.name;
    key("center_m"); vector(tree.center_m);
    key("size_m"); vector(tree.size_m);
    number("height_m", tree.height_m);
    key("valves");
    if (tree.valves.empty()) out << YAML::Flow;  // "valves: []" on one line
    out << YAML::BeginSeq;
    for (const Valve& valve : tree.valves) {
      out << YAML::Flow << YAML::BeginMap;
      key("name") << valve.name;
      key("position_m"); vector(valve.position_m);
      key("covariance_m2") << YAML::BeginSeq;
      vector(valve.covariance_m2.row(0).transpose());
      vector(valve.covariance_m2.row(1).transpose());
      out << YAML::EndSeq << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
  key("vehicles") << YAML::BeginSeq;
  for (const VehicleSpec& vehicle : s.vehicles) vehicle_map(vehicle);
  out << YAML::EndSeq;
  key("fleet") << YAML::Flow << YAML::BeginMap;
  key("assignment") << ToString(s.fleet.assignment);
  number("coverage_period_s", s.fleet.coverage_period_s);
  number("liveliness_lease_s", s.fleet.liveliness_lease_s);
  number("age_weighting_laps", s.fleet.age_weighting_laps);
  number("risk_share", s.fleet.risk_share);
  out << YAML::EndMap;
  key("fleet_events");
  if (s.fleet_events.empty()) out << YAML::Flow;  // "fleet_events: []" on one line
  out << YAML::BeginSeq;
  for (const FleetEvent& event : s.fleet_events) {
    out << YAML::Flow << YAML::BeginMap;
    number("time_s", event.time_s);
    key(EventKey(event.kind));
    if (event.kind == FleetEvent::Kind::kJoin) vehicle_map(event.vehicle);
    else out << event.vehicle.name;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  // The seabed sections only when the scenario has them: a flat scenario writes what it always did.
  if (s.seabed) {
    const SeabedSettings& b = *s.seabed;
    key("seabed") << YAML::Flow << YAML::BeginMap;
    if (!b.map.empty()) key("map") << b.map;
    if (b.origin_m) { key("origin_m"); vector(*b.origin_m); }
    key("values") << ToString(b.values);
    key("altitude_band_m"); vector(Eigen::Vector2d(b.altitude_min_m, b.altitude_max_m));
    number("trend_radius_m", b.trend_radius_m);
    out << YAML::EndMap;
  }
  if (!s.flowlines.empty()) {
    key("flowlines") << YAML::BeginSeq;
    for (const Flowline& f : s.flowlines) {
      out << YAML::Flow << YAML::BeginMap;
      key("name") << f.name;
      number("diameter_m", f.diameter_m);
      key("points_m") << YAML::BeginSeq;
      for (const Eigen::Vector2d& p : f.points_m) vector(p);
      out << YAML::EndSeq << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (!s.boulders.empty()) {
    key("boulders") << YAML::BeginSeq;
    for (const Boulder& b : s.boulders) {
      out << YAML::Flow << YAML::BeginMap;
      key("center_m"); vector(b.center_m);
      number("diameter_m", b.diameter_m);
      number("height_m", b.height_m);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  // Only when set: a mission on this machine alone writes what it always wrote.
  if (!(s.network == NetworkSettings{})) {
    key("network") << YAML::Flow << YAML::BeginMap;
    key("interface") << s.network.interface_name;
    key("peers") << YAML::Flow << YAML::BeginSeq;
    for (const std::string& peer : s.network.peers) out << peer;
    out << YAML::EndSeq;
    key("multicast") << s.network.multicast;
    out << YAML::EndMap;
  }
  key("default_profile") << s.default_profile;
  key("profiles") << YAML::BeginMap;
  for (const RiskProfile& profile : s.profiles) {
    key(profile.name) << YAML::BeginMap;
    key("weights") << YAML::Flow << YAML::BeginMap;
    for (const auto& [valve, weight] : profile.weights) number(valve, weight);
    out << YAML::EndMap;
    key("events") << YAML::Flow << YAML::BeginSeq;
    for (const RiskEvent& event : profile.events) {
      out << YAML::BeginMap;
      number("time_s", event.time_s);
      key("valve") << event.valve;
      number("weight", event.weight);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap;
  // Leak sensing, only where the scenario has some: a scenario without writes what it always did.
  if (!s.sensors.empty()) {
    key("sensors") << YAML::BeginSeq;
    for (const SensorSpec& sensor : s.sensors) {
      out << YAML::Flow << YAML::BeginMap;
      key("name") << sensor.name;
      key("kind") << ToString(sensor.kind);
      number("range_m", sensor.range_m);
      number("fov_deg", sensor.fov_deg);
      number("p_detect", sensor.p_detect);
      number("half_range_m", sensor.half_range_m);
      number("false_alarms_per_s", sensor.false_alarms_per_s);
      number("position_sigma_m", sensor.position_sigma_m);
      number("rate_hz", sensor.rate_hz);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (s.gaze != Gaze::kTravel) key("gaze") << ToString(s.gaze);
  if (!s.leaks.empty()) {
    key("leaks") << YAML::BeginSeq;
    for (const LeakSpec& leak : s.leaks) {
      out << YAML::Flow << YAML::BeginMap;
      key("at") << YAML::Flow << YAML::BeginMap;
      if (!leak.valve.empty()) {
        key("valve") << leak.valve;
      } else if (!leak.flowline.empty()) {
        key("flowline") << leak.flowline;
        number("s_m", leak.s_m);
      } else {
        key("point_m");
        vector(leak.point_m);
      }
      out << YAML::EndMap;
      number("start_s", leak.start_s);
      number("strength", leak.strength);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (!(s.fusion == FusionSettings{})) {
    const FusionSettings& f = s.fusion;
    key("fusion") << YAML::Flow << YAML::BeginMap;
    key("steer") << (f.steer ? "posterior" : "prior");
    number("prior_probability", f.prior_probability);
    number("relax_time_s", f.relax_time_s);
    number("confirm_probability", f.confirm_probability);
    number("alarm_probability", f.alarm_probability);
    number("leak_mass", f.leak_mass);
    number("spread_m", f.spread_m);
    number("max_log_odds", f.max_log_odds);
    number("min_evidence", f.min_evidence);
    key("regrowth") << (f.onset_regrowth ? "onset" : "relax");
    if (f.joint_prior_probability > 0.0) number("joint_prior_probability", f.joint_prior_probability);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace sage::maps
