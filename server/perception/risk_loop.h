#pragma once
// The Bayesian risk loop of a mission, server side: the vehicles' scans are checked at the door,
// fused into the leak belief (LeakBelief) in a fixed order whatever order the transport brought
// them in, and the belief is turned into what the vehicles steer on:
//  - evidence of a leak adds risk to its leaf of the risk layer,
//      e_c = leak_mass (P_c - P0) / r^2   (1/m^2; a certain leak adds leak_mass, the prior holds 1),
//    so a detection pulls vehicles there on the next cycle; the flowlines' joints, whose prior
//    is above P0 when fusion.joint_prior_probability is set, add theirs from the start, as a
//    valve's prior does, and weigh less once looked at and found clean;
//  - evidence of no leak at a valve (its leaf below the prior) scales the valve's weight by
//    P / P0 <= 1 until relaxation brings it back: a valve just looked at weighs less, one nobody
//    looked at for a while its full risk (FleetServer::SetWeightFactors).
// Under fusion.steer = prior (the paper's fixed profiles) the belief is kept and scored but feeds
// neither. It also scores the mission against the scenario's hidden leaks (which the fusion never
// sees): when each was first detected and confirmed, and the alarms raised where no leak was.
// No transport, no files.
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "maps/nearby_points.h"
#include "maps/risk_layer.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/metrics.h"
#include "server/perception/expected_detection.h"
#include "server/perception/leak_belief.h"
#include "server/rejections.h"
#include "server/roster.h"

namespace sage::server {

class RiskLoop {
 public:
  /// Detections a scan may carry, more refused at the door: 64, or what the scenario's own sensors
  /// can honestly report (every hidden leak, and the busiest sensor's false alarms a scan, mean
  /// plus ten standard deviations; a camera at 100 false alarms a second scanning once a second had
  /// its own scans refused), up to kMostDetectionsPerScan.
  static constexpr std::size_t kMinDetectionsPerScan = 64, kMostDetectionsPerScan = 4096;
  static std::size_t MaxDetectionsPerScan(const maps::Scenario& scenario);

  /// scenario, world and layer outlive the loop; the loop writes the layer's excess.
  RiskLoop(const maps::Scenario& scenario, const maps::World& world, maps::RiskLayer& layer);

  /// The scenario's vehicles carry sensors.
  bool sensing() const { return !belief_.sensors().empty(); }
  bool steers() const { return sensing() && scenario_.fusion.steer; }
  const LeakBelief& belief() const { return belief_; }

  /// A scan at the door: held for its cycle's fusion, or refused (returns the kind, one line, and
  /// keeps nothing). latest_s: the latest mission time the server will take input for.
  const char* Take(const agents::ScanReport& scan, double latest_s);
  /// Scans taken so far that wait for their cycle.
  std::size_t held() const { return held_.size(); }

  /// The server's cycle `cycle` at time_s: fuses the held scans of cycles <= cycle in (cycle,
  /// vehicle, sensor) order, each at its own time, after checking it against the roster (a live
  /// vehicle; the pose of its state of that cycle when the server has it); refusals are counted
  /// in `rejected`. Then scores the mission at time_s.
  void Fuse(std::int64_t cycle, double time_s, const Roster& roster, RejectionCounts& rejected);
  /// Per valve, what the vehicles' weights are scaled by (evidence of no leak); empty when the
  /// loop does not steer or nothing was seen yet.
  Eigen::VectorXd ValveFactors(double time_s) const;
  /// For the look planner: per valve, the moments since the mission's start a leak from which
  /// would still be unseen (s, as of time_s; ExpectedDetection::Undetected; empty unless
  /// astar.order is looks), and the chance of a leak at the valve the scans
  /// give (the likeliest leaf with evidence of one within the association radius; 0 if none).
  Eigen::VectorXd Undetected(double time_s) const;
  Eigen::VectorXd ValveLeakProbabilities(double time_s) const;
  /// Writes the belief's evidence of leaks into the layer's excess (when the loop steers).
  void UpdateLayer(double time_s);

  /// Leaks, false alarms and scans as of end_s into `metrics` (its valves' visit times give the
  /// revisits after a detection).
  void Fill(MissionMetrics& metrics, double end_s) const;

  /// What a resumed server starts from (the layer is saved on its own, as .ot bytes).
  struct LeakTrack {
    double detected_s, confirmed_s;
    int detections;
  };
  struct Alarm {
    Eigen::Vector2d anchor_m = Eigen::Vector2d::Zero();
    double raised_s = 0.0;
    double cleared_s = -1.0;  ///< -1 while open
    bool confirmed = false;
    int leak = -1;            ///< the leak it is near, or -1: a false alarm
  };
  struct State {
    std::vector<LeakBelief::Entry> belief;
    std::vector<agents::ScanReport> held;
    std::map<std::pair<int, int>, std::int64_t> last_fused;  ///< (vehicle, sensor) -> cycle
    std::vector<LeakTrack> leaks;
    std::vector<Alarm> alarms;
    int false_detections = 0;
    std::uint64_t scans = 0;
    std::vector<std::pair<LeakBelief::Cell, float>> written;  ///< leaves whose excess the loop set
    ExpectedDetection::State scan_waits;
    ExpectedDetection::State look_waits;  ///< the look planner's U (astar.order: looks), or empty
  };
  State Checkpoint() const;
  /// Throws std::invalid_argument if the state does not fit the scenario.
  void Restore(const State& state);

 private:
  void Score(const std::vector<agents::ScanReport>& fused, double time_s);

  const maps::Scenario& scenario_;
  std::size_t max_detections_;  // MaxDetectionsPerScan(scenario_)
  const maps::World& world_;
  maps::RiskLayer& layer_;
  LeakBelief belief_;
  double association_m_ = 0.5;
  struct Truth {
    Eigen::Vector2d position_m;
    int valve;
    double start_s;
  };
  std::vector<Truth> truth_;
  // What each valve's leak would have waited for the scans fused (metrics' expected detection),
  // and the valves by place for a scan's reach.
  ExpectedDetection scan_waits_;
  ExpectedDetection look_waits_;  // over the whole mission, for the look planner (astar.order: looks)
  std::vector<Eigen::Vector2d> valve_positions_;
  std::optional<maps::NearbyPoints> valve_index_;
  void LookAtValves(const agents::ScanReport& scan);
  std::vector<agents::ScanReport> held_;
  std::set<std::tuple<int, int, std::int64_t>> held_keys_;  // (vehicle, sensor, cycle)
  std::map<std::pair<int, int>, std::int64_t> last_fused_;
  std::vector<LeakTrack> leaks_;
  std::vector<Alarm> alarms_;
  int false_detections_ = 0;
  std::uint64_t scans_ = 0;
  std::unordered_map<std::uint64_t, float> written_;  // leaves of the layer this loop set (CellKey), and to what
  struct Offset {
    int di, dj;
    double weight;
  };
  std::vector<Offset> kernel_;                         // the spread (fusion.spread_m), made at first use
  std::unordered_map<std::uint64_t, bool> reachable_;  // leaves whose centre a hull can reach, as asked
  static std::uint64_t CellKey(const LeakBelief::Cell& c) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.i)) << 32) | static_cast<std::uint32_t>(c.j);
  }
  static LeakBelief::Cell KeyCell(std::uint64_t key) {
    return {static_cast<int>(static_cast<std::uint32_t>(key >> 32)), static_cast<int>(static_cast<std::uint32_t>(key))};
  }
};

}  // namespace sage::server
