#pragma once
// What a scenario says about leaks and leak sensing (issue 9): the leaks the mission hides from
// its server (`leaks:`, each at a valve or a seabed point, with its onset and strength), the
// sensors every vehicle carries (`sensors:`, cameras and sonars with a range, a field of view, a
// detection probability that falls with distance and a false-alarm rate), and how the server
// fuses their scans into the risk layer (`fusion:`). Plain structs with defaults; the rules are
// checked by Scenario::Validate (ValidatePerception), the YAML read and written with the rest.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

struct Scenario;
struct Flowline;

enum class SensorKind {
  kCamera,  ///< a forward camera: short range, narrow view, few false alarms
  kSonar,   ///< a forward-looking sonar: longer range, wider view, more false alarms
};

/// Where a vehicle's sensors look (`gaze:`). kTravel: along the direction of travel, the camera
/// looking ahead (the default; missions fly as they always did). kValves: at the nearest valve
/// within a sensor's range and in its line of sight; the BlueROV2 yaws to it while its vectored
/// thrusters hold the commanded velocity, so the controller's path is the same command and only
/// the heading differs (no valve in reach: along the travel again). A vehicle's gaze follows from
/// its state alone, so it looks the same whichever host simulates it, resumed or not.
enum class Gaze {
  kTravel,
  kValves,
};

/// A leak sensor every vehicle carries, looking along the vehicle's heading. A point y is in view
/// of a vehicle at x with heading psi if |y - x| <= range_m, the bearing of y is within fov_deg / 2
/// of psi, and the straight line x -> y crosses no structure of the seabed map (occlusion). An
/// active leak of strength s in view is detected in one scan with probability
///   p(d) = p_detect * 2^(-(d / (half_range_m * sqrt(s)))^2),   d = |y - x|,
/// its reported position off by a Gaussian of position_sigma_m; besides, each scan reports a
/// Poisson number of false alarms (false_alarms_per_s / rate_hz on average) anywhere in view.
struct SensorSpec {
  std::string name;                 ///< unique among the sensors, e.g. "camera"
  SensorKind kind = SensorKind::kCamera;
  double range_m = 1.5;             ///< > 0
  double fov_deg = 80.0;            ///< full opening angle, (0, 360]
  double p_detect = 0.9;            ///< detection probability at the sensor, (0, 1]
  double half_range_m = 1.0;        ///< where a nominal leak's detection probability halves, > 0
  double false_alarms_per_s = 0.05; ///< >= 0
  double position_sigma_m = 0.1;    ///< standard deviation of a detection's position, > 0
  double rate_hz = 2.0;             ///< scans a second, in (0, control_rate_hz]; scans fall on whole cycles
};

/// Control cycles between a sensor's scans: scans fall on whole cycles, the nearest whole number
/// to control_rate_hz / rate_hz and at least 1 (7 Hz under 10 Hz control scans every cycle, at
/// 10 Hz). Both rates > 0.
inline int ScanEveryCycles(double control_rate_hz, double rate_hz) {
  const double cycles = control_rate_hz / rate_hz;
  return cycles < 1.5 ? 1 : static_cast<int>(cycles + 0.5);
}

/// A leak the mission hides from its server: the vehicles' sensors see it from start_s on.
struct LeakSpec {
  /// Where, one of three: a valve (`at: {valve: P3}`, its position); a point along a flowline's
  /// axis (`at: {flowline: FL-A, s_m: 12.5}`, s_m metres from its first vertex: a flange, a weld or
  /// a corroded stretch); or, when both names are empty, a seabed point (`at: {point_m: [x, y]}`).
  std::string valve;
  Eigen::Vector2d point_m = Eigen::Vector2d::Zero();
  double start_s = 0.0;   ///< onset, mission time, in [0, duration_s]
  double strength = 1.0;  ///< > 0: 1 = the leak the sensors' parameters describe; s scales half_range_m by sqrt(s)
  std::string flowline;   ///< the flowline's name (then s_m), or empty
  double s_m = 0.0;       ///< metres along the flowline's axis from its first point, in [0, its length]
};

/// How the server turns scans into risk. Each leaf of the risk layer holds the log-odds that a
/// leak is there; a scan updates every leaf in view by Bayes' rule with the sensor's model
/// (a detection raises it at once, looking and seeing nothing lowers it), and between scans it
/// relaxes to the prior with relax_time_s. Evidence of a leak adds leak_mass * (P - P0) of risk
/// around the leaf (spread_m; the valves' prior holds 1); evidence of no leak at a valve scales that valve's
/// weight by P / P0 (a valve just looked at weighs less until the prior comes back).
struct FusionSettings {
  /// true: the vehicles steer on the posterior (the Bayesian loop); false: the scans are fused and
  /// scored but the vehicles keep to the profile's weights (the paper's fixed profiles).
  bool steer = true;
  /// Of a leak in one leaf (0.2 m) before anyone looked, (0, 0.5): 1e-3 is about one leak in
  /// 40 m^2 of seabed, so one detection raises an alarm and a second one confirms it.
  double prior_probability = 1e-3;
  double relax_time_s = 60.0;        ///< back to the prior with this time constant (s), > 0 (.inf: never)
  double confirm_probability = 0.9;  ///< a leak is confirmed when a leaf's posterior reaches this, (prior, 1)
  double alarm_probability = 0.5;    ///< an alarm is raised at this posterior, cleared below half of it, (prior, confirm]
  double leak_mass = 1.0;            ///< risk a certain leak adds (the valves' prior holds 1), >= 0
  /// A leaf's evidence of a leak is spread over the leaves around it as a Gaussian of this sigma
  /// (m), as a valve's prior is: the vehicles loop through a suspected leak instead of hovering on
  /// one leaf. >= 0 (0: the leaf alone).
  double spread_m = 0.3;
  double max_log_odds = 4.6;         ///< the posterior's ceiling (logit 0.99), > logit(confirm_probability)
  double min_evidence = -3.0;        ///< the floor of log-odds below the prior (a valve at most e^-3 lighter), < 0
  /// How a leaf looked at and found clean comes back to the prior. false (relax): its log-odds
  /// relax as exp(-t / relax_time_s), as a detection's do. true (onset): leaks begin in a leaf at
  /// the hazard P0 / relax_time_s a second, so the chance that one began since the look grows
  /// linearly, P(t) = min(P0, P_after + P0 t / relax_time_s): a valve not looked at for a while
  /// weighs in proportion to how long, as an inspection schedule's "longest waiting" rule.
  bool onset_regrowth = false;
  /// Of a leak in the leaf of a flowline joint (a tie-in at either end of a flowline, a flange at
  /// each bend: its vertices), before anyone looked. Joints leak more often than straight pipe or
  /// open seabed; their prior draws the vehicles as a valve's does, leak_mass * (P - P0) each, and
  /// looking at a joint and seeing nothing makes it lighter until its prior comes back. 0: a joint
  /// is any leaf (prior_probability); else in [prior_probability, alarm_probability / 2) (a joint
  /// alone never raises an alarm).
  double joint_prior_probability = 0.0;

  bool operator==(const FusionSettings&) const = default;
};

/// Where a leak is (m): its valve's position, its flowline's point or its seabed point. Throws
/// std::out_of_range for an unknown valve, ScenarioError for an unknown flowline or an s_m off it.
Eigen::Vector2d LeakPosition(const Scenario& scenario, const LeakSpec& leak);
/// A flowline joint: a vertex of a flowline (a tie-in at an end, a flange at a bend).
struct FlowlineJoint {
  Eigen::Vector2d point_m;
  const Flowline* flowline;  ///< the first flowline through it (the scenario's own)
  double s_m;                ///< metres along that flowline to it
};
/// Every vertex of every flowline, in flowline then vertex order, a point two flowlines share
/// once (by the first); the joints point into `scenario`.
std::vector<FlowlineJoint> FlowlineJoints(const Scenario& scenario);
/// How a leak is named in tables and metrics.json: its valve ("P3"), "FL-A at 12.5 m" or
/// "seabed (x, y)".
std::string LeakWhere(const LeakSpec& leak);

/// Where random leaks are drawn.
enum class LeakSites {
  /// At a valve, drawn in proportion to the default profile's risk: a leak is as likely as a
  /// valve's risk. The default profile is the field's risk as known (a --profile given on the
  /// command line becomes the effective scenario's default, and so draws the leaks); the leak
  /// bench's fixed-profile configurations fly other profiles over the same leaks.
  kValves,
  kValvesEven,  ///< at a valve, every valve alike
  kSeabed,      ///< at a seabed point in open water, at least 1 m from every valve and clear of the structures
  /// Along the flowlines, uniform over their total length, where the point is as a seabed
  /// leak's would be: at least 1 m from every valve and clear of the structures and edges.
  kFlowlines,
  /// At a flowline joint (a vertex: tie-in, flange), every joint alike, among those where a
  /// seabed leak could be (1 m from every valve, clear of the structures and edges).
  kJoints,
};

/// Random leaks start uniformly within this part of the mission (of its duration).
inline constexpr double kRandomLeakOnsetFrom = 0.1, kRandomLeakOnsetTo = 0.9;

/// A copy whose leaks are `count` random ones (replacing the file's), drawn from the scenario's
/// seed alone: onsets uniform in [0.1, 0.9] of the mission, strength 1, sites as asked. Throws
/// ScenarioError if count is out of 0..1000 or no seabed point (flowline point) qualifies; the
/// message starts with the option that asked (`options`: sage run's, or a bench's own).
struct LeakDrawOptions {
  std::string count = "--random-leaks";
  std::string sites = "--leak-sites";
};
Scenario WithRandomLeaks(const Scenario& scenario, int count, LeakSites sites, const LeakDrawOptions& options = {});
/// Throws ScenarioError (`where` starts the message) unless text is "valves", "valves-even",
/// "seabed", "flowlines" or "joints".
LeakSites ParseLeakSites(const std::string& text, const std::string& where);
const char* ToString(LeakSites sites);

const char* ToString(SensorKind kind);
const char* ToString(Gaze gaze);

/// Most sensors a vehicle may carry, most leaks a scenario may hide.
inline constexpr std::size_t kMaxSensors = 8;
inline constexpr std::size_t kMaxLeaks = 1000;
/// A sensor's false alarms a scan on average (false_alarms_per_s / rate_hz) at most: a scan and
/// its detections go to the server whole.
inline constexpr double kMaxFalseAlarmsPerScan = 1000.0;
/// Two leaks closer than this (m; the least association radius) are one site, whose detections
/// the scoring could not tell apart: a scenario's are refused, random ones are drawn apart (a new
/// user's three random joint leaks had all fallen on one joint, one "confirmed" before it was
/// "detected" by the other's evidence).
inline constexpr double kLeakSiteSeparation_m = 0.5;

}  // namespace sage::maps
