#pragma once
// The leak sensors of a host's vehicles, simulated: each vehicle carries every sensor of the
// scenario, and on each sensor's scan cycles looks from its state of that cycle along its
// heading. It sees the scenario's hidden leaks that have started and are in view (range, field
// of view, occlusion by the structures through the seabed map's obstacle grid), each with the
// sensor model's detection probability, reported off by its position noise; and it reports
// false alarms anywhere in view. Every draw comes from a stream keyed by (seed, vehicle, sensor,
// cycle): a vehicle scans the same whichever host simulates it, in-process or over DDS, resumed
// or not. No transport here; the host's mission (AgentMission) hands the scans on.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "agents/fleet_messages.h"
#include "maps/perception/sensor_model.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::agents {

class LeakSensors {
 public:
  /// world and scenario outlive the object.
  LeakSensors(const maps::World& world, const maps::Scenario& scenario);

  /// The scenario gives its vehicles sensors.
  bool any() const { return !models_.empty(); }
  const std::vector<maps::SensorModel>& models() const { return models_; }

  /// Appends the scans vehicle `id` makes at `cycle` (one per sensor whose scan falls on it) from
  /// `state`, its state at the cycle's time.
  void Scan(VehicleId id, std::int64_t cycle, const VehicleState& state, std::vector<ScanReport>& out) const;

 private:
  struct Leak {
    Eigen::Vector2d position_m;
    double start_s;
    double strength;
  };
  const maps::Scenario& scenario_;
  std::vector<maps::SensorModel> models_;
  std::vector<Leak> leaks_;
};

/// Uniform and Gaussian draws from a stream keyed by a few integers (SplitMix64 over the key, then
/// its sequence): the same key, the same draws, on any machine.
class KeyedRandom {
 public:
  KeyedRandom(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d, std::uint64_t e);
  std::uint64_t Next();
  double Uniform();   ///< [0, 1)
  double Gaussian();  ///< standard normal (Box-Muller)
  /// Poisson with mean `mean` (>= 0) by inversion, at most 64.
  int Poisson(double mean);

 private:
  std::uint64_t state_;
};

}  // namespace sage::agents
