// Where a vehicle looks with `gaze: valves`: the nearest valve in its sensor's reach and line of
// sight (checked against a brute force over every valve, on a grid of positions that includes
// valves hidden behind the XTs), nothing otherwise; and a host's ergodic vehicle that looks at the
// valves has one in its camera's view more often than one that looks ahead, flying the same way.
#include "agents/perception/gaze.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "agents/agent_host.h"
#include "maps/perception/sensor_model.h"
#include "maps/risk_field.h"
#include "maps/world.h"

namespace sage::agents {
namespace {

const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";

// Points of a grid of `step_m` over the workspace (the first at step_m / 2) in open water.
std::vector<Eigen::Vector2d> OpenWaterGrid(const maps::World& world, const maps::Scenario& s, double step_m) {
  std::vector<Eigen::Vector2d> points;
  for (double x = step_m / 2; x < s.workspace.width_m; x += step_m) {
    for (double y = step_m / 2; y < s.workspace.height_m; y += step_m) {
      const Eigen::Vector2i cell = world.obstacles().CellOf({x, y});
      if (!world.obstacles().Occupied(cell.x(), cell.y())) points.emplace_back(x, y);
    }
  }
  return points;
}

maps::Scenario Looking(maps::Gaze gaze, double range_m = 1.2) {
  maps::Scenario s = maps::LoadScenario(kTwoXtLeaks);
  s.gaze = gaze;
  s.sensors[0].range_m = range_m;
  s.Validate();
  return s;
}

TEST(ValveGaze, LooksAtTheNearestValveInSight) {
  int looked = 0, none = 0, nearest_hidden = 0;
  // two_xt's 1.2 m camera (points out of every valve's reach), and a 2.5 m one (from many points
  // the nearest valve lies behind an XT).
  for (const double range_m : {1.2, 2.5}) {
    const maps::Scenario s = Looking(maps::Gaze::kValves, range_m);
    const maps::World world(s);
    const ValveGaze gaze(world, s);
    ASSERT_TRUE(gaze.active());
    const maps::SensorModel model(s.sensors[0], world.obstacles(), s.control_rate_hz);
    const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
    std::vector<int> scratch;
    for (const Eigen::Vector2d& p : OpenWaterGrid(world, s, 0.05)) {
      // Brute force: every valve, by distance, the first one in sight.
      int expected = -1, nearest = -1;
      double best = std::numeric_limits<double>::infinity(), nearest_d = best;
      for (std::size_t k = 0; k < valves.size(); ++k) {
        const double d = (valves[k] - p).norm();
        if (d > range_m) continue;
        if (d < nearest_d) nearest_d = d, nearest = static_cast<int>(k);
        if (d < best && model.LineOfSight(p, valves[k])) best = d, expected = static_cast<int>(k);
      }
      const double heading = gaze.HeadingFor(p, scratch);
      if (expected < 0) {
        EXPECT_TRUE(std::isnan(heading)) << "at " << p.transpose();
        ++none;
        continue;
      }
      ++looked;
      if (nearest != expected) ++nearest_hidden;
      const Eigen::Vector2d to = valves[static_cast<std::size_t>(expected)] - p;
      EXPECT_NEAR(heading, std::atan2(to.y(), to.x()), 1e-12) << "at " << p.transpose();
      // Looking that way, the valve is in the sensor's view.
      EXPECT_TRUE(model.InView(p, heading, valves[static_cast<std::size_t>(expected)])) << "at " << p.transpose();
    }
  }
  EXPECT_GT(looked, 2000);
  EXPECT_GT(none, 100) << "with the 1.2 m camera, much of the field is out of every valve's reach";
  EXPECT_GT(nearest_hidden, 20) << "the grid must include points whose nearest valve an XT hides";
}

// Weighted: the valve where weight x p(d) is largest, checked against a brute force on the same
// grid with weights 1..5 (P1..P5) and with one valve weighing 0; a far valve wins over a near one
// only when its weight makes up for the lower detection probability.
TEST(ValveGaze, LooksWhereALookIsWorthMost) {
  const maps::Scenario s = Looking(maps::Gaze::kValves, 2.5);
  const maps::World world(s);
  const ValveGaze gaze(world, s);
  const maps::SensorModel model(s.sensors[0], world.obstacles(), s.control_rate_hz);
  const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
  std::vector<int> scratch;
  for (const std::vector<double>& weights : {std::vector<double>{1, 2, 3, 4, 5}, std::vector<double>{0, 1, 1, 1, 1}}) {
    const ValveGaze::ValveWeight weight = [&](int k, const Eigen::Vector2d&) { return weights[static_cast<std::size_t>(k)]; };
    int not_nearest = 0;
    for (const Eigen::Vector2d& p : OpenWaterGrid(world, s, 0.1)) {
      int expected = -1, nearest = -1;
      double best = -1.0, nearest_d = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < valves.size(); ++k) {
        const double d = (valves[k] - p).norm();
        if (d > 2.5 || !model.LineOfSight(p, valves[k])) continue;
        if (d < nearest_d) nearest_d = d, nearest = static_cast<int>(k);
        const double worth = weights[k] * model.DetectionProbability(d);
        if (worth > best) best = worth, expected = static_cast<int>(k);
      }
      const double heading = gaze.HeadingFor(p, scratch, weight);
      if (expected < 0) continue;
      if (expected != nearest) ++not_nearest;
      const Eigen::Vector2d to = valves[static_cast<std::size_t>(expected)] - p;
      EXPECT_NEAR(heading, std::atan2(to.y(), to.x()), 1e-12) << "at " << p.transpose();
    }
    EXPECT_GT(not_nearest, 50) << "the weights must change some choices";
  }
}

TEST(ValveGaze, TravelGazeNeverTurns) {
  const maps::Scenario s = Looking(maps::Gaze::kTravel);
  const maps::World world(s);
  const ValveGaze gaze(world, s);
  EXPECT_FALSE(gaze.active());
  std::vector<int> scratch;
  EXPECT_TRUE(std::isnan(gaze.HeadingFor(s.ValvePositions()[0] + Eigen::Vector2d(0.3, 0.0), scratch)));
}

// One ergodic BlueROV2 on two_xt's risk for 120 s, once looking ahead and once at the valves:
// with the gaze some valve is in the camera's view (range, field of view, occlusion) in at least
// 1.5x as many control cycles, and the vehicle still flies at its transit speed (within 10 %).
TEST(ValveGaze, AHostsVehicleKeepsValvesInView) {
  double share[2] = {0.0, 0.0}, speed[2] = {0.0, 0.0};
  for (const maps::Gaze g : {maps::Gaze::kTravel, maps::Gaze::kValves}) {
    const maps::Scenario s = Looking(g);
    const maps::World world(s);
    const maps::SensorModel model(s.sensors[0], world.obstacles(), s.control_rate_hz);
    const std::vector<Eigen::Vector2d> valves = s.ValvePositions();
    AgentHost host(world, s, Guidance::kErgodic);
    host.AddVehicle(0, s.vehicles[0]);
    host.SetTarget(0, {maps::RiskField::ForScenario(s, host.basis()).coefficients(), {}, 0.0});
    const int cycles = static_cast<int>(120.0 / host.control_period_s());
    int in_view = 0;
    double speed_sum = 0.0;
    for (int k = 0; k < cycles; ++k) {
      host.Step(k * host.control_period_s());
      const VehicleState v = host.State(0);
      for (const Eigen::Vector2d& valve : valves) {
        if (model.InView(v.position_m, v.heading_rad, valve)) {
          ++in_view;
          break;
        }
      }
      speed_sum += v.velocity_mps.norm();
    }
    share[g == maps::Gaze::kValves] = static_cast<double>(in_view) / cycles;
    speed[g == maps::Gaze::kValves] = speed_sum / cycles;
  }
  std::printf("valve in view: %.3f of the cycles looking ahead, %.3f looking at the valves; speed %.3f / %.3f m/s\n",
              share[0], share[1], speed[0], speed[1]);
  EXPECT_GE(share[1], 1.5 * share[0]) << "looking ahead " << share[0] << ", at the valves " << share[1];
  EXPECT_NEAR(speed[1], speed[0], 0.1 * speed[0]);
}

}  // namespace
}  // namespace sage::agents
