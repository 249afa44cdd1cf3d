#include "server/app/cli_scenario.h"

#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "maps/scenario/duration_rule.h"
#include "maps/scenario/field_generator.h"
#include "proto/dds_config.h"
#include "maps/seabed/seabed_obstacles.h"
#include "server/region_split.h"

namespace sage::server {

namespace {

// Checked here rather than by CLI11 validators, so the message says what is allowed in the
// project's words: "--duration = -5: must be > 0".
void CheckOverrides(const ScenarioOverrides& o) {
  if (o.vehicles && *o.vehicles < 1) throw maps::ScenarioError(fmt::format("--vehicles = {}: must be >= 1", *o.vehicles));
  if (o.duration_s) {
    if (const std::string problem = maps::DurationRangeProblem(*o.duration_s); !problem.empty()) {
      throw maps::ScenarioError(fmt::format("--duration = {}: {}", *o.duration_s, problem));
    }
  }
  if (o.basis_order && (*o.basis_order < 1 || *o.basis_order > 64)) {
    throw maps::ScenarioError(fmt::format("--basis-order = {}: must be in 1..64", *o.basis_order));
  }
  if (o.forgetting_time_s && !(*o.forgetting_time_s > 0.0)) {
    throw maps::ScenarioError(fmt::format("--forgetting = {}: must be > 0 (inf = never forget)", *o.forgetting_time_s));
  }
  if (o.weight_exponent && !(*o.weight_exponent >= 0.0 && *o.weight_exponent <= 4.0)) {
    throw maps::ScenarioError(fmt::format("--weight-exponent = {}: must be in [0, 4] (1 = by risk, 0.5 = square-root law)",
                                          *o.weight_exponent));
  }
  if (o.age_weighting_laps && !(*o.age_weighting_laps >= 0.0 && *o.age_weighting_laps <= 100.0)) {
    throw maps::ScenarioError(fmt::format("--age-weighting = {}: must be in [0, 100] laps (0 = off)", *o.age_weighting_laps));
  }
  if (o.risk_share && !(*o.risk_share >= 0.0 && *o.risk_share <= 10.0)) {
    throw maps::ScenarioError(fmt::format("--risk-share = {}: must be in [0, 10] (0 = regions balanced on laps alone)", *o.risk_share));
  }
  if (o.start_jitter_m && !(*o.start_jitter_m >= 0.0 && *o.start_jitter_m <= maps::kMaxStartJitter_m)) {
    throw maps::ScenarioError(fmt::format("--start-jitter = {}: must be in [0, {}] m (0 = start exactly at start_m)",
                                          *o.start_jitter_m, maps::kMaxStartJitter_m));
  }
  if (o.min_turn_radius_m && !(*o.min_turn_radius_m >= 0.0 && std::isfinite(*o.min_turn_radius_m))) {
    throw maps::ScenarioError(fmt::format("--turn-radius = {}: must be a finite number >= 0 (0 = turn at once)",
                                          *o.min_turn_radius_m));
  }
  if (o.final_approach_m && !(*o.final_approach_m >= 0.0 && *o.final_approach_m <= maps::kMaxFinalApproach_m)) {
    throw maps::ScenarioError(fmt::format("--final-approach = {}: must be in [0, {}] m (0 = off, the paper's law)",
                                          *o.final_approach_m, maps::kMaxFinalApproach_m));
  }
}

}  // namespace

maps::NetworkSettings NetworkOverrides::Applied(maps::NetworkSettings network) const {
  if (interface_name) network.interface_name = *interface_name;
  if (!peers.empty()) network.peers = peers;
  if (multicast) network.multicast = *multicast == "on";
  // The file's network was checked as it was read: a problem here is an option's, said as given
  // ("--peer = a..b: must be ...", not the scenario field's name).
  if (std::string problem = maps::NetworkProblem(network, "command line"); !problem.empty()) {
    for (const auto& [field, option] : {std::pair<std::string, std::string>{"command line: network.interface", "--interface"},
                                        {"command line: network.peers", "--peer"}}) {
      if (!problem.starts_with(field)) continue;
      std::size_t end = field.size();
      if (end < problem.size() && problem[end] == '[') end = problem.find(']', end) + 1;  // a peer's index
      problem.replace(0, end, option);
      break;
    }
    throw maps::ScenarioError(problem);
  }
  return network;
}

std::string RecordRateNote(const maps::Scenario& scenario) {
  if (scenario.TrajectoryEvery() == 1) return "";
  return fmt::format(" (a vehicle's row every {} cycles: trajectory_rate_hz = {:g})", scenario.TrajectoryEvery(),
                     scenario.trajectory_rate_hz);
}

std::string FirstScenarioOverride(const ScenarioOverrides& o) {
  const std::pair<const char*, bool> given[] = {
      {"--profile", !o.profile.empty()},
      {"--duration", o.duration_s.has_value()},
      {"--seed", o.seed.has_value()},
      {"--guard", o.guard.has_value()},
      {"--forgetting", o.forgetting_time_s.has_value()},
      {"--basis-order", o.basis_order.has_value()},
      {"--turn-radius", o.min_turn_radius_m.has_value()},
      {"--final-approach", o.final_approach_m.has_value()},
      {"--model", o.model.has_value()},
      {"--vehicles", o.vehicles.has_value()},
      {"--assignment", o.assignment.has_value()},
      {"--order", o.order.has_value()},
      {"--start-jitter", o.start_jitter_m.has_value()},
      {"--weight-exponent", o.weight_exponent.has_value()},
      {"--age-weighting", o.age_weighting_laps.has_value()},
      {"--risk-share", o.risk_share.has_value()},
      {"--trajectory-rate", o.trajectory_rate_hz.has_value()},
      {"--random-leaks", o.random_leaks.has_value()},
      {"--leak-sites", o.leak_sites.has_value()},
      {"--steer", o.steer.has_value()},
  };
  for (const auto& [name, is_given] : given)
    if (is_given) return name;
  return "";
}

std::string LeftOutByDuration(const maps::Scenario& scenario, double duration_s, bool leaks_drawn_anew) {
  std::vector<std::string> dropped;
  if (!leaks_drawn_anew) {
    for (const maps::LeakSpec& leak : scenario.leaks) {
      if (leak.start_s >= duration_s) dropped.push_back(fmt::format("the leak at {} from {} s", maps::LeakWhere(leak), leak.start_s));
    }
  }
  // The mission flies its default profile (a --profile given has become it): only that one's events.
  std::size_t risk_events = 0, fleet_events = 0;
  for (const maps::RiskEvent& e : scenario.ProfileOrThrow("").events) risk_events += e.time_s > duration_s ? 1 : 0;
  for (const maps::FleetEvent& e : scenario.fleet_events) fleet_events += e.time_s > duration_s ? 1 : 0;
  if (risk_events > 0) {
    dropped.push_back(fmt::format("{} risk event(s) of profile {}", risk_events, scenario.ProfileOrThrow("").name));
  }
  if (fleet_events > 0) dropped.push_back(fmt::format("{} fleet event(s)", fleet_events));
  if (dropped.empty()) return "";
  return fmt::format("--duration = {}: the mission ends before {} (left out)", duration_s, fmt::join(dropped, ", "));
}

void WarnOfLargeRecord(const maps::Scenario& scenario) {
  const int every = maps::RecordEveryForFleet(static_cast<int>(scenario.vehicles.size()), scenario.control_rate_hz);
  if (scenario.TrajectoryEvery() != 1 || every == 1) return;
  constexpr double kBytesPerRow = 150;  // a 10,000-vehicle minute at 1 Hz: 88 MB for 610,000 rows
  const double rows_per_minute = 60.0 * static_cast<double>(scenario.vehicles.size()) * scenario.control_rate_hz;
  spdlog::warn("trajectory.csv keeps every control cycle of {} vehicles: about {:.0f} MB a mission minute; "
               "--trajectory-rate {:g} (trajectory_rate_hz in the scenario) keeps a vehicle's row every {} cycles, "
               "about {:.0f} MB a minute (the metrics count every cycle either way)",
               scenario.vehicles.size(), rows_per_minute * kBytesPerRow / 1e6, scenario.control_rate_hz / every,
               every, rows_per_minute / every * kBytesPerRow / 1e6);
}

void CheckNetworkHere(const maps::Scenario& scenario, const NetworkOverrides& given) {
  const maps::NetworkSettings& network = scenario.network;
  const std::string file = scenario.source_path.empty() ? std::string("<scenario>") : scenario.source_path;
  if (network.interface_name != "lo" && proto::InterfaceAddress(network.interface_name).empty()) {
    throw maps::ScenarioError(fmt::format(
        "{} = '{}': no such interface with an IPv4 address on this machine (`ip -4 addr` lists them; lo keeps the "
        "mission on this machine)",
        given.interface_name ? std::string("--interface") : file + ": network.interface", network.interface_name));
  }
  if (network.peers.empty()) return;
  // Every peer asked at once, all answered within kResolveWait_s: a resolver that does not answer
  // (no DNS on the mission's network) is said once, not waited for name by name (32 peers at a
  // resolver's timeouts each). The requests live on the heap and are let go when one cannot be
  // cancelled: the resolver may still write to it as this process exits with the error.
  constexpr double kResolveWait_s = 5.0;
  struct Request {
    std::string name;
    addrinfo hints{};
    gaicb call{};
  };
  const std::size_t n = network.peers.size();
  auto requests = std::make_unique<Request[]>(n);
  std::vector<gaicb*> calls(n);
  for (std::size_t i = 0; i < n; ++i) {
    requests[i].name = network.peers[i];
    requests[i].hints.ai_family = AF_INET;
    requests[i].call.ar_name = requests[i].name.c_str();
    requests[i].call.ar_request = &requests[i].hints;
    calls[i] = &requests[i].call;
  }
  if (const int status = ::getaddrinfo_a(GAI_NOWAIT, calls.data(), static_cast<int>(n), nullptr); status != 0) {
    throw maps::ScenarioError(fmt::format("network.peers: cannot ask the resolver ({})", ::gai_strerror(status)));
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kResolveWait_s);
  const auto pending = [&] {
    return std::any_of(calls.begin(), calls.end(), [](gaicb* c) { return ::gai_error(c) == EAI_INPROGRESS; });
  };
  while (pending() && std::chrono::steady_clock::now() < deadline) {
    const timespec slice{0, 100'000'000};  // re-checked every 0.1 s up to the deadline
    ::gai_suspend(calls.data(), static_cast<int>(n), &slice);
  }
  std::string problem;
  bool let_go = false;
  for (std::size_t i = 0; i < n; ++i) {
    int status = ::gai_error(calls[i]);
    if (status == EAI_INPROGRESS) let_go = let_go || ::gai_cancel(calls[i]) != EAI_CANCELED;
    if (status == 0 && calls[i]->ar_result != nullptr) ::freeaddrinfo(calls[i]->ar_result);
    if (status == 0 || !problem.empty()) continue;
    const std::string why = status == EAI_INPROGRESS ? fmt::format("no answer from the resolver within {:.0f} s", kResolveWait_s)
                                                     : std::string(::gai_strerror(status));
    problem = fmt::format("{} = '{}': no IPv4 address for that host name on this machine ({}); give the machine's "
                          "IPv4 address or a name /etc/hosts or DNS resolves",
                          given.peers.empty() ? fmt::format("{}: network.peers[{}]", file, i) : std::string("--peer"),
                          requests[i].name, why);
  }
  if (let_go) static_cast<void>(requests.release());
  if (!problem.empty()) throw maps::ScenarioError(problem);
}

void WarnOfLossySettings(const maps::Scenario& scenario) {
  const maps::ChristmasTree* smallest = nullptr;
  for (const maps::ChristmasTree& tree : scenario.structures) {
    if (smallest == nullptr || tree.size_m.minCoeff() < smallest->size_m.minCoeff()) smallest = &tree;
  }
  if (smallest != nullptr && scenario.astar.grid_resolution_m > smallest->size_m.minCoeff() / 2) {
    spdlog::warn("astar.grid_resolution_m = {}: coarser than half the smallest structure ({}, {} x {} m): the seabed map "
                 "and the A* grid, in cells of {} m, cannot resolve the structures (a vehicle may find no way past them, "
                 "a tour no path)",
                 scenario.astar.grid_resolution_m, smallest->name, smallest->size_m.x(), smallest->size_m.y(),
                 scenario.astar.grid_resolution_m);
  }
  for (std::size_t i = 0; i < scenario.sensors.size(); ++i) {
    const maps::SensorSpec& sensor = scenario.sensors[i];
    const int every = maps::ScanEveryCycles(scenario.control_rate_hz, sensor.rate_hz);
    const double flown_hz = scenario.control_rate_hz / every;
    if (std::abs(flown_hz - sensor.rate_hz) <= 1e-9 * sensor.rate_hz) continue;
    spdlog::warn("sensors[{}] ({}): rate_hz = {}: scans fall on whole control cycles (control_rate_hz = {}): it scans "
                 "{}, at {:.4g} Hz (a rate of {} Hz / k scans as asked)",
                 i, sensor.name, sensor.rate_hz, scenario.control_rate_hz,
                 every == 1 ? std::string("every cycle") : fmt::format("every {} cycles", every), flown_hz,
                 scenario.control_rate_hz);
  }
  // Hidden leaks nobody can see (the table had read "detected never" as a fleet that missed them;
  // sage bench leaks refuses such a file).
  if (scenario.sensors.empty() && !scenario.leaks.empty()) {
    spdlog::warn("leaks: {} hidden leak(s) and no sensors: the vehicles cannot detect them (give them a sensors: "
                 "section, as scenarios/two_xt_leaks.yaml has); the leaks are scored \"detected never\"",
                 scenario.leaks.size());
  } else if (scenario.sensors.empty() && scenario.fusion != maps::FusionSettings{}) {
    spdlog::warn("fusion: the settings weigh the sensors' scans, and the vehicles carry no sensors: they change nothing");
  }
}

maps::Scenario LoadWithOverrides(const ScenarioOverrides& o) {
  CheckOverrides(o);
  maps::Scenario scenario = maps::LoadScenario(o.scenario_path);
  if (!o.profile.empty()) {
    scenario.ProfileOrThrow(o.profile);  // before anything starts, naming the user's file
    // The effective scenario flies it by default: `sage run DIR/scenario.yaml` (and `sage evaluate
    // DIR/trajectory.csv -s DIR/scenario.yaml`) fly and score the run's profile, not the file's.
    scenario.default_profile = o.profile;
  }
  if (o.vehicles) {
    const std::vector<maps::FleetEvent> events = scenario.fleet_events;
    const std::size_t own = scenario.vehicles.size();
    scenario = maps::WithVehicleCount(scenario, *o.vehicles);
    // Added starts were placed without the seabed's terrain: those on blocked seabed move off it.
    if (const int moved = maps::MoveStartsOffBlockedSeabed(scenario, own); moved > 0) {
      spdlog::info("--vehicles = {}: {} added start(s) moved off blocked seabed", *o.vehicles, moved);
    }
    // Losing or removing a vehicle the smaller fleet does not have is dropped; say so.
    for (const maps::FleetEvent& e : events) {
      const bool kept = std::any_of(scenario.fleet_events.begin(), scenario.fleet_events.end(), [&](const auto& k) {
        return k.kind == e.kind && k.vehicle.name == e.vehicle.name && k.time_s == e.time_s;
      });
      if (!kept) {
        spdlog::warn("--vehicles = {}: fleet event at t = {} s dropped: {} is not in the fleet", *o.vehicles, e.time_s,
                     e.vehicle.name);
      }
    }
  }
  if (o.assignment) scenario.fleet.assignment = maps::ParseFleetAssignment(*o.assignment, "--assignment");
  if (o.order) {
    scenario.astar.order = *o.order == "looks" ? maps::AstarSettings::Order::kLooks : maps::AstarSettings::Order::kShortest;
  }
  if (o.duration_s) {
    // Said of the option, not of the file whose control rate it meets.
    if (const std::string problem = maps::DurationCycleProblem(*o.duration_s, scenario.control_rate_hz); !problem.empty()) {
      throw maps::ScenarioError(fmt::format("--duration = {}: {}", *o.duration_s, problem));
    }
    // What starts after the shorter mission's end is left out; say so (a leak that silently went
    // read as "none hidden" in the run's table).
    if (const std::string left_out = LeftOutByDuration(scenario, *o.duration_s, o.random_leaks.has_value()); !left_out.empty()) {
      spdlog::warn("{}", left_out);
    }
    scenario = maps::WithDuration(scenario, *o.duration_s);
  }
  if (o.seed) scenario.seed = *o.seed;
  if (o.weight_exponent) scenario.ergodic.weight_exponent = scenario.astar.weight_exponent = *o.weight_exponent;
  if (o.start_jitter_m) scenario.start_jitter_m = *o.start_jitter_m;
  if (o.age_weighting_laps) scenario.fleet.age_weighting_laps = *o.age_weighting_laps;
  if (o.risk_share) scenario.fleet.risk_share = *o.risk_share;
  if (o.trajectory_rate_hz) {
    if (const std::string rule = maps::TrajectoryRateRule(*o.trajectory_rate_hz, scenario.control_rate_hz); !rule.empty()) {
      throw maps::ScenarioError(fmt::format("--trajectory-rate = {}: {}", *o.trajectory_rate_hz, rule));
    }
    scenario.trajectory_rate_hz = *o.trajectory_rate_hz;
  }
  if (o.guard) scenario.guard.enabled = (*o.guard == "on");
  scenario.network = o.network.Applied(scenario.network);
  if (o.forgetting_time_s) scenario.ergodic.forgetting_time_s = *o.forgetting_time_s;
  if (o.basis_order) scenario.ergodic.basis_order = *o.basis_order;
  if (o.min_turn_radius_m) scenario.ergodic.min_turn_radius_m = *o.min_turn_radius_m;
  if (o.final_approach_m) scenario.ergodic.final_approach_m = *o.final_approach_m;
  if (o.steer) {
    if (*o.steer != "posterior" && *o.steer != "prior") {
      throw maps::ScenarioError("--steer = " + *o.steer + ": must be posterior (the Bayesian loop) or prior");
    }
    // Without sensors it changes nothing and is warned of below, alone (taken, it had also set off
    // the warning of fusion settings that weigh no scans).
    if (!scenario.sensors.empty()) scenario.fusion.steer = *o.steer == "posterior";
  }
  // Drawn last, from the effective seed and duration, so `sage run DIR/scenario.yaml` (which holds
  // them) and agent hosts given the same options meet the same leaks.
  if (o.leak_sites && !o.random_leaks) {
    throw maps::ScenarioError("--leak-sites = " + *o.leak_sites + ": says where --random-leaks N draws its leaks; give N");
  }
  if (o.random_leaks && *o.random_leaks > 0 && scenario.sensors.empty()) {
    throw maps::ScenarioError(fmt::format("--random-leaks = {}: {} has no sensors: the vehicles could not see a leak (give "
                                          "them a sensors: section, as scenarios/two_xt_leaks.yaml does)",
                                          *o.random_leaks, o.scenario_path));
  }
  if (o.random_leaks) {
    const maps::LeakSites sites = maps::ParseLeakSites(o.leak_sites.value_or("valves"), "--leak-sites");
    scenario = maps::WithRandomLeaks(scenario, *o.random_leaks, sites);
  }
  if (o.model) {
    const maps::MotionModel model = maps::ParseMotionModel(*o.model, "--model");
    for (maps::VehicleSpec& v : scenario.vehicles) v.model = model;
    for (maps::FleetEvent& e : scenario.fleet_events)
      if (e.kind == maps::FleetEvent::Kind::kJoin) e.vehicle.model = model;
  }
  // The file's own rule, said of the option that broke it (it had named the scenario's file,
  // which holds no astar.order).
  if (o.order && *o.order == "looks" && scenario.sensors.empty()) {
    throw maps::ScenarioError("--order = looks: the look planner chooses the next valves on the vehicles' scans, and " +
                              o.scenario_path + " has no sensors (give them a sensors: section, as "
                              "scenarios/two_xt_leaks.yaml does, or --order shortest)");
  }
  scenario.Validate();  // the overrides obey the same rules as the file
  if (o.steer && scenario.sensors.empty()) {
    spdlog::warn("--steer = {}: {} has no sensors, so no Bayesian risk loop to steer on (it steers on the profile's "
                 "risk either way)",
                 *o.steer, scenario.name);
  }
  if (o.order && *o.order == "looks" && scenario.gaze != maps::Gaze::kValves) {
    spdlog::warn("--order looks: the look planner prices each leg with the camera turned to the nearest valve "
                 "(gaze: valves); this scenario's vehicles look along their travel, so its legs see less than planned");
  }
  return scenario;
}

std::vector<std::string> UnusedOverrides(const ScenarioOverrides& o, const maps::Scenario& scenario, Flown flown) {
  std::vector<std::string> unused;
  if (flown == Flown::kTours) {
    std::vector<std::string> given;
    if (o.basis_order) given.emplace_back("--basis-order");
    if (o.forgetting_time_s) given.emplace_back("--forgetting");
    if (o.min_turn_radius_m) given.emplace_back("--turn-radius");
    if (o.final_approach_m) given.emplace_back("--final-approach");
    if (o.steer) given.emplace_back("--steer");  // tours never steer on the posterior (an operator re-plans them)
    // A fleet of tours is shared out by the tour planner, whatever the ergodic fleet's assignment.
    if (o.assignment) given.emplace_back("--assignment");
    if (o.age_weighting_laps) given.emplace_back("--age-weighting");
    if (o.risk_share) given.emplace_back("--risk-share");
    if (!given.empty()) {
      unused.push_back(fmt::format("{}: the ergodic controller's; -c astar flies tours without {} (given, not used)",
                                   fmt::join(given, ", "), given.size() == 1 ? "it" : "them"));
    }
    return unused;
  }
  if (o.order && flown == Flown::kErgodic) {
    unused.emplace_back("--order: the A* vehicles' next valves; the ergodic fleet flies without it (given, not used; add "
                        "-c astar)");
  }
  if ((o.age_weighting_laps || o.risk_share) && scenario.fleet.assignment != maps::FleetAssignment::kRegions) {
    unused.push_back(fmt::format("--age-weighting and --risk-share shape regions only; this mission's assignment is {} "
                                 "(given, not used; --assignment regions to use them)",
                                 maps::ToString(scenario.fleet.assignment)));
  }
  return unused;
}

void WarnOfUnusedOverrides(const ScenarioOverrides& o, const maps::Scenario& scenario, Flown flown) {
  for (const std::string& line : UnusedOverrides(o, scenario, flown)) spdlog::warn("{}", line);
}

FleetNote FleetDensityNote(const maps::Scenario& scenario, Flown flown) {
  const bool regions = flown != Flown::kTours && scenario.fleet.assignment == maps::FleetAssignment::kRegions;
  const bool tours = flown != Flown::kErgodic;
  const std::size_t valves = static_cast<std::size_t>(scenario.ValveCount()), vehicles = scenario.vehicles.size();
  if ((regions || tours) && vehicles > valves) {
    return {false, fmt::format("{} vehicles for {} valves: {} fly one vehicle a valve and hold the other {} in reserve, "
                               "out of the valves' way, to take a lost vehicle's place{}",
                               vehicles, valves, regions && tours ? "regions and tours" : (regions ? "regions" : "tours"),
                               vehicles - valves, regions ? " (--assignment shared flies them all)" : "")};
  }
  constexpr double kSparseValvesPerVehicle = 10.0;
  const double per_vehicle = static_cast<double>(valves) / static_cast<double>(std::max<std::size_t>(vehicles, 1));
  const bool ergodic = flown != Flown::kTours;
  if (ergodic && per_vehicle > kSparseValvesPerVehicle) {
    // Measured (600 s, generated fields): the regions' longest gap 2.3-2.9x the tours' at 12-23
    // valves a vehicle (1.99x on the README's 12-a-vehicle field), and 42 valves never seen with
    // two vehicles (none by tours); one vehicle (the shared target) on 200 valves left 147 unseen,
    // the tour 27 (`sage field generate --xts 50 --valves 200 --vehicles 1`; it had gone unwarned).
    return {true, fmt::format(
        "{} valves for {} vehicle{} ({:.3g} a vehicle): ergodic coverage this sparse leaves valves unwatched far longer "
        "than tours (measured on generated fields, 600 s: regions 2.0-2.9x the tours' longest gap at 12-23 valves a "
        "vehicle; one vehicle on 200 valves: 147 never seen, the tour's 27); -c astar flies tours",
        valves, vehicles, vehicles == 1 ? "" : "s", per_vehicle)};
  }
  return {};
}

void WarnOfFleetDensity(const maps::Scenario& scenario, Flown flown) {
  const FleetNote note = FleetDensityNote(scenario, flown);
  if (note.text.empty()) return;
  if (note.warning) {
    spdlog::warn("{}", note.text);
  } else {
    spdlog::info("{}", note.text);
  }
}

void CheckFleetFitsField(const maps::Scenario& scenario, bool tours) {
  if (!tours && scenario.fleet.assignment != maps::FleetAssignment::kRegions) return;
  const std::string why = FleetTooSmallForField(static_cast<std::size_t>(scenario.ValveCount()), scenario.vehicles.size());
  if (!why.empty()) throw maps::ScenarioError(why);
}

}  // namespace sage::server
