#pragma once
// A SAGE mission as written in scenarios/*.yaml: the workspace, the subsea Christmas trees
// (XTs) with their valves, named risk profiles with timed events, the vehicles, and the
// controller settings. Plain structs with defaults; LoadScenario() validates and throws
// ScenarioError with one line naming file, field, value and rule.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/perception.h"

namespace sage::maps {

/// Bad user input (scenario file, CLI value). what() is one line meant for the user:
/// "scenarios/x.yaml: vehicles[2].transit_speed_mps = -1: must be > 0".
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Workspace {
  double width_m = 12.0;   ///< extent along x (m), > 0; the box is [0, width] x [0, height]
  double height_m = 10.0;  ///< extent along y (m), > 0

  /// Where a vehicle of the mission may report being: a finite place inside the box or at most
  /// max(width, height, 10 m) beyond its edge (a crowded fleet pushes hulls a little out; a place
  /// a whole workspace away is no vehicle of this mission). The server's door and sage status
  /// both ask it.
  bool Reaches(const Eigen::Vector2d& x_m) const {
    const double margin_m = std::max({width_m, height_m, 10.0});
    return x_m.allFinite() && x_m.x() > -margin_m && x_m.y() > -margin_m && x_m.x() < width_m + margin_m &&
           x_m.y() < height_m + margin_m;
  }
};

/// A point of interest on an XT.
struct Valve {
  std::string name;                                       ///< unique, e.g. "P1"
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();   ///< inside the workspace, outside structures
  Eigen::Matrix2d covariance_m2 = 0.25 * Eigen::Matrix2d::Identity();  ///< risk spread (SPD), m^2
};

/// A subsea Christmas tree: a rectangular footprint (a static obstacle) and its valves.
struct ChristmasTree {
  std::string name;                                       ///< unique, e.g. "XT-A"
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();     ///< footprint centre (m)
  Eigen::Vector2d size_m = Eigen::Vector2d(1.5, 1.5);     ///< footprint width, depth (m), > 0
  double height_m = 2.5;                                  ///< height above seabed (m), for the OctoMap
  std::vector<Valve> valves;
};

/// A valve's weight set at a time, e.g. a leak found at P1 at t = 150 s.
struct RiskEvent {
  double time_s = 0.0;  ///< mission time (s), >= 0
  std::string valve;    ///< a valve name
  double weight = 0.0;  ///< raw weight, >= 0
};

/// Largest raw risk weight a profile, an event or an operator may give a valve. Weights are
/// relative, so 1e12 is far past any useful ratio, and sums over thousands of valves stay finite
/// (two valves at 1e308 overflowed the normalisation and stopped a running mission).
inline constexpr double kMaxRawWeight = 1e12;

/// Named raw weights per valve (any positive scale; normalised on use) plus timed events.
struct RiskProfile {
  std::string name;
  std::map<std::string, double> weights;  ///< every valve must have one, >= 0, not all zero
  std::vector<RiskEvent> events;          ///< sorted by time on load
};

enum class MotionModel {
  kSingleIntegrator,  ///< x' = u at constant speed: the paper's and reference code's model
  kBlueRov2,          ///< Box2D dynamic body with BlueROV2 Heavy added mass, drag, thrust limits
};

/// Voxels the seabed OctoMap spans along an axis (its keys are 16 bits, centred): the workspace
/// fits within this many A* grid cells.
inline constexpr double kMaxOctoMapVoxels = 32767.0;

/// Largest start jitter (m): a vehicle's start stays near the start_m the scenario names.
inline constexpr double kMaxStartJitter_m = 0.5;

/// How close (m) a vehicle's centre comes to a structure: a BlueROV2 Heavy's half diagonal
/// (0.37 m) and a little water. The obstacle filter keeps vehicles this far out, and the risk
/// field puts no coverage inside it.
inline constexpr double kVehicleClearance_m = 0.4;
/// A final approach longer than this is a leg of a tour, not the end of a pass (m).
inline constexpr double kMaxFinalApproach_m = 5.0;
/// Largest target-shaping exponent alpha (ergodic and astar weight_exponent, --weight-exponent):
/// w^4 already gives a valve of twice the risk 16 times the share.
inline constexpr double kMaxWeightExponent = 4.0;
/// A BlueROV2 Heavy's hull diagonal (m; 0.457 x 0.575 m): BlueROV2s that start together start
/// at least this far apart.
inline constexpr double kBlueRov2Diagonal_m = 0.74;
/// How far (m) a vehicle's start_m keeps from every structure's footprint: the start jitter may
/// move it that far, and a BlueROV2's hull (hull = true) reaches kVehicleClearance_m beyond.
inline constexpr double StartFootprintReach(double start_jitter_m, bool hull) {
  return start_jitter_m + (hull ? kVehicleClearance_m : 0.0);
}

/// Longest name of a scenario, structure, valve, vehicle or profile (characters).
inline constexpr std::size_t kMaxNameLength = 64;

/// Bounds on what a scenario may cost to load and to run (each broken one is a one-line error).
/// A scenario file is read only up to this size (a 10,000-XT field is 6.3 MB).
inline constexpr std::size_t kMaxScenarioBytes = std::size_t{64} << 20;
/// A mission of at most a week of mission time.
inline constexpr double kMaxDuration_s = 7.0 * 86400.0;
/// Control at most 100 Hz, physics at most 1 kHz (BlueROV2 dynamics need no more).
inline constexpr double kMaxControlRate_hz = 100.0;
inline constexpr double kMaxPhysicsRate_hz = 1000.0;
/// The A* grid: cells of at least 1 cm and at most 64 million of them (the 10,000-vehicle field
/// at 0.25 m has 12.8 million).
inline constexpr double kMinGridResolution_m = 0.01;
inline constexpr double kMaxGridCells = 64e6;
/// Clearance kept from structures by the tours (m); a BlueROV2 needs ~0.3.
inline constexpr double kMaxClearance_m = 10.0;
/// Structures at most 100 m tall (an XT stands 2-5 m; the seabed map voxelises every height).
inline constexpr double kMaxStructureHeight_m = 100.0;
/// Seabed per vehicle, counting those who join (m^2): a BlueROV2's hull covers 0.26 m^2; the
/// paper's point vehicles start 0.3 m apart.
inline constexpr double kMinAreaPerBlueRov2_m2 = 1.0;
inline constexpr double kMinAreaPerPointVehicle_m2 = 0.1;

/// The BlueROV2 Heavy's top speed in surge at full thrust (m/s): the drag law of its model
/// (agents/physics_world) gives 0.848, and tests/agents/physics_world_test.cpp checks the two
/// agree. A faster commanded transit speed could not be flown, only asked for.
inline constexpr double kBlueRov2TopSpeed_mps = 0.85;

struct VehicleSpec {
  std::string name;                                      ///< unique, e.g. "rov1"
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();     ///< start position (m)
  double start_heading_rad = 0.0;                        ///< start heading (rad, from +x, CCW)
  MotionModel model = MotionModel::kBlueRov2;
  double transit_speed_mps = 0.5;                        ///< commanded speed (m/s), > 0
};

/// Ergodic (SMC) controller settings.
struct ErgodicSettings {
  int basis_order = 10;  ///< K, wave numbers per dimension (K^2 coefficients), 1..64
  /// Time constant (s) of exponential forgetting of the coverage c_k; infinity = the
  /// paper's behaviour (c_k averages over the whole mission).
  double forgetting_time_s = std::numeric_limits<double>::infinity();
  /// Tightest turn (m) of the commanded direction: it turns at most speed / radius rad/s, so a
  /// vehicle passes through a hot valve and loops back instead of hovering on it. 0 = turn at
  /// once, the paper's law.
  double min_turn_radius_m = 0.0;
  /// alpha >= 0: the target phi is the mixture of the valves with weights w^alpha (renormalised)
  /// instead of w. 1 = the paper (time at a valve in proportion to its risk); 0.5 = search
  /// theory's square-root law, which minimises the expected time a leak goes unnoticed.
  double weight_exponent = 1.0;
  /// Within this distance (m) of a valve its target wants, ahead and in sight, a vehicle flies
  /// straight to it (agents/final_approach.h): the law's passes that would miss the visit radius
  /// become inspections. 0 = the paper's law, untouched; at most kMaxFinalApproach_m.
  double final_approach_m = 0.0;
};

/// The "no starving valve" guard (the paper's named limitation): a floor on each valve's
/// normalised weight and a revisit bound after which an overdue valve is boosted.
struct StarvationGuard {
  bool enabled = true;           ///< off for paper-reproduction runs
  double weight_floor = 0.05;    ///< minimum normalised weight of any valve, in [0, 1/M)
  double revisit_bound_s = 60.0; ///< a valve not visited for this long (s) is boosted, > 0
};

/// The A* inspection-tour baseline: with one vehicle the paper's tour through every valve; with
/// a fleet the valves partitioned among the vehicles, one closed tour each (agents/fleet_tour_planner).
struct AstarSettings {
  double grid_resolution_m = 0.1;  ///< cell size of the 8-connected grid (m), > 0
  double clearance_m = 0.35;       ///< obstacles inflated by this (m), >= 0
  double wait_per_lap_s = 2.0;     ///< total wait per lap (s), split over valves by weight, >= 0
  /// alpha >= 0: a lap's wait is split over the tour's valves as w^alpha (1 = by weight).
  double weight_exponent = 1.0;
  /// A fleet's tours are planned again this long (s) after a vehicle joins, is lost or leaves,
  /// or a risk changes, as an operator would re-plan by hand; >= 0.
  double replan_delay_s = 10.0;
  /// How a tour vehicle's next valves are ordered: the shortest closed tour, flown lap after lap
  /// (the operator's, the paper's baseline), or chosen on what the fleet's scans have seen
  /// (agents/look_planner.h: the next valves that keep the time a leak would wait unseen the
  /// shortest over a horizon; needs sensors).
  enum class Order { kShortest, kLooks };
  Order order = Order::kShortest;
  /// Under order looks a valve weighs r^look_exponent (r its risk, the risks normalised to sum
  /// 1: at 1 a leak is as likely as risk, which the planner's objective turns into the
  /// square-root law's rates by itself) plus look_leak_weight times the chance of a leak there
  /// the scans give, so that a leak seen is watched (at 3 a confirmed leak weighs ~2.7 against the
  /// risks' 1). Both >= 0. Measured on two_xt_leaks (sage bench leaks, 400 runs on each of two
  /// sets of seeds): look_exponent 0.5-0.8 raised the time to detection's mean by up to 0.9 s and
  /// its p90 by up to 2.4 s; look_leak_weight 1-30 moved them by 0.1 and 0.4 s at most, and the
  /// visits to a leak found from 5.6 to 13 a minute (3: 8.2), the other valves' gaps growing with them.
  double look_exponent = 1.0;
  double look_leak_weight = 3.0;
};

/// How the server divides the risk among the vehicles of a fleet.
enum class FleetAssignment {
  kShared,     ///< Mathew & Mezic: every vehicle steers on the whole fleet's coverage of the whole field
  kPartition,  ///< the valves are partitioned among the vehicles; each covers its own share alone
  /// Each vehicle's share (balanced on travel, as the fleet's tours are) is a region of its own:
  /// a box around its valves with its own cosine basis, so a vehicle's step costs the same on any
  /// field and its detail is a region's, not the whole field's.
  kRegions,
};

/// Fleet settings (a single-vehicle mission ignores them).
struct FleetSettings {
  FleetAssignment assignment = FleetAssignment::kShared;
  double coverage_period_s = 0.5;  ///< how often a vehicle publishes its coverage sums (s), > 0
  double liveliness_lease_s = 0.5; ///< a vehicle silent this long is lost (s), > 0
  /// Regions: a valve weighs w (1 + age / (L lap)) in its region's target, age the time since its
  /// last visit and lap its share's tour lap: the chance that a leak has started there unseen
  /// grows with the time nobody looked. In [0, 100]; 0 = off (the weights alone).
  double age_weighting_laps = 1.0;
  /// Regions: the split balances lap x (1 + beta n W), W the share of the field's risk a region
  /// holds, so that the riskier valves come in smaller regions. In [0, 10]; 0 = laps alone.
  double risk_share = 0.5;
};

/// Where a mission's DDS traffic goes, so that agent hosts (and operators) on other machines can
/// join it. The default is this machine alone: the loopback interface, no multicast. A process
/// on another machine takes the same scenario with its own interface (--interface).
struct NetworkSettings {
  /// A network interface by name ("eth0") or by one of its IPv4 addresses; "lo" = this machine.
  std::string interface_name = "lo";
  /// IPv4 addresses or host names of the mission's other machines: without multicast, where
  /// discovery looks for the other processes (this machine's own address is always looked at).
  std::vector<std::string> peers;
  /// Discovery by multicast on the interface (no peers needed on a network that carries it).
  bool multicast = false;
  bool operator==(const NetworkSettings&) const = default;
};
/// Peers a network may list.
inline constexpr std::size_t kMaxPeers = 32;
/// Empty if `network` is well formed, else one line "WHERE: FIELD = VALUE: RULE" (`where` is
/// e.g. the scenario file or "command line"): an interface name of 1-15 characters of
/// [A-Za-z0-9_.:-] or an IPv4 address; peers IPv4 addresses or host names (1-253 characters of
/// [A-Za-z0-9.-]), at most kMaxPeers.
std::string NetworkProblem(const NetworkSettings& network, const std::string& where);
/// Most control cycles between a vehicle's trajectory rows (a day's mission at 10 Hz keeps a row
/// every 2.8 hours).
inline constexpr double kMaxTrajectoryEvery = 100000;
/// Empty if rate_hz is a trajectory rate a mission at control_rate_hz can record (0, or the
/// control rate over a whole number k in 1..kMaxTrajectoryEvery, to five significant figures),
/// else what is allowed and the nearest rates that are, as one line.
std::string TrajectoryRateRule(double rate_hz, double control_rate_hz);

/// A change of the fleet during a mission: a vehicle joins, is lost (dies without a word), or
/// leaves cleanly.
struct FleetEvent {
  enum class Kind { kJoin, kLose, kLeave };
  double time_s = 0.0;  ///< mission time (s), in [0, duration]
  Kind kind = Kind::kJoin;
  VehicleSpec vehicle;  ///< join: the whole spec (a new unique name); lose/leave: only the name matters
};

/// A flowline (or a spool, jumper or umbilical): a pipe lying on the seabed along a polyline. It is
/// part of the seabed map: a vehicle's altitude band clears a pipe lower than the band's floor,
/// and a pipe that rises into the band blocks it like a structure.
struct Flowline {
  std::string name;                       ///< unique among flowlines, e.g. "FL-A"
  std::vector<Eigen::Vector2d> points_m;  ///< the pipe's axis: >= 2 vertices in the workspace, no two consecutive equal
  double diameter_m = 0.25;               ///< outer diameter (m), in (0, kMaxFlowlineDiameter_m]
  /// Length of the axis (m).
  double Length_m() const;
  /// The point of the axis s_m along it (m, from its first vertex), s_m in [0, Length_m()].
  Eigen::Vector2d PointAt(double s_m) const;
};

/// A boulder on the seabed: half an ellipsoid standing on the seabed at its centre.
struct Boulder {
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();  ///< inside the workspace
  double diameter_m = 1.0;  ///< across (m), in (0, kMaxBoulderSize_m]
  double height_m = 0.6;    ///< above the seabed at its centre (m), in (0, kMaxBoulderSize_m]
};

/// What the numbers of a seabed map mean: heights (up) or depths (down).
enum class SeabedValues { kElevation, kDepth };

/// The seabed the vehicles fly over, when it is more than today's flat plane (the `seabed:`
/// section). The vehicles keep an altitude band above the local seabed: the plane fitted to the
/// bare seabed within trend_radius_m of a point (a vehicle's depth follows the seabed's trend,
/// not each rock); whatever rises from there into the band (terrain, boulders, pipes,
/// structures) blocks them like a structure.
struct SeabedSettings {
  /// The seabed map: a GeoTIFF (.tif, .tiff), a gridded XYZ/CSV (.xyz, .csv: x y z, one line a
  /// grid node) or an OctoMap (.bt, .ot: the top of its occupied voxels in each column). Written
  /// relative to the scenario file's folder; LoadScenario resolves it to an absolute path. Empty:
  /// a flat seabed (boulders and flowlines still stand on it).
  std::string map;
  /// The map's coordinates (m) of the workspace's corner (0, 0); none = the map's south-west
  /// corner. The workspace's x runs east, y north.
  std::optional<Eigen::Vector2d> origin_m;
  SeabedValues values = SeabedValues::kElevation;  ///< depth: the map holds depths (positive down)
  double altitude_min_m = 0.5;  ///< the vehicles' altitude band above the local seabed (m): floor
  double altitude_max_m = 1.5;  ///< ... and ceiling, > floor by at least the A* grid resolution
  double trend_radius_m = 2.5;  ///< the local seabed is the plane fitted within +- this (m) of a point
  /// FNV-1a of the map file's bytes, read when the scenario is loaded (not written in YAML): a
  /// server and an agent host, or a checkpoint and its resume, that see different maps disagree.
  std::uint64_t map_fnv1a = 0;
};

/// The kinds of seabed map file, told by the file name's extension (any case).
enum class SeabedMapFormat {
  kUnknown,
  kGeoTiff,  ///< .tif, .tiff (read through GDAL)
  kXyz,      ///< .xyz, .csv: a gridded x y z file (read through GDAL's XYZ driver)
  kOctoMap,  ///< .bt (OctoMap binary) or .ot (OctoMap full: OcTree, ColorOcTree, OcTreeStamped)
};
SeabedMapFormat SeabedMapFormatOf(const std::string& path);

/// Bounds on the seabed's objects (each broken one is a one-line error).
inline constexpr double kMaxFlowlineDiameter_m = 5.0;
inline constexpr double kMaxBoulderSize_m = 20.0;
inline constexpr std::size_t kMaxFlowlinePoints = 100000;  ///< over all flowlines
inline constexpr std::size_t kMaxBoulders = 100000;
/// A seabed map file is read only up to this size (a 4,000 x 4,000 float GeoTIFF is 64 MB).
inline constexpr std::size_t kMaxSeabedMapBytes = std::size_t{256} << 20;
/// The altitude band lies within this of the local seabed (m).
inline constexpr double kMaxAltitude_m = 100.0;

struct Scenario {
  std::string name;                         ///< from the file name or `name:` field
  std::string source_path;                  ///< file it was loaded from (for messages)
  Workspace workspace;
  std::vector<ChristmasTree> structures;
  std::vector<RiskProfile> profiles;        ///< at least one
  std::string default_profile;              ///< a profile name; the first profile if empty in YAML
  std::vector<VehicleSpec> vehicles;        ///< at least one
  double duration_s = 300.0;                ///< mission length (s), > 0
  double control_rate_hz = 10.0;            ///< SMC / tour controller rate (Hz), > 0
  double physics_rate_hz = 50.0;            ///< Box2D step rate (Hz), a multiple of control rate
  /// Rows a vehicle per mission second in trajectory.csv: the control rate over a whole number
  /// k, a row every k-th control cycle (a 10,000-vehicle field at 1 Hz writes 88 MB a minute,
  /// not 880); 0 = every control cycle. The metrics count every cycle either way.
  double trajectory_rate_hz = 0.0;
  double visit_radius_m = 0.5;              ///< a visit is an entry within this of a valve (m), > 0
  double rearm_radius_m = 1.0;              ///< re-armed only after leaving this (m), > visit radius
  std::uint64_t seed = 1;                   ///< fixed seed, same mission
  /// Each vehicle starts within this radius (m) of its start_m, at a point drawn from the seed
  /// and its id, so seeds give distinct but repeatable missions; 0 = exactly at start_m.
  double start_jitter_m = 0.2;
  ErgodicSettings ergodic;
  StarvationGuard guard;
  AstarSettings astar;
  FleetSettings fleet;
  std::vector<FleetEvent> fleet_events;     ///< sorted by time on load
  /// The seabed (the `seabed:`, `flowlines:` and `boulders:` sections); none of the three: the
  /// flat seabed with the XTs alone, as before there were maps.
  std::optional<SeabedSettings> seabed;
  std::vector<Flowline> flowlines;
  std::vector<Boulder> boulders;
  NetworkSettings network;                  ///< where its DDS traffic goes (not part of ScenarioHash)
  // Leak sensing (maps/scenario/perception.h): none of it by default, and then a mission flies
  // exactly as without.
  std::vector<SensorSpec> sensors;          ///< every vehicle carries each
  Gaze gaze = Gaze::kTravel;                ///< where they look (needs sensors unless kTravel)
  std::vector<LeakSpec> leaks;              ///< hidden from the server; sorted by start on load
  FusionSettings fusion;

  /// All valves in file order (P1..Pn), structure after structure.
  std::vector<Valve> AllValves() const;
  int ValveCount() const;  ///< AllValves().size() without the copy (checked on every assignment)
  int ValveIndex(const std::string& name) const;  ///< index into AllValves(); -1 if none
  /// The valves' names for a refusal that lists them: "P1, P2, P3", or past max_named the first
  /// max_named and the count ("V1, ..., V20, ... (35000 in all)": a generated field has thousands).
  std::string ValveNames(int max_named = 20) const;
  std::vector<Eigen::Vector2d> ValvePositions() const;  ///< AllValves()' positions, same order
  /// A vehicle's mission id by name: its index among `vehicles`, or for a fleet_events join
  /// vehicles.size() plus the join's rank among the joins; -1 if no vehicle has the name.
  int VehicleId(const std::string& name) const;
  /// The first control cycle at or after mission time t: the cycle a timed event happens on.
  std::int64_t CycleAt(double time_s) const;
  /// Control cycles from one trajectory.csv row of a vehicle to its next (1 at trajectory_rate_hz
  /// 0): cycle c is recorded when c is a multiple of it.
  std::int64_t TrajectoryEvery() const;
  /// Vehicle id -> the control cycle of its first fleet_events loss or leave (none: not listed).
  std::map<int, std::int64_t> VehicleEndCycles() const;
  const RiskProfile* FindProfile(const std::string& name) const;  ///< nullptr if none
  /// The named profile (empty: default_profile); throws ScenarioError listing the profiles.
  const RiskProfile& ProfileOrThrow(const std::string& name) const;
  /// A profile's raw weights in AllValves() order (before its events).
  Eigen::VectorXd ProfileWeights(const RiskProfile& profile) const;
  /// True if the seabed is more than the flat plane with the XTs alone: a seabed section, a
  /// flowline or a boulder (SeabedMap then builds the terrain).
  bool HasSeabedModel() const { return seabed.has_value() || !flowlines.empty() || !boulders.empty(); }
  /// The seabed's settings: the scenario's, or the defaults (a flat seabed, the 0.5-1.5 m band).
  SeabedSettings SeabedOrDefault() const { return seabed.value_or(SeabedSettings{}); }
  /// The point s_m (m) along the axis of the flowline named `flowline` (a leak "at FL-A, 12 m"):
  /// throws ScenarioError naming the flowlines, or the length, if there is no such point.
  Eigen::Vector2d FlowlinePoint(const std::string& flowline, double s_m) const;
  /// Throws ScenarioError for the first field that breaks a rule.
  void Validate() const;
};

/// Loads and validates a scenario. Throws ScenarioError (one line) on any problem.
Scenario LoadScenario(const std::string& path);
/// Parses YAML text; `source` names it in error messages.
Scenario ParseScenario(const std::string& yaml_text, const std::string& source);
/// Writes YAML that LoadScenario reads back to an equal Scenario. Its first line is
/// kEmittedScenarioHeader (so a file sage wrote can be told from one a person wrote).
std::string EmitScenario(const Scenario& scenario);
inline constexpr const char* kEmittedScenarioHeader =
    "# SAGE Fleet scenario (written by EmitScenario); units are in the field names";

/// A copy that lasts `duration_s`; risk and fleet events and leaks after the new end are dropped
/// (they would never happen).
Scenario WithDuration(const Scenario& scenario, double duration_s);

/// A copy with exactly `count` vehicles (>= 1): the first `count` of the file's, or all of them
/// plus new ones named rov<N> with the first vehicle's model and speed, their starts spread
/// evenly along the bottom edge of the workspace (0.5 m in), so a fleet size can be chosen on
/// the command line. Fleet events naming a dropped vehicle are dropped too.
Scenario WithVehicleCount(const Scenario& scenario, int count);

/// Where vehicle `id` of a mission with `seed` starts: spec.start_m moved by up to `jitter_m`
/// (uniform over the disc) by a generator seeded from (seed, id), so in-process and over DDS,
/// whichever host adds it and in whatever order, a vehicle starts at the same point.
Eigen::Vector2d JitteredStart(const VehicleSpec& spec, std::uint64_t seed, int id, double jitter_m);

/// A hash (FNV-1a) of what shapes the vehicles' own simulation and control: workspace,
/// structures and valves, rates, seed, vehicles, SMC settings (K, forgetting, turning radius)
/// and the fleet's reporting periods. Not the mission's length, risk profiles, guard, A*,
/// coverage assignment or fleet events, which only the server uses. A server and an agent host
/// that disagree on it would fly vehicles in a different world than the one accounted.
std::uint64_t VehicleFingerprint(const Scenario& scenario);
/// A hash (FNV-1a) of the whole scenario as EmitScenario writes it, but its network (the same
/// mission may be resumed on another): a checkpoint is resumed only by the scenario it was taken of.
std::uint64_t ScenarioHash(const Scenario& scenario);

const char* ToString(MotionModel model);
const char* ToString(FleetAssignment assignment);
const char* ToString(SeabedValues values);
/// Throws ScenarioError unless text is "shared" or "partition"; `where` starts the message.
FleetAssignment ParseFleetAssignment(const std::string& text, const std::string& where);
/// Throws ScenarioError if `text` is not "single_integrator" or "bluerov2"; `where` starts the
/// message, e.g. "scenarios/x.yaml: vehicles[0].model" or "command line: --model".
MotionModel ParseMotionModel(const std::string& text, const std::string& where);

}  // namespace sage::maps
