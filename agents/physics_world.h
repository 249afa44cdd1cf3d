#pragma once
// Box2D world of a mission: zero gravity, the XT structures and the seabed's blocked terrain as
// static bodies, one body per vehicle. Every vehicle's motion goes through Box2D:
//  - single_integrator: a kinematic body whose velocity is set to the command (x' = u exactly,
//    passes through structures like the paper's point model);
//  - bluerov2: a dynamic body with the BlueROV2 Heavy rigid-body + added mass, body-frame linear
//    and quadratic drag and thrust limits (von Benzon et al. 2022), and a velocity controller
//    that tracks the commanded velocity; collides with structures and other vehicles.
#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "agents/vehicle_controller.h"
#include "maps/scenario/scenario.h"
#include "maps/seabed/seabed_obstacles.h"

class b2World;
class b2Body;
struct b2BodyDef;

namespace sage::agents {

/// BlueROV2 Heavy, planar (surge u, sway v, yaw r). SI units.
struct BlueRov2Params {
  double mass_kg = 13.5;
  double yaw_inertia_kgm2 = 0.37;
  double added_mass_surge_kg = 6.36;    ///< X_udot
  double added_mass_sway_kg = 7.12;     ///< Y_vdot
  double added_inertia_yaw_kgm2 = 0.22; ///< N_rdot
  double drag_linear_surge = 13.7;      ///< X_u (N s/m)
  double drag_linear_sway = 0.0;        ///< Y_v (N s/m)
  double drag_linear_yaw = 0.0;         ///< N_r (N m s/rad)
  double drag_quadratic_surge = 141.0;  ///< X_uu (N s^2/m^2)
  double drag_quadratic_sway = 217.0;   ///< Y_vv (N s^2/m^2)
  double drag_quadratic_yaw = 1.5;      ///< N_rr (N m s^2/rad^2)
  double max_force_surge_n = 113.0;     ///< thrust limit along body x (N)
  double max_force_sway_n = 113.0;      ///< thrust limit along body y (N)
  double max_torque_nm = 20.0;          ///< yaw torque limit (N m)
  double length_m = 0.457;              ///< hull footprint for collisions
  double width_m = 0.575;
  double velocity_gain_per_s = 4.0;     ///< velocity loop bandwidth (1/s)
  double heading_gain_per_s = 2.0;      ///< heading loop bandwidth (1/s): faces its direction of travel
};

class PhysicsWorld {
 public:
  /// shards (>= 1): how many Box2D worlds the vehicles are dealt over. The shards are bands of
  /// the workspace across y (the first and last reaching on past its edges), each holding the
  /// structures and terrain within kBandMargin_m of it; a vehicle is in the band it is over, and
  /// Rebalance() moves one that has flown more than kBandHysteresis_m out of its band into the
  /// band it is over now. Vehicles of one band collide with each other; a vehicle in a band
  /// and one kept in the next by the hysteresis pass through each other (guidance keeps them
  /// apart, as it keeps apart the vehicles of different agent hosts). A band is a small world
  /// whose few hundred vehicles stay in a core's cache through the substeps of a cycle, and the
  /// bands can be stepped on different threads.
  /// `terrain`: the seabed's obstacles that are not structures (maps::World::terrain_blocks()),
  /// one static box fixture each.
  static constexpr double kBandHysteresis_m = 1.0;
  static constexpr double kBandMargin_m = 2.5;
  PhysicsWorld(const maps::Workspace& workspace, const std::vector<maps::ChristmasTree>& structures,
               BlueRov2Params rov_params = {}, int shards = 1, const std::vector<maps::CellRectangle>& terrain = {});
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  /// Adds a vehicle at its start pose; returns its id (ids are never reused).
  VehicleId AddVehicle(const maps::VehicleSpec& spec);
  void RemoveVehicle(VehicleId id);
  bool Contains(VehicleId id) const;
  int vehicle_count() const;

  /// Desired world-frame velocity (m/s), held until the next call.
  void SetVelocityCommand(VehicleId id, const Eigen::Vector2d& velocity_mps);
  /// Heading to hold (rad, world frame), held until the next call; NaN (the default): face the
  /// direction of the velocity command. A BlueROV2 yaws to it while its vectored thrusters keep
  /// the commanded velocity (surge and sway together); the point model takes it at once.
  void SetHeadingCommand(VehicleId id, double heading_rad);
  /// Applies drag and thrust to every BlueROV2, then advances Box2D by dt_s (every shard).
  void Step(double dt_s);
  int shard_count() const;
  /// `steps` times: drag and thrust on the shard's BlueROV2s, then its Box2D world advanced by
  /// dt_s. Shards share nothing but the (read-only) parameters: different shards may be stepped
  /// on different threads at once, and the result is the same as stepping them one by one.
  void StepShard(int shard, double dt_s, int steps);
  /// Moves every vehicle more than kBandHysteresis_m outside its band at the end of its shard's
  /// last StepShard into the band it is over, with its pose and velocities (its contacts are made
  /// again in the new world); in id order, so a seed gives the same mission. Returns how many
  /// moved. Call between steps, on one thread.
  int Rebalance();
  /// The band (shard) a vehicle is in.
  int ShardOf(VehicleId id) const;
  VehicleState State(VehicleId id) const;
  /// Asks for what State(id) reads (the vehicle's Box2D body) to be brought into cache
  /// (maps/prefetch.h); changes nothing. An unknown id is ignored.
  void Prefetch(VehicleId id) const;
  /// Thrust the BlueROV2 velocity controller applied in the last Step, body frame:
  /// (surge N, sway N, yaw N m), within the thrust limits; zero for a single integrator.
  Eigen::Vector3d Thrust(VehicleId id) const;

  const BlueRov2Params& rov_params() const { return rov_params_; }

 private:
  struct Vehicle;
  Vehicle& Find(VehicleId id);
  const Vehicle& Find(VehicleId id) const;
  const Vehicle* Lookup(VehicleId id) const;  // nullptr if there is no such vehicle
  void ApplyBlueRov2Forces(Vehicle& vehicle);
  // The band over y (0 when there is one world), and a vehicle's body in a shard's world: `def`
  // with the model's type, and a BlueROV2's hull and mass.
  int BandAt(double y_m) const;
  bool OutOfBand(const Vehicle& vehicle) const;
  b2Body* CreateVehicleBody(int shard, maps::MotionModel model, b2BodyDef def);

  BlueRov2Params rov_params_;
  std::vector<std::unique_ptr<b2World>> worlds_;  // the shards
  double band_height_m_ = 0.0;  // shards > 1: the workspace's height / shards
  std::vector<Vehicle> vehicles_;  // sorted by id
  // Each shard's vehicles, as indices into vehicles_ in id order: a shard's step walks its own,
  // not every vehicle of the host (rebuilt when a vehicle is added or removed).
  std::vector<std::vector<std::size_t>> shard_members_;
  // Each shard's vehicles its last step left out of their band (indices into vehicles_), for
  // Rebalance: written by the thread stepping the shard, read between steps.
  std::vector<std::vector<std::size_t>> leaving_;
  VehicleId next_id_ = 0;

  void IndexShards();
};

}  // namespace sage::agents
