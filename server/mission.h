#pragma once
// A SAGE mission run in-process, in deterministic lockstep: the server side (risk field with
// its timed events and the no-starving-valve guard, visit accounting, the fleet's shared
// coverage) and the vehicles (Box2D bodies, each with its SMC or A* guidance) advance one
// control cycle at a time, with several physics steps per cycle. The same objects are what a
// DDS launch drives; here nothing crosses a process boundary, so a fixed seed gives the same run.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"
#include "server/metrics.h"
#include "server/trajectory.h"

namespace sage::server {

enum class ControllerKind { kErgodic, kAstar };
const char* ToString(ControllerKind kind);
/// Throws maps::ScenarioError unless text is "ergodic" or "astar".
ControllerKind ParseControllerKind(const std::string& text);

struct MissionResult {
  Trajectory trajectory;
  std::vector<WeightChange> weights;  ///< the profile's normalised weights over time (no guard)
  MissionMetrics metrics;
  double wall_time_s = 0.0;
};

class Mission {
 public:
  /// scenario must already be validated; profile: a profile name (empty: the default).
  Mission(maps::Scenario scenario, ControllerKind controller, const std::string& profile = "");
  ~Mission();
  Mission(const Mission&) = delete;
  Mission& operator=(const Mission&) = delete;

  /// Advances one control cycle: events, guard, guidance, physics. Returns false once the
  /// mission time has reached the duration.
  bool Step();
  double time_s() const;
  double duration_s() const;
  const maps::Scenario& scenario() const;
  /// The risk weights the controllers see now (normalised, guard applied).
  const Eigen::VectorXd& effective_weights() const;

  /// Runs to the end; calls progress(fraction) about every percent. Computes metrics.
  MissionResult Run(const std::function<void(double)>& progress = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Angle (rad, 0..pi) between two commanded velocities; 0 if either is (near) zero. The
/// heading change of a risk event (EventResponse::heading_change_rad).
double HeadingChange(const Eigen::Vector2d& before_mps, const Eigen::Vector2d& after_mps);

/// Fills each risk event's time to the valve's next visit and its revisit interval before and
/// after, from the visit times in `metrics`.
void FillEventResponses(const maps::Scenario& scenario, MissionMetrics& metrics);

/// The SAGE paper's protocol for a fair baseline: the A* wait per lap (s) that makes A* spend as
/// long near the dominant valve (highest time-averaged weight) as the given ergodic run did, to
/// 0.05 s. Zero if A* already lingers longer without waiting.
double CalibratedAstarWait(maps::Scenario scenario, const std::string& profile, const MissionMetrics& ergodic);

}  // namespace sage::server
