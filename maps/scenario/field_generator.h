#pragma once
// A synthetic subsea field for scale runs (`sage field generate`): XTs in uneven manifold
// clusters, their valves, a fleet of BlueROV2s and controller settings sized for the field,
// deterministic by seed. The field grows with the counts (weak scaling), so a 10-vehicle field
// and a 10,000-vehicle field have the same density of structures.
//
// Density rule: the workspace covers max(xts * area_per_xt_m2, vehicles * kFieldAreaPerVehicle_m2)
// of seabed (80 m^2 per XT by default), 3 : 2 wide, and grows (10 % a side, at most
// kFieldMaxGrowths times) only when the clusters do not fit, which happens for a few small
// fields. With one XT per vehicle, 10 / 100 / 1,000 / 10,000 vehicles get fields about
// 35 m / 110 m / 350 m / 1.1 km wide.
#include <cstdint>
#include <string>

#include "maps/scenario/scenario.h"

namespace sage::maps {

/// Seabed area (m^2) kept per vehicle at least, so starts 1.5 m apart fit however few XTs.
inline constexpr double kFieldAreaPerVehicle_m2 = 4.0;
/// Times the workspace may grow by 10 % a side when the clusters do not fit at first.
inline constexpr int kFieldMaxGrowths = 4;
/// Water (m) between two XT footprints of one cluster at least: a valve 0.8 m off each face
/// still leaves 1.0 m between facing valves and 1.8 m to the other footprint.
inline constexpr double kFieldXtGap_m = 2.6;
/// Water (m) between two clusters' envelopes (footprints and valves) at least.
inline constexpr double kFieldClusterGap_m = 3.0;
/// A valve's distance (m) from its XT's face: the inspection standoff.
inline constexpr double kFieldValveStandoff_m = 0.8;
/// Each valve's risk spread (m), isotropic: under a third of the closest valve spacing (0.8 m),
/// so a hot valve does not lend its risk to its neighbour.
inline constexpr double kFieldValveSigma_m = 0.25;
/// A start keeps this far (m) from every footprint and valve, and starts keep
/// kFieldStartSeparation_m apart, so starts jittered by up to 0.5 m stay clear of structures and
/// of each other's BlueROV2 hull (0.46 x 0.58 m).
inline constexpr double kFieldStartClearance_m = 1.0;
inline constexpr double kFieldStartSeparation_m = 1.5;

/// The control rate of every generated field (Hz).
inline constexpr double kFieldControlRate_hz = 10;

/// Rows of trajectory.csv a mission second a large fleet's record keeps at most (about 150 bytes a
/// row: 1.5 MB a mission second, 88 MB a 10,000-vehicle minute). The metrics count every cycle
/// whatever the record keeps.
inline constexpr double kFieldRecordRowsPerSecond = 10000;
/// The k of "a vehicle's row every k-th control cycle" that keeps a fleet of `vehicles` at
/// control_rate_hz within kFieldRecordRowsPerSecond: 1 (every cycle) up to 1,000 vehicles at 10 Hz,
/// then ceil(vehicles * control_rate_hz / kFieldRecordRowsPerSecond).
int RecordEveryForFleet(int vehicles, double control_rate_hz);

/// What `sage field generate` asks for; each field is one command-line option.
/// Leak sensors a generated field's vehicles carry (--sensors).
enum class FieldSensors {
  kNone,            ///< none: the field is inspected by visits (the default; what sage bench scale flies)
  kCamera,          ///< two_xt_leaks' camera, the vehicles turning to the valves in reach (gaze: valves)
  kCameraAndSonar,  ///< fleet_field_leaks' camera and sonar, gaze: valves
};
/// "none", "camera" or "camera+sonar"; anything else throws ScenarioError naming `option`.
FieldSensors ParseFieldSensors(const std::string& text, const std::string& option);

struct FieldOptions {
  int xts = 28;                  ///< --xts: Christmas trees (count), >= 1; default 28
  int valves = 87;               ///< --valves: valves in all (count), 2 to 5 per XT; default 87
  int vehicles = 24;             ///< --vehicles: BlueROV2s (count), >= 1; default 24
  std::uint64_t seed = 1;        ///< --seed: same seed, same field; also the mission's seed; default 1
  double area_per_xt_m2 = 80.0;  ///< --area-per-xt: seabed per XT (m^2), in [50, 10000]; default 80
  /// --name: the scenario's name; empty (default): "field_<xts>xt_<valves>v_<vehicles>rov_s<seed>"
  /// (then "_camera" or "_camera_sonar" with sensors).
  std::string name;
  /// --sensors: with any, the field can hide leaks (sage run --random-leaks, sage bench leaks) and
  /// the Bayesian loop steers on what the vehicles see.
  FieldSensors sensors = FieldSensors::kNone;
};

/// A valid scenario (Scenario::Validate() passes, EmitScenario/ParseScenario round-trips it
/// exactly) with exactly options.xts XTs, options.valves valves and options.vehicles vehicles:
/// - XTs: footprints 0.5-1.5 m a side, 2.0-3.0 m high, in clusters of 1 (satellite wells), 2-3
///   (templates) or 4-8 (around a manifold point, 2.5 m clear), at most a third of the XTs per
///   cluster; >= kFieldXtGap_m apart in a cluster, clusters >= kFieldClusterGap_m apart.
///   Valves 2-5 per XT on distinct faces (two on one face for 5), kFieldValveStandoff_m off the
///   face, >= 0.8 m apart, >= 1 m from the edges and from other XTs, sigma kFieldValveSigma_m.
///   Names XT-01.. (zero-padded), P1.., in reading order (20 m bands, south to north).
/// - Risk: profile `graded` (the default: log-normal raw weights, median 1, capped at 5, plus
///   1-5 leaks at 10-20, one per 20 valves) and `equal`.
/// - Vehicles rov1..: bluerov2 at 0.70, 0.75 or 0.80 m/s, random headings, starts spread over the
///   whole field (one per cell of a grid of about N cells, south to north), clear of footprints
///   and valves.
/// - Settings: 600 s, 10 Hz control, 50 Hz physics, visit/re-arm 0.3/0.45 m. SMC: K = 1 +
///   ceil(longest side / 1.25 m) in [20, 64] (so no global basis resolves a field much wider
///   than 80 m: that needs regions), forgetting 60 s, turning radius 0.3 m. Guard on, floors a
///   quarter of the risk, revisit bound 18 s per valve a vehicle holds, in [90, 300] s. A* grid
///   0.05, 0.1, 0.2 or 0.25 m, the finest with <= 200,000 cells over the field (the OctoMap uses
///   it too), clearance 0.3 m. Coverage reports every max(0.5, N / 500) s (about 500 a second
///   from the fleet); regions coverage for a fleet (shared for one vehicle).
/// Throws ScenarioError (one line, naming the option) for a bad option, or when the field would
/// be wider than an OctoMap spans at its grid (2^15 - 1 voxels: 8,191 m at 0.25 m).
Scenario GenerateField(const FieldOptions& options);

}  // namespace sage::maps
