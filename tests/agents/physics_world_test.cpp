// PhysicsWorld: the single integrator is exact; the BlueROV2 follows its drag law, thrust limits,
// heading loop and collides with structures and other vehicles. Physics at 50 Hz.
#include "agents/physics_world.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace sage::agents {
namespace {

constexpr double kDt = 0.02;  // 50 Hz physics

maps::VehicleSpec Spec(maps::MotionModel model, Eigen::Vector2d start, double heading_rad = 0.0) {
  maps::VehicleSpec spec;
  spec.name = "rov";
  spec.model = model;
  spec.start_m = start;
  spec.start_heading_rad = heading_rad;
  return spec;
}

maps::ChristmasTree Tree(Eigen::Vector2d center, Eigen::Vector2d size) {
  maps::ChristmasTree tree;
  tree.name = "XT";
  tree.center_m = center;
  tree.size_m = size;
  return tree;
}

void RunFor(PhysicsWorld& world, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / kDt));
  for (int n = 0; n < steps; ++n) world.Step(kDt);
}

// Corners of a vehicle's hull footprint (world frame).
std::array<Eigen::Vector2d, 4> Hull(const VehicleState& state, const BlueRov2Params& p) {
  const Eigen::Vector2d ex(std::cos(state.heading_rad), std::sin(state.heading_rad));
  const Eigen::Vector2d ey(-ex.y(), ex.x());
  const Eigen::Vector2d a = 0.5 * p.length_m * ex, b = 0.5 * p.width_m * ey;
  return {state.position_m + a + b, state.position_m - a + b, state.position_m - a - b, state.position_m + a - b};
}

// Penetration depth of two convex quadrilaterals by separating axes (<= 0 when apart).
double Penetration(const std::array<Eigen::Vector2d, 4>& p, const std::array<Eigen::Vector2d, 4>& q) {
  double depth = 1e9;
  for (const auto* poly : {&p, &q}) {
    for (int e = 0; e < 2; ++e) {
      const Eigen::Vector2d edge = (*poly)[e + 1] - (*poly)[e];
      const Eigen::Vector2d axis = Eigen::Vector2d(-edge.y(), edge.x()).normalized();
      double p_min = 1e9, p_max = -1e9, q_min = 1e9, q_max = -1e9;
      for (const auto& x : p) p_min = std::min(p_min, axis.dot(x)), p_max = std::max(p_max, axis.dot(x));
      for (const auto& x : q) q_min = std::min(q_min, axis.dot(x)), q_max = std::max(q_max, axis.dot(x));
      depth = std::min(depth, std::min(p_max, q_max) - std::max(p_min, q_min));
    }
  }
  return depth;
}

// x' = u exactly (1e-9 m), passing through a structure, heading along the command.
TEST(PhysicsWorld, SingleIntegratorMovesExactlyUTimesT) {
  PhysicsWorld world({}, {Tree({2.0, 1.5}, {1.0, 1.0})});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kSingleIntegrator, {1.0, 2.0}));
  const Eigen::Vector2d u(0.3, -0.2);
  world.SetVelocityCommand(id, u);
  RunFor(world, 10.0);  // 3 m along x: straight through the 1 m box at (2, 1.5)
  const VehicleState state = world.State(id);
  EXPECT_NEAR(state.position_m.x(), 1.0 + 0.3 * 10.0, 1e-9);
  EXPECT_NEAR(state.position_m.y(), 2.0 - 0.2 * 10.0, 1e-9);
  EXPECT_NEAR(state.heading_rad, std::atan2(-0.2, 0.3), 1e-12);
  EXPECT_TRUE(state.velocity_mps.isApprox(u));
  EXPECT_EQ(world.Thrust(id), Eigen::Vector3d::Zero());
}

// Ids increase and are never reused; unknown ids throw std::out_of_range.
TEST(PhysicsWorld, IdsAreNeverReusedAndUnknownIdsThrow) {
  PhysicsWorld world({}, {});
  const VehicleId a = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {1.0, 1.0}));
  const VehicleId b = world.AddVehicle(Spec(maps::MotionModel::kSingleIntegrator, {3.0, 1.0}));
  world.RemoveVehicle(a);
  const VehicleId c = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {5.0, 1.0}));
  EXPECT_LT(a, b);
  EXPECT_LT(b, c);
  EXPECT_EQ(world.vehicle_count(), 2);
  EXPECT_FALSE(world.Contains(a));
  EXPECT_TRUE(world.Contains(b) && world.Contains(c));
  EXPECT_THROW(world.State(a), std::out_of_range);
  EXPECT_THROW(world.SetVelocityCommand(a, {1.0, 0.0}), std::out_of_range);
  EXPECT_THROW(world.RemoveVehicle(42), std::out_of_range);
  world.Step(kDt);  // the remaining bodies still step
  EXPECT_NEAR(world.State(c).position_m.x(), 5.0, 1e-6);
}

// 0.5 m/s surge from rest: within 0.03 m/s by 3 s, steady thrust = X_u u + X_uu u^2 within 5 %.
TEST(PhysicsWorld, BlueRov2TracksSurgeCommandWithDragBalancingThrust) {
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {1.0, 5.0}));
  world.SetVelocityCommand(id, {0.5, 0.0});
  RunFor(world, 3.0);
  EXPECT_NEAR(world.State(id).velocity_mps.x(), 0.5, 0.03);
  EXPECT_NEAR(world.State(id).velocity_mps.y(), 0.0, 0.03);
  RunFor(world, 2.0);
  const double drag_n = 13.7 * 0.5 + 141.0 * 0.25;  // 42.1 N
  EXPECT_NEAR(world.Thrust(id).x(), drag_n, 0.05 * drag_n);
}

// A commanded heading (a gaze) is held while the vectored thrusters keep the commanded velocity:
// flying along x while looking along y, the heading settles within 0.02 rad of pi/2 and the
// velocity within 0.03 m/s of the command, the sway thrust carrying the drag (Y_vv v^2, 5 %).
// NaN hands the heading back to the travel's direction.
TEST(PhysicsWorld, BlueRov2HoldsACommandedHeadingWhileItFliesTheCommand) {
  const BlueRov2Params p;
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {1.0, 5.0}));
  world.SetVelocityCommand(id, {0.4, 0.0});
  world.SetHeadingCommand(id, std::numbers::pi / 2);
  RunFor(world, 8.0);
  EXPECT_NEAR(world.State(id).heading_rad, std::numbers::pi / 2, 0.02);
  EXPECT_NEAR(world.State(id).velocity_mps.x(), 0.4, 0.03);
  EXPECT_NEAR(world.State(id).velocity_mps.y(), 0.0, 0.03);
  // Travelling along +x with the body's x along +y: the body sways to its right (v = -0.4).
  const double sway_drag_n = p.drag_linear_sway * 0.4 + p.drag_quadratic_sway * 0.16;
  EXPECT_NEAR(-world.Thrust(id).y(), sway_drag_n, 0.05 * sway_drag_n);
  world.SetHeadingCommand(id, std::numeric_limits<double>::quiet_NaN());
  RunFor(world, 8.0);
  EXPECT_NEAR(world.State(id).heading_rad, 0.0, 0.02);
  EXPECT_NEAR(world.State(id).velocity_mps.x(), 0.4, 0.03);
  // The point model takes the heading at once and still moves exactly u dt.
  const VehicleId point = world.AddVehicle(Spec(maps::MotionModel::kSingleIntegrator, {1.0, 2.0}));
  world.SetVelocityCommand(point, {0.5, 0.0});
  world.SetHeadingCommand(point, -1.0);
  world.Step(kDt);
  EXPECT_DOUBLE_EQ(world.State(point).heading_rad, -1.0);
  EXPECT_NEAR(world.State(point).position_m.x(), 1.0 + 0.5 * kDt, 1e-12);
}

// Full thrust saturates at the drag-law top speed: X_u u + X_uu u^2 = 113 N -> 0.848 m/s (3 %).
TEST(PhysicsWorld, BlueRov2TopSpeedMatchesDragLaw) {
  const BlueRov2Params p;
  const double a = p.drag_quadratic_surge, b = p.drag_linear_surge, f = p.max_force_surge_n;
  const double top_speed = (-b + std::sqrt(b * b + 4.0 * a * f)) / (2.0 * a);
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {1.0, 5.0}));
  world.SetVelocityCommand(id, {5.0, 0.0});  // far beyond reach: thrust stays at its limit
  RunFor(world, 10.0);
  EXPECT_NEAR(world.Thrust(id).x(), p.max_force_surge_n, 1e-9);
  EXPECT_NEAR(world.State(id).velocity_mps.norm(), top_speed, 0.03 * top_speed);
  // The limit scenarios are validated against (a bluerov2's transit_speed_mps) is this speed.
  EXPECT_NEAR(maps::kBlueRov2TopSpeed_mps, top_speed, 0.005);
}

// Driven into an XT for 10 s, the hull stays outside the box (0.05 m tolerance).
TEST(PhysicsWorld, BlueRov2DoesNotPenetrateStructure) {
  const BlueRov2Params p;
  PhysicsWorld world({}, {Tree({6.0, 5.0}, {1.5, 1.5})});  // x in [5.25, 6.75]
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {3.0, 5.0}));
  world.SetVelocityCommand(id, {0.8, 0.0});
  double max_x = 0.0;
  for (int n = 0; n < 500; ++n) {
    world.Step(kDt);
    max_x = std::max(max_x, world.State(id).position_m.x());
  }
  const double touching_x = 5.25 - 0.5 * p.length_m;
  EXPECT_LT(max_x, touching_x + 0.05);
  EXPECT_GT(max_x, touching_x - 0.05);  // it did reach the structure
}

// Blocked seabed as rectangles of cells (a ridge's stair-stepped edge): a BlueROV2 driven into
// it and then along it for 20 s never overlaps any rectangle by more than 0.02 m and is held at
// it; a point vehicle passes through, as through a structure.
TEST(PhysicsWorld, BlueRov2IsHeldByBlockedTerrain) {
  const BlueRov2Params p;
  std::vector<maps::CellRectangle> ridge;
  for (int k = 0; k < 8; ++k) {  // steps 0.5 m wide rising 0.2 m each along x
    ridge.push_back({Eigen::Vector2d(3.0 + 0.5 * k, 5.0 + 0.2 * k), Eigen::Vector2d(3.5 + 0.5 * k, 7.0)});
  }
  PhysicsWorld world({}, {}, {}, 1, ridge);
  const VehicleId rov = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {4.0, 3.5}, std::numbers::pi / 2));
  const VehicleId point = world.AddVehicle(Spec(maps::MotionModel::kSingleIntegrator, {5.0, 3.0}));
  world.SetVelocityCommand(point, {0.0, 0.5});
  double deepest = -1.0, highest_y = 0.0;
  for (int n = 0; n < 1000; ++n) {
    // Into the ridge for 5 s, then along it (east and a little into it) for 15 s.
    world.SetVelocityCommand(rov, n < 250 ? Eigen::Vector2d(0.0, 0.6) : Eigen::Vector2d(0.6, 0.15));
    world.Step(kDt);
    const auto hull = Hull(world.State(rov), p);
    for (const maps::CellRectangle& box : ridge) {
      const std::array<Eigen::Vector2d, 4> corners = {box.min_m, Eigen::Vector2d(box.max_m.x(), box.min_m.y()), box.max_m,
                                                      Eigen::Vector2d(box.min_m.x(), box.max_m.y())};
      deepest = std::max(deepest, Penetration(hull, corners));
    }
    if (n == 249) highest_y = world.State(rov).position_m.y();
  }
  EXPECT_LT(deepest, 0.02);
  EXPECT_GT(deepest, -0.05) << "it did reach the ridge";
  EXPECT_LT(highest_y, 5.2) << "held below the ridge's edge at y = 5.2 there";
  EXPECT_GT(world.State(rov).position_m.x(), 6.0) << "it slid along the ridge";
  EXPECT_GT(world.State(point).position_m.y(), 12.0) << "the point model passes through";
}

// Two BlueROV2s driven at each other (slightly offset) never overlap by more than 0.02 m.
TEST(PhysicsWorld, BlueRov2sDoNotOverlap) {
  PhysicsWorld world({}, {});
  const VehicleId a = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {3.0, 5.0}, 0.0));
  const VehicleId b = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {6.0, 5.2}, std::numbers::pi));
  world.SetVelocityCommand(a, {0.8, 0.0});
  world.SetVelocityCommand(b, {-0.8, 0.0});
  double worst = -1e9;
  for (int n = 0; n < 500; ++n) {
    world.Step(kDt);
    worst = std::max(worst, Penetration(Hull(world.State(a), world.rov_params()),
                                        Hull(world.State(b), world.rov_params())));
  }
  EXPECT_LT(worst, 0.02);
  EXPECT_GT(worst, -0.05);  // they did meet
}

// Shards are bands of the workspace across y (here 20 m high, two bands of 10 m). Driven head
// on, two BlueROV2s in one band meet and stay a hull apart (> 0.4 m between centres) and stop
// at the XTs ahead of them; an XT standing across the bands' edge (y 9.2..10.8) stops a vehicle
// coming at it from either band.
TEST(PhysicsWorld, BandsCollideWithinAndHoldTheStructuresNearThem) {
  const BlueRov2Params p;
  const maps::Workspace field{40.0, 20.0};
  const std::vector<maps::ChristmasTree> trees{Tree({12.0, 5.0}, {1.5, 1.5}), Tree({-3.0, 5.0}, {1.5, 1.5}),
                                               Tree({20.0, 10.0}, {1.6, 1.6})};
  PhysicsWorld world(field, trees, {}, 2);
  ASSERT_EQ(world.shard_count(), 2);
  const VehicleId a = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {3.0, 5.0}, 0.0));
  const VehicleId b = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {6.0, 5.0}, std::numbers::pi));
  const VehicleId below = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {20.0, 6.0}, 0.5 * std::numbers::pi));
  const VehicleId above = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {20.0, 14.0}, -0.5 * std::numbers::pi));
  EXPECT_EQ(world.ShardOf(a), 0);
  EXPECT_EQ(world.ShardOf(above), 1);
  world.SetVelocityCommand(a, {0.8, 0.0});
  world.SetVelocityCommand(b, {-0.8, 0.0});
  world.SetVelocityCommand(below, {0.0, 0.8});
  world.SetVelocityCommand(above, {0.0, -0.8});
  double closest = 1e9;
  for (int n = 0; n < 1000; ++n) {
    world.Step(kDt);
    world.Rebalance();
    closest = std::min(closest, (world.State(a).position_m - world.State(b).position_m).norm());
  }
  EXPECT_GT(closest, 0.4) << "one band: the hulls meet";
  // After they met, each went on round the other and came to rest at the XT ahead of it, or
  // against the other still; neither passed through the XT.
  EXPECT_LT(world.State(a).position_m.x(), 11.25 - 0.5 * p.length_m + 0.05);
  EXPECT_GT(world.State(b).position_m.x(), -2.25 + 0.5 * p.length_m - 0.05);
  EXPECT_NEAR(world.State(below).position_m.y(), 9.2 - 0.5 * p.length_m, 0.05) << "stopped below the XT";
  EXPECT_NEAR(world.State(above).position_m.y(), 10.8 + 0.5 * p.length_m, 0.05) << "stopped above the XT";
  EXPECT_EQ(world.ShardOf(below), 0);
  EXPECT_EQ(world.ShardOf(above), 1);
  EXPECT_THROW(PhysicsWorld(maps::Workspace{40.0, 0.0}, trees, {}, 2), std::invalid_argument);
}

// A vehicle flying across bands changes worlds with its pose and velocities: in open water its
// motion is the one it has in a single world (to Box2D's float rounding, 1e-4 m), and it is
// moved only once it is kBandHysteresis_m past its band's edge. Three BlueROV2s and a single
// integrator, 60 s of turning flight over a 30 m field in five bands of 6 m.
TEST(PhysicsWorld, CrossingBandsKeepsTheMotionOfOneWorld) {
  const maps::Workspace field{30.0, 30.0};
  const std::vector<maps::ChristmasTree> none;
  PhysicsWorld one(field, none, {}, 1), banded(field, none, {}, 5);
  std::vector<VehicleId> ids;
  for (int k = 0; k < 4; ++k) {
    const maps::MotionModel model = k == 3 ? maps::MotionModel::kSingleIntegrator : maps::MotionModel::kBlueRov2;
    const Eigen::Vector2d start(4.0 + 7.0 * k, 2.0 + 6.5 * k);
    ids.push_back(one.AddVehicle(Spec(model, start, 0.4 * k)));
    banded.AddVehicle(Spec(model, start, 0.4 * k));
  }
  int moves = 0;
  std::vector<std::set<int>> bands_seen(ids.size());
  for (int cycle = 0; cycle < 600; ++cycle) {
    for (std::size_t k = 0; k < ids.size(); ++k) {
      // A slow circle of ~8 m radius round each start: across two or three bands and back.
      const double angle = 0.01 * cycle + static_cast<double>(k);  // 0.1 rad/s at 0.8 m/s
      const Eigen::Vector2d command(0.8 * std::cos(angle), 0.8 * std::sin(angle));
      one.SetVelocityCommand(ids[k], command);
      banded.SetVelocityCommand(ids[k], command);
    }
    one.StepShard(0, kDt, 5);
    for (int shard = 0; shard < banded.shard_count(); ++shard) banded.StepShard(shard, kDt, 5);
    moves += banded.Rebalance();
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const double y = banded.State(ids[k]).position_m.y();
      const int band = banded.ShardOf(ids[k]);
      bands_seen[k].insert(band);
      // Within its band, or within the hysteresis of it (the edge bands reach on past the field).
      if (band > 0) {
        ASSERT_GE(y, 6.0 * band - PhysicsWorld::kBandHysteresis_m) << "vehicle " << ids[k];
      }
      if (band < 4) {
        ASSERT_LE(y, 6.0 * (band + 1) + PhysicsWorld::kBandHysteresis_m) << "vehicle " << ids[k];
      }
    }
  }
  EXPECT_GE(moves, 4);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    EXPECT_GE(bands_seen[k].size(), 2u) << "vehicle " << ids[k] << " crossed a band's edge";
    const VehicleState x = one.State(ids[k]), y = banded.State(ids[k]);
    EXPECT_LT((x.position_m - y.position_m).norm(), 1e-4) << "vehicle " << ids[k];
    EXPECT_LT((x.velocity_mps - y.velocity_mps).norm(), 1e-4) << "vehicle " << ids[k];
    EXPECT_NEAR(x.heading_rad, y.heading_rad, 1e-4) << "vehicle " << ids[k];
  }
}

// Stepping the shards one at a time, in any order, on other threads, gives what Step gives: the
// shards share nothing. 40 BlueROV2s over 3 shards, crowded round two XTs, 5 s; states equal
// bit for bit.
TEST(PhysicsWorld, ShardsSteppedApartMatchStepTogether) {
  const std::vector<maps::ChristmasTree> trees{Tree({5.0, 5.0}, {1.5, 1.5}), Tree({9.0, 6.0}, {2.0, 1.0})};
  PhysicsWorld together({}, trees, {}, 3), apart({}, trees, {}, 3);
  std::vector<VehicleId> ids;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector2d start(1.0 + 0.6 * (k % 8), 1.0 + 0.9 * (k / 8));
    ids.push_back(together.AddVehicle(Spec(maps::MotionModel::kBlueRov2, start, 0.3 * k)));
    apart.AddVehicle(Spec(maps::MotionModel::kBlueRov2, start, 0.3 * k));
  }
  for (int cycle = 0; cycle < 50; ++cycle) {
    for (int k = 0; k < 40; ++k) {
      const Eigen::Vector2d command(0.7 * std::cos(0.1 * cycle + k), 0.7 * std::sin(0.13 * cycle - k));
      together.SetVelocityCommand(ids[k], command);
      apart.SetVelocityCommand(ids[k], command);
    }
    for (int s = 0; s < 5; ++s) together.Step(kDt);
    std::thread other([&] { apart.StepShard(2, kDt, 5); });
    apart.StepShard(1, kDt, 5);
    other.join();
    apart.StepShard(0, kDt, 5);
  }
  for (VehicleId id : ids) {
    const VehicleState x = together.State(id), y = apart.State(id);
    ASSERT_EQ(x.position_m, y.position_m) << "vehicle " << id;
    ASSERT_EQ(x.heading_rad, y.heading_rad) << "vehicle " << id;
    ASSERT_EQ(x.velocity_mps, y.velocity_mps) << "vehicle " << id;
  }
  EXPECT_THROW(PhysicsWorld({}, trees, {}, 0), std::invalid_argument);
}

// A vehicle removed from a sharded world takes nothing of the others with it: each shard steps
// its own vehicles from a list of its own, rebuilt on removal. Nine BlueROV2s over 3 shards, 8 m
// apart (no two touch), the single integrator among them; with vehicle 4 removed after 1 s, the
// other eight end where they end in a world that keeps it, bit for bit (a stale list would step
// a vehicle twice, or not, or another world's body).
TEST(PhysicsWorld, RemovalFromAShardLeavesTheOthersAsTheyWere) {
  const std::vector<maps::ChristmasTree> trees{Tree({50.0, 50.0}, {1.0, 1.0})};
  PhysicsWorld kept({}, trees, {}, 3), removed({}, trees, {}, 3);
  std::vector<VehicleId> ids;
  for (int k = 0; k < 9; ++k) {
    const maps::MotionModel model = k == 7 ? maps::MotionModel::kSingleIntegrator : maps::MotionModel::kBlueRov2;
    const Eigen::Vector2d start(8.0 * k, 1.5 + 3.4 * (k % 3));  // in bands 0, 1, 2 in turn
    ids.push_back(kept.AddVehicle(Spec(model, start, 0.2 * k)));
    removed.AddVehicle(Spec(model, start, 0.2 * k));
  }
  const auto command = [](int k, int cycle) {
    return Eigen::Vector2d(0.5 * std::cos(0.05 * cycle + k), 0.5 * std::sin(0.05 * cycle + k));  // a slow turn
  };
  for (int cycle = 0; cycle < 30; ++cycle) {
    if (cycle == 10) removed.RemoveVehicle(ids[4]);
    for (int k = 0; k < 9; ++k) {
      kept.SetVelocityCommand(ids[k], command(k, cycle));
      if (removed.Contains(ids[k])) removed.SetVelocityCommand(ids[k], command(k, cycle));
    }
    for (int shard = 0; shard < 3; ++shard) {
      kept.StepShard(shard, kDt, 5);
      removed.StepShard(shard, kDt, 5);
    }
    kept.Rebalance();  // with the records moved down one, the moves found in the step still apply
    removed.Rebalance();
  }
  ASSERT_FALSE(removed.Contains(ids[4]));
  EXPECT_EQ(removed.vehicle_count(), 8);
  for (int k = 0; k < 9; ++k) {
    if (k == 4) continue;
    const VehicleState x = kept.State(ids[k]), y = removed.State(ids[k]);
    ASSERT_EQ(x.position_m, y.position_m) << "vehicle " << ids[k];
    ASSERT_EQ(x.velocity_mps, y.velocity_mps) << "vehicle " << ids[k];
    ASSERT_EQ(x.heading_rad, y.heading_rad) << "vehicle " << ids[k];
    EXPECT_GT((x.position_m - Eigen::Vector2d(8.0 * k, 1.5 + 3.4 * (k % 3))).norm(), 0.3) << "vehicle " << ids[k] << " moved";
  }
}

// Commanded along +y from heading 0, the vehicle faces +y within 3 s (0.05 rad).
TEST(PhysicsWorld, BlueRov2TurnsToFaceCommand) {
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {5.0, 5.0}, 0.0));
  world.SetVelocityCommand(id, {0.0, 0.4});
  RunFor(world, 3.0);
  EXPECT_NEAR(world.State(id).heading_rad, std::numbers::pi / 2.0, 0.05);
  EXPECT_NEAR(world.State(id).yaw_rate_radps, 0.0, 0.05);
  EXPECT_NEAR(world.State(id).velocity_mps.y(), 0.4, 0.03);
}

// A sway command moves the vehicle sideways before it has turned (vectored thrusters strafe).
TEST(PhysicsWorld, BlueRov2StrafesBeforeTurning) {
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {5.0, 5.0}, 0.0));
  world.SetVelocityCommand(id, {0.0, 0.4});
  RunFor(world, 0.2);
  const VehicleState state = world.State(id);
  const double sway_mps = -std::sin(state.heading_rad) * state.velocity_mps.x() +
                          std::cos(state.heading_rad) * state.velocity_mps.y();
  EXPECT_LT(state.heading_rad, std::numbers::pi / 4.0);  // still mostly facing +x
  EXPECT_GT(world.Thrust(id).y(), 10.0);     // body-frame sway thrust (N)
  EXPECT_GT(sway_mps, 0.2);                  // body-frame sway velocity (m/s)
  EXPECT_GT(state.position_m.y() - 5.0, 0.03);
}

// With a zero command the vehicle brakes to rest and holds its heading.
TEST(PhysicsWorld, BlueRov2HoldsPositionOnZeroCommand) {
  PhysicsWorld world({}, {});
  const VehicleId id = world.AddVehicle(Spec(maps::MotionModel::kBlueRov2, {5.0, 5.0}, 0.7));
  world.SetVelocityCommand(id, {0.5 * std::cos(0.7), 0.5 * std::sin(0.7)});
  RunFor(world, 3.0);
  world.SetVelocityCommand(id, Eigen::Vector2d::Zero());
  RunFor(world, 3.0);
  EXPECT_LT(world.State(id).velocity_mps.norm(), 1e-3);
  EXPECT_NEAR(world.State(id).heading_rad, 0.7, 0.02);
}

}  // namespace
}  // namespace sage::agents
