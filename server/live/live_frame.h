#pragma once
// What the live view shows, as plain data: the scene that does not change during a mission
// (the workspace, the XTs, the valves and their risk spread) and one frame of the mission as it
// stands (every vehicle with its heading and status, each valve's risk and when it was last
// visited, the mission clock, the events since the last frame). A running mission's frames are
// made from its mission core (mission_frames.h), a finished or partial one's from its run
// directory (replay.h); the page, the Foxglove channels and the JSON (frame_json.h) read only
// these structs.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"

namespace sage::live {

/// How the page shows a vehicle: alive and heard lately, alive but not heard for a while
/// (stale), lost (its liveliness lapsed), or left cleanly. Stale, lost and left vehicles are
/// drawn grey where they were last seen, never dropped.
enum class VehicleStatus : std::uint8_t { kAlive = 0, kStale = 1, kLost = 2, kLeft = 3 };
const char* ToString(VehicleStatus status);

struct VehicleView {
  int id = 0;
  std::string name;
  float x_m = 0.0f, y_m = 0.0f;   ///< last known position (workspace frame, m)
  float heading_rad = 0.0f;       ///< counter-clockwise from +x
  VehicleStatus status = VehicleStatus::kAlive;
};

struct ValveView {
  double raw_weight = 0.0;  ///< the weight the profile or an operator set
  double share = 0.0;       ///< raw_weight over the sum of all valves' (0..1)
  double last_visit_s = -std::numeric_limits<double>::infinity();  ///< -inf: never visited
  int visits = 0;
};

/// A line of the event log: a risk change, a join, a loss, a leave, an outage.
struct EventView {
  double time_s = 0.0;
  std::string kind;  ///< "risk", or the fleet event's word (joined, lost, left, outage, ...)
  std::string text;  ///< one line for the operator
};

struct LiveFrame {
  double time_s = 0.0;       ///< mission clock (s)
  double duration_s = 0.0;   ///< planned length (s)
  bool finished = false;     ///< the mission has ended
  double ergodic_metric = std::numeric_limits<double>::quiet_NaN();  ///< of the record so far; NaN before any
  double cycle_ms = 0.0;     ///< the server's last cycle (live only)
  std::vector<VehicleView> vehicles;  ///< ascending id, every vehicle ever heard of
  std::vector<ValveView> valves;      ///< in the scene's valve order
  std::vector<EventView> new_events;  ///< since the previous frame (live) or up to time_s (replay)
  /// Each vehicle's short trail (same order as vehicles): x, y pairs, oldest first. Filled by
  /// the publisher (live) or from the record (replay).
  std::vector<std::vector<float>> trails;
};

struct StructureView {
  std::string name;
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d size_m = Eigen::Vector2d::Zero();
};

/// A pipe on the seabed (a flowline, jumper or umbilical): the page draws its axis at its width.
struct FlowlineView {
  std::string name;
  double diameter_m = 0.0;
  std::vector<Eigen::Vector2d> points_m;
};

/// A boulder on the seabed: its footprint as a circle.
struct BoulderView {
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  double diameter_m = 0.0;
};

struct ValveSite {
  std::string name;
  std::string xt;  ///< the XT it is on
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Identity();
};

/// What does not change during a mission.
struct LiveScene {
  std::string mission;         ///< the scenario's name
  std::string mode = "live";   ///< "live" (a running mission) or "replay" (sage view)
  double width_m = 0.0, height_m = 0.0;
  double duration_s = 0.0;
  double visit_radius_m = 0.0;
  std::string controller, assignment, profile;
  std::vector<StructureView> structures;
  std::vector<FlowlineView> flowlines;  ///< the seabed's pipes, in the scenario's order
  std::vector<BoulderView> boulders;
  std::vector<ValveSite> valves;  ///< maps::Scenario::AllValves() order
  double replay_end_s = 0.0;      ///< replay: the record's last time
  bool actions = false;           ///< operators may act (a running mission)
};

/// The scene of a validated scenario.
LiveScene SceneOf(const maps::Scenario& scenario);

}  // namespace sage::live
