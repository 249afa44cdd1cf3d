// Leaks, sensors and fusion in a scenario (maps/scenario/perception.h): their rules, where a
// leak is, and random leaks drawn by seed for Monte Carlo runs.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

#include "maps/scenario/scenario.h"
#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::FormatNumber;
using detail::OneLine;

// A leak on open seabed keeps this clear of every structure's footprint (a hull's clearance)
// and of the workspace's edge, and (random ones) this far from every valve.
constexpr double kSeabedLeakClearance_m = 0.5;
constexpr double kRandomSeabedFromValves_m = 1.0;

double LeakLogit(double p) { return std::log(p / (1.0 - p)); }

}  // namespace

const char* ToString(SensorKind kind) { return kind == SensorKind::kSonar ? "sonar" : "camera"; }
const char* ToString(Gaze gaze) { return gaze == Gaze::kValves ? "valves" : "travel"; }

LeakSites ParseLeakSites(const std::string& text, const std::string& where) {
  if (text == "valves") return LeakSites::kValves;
  if (text == "valves-even") return LeakSites::kValvesEven;
  if (text == "seabed") return LeakSites::kSeabed;
  if (text == "flowlines") return LeakSites::kFlowlines;
  if (text == "joints") return LeakSites::kJoints;
  throw ScenarioError(
      OneLine(where + " = " + text + ": must be valves (by risk), valves-even, seabed, flowlines or joints"));
}

const char* ToString(LeakSites sites) {
  switch (sites) {
    case LeakSites::kValves: return "valves";
    case LeakSites::kValvesEven: return "valves-even";
    case LeakSites::kSeabed: return "seabed";
    case LeakSites::kFlowlines: return "flowlines";
    case LeakSites::kJoints: return "joints";
  }
  return "?";
}

Eigen::Vector2d LeakPosition(const Scenario& scenario, const LeakSpec& leak) {
  if (!leak.flowline.empty()) return scenario.FlowlinePoint(leak.flowline, leak.s_m);
  if (leak.valve.empty()) return leak.point_m;
  for (const ChristmasTree& tree : scenario.structures)
    for (const Valve& valve : tree.valves)
      if (valve.name == leak.valve) return valve.position_m;
  throw std::out_of_range("leak at valve " + leak.valve + ": no such valve");
}

std::vector<FlowlineJoint> FlowlineJoints(const Scenario& scenario) {
  std::vector<FlowlineJoint> joints;
  std::set<std::pair<double, double>> seen;
  for (const Flowline& line : scenario.flowlines) {
    double s = 0.0;
    for (std::size_t v = 0; v < line.points_m.size(); ++v) {
      if (v > 0) s += (line.points_m[v] - line.points_m[v - 1]).norm();
      const Eigen::Vector2d& p = line.points_m[v];
      if (seen.insert({p.x(), p.y()}).second) joints.push_back({p, &line, std::min(s, line.Length_m())});
    }
  }
  return joints;
}

std::string LeakWhere(const LeakSpec& leak) {
  if (!leak.valve.empty()) return leak.valve;
  if (!leak.flowline.empty()) return leak.flowline + " at " + FormatNumber(std::round(leak.s_m * 100.0) / 100.0) + " m";
  return "seabed (" + FormatNumber(std::round(leak.point_m.x() * 100.0) / 100.0) + ", " +
         FormatNumber(std::round(leak.point_m.y() * 100.0) / 100.0) + ")";
}

namespace detail {

void ValidatePerception(const Scenario& s, const std::string& file) {
  const auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw ScenarioError(OneLine(file + ": " + field + " = " + value + ": " + rule));
  };
  const auto in_range = [&](const std::string& field, double v, double lo, double hi, bool lo_open, bool hi_open,
                            const std::string& rule) {
    const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    if (!ok) fail(field, FormatNumber(v), rule);
  };
  const auto positive = [&](const std::string& field, double v) {
    in_range(field, v, 0.0, std::numeric_limits<double>::max(), true, false, "must be > 0");
  };
  if (s.sensors.size() > kMaxSensors) {
    fail("sensors", std::to_string(s.sensors.size()) + " sensors", "at most " + std::to_string(kMaxSensors) + " a vehicle");
  }
  if (s.gaze != Gaze::kTravel && s.sensors.empty()) {
    fail("gaze", ToString(s.gaze), "needs sensors: the gaze turns the vehicles' sensors (without any: leave gaze out)");
  }
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < s.sensors.size(); ++i) {
    const SensorSpec& sensor = s.sensors[i];
    const std::string path = "sensors[" + std::to_string(i) + "]";
    if (sensor.name.empty() || sensor.name.size() > kMaxNameLength ||
        std::any_of(sensor.name.begin(), sensor.name.end(),
                    [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; })) {
      fail(path + ".name", sensor.name.empty() ? "\"\"" : sensor.name.substr(0, 20),
           "must be 1-64 characters without control characters");
    }
    if (const auto [it, inserted] = names.emplace(sensor.name, i); !inserted) {
      fail(path + ".name", sensor.name, "duplicate name (also sensors[" + std::to_string(it->second) + "])");
    }
    if (sensor.kind != SensorKind::kCamera && sensor.kind != SensorKind::kSonar) {
      fail(path + ".kind", std::to_string(static_cast<int>(sensor.kind)), "must be camera or sonar");
    }
    positive(path + ".range_m", sensor.range_m);
    // A sensor's view is checked leaf by leaf each scan: a field's width at most.
    in_range(path + ".range_m", sensor.range_m, 0.0,
             std::max(1.0, std::hypot(s.workspace.width_m, s.workspace.height_m)), true, false,
             "must be in (0, the workspace's diagonal]");
    in_range(path + ".fov_deg", sensor.fov_deg, 0.0, 360.0, true, false, "must be in (0, 360] degrees");
    in_range(path + ".p_detect", sensor.p_detect, 0.0, 1.0, true, false, "must be in (0, 1]");
    positive(path + ".half_range_m", sensor.half_range_m);
    in_range(path + ".false_alarms_per_s", sensor.false_alarms_per_s, 0.0, 100.0, false, false,
             "must be in [0, 100] a second");
    in_range(path + ".position_sigma_m", sensor.position_sigma_m, 0.0, 10.0, true, false, "must be in (0, 10] m");
    in_range(path + ".rate_hz", sensor.rate_hz, 0.0, s.control_rate_hz, true, false,
             "must be in (0, control_rate_hz = " + FormatNumber(s.control_rate_hz) + "] (scans fall on control cycles)");
    // A scan's false alarms on average: what a scan may carry to the server is bounded.
    if (sensor.rate_hz > 0.0 && sensor.false_alarms_per_s / sensor.rate_hz > kMaxFalseAlarmsPerScan) {
      fail(path + ".false_alarms_per_s", FormatNumber(sensor.false_alarms_per_s),
           "at rate_hz = " + FormatNumber(sensor.rate_hz) + " that is " +
               FormatNumber(sensor.false_alarms_per_s / sensor.rate_hz) + " false alarms a scan; at most " +
               FormatNumber(kMaxFalseAlarmsPerScan) + " (scan more often, or fewer false alarms)");
    }
  }

  if (s.leaks.size() > kMaxLeaks) {
    fail("leaks", std::to_string(s.leaks.size()) + " leaks", "at most " + std::to_string(kMaxLeaks));
  }
  const Eigen::Vector2d workspace(s.workspace.width_m, s.workspace.height_m);
  for (std::size_t i = 0; i < s.leaks.size(); ++i) {
    const LeakSpec& leak = s.leaks[i];
    const std::string path = "leaks[" + std::to_string(i) + "]";
    if (!leak.valve.empty()) {
      if (s.ValveIndex(leak.valve) < 0) {
        // Name the valves a user may have meant (names are case-sensitive), the first dozen of a large field.
        constexpr std::size_t kNamed = 12;
        const std::vector<Valve> valves = s.AllValves();
        std::string names;
        for (std::size_t k = 0; k < std::min(kNamed, valves.size()); ++k) names += (k == 0 ? "" : ", ") + valves[k].name;
        if (valves.size() > kNamed) names += ", ... (" + std::to_string(valves.size()) + " in all)";
        fail(path + ".at.valve", leak.valve, "no such valve (names are case-sensitive; the scenario's: " + names + ")");
      }
    } else if (!leak.flowline.empty()) {
      const auto line = std::find_if(s.flowlines.begin(), s.flowlines.end(),
                                     [&](const Flowline& f) { return f.name == leak.flowline; });
      if (line == s.flowlines.end()) {
        std::string names;
        for (const Flowline& f : s.flowlines) names += (names.empty() ? "" : ", ") + f.name;
        fail(path + ".at.flowline", leak.flowline, "no such flowline (flowlines: " + (names.empty() ? "none" : names) + ")");
      }
      const double length = line->Length_m();
      in_range(path + ".at.s_m", leak.s_m, 0.0, length, false, false,
               "must be in [0, " + FormatNumber(length) + "] m (" + leak.flowline + "'s length)");
      // A flowline ends at its structures: the stretch under a footprint is not in any view.
      const Eigen::Vector2d p = line->PointAt(leak.s_m);
      for (const ChristmasTree& tree : s.structures) {
        if (((p - tree.center_m).array().abs() < (tree.size_m / 2).array()).all()) {
          fail(path + ".at.s_m", FormatNumber(leak.s_m),
               leak.flowline + " is inside the footprint of " + tree.name + " there (no sensor could see it)");
        }
      }
    } else {
      const Eigen::Vector2d& p = leak.point_m;
      const std::string shown = "[" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) + "]";
      if (!p.allFinite() || !(p.array() >= 0.0).all() || !(p.array() <= workspace.array()).all()) {
        fail(path + ".at.point_m", shown, "must be inside the workspace");
      }
      for (std::size_t b = 0; b < s.boulders.size(); ++b) {
        const Boulder& boulder = s.boulders[b];
        if ((p - boulder.center_m).norm() < boulder.diameter_m / 2) {
          fail(path + ".at.point_m", shown,
               "lies under boulders[" + std::to_string(b) + "] (centre " + FormatNumber(boulder.center_m.x()) + ", " +
                   FormatNumber(boulder.center_m.y()) + ", " + FormatNumber(boulder.diameter_m) +
                   " m across; no sensor could see it)");
        }
      }
      for (const ChristmasTree& tree : s.structures) {
        const Eigen::Vector2d half = tree.size_m / 2;
        if (((p - tree.center_m).array().abs() < half.array()).all()) {
          fail(path + ".at.point_m", shown, "lies inside the footprint of " + tree.name + " (no sensor could see it)");
        }
      }
    }
    // A leak that starts as the mission ends could only be missed: before the end, or left out.
    in_range(path + ".start_s", leak.start_s, 0.0, s.duration_s, false, true,
             "must be in [0, duration_s = " + FormatNumber(s.duration_s) + ")");
    in_range(path + ".strength", leak.strength, 0.0, 1e6, true, false, "must be in (0, 1e6] (1 = nominal)");
  }

  // One leak a site: a valve twice, or two leaks off valves closer than the separation.
  std::vector<Eigen::Vector2d> sites;
  for (const LeakSpec& leak : s.leaks) sites.push_back(LeakPosition(s, leak));
  for (std::size_t i = 0; i < s.leaks.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const bool both_valves = !s.leaks[i].valve.empty() && !s.leaks[j].valve.empty();
      const double apart = (sites[i] - sites[j]).norm();
      if (both_valves ? s.leaks[i].valve != s.leaks[j].valve : apart >= kLeakSiteSeparation_m) continue;
      const std::string shown = FormatNumber(std::round(apart * 100.0) / 100.0);  // to the centimetre
      fail("leaks[" + std::to_string(i) + "].at", LeakWhere(s.leaks[i]),
           "the site of leaks[" + std::to_string(j) + "] (" + LeakWhere(s.leaks[j]) + ", " + shown +
               " m off): one leak a site, at least " + FormatNumber(kLeakSiteSeparation_m) +
               " m apart (their detections could not be told apart)");
    }
  }

  const FusionSettings& f = s.fusion;
  in_range("fusion.prior_probability", f.prior_probability, 0.0, 0.5, true, true, "must be in (0, 0.5)");
  if (!(f.relax_time_s > 0.0)) fail("fusion.relax_time_s", FormatNumber(f.relax_time_s), "must be > 0 (.inf: never)");
  in_range("fusion.confirm_probability", f.confirm_probability, f.prior_probability, 1.0, true, true,
           "must be in (prior_probability, 1)");
  in_range("fusion.alarm_probability", f.alarm_probability, f.prior_probability, f.confirm_probability, true, false,
           "must be in (prior_probability, confirm_probability]");
  in_range("fusion.leak_mass", f.leak_mass, 0.0, 1e6, false, false, "must be in [0, 1e6] (the valves' prior holds 1)");
  in_range("fusion.spread_m", f.spread_m, 0.0, 10.0, false, false, "must be in [0, 10] m (0: the leaf alone)");
  in_range("fusion.max_log_odds", f.max_log_odds, LeakLogit(f.confirm_probability), 30.0, true, false,
           "must be in (logit(confirm_probability) = " + FormatNumber(LeakLogit(f.confirm_probability)) + ", 30]");
  in_range("fusion.min_evidence", f.min_evidence, -30.0, 0.0, false, true, "must be in [-30, 0)");
  if (f.joint_prior_probability != 0.0) {
    in_range("fusion.joint_prior_probability", f.joint_prior_probability, f.prior_probability,
             0.5 * f.alarm_probability, false, true,
             "must be 0 (a joint is any leaf) or in [prior_probability, alarm_probability / 2)");
    if (s.flowlines.empty()) {
      fail("fusion.joint_prior_probability", FormatNumber(f.joint_prior_probability),
           "weights the flowlines' joints, and the scenario has no flowlines");
    }
  }
}

}  // namespace detail

Scenario WithRandomLeaks(const Scenario& scenario, int count, LeakSites sites, const LeakDrawOptions& options) {
  // Refusals start with the caller's option: the count's ("--random-leaks = 3: ...") or the sites'.
  const std::string count_is = options.count + " = " + std::to_string(count);
  const std::string sites_are = options.sites + " = " + ToString(sites);
  if (count < 0 || count > static_cast<int>(kMaxLeaks)) {
    throw ScenarioError(count_is + ": must be in 0.." + std::to_string(kMaxLeaks));
  }
  Scenario out = scenario;
  out.leaks.clear();
  // SplitMix64 of the seed, then a stream of its own, so the leaks do not move with any other draw.
  std::uint64_t z = scenario.seed + 0x9E3779B97F4A7C15ull * 0x4C45414Bull;  // "LEAK"
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  std::mt19937_64 rng(z ^ (z >> 31));
  const auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  const std::vector<Valve> valves = scenario.AllValves();
  Eigen::VectorXd weights = scenario.ProfileWeights(scenario.ProfileOrThrow(""));
  if (sites == LeakSites::kValvesEven) weights.setOnes();
  double total = weights.sum();
  if (sites == LeakSites::kValves || sites == LeakSites::kValvesEven) {
    const auto weighed = static_cast<int>((weights.array() > 0.0).count());
    if (count > weighed) {
      const std::string which =
          sites == LeakSites::kValves ? " valves of nonzero risk in profile " + scenario.ProfileOrThrow("").name : " valves";
      throw ScenarioError(count_is + ": at most one leak a valve, and " + scenario.name +
                          " has " + std::to_string(weighed) + which);
    }
  }
  const Eigen::Vector2d workspace(scenario.workspace.width_m, scenario.workspace.height_m);
  const auto open_seabed = [&](const Eigen::Vector2d& p) {
    if (!(p.array() >= kSeabedLeakClearance_m).all() || !(p.array() <= workspace.array() - kSeabedLeakClearance_m).all()) {
      return false;
    }
    for (const ChristmasTree& tree : scenario.structures) {
      const Eigen::Vector2d half = tree.size_m / 2 + Eigen::Vector2d::Constant(kSeabedLeakClearance_m);
      if (((p - tree.center_m).array().abs() < half.array()).all()) return false;
    }
    // Nor on a boulder: open water, as the help says (a new user's boulder had held 1-2 of 50 draws).
    for (const Boulder& boulder : scenario.boulders) {
      if ((p - boulder.center_m).norm() < boulder.diameter_m / 2 + kSeabedLeakClearance_m) return false;
    }
    for (const Valve& valve : valves)
      if ((p - valve.position_m).norm() < kRandomSeabedFromValves_m) return false;
    return true;
  };
  // Flowline sites: a point uniform over the flowlines' total length, then its flowline and s.
  double flowline_length = 0.0;
  for (const Flowline& f : scenario.flowlines) flowline_length += f.Length_m();
  if (sites == LeakSites::kFlowlines && !(flowline_length > 0.0)) {
    throw ScenarioError(sites_are + ": " + scenario.name + " has no flowlines to draw leaks along (give it a "
                        "flowlines: section, as scenarios/fleet_field_leaks.yaml has, or draw at valves or seabed)");
  }
  const auto flowline_site = [&](LeakSpec& leak) {
    double s = uniform() * flowline_length;
    std::size_t k = 0;
    while (k + 1 < scenario.flowlines.size() && s > scenario.flowlines[k].Length_m()) s -= scenario.flowlines[k++].Length_m();
    const Flowline& line = scenario.flowlines[k];
    leak.flowline = line.name;
    // Rounded to the centimetre, as a seabed point is, and kept on the line.
    leak.s_m = std::min(std::round(s * 100.0) / 100.0, line.Length_m());
    return open_seabed(line.PointAt(leak.s_m));
  };
  // Joint sites: the flowlines' vertices where a seabed leak could be.
  std::vector<FlowlineJoint> joints;
  if (sites == LeakSites::kJoints) {
    if (scenario.flowlines.empty()) {
      throw ScenarioError(sites_are + ": " + scenario.name + " has no flowlines, so no joints to draw leaks at (give it a "
                          "flowlines: section, as scenarios/fleet_field_leaks.yaml has, or draw at valves or seabed)");
    }
    for (const FlowlineJoint& joint : FlowlineJoints(scenario)) {
      if (open_seabed(joint.point_m)) joints.push_back(joint);
    }
    if (joints.empty()) {
      throw ScenarioError(sites_are + ": " + scenario.name + " has no flowline joint " +
                          FormatNumber(kRandomSeabedFromValves_m) + " m from every valve and " +
                          FormatNumber(kSeabedLeakClearance_m) + " m from the structures and edges");
    }
    if (count > static_cast<int>(joints.size())) {
      throw ScenarioError(count_is + ": at most one leak a joint, and " +
                          scenario.name + " has " + std::to_string(joints.size()) + " joints where one could be");
    }
  }
  // A site drawn is taken: later draws keep kLeakSiteSeparation_m from it.
  std::vector<Eigen::Vector2d> taken;
  const auto no_room = [&](const std::string& where) {
    return ScenarioError(count_is + ": " + scenario.name + " has room for " +
                         std::to_string(taken.size()) + " leaks at least " + FormatNumber(kLeakSiteSeparation_m) +
                         " m apart " + where + " (one leak a site)");
  };
  const auto apart = [&](const Eigen::Vector2d& p) {
    return std::all_of(taken.begin(), taken.end(),
                       [&](const Eigen::Vector2d& q) { return (p - q).norm() >= kLeakSiteSeparation_m; });
  };
  for (int n = 0; n < count; ++n) {
    LeakSpec leak;
    leak.start_s = scenario.duration_s * (kRandomLeakOnsetFrom + (kRandomLeakOnsetTo - kRandomLeakOnsetFrom) * uniform());
    if (sites == LeakSites::kJoints) {
      if (joints.empty()) throw no_room("at its flowline joints");
      const std::size_t at = std::min(joints.size() - 1, static_cast<std::size_t>(uniform() * joints.size()));
      const FlowlineJoint joint = joints[at];
      leak.flowline = joint.flowline->name;
      leak.s_m = joint.s_m;
      // Drawn without replacement, and no later joint within the separation of this one.
      std::erase_if(joints, [&](const FlowlineJoint& j) {
        return (j.point_m - joint.point_m).norm() < kLeakSiteSeparation_m;
      });
    } else if (sites == LeakSites::kFlowlines) {
      bool found = false;
      for (int attempt = 0; attempt < 100000 && !found; ++attempt) {
        found = flowline_site(leak) && apart(LeakPosition(scenario, leak));
      }
      if (!found && !taken.empty()) throw no_room("along its flowlines");
      if (!found) {
        throw ScenarioError(sites_are + ": " + scenario.name + " has no flowline point " +
                            FormatNumber(kRandomSeabedFromValves_m) + " m from every valve and " +
                            FormatNumber(kSeabedLeakClearance_m) + " m from the structures and edges");
      }
    } else if (sites != LeakSites::kSeabed) {
      // Without replacement: two leaks at one valve would be found by the same detections and
      // counted twice (a new user's 3 leaks had held two at V33, 1 s apart). The valve drawn
      // weighs nothing for the next draw.
      double pick = uniform() * total;
      std::size_t i = 0;
      const auto w = [&](std::size_t k) -> double& { return weights[static_cast<Eigen::Index>(k)]; };
      while (i + 1 < valves.size() && (pick >= w(i) || w(i) <= 0.0)) pick -= w(i++);
      while (i > 0 && w(i) <= 0.0) --i;  // rounding ran past the last valve left
      leak.valve = valves[i].name;
      total -= w(i);
      w(i) = 0.0;
    } else {
      bool found = false;
      for (int attempt = 0; attempt < 100000 && !found; ++attempt) {
        leak.point_m = Eigen::Vector2d(uniform() * workspace.x(), uniform() * workspace.y());
        // Rounded to the centimetre: the scenario file it goes into stays readable.
        leak.point_m = (leak.point_m * 100.0).array().round() / 100.0;
        found = open_seabed(leak.point_m) && apart(leak.point_m);
      }
      if (!found && !taken.empty()) throw no_room("on its open seabed");
      if (!found) {
        throw ScenarioError(sites_are + ": " + scenario.name + " has no open seabed " +
                            FormatNumber(kRandomSeabedFromValves_m) + " m from every valve and " +
                            FormatNumber(kSeabedLeakClearance_m) + " m from the structures and edges");
      }
    }
    if (leak.valve.empty()) taken.push_back(LeakPosition(scenario, leak));
    out.leaks.push_back(leak);
  }
  std::stable_sort(out.leaks.begin(), out.leaks.end(),
                   [](const LeakSpec& a, const LeakSpec& b) { return a.start_s < b.start_s; });
  return out;
}

}  // namespace sage::maps
