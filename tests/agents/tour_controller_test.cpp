// TourController driving a single integrator integrated here (x += u dt, dt = 0.1 s): valves in
// tour order every lap, lap time = length / speed + wait, waits proportional to the weights,
// new weights from the next lap on.
#include "agents/tour_controller.h"

#include <cmath>

#include <gtest/gtest.h>

namespace sage::agents {
namespace {

constexpr double kDt = 0.1;  // control period (s)
constexpr double kSpeed = 0.5;

// Four valves on the corners of a 6 m square around an XT at the centre of a 12 x 10 m box.
const std::vector<Eigen::Vector2d> kValves = {{3.05, 2.05}, {9.05, 2.05}, {9.05, 8.05}, {3.05, 8.05}};

maps::OccupancyGrid SquareSiteGrid() {
  maps::OccupancyGrid grid(12.0, 10.0, 0.1);
  grid.FillBox({5.25, 4.25}, {6.75, 5.75});
  return grid.Inflated(0.35);
}

// One stay within radius of a valve.
struct Visit {
  int valve = -1;
  int lap = 0;          // laps_completed() during the stay (after the arrival)
  double duration_s = 0.0;
};

// Runs the closed loop for `seconds` and records every stay within `radius_m` of a valve. The
// optional hook runs before each control cycle.
template <typename Hook>
std::vector<Visit> Simulate(TourController& controller, double seconds, double radius_m, Hook hook,
                            std::vector<double>* lap_end_times = nullptr) {
  VehicleState state;
  state.position_m = Eigen::Vector2d(1.0, 1.0);
  std::vector<Visit> visits;
  int inside = -1;
  int laps = 0;
  for (int n = 0; n * kDt < seconds; ++n) {
    const double t = n * kDt;
    hook(t, visits);
    const Eigen::Vector2d u = controller.Command(state, t);
    if (controller.laps_completed() != laps && lap_end_times != nullptr) lap_end_times->push_back(t);
    laps = controller.laps_completed();
    state.position_m += u * kDt;
    state.velocity_mps = u;
    int now_inside = -1;
    for (int v = 0; v < static_cast<int>(kValves.size()); ++v) {
      if ((state.position_m - kValves[v]).norm() < radius_m) now_inside = v;
    }
    if (now_inside >= 0 && now_inside != inside) visits.push_back({now_inside, laps, 0.0});
    if (now_inside >= 0) {
      visits.back().duration_s += kDt;
      visits.back().lap = laps;  // a lap ends on arrival, inside the disc: the wait belongs to the next
    }
    inside = now_inside;
  }
  return visits;
}

auto NoHook = [](double, const std::vector<Visit>&) {};

// After the approach, valves are reached in tour order, lap after lap.
TEST(TourController, VisitsValvesInTourOrderEveryLap) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const Tour tour = PlanTour(grid, kValves);
  ASSERT_TRUE(tour.ok);
  EXPECT_NEAR(tour.length_m, 24.0, 1e-9);
  TourController controller(tour, grid, kSpeed, 4.0, Eigen::Vector4d(0.4, 0.3, 0.2, 0.1));
  const auto visits = Simulate(controller, 200.0, 0.15, NoHook);
  EXPECT_GE(controller.laps_completed(), 3);
  ASSERT_GE(visits.size(), 4u * 3u);
  for (std::size_t k = 0; k < visits.size(); ++k) {
    EXPECT_EQ(visits[k].valve, tour.order[k % tour.order.size()]) << "visit " << k;
  }
}

// Each lap takes length / speed + wait_per_lap_s, within 5 % + 3 control periods.
TEST(TourController, LapTimeIsLengthOverSpeedPlusWait) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const Tour tour = PlanTour(grid, kValves);
  const double wait_per_lap_s = 8.0;
  TourController controller(tour, grid, kSpeed, wait_per_lap_s, Eigen::Vector4d(0.4, 0.3, 0.2, 0.1));
  std::vector<double> lap_ends;
  Simulate(controller, 250.0, 0.15, NoHook, &lap_ends);
  ASSERT_GE(lap_ends.size(), 3u);
  const double expected = tour.length_m / kSpeed + wait_per_lap_s;  // 56 s
  for (std::size_t k = 1; k < lap_ends.size(); ++k) {
    EXPECT_NEAR(lap_ends[k] - lap_ends[k - 1], expected, 0.05 * expected + 3 * kDt) << "lap " << k;
  }
}

// Time within 0.05 m of each valve = wait_per_lap_s * w_i plus the crossing of that disc
// (about 0.5 s at the 0.1 m/s approach floor), within 0.7 s.
TEST(TourController, WaitsAreProportionalToWeights) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const Tour tour = PlanTour(grid, kValves);
  const Eigen::Vector4d weights(0.4, 0.3, 0.2, 0.1);
  const double wait_per_lap_s = 20.0;
  TourController controller(tour, grid, kSpeed, wait_per_lap_s, weights, /*arrive_radius_m=*/0.02);
  const auto visits = Simulate(controller, 160.0, 0.05, NoHook);
  int checked = 0;
  for (const Visit& visit : visits) {
    EXPECT_NEAR(visit.duration_s, wait_per_lap_s * weights[visit.valve], 0.7) << "valve " << visit.valve;
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

// Weights set mid-lap leave the rest of that lap unchanged and apply from the next lap.
TEST(TourController, SetWeightsTakesEffectFromNextLap) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const Tour tour = PlanTour(grid, kValves);
  const Eigen::Vector4d before(0.25, 0.25, 0.25, 0.25), after(0.7, 0.1, 0.1, 0.1);
  const double wait_per_lap_s = 20.0;
  TourController controller(tour, grid, kSpeed, wait_per_lap_s, before, /*arrive_radius_m=*/0.02);
  bool switched = false;
  // Switch while waiting at the second valve of lap index 1 (after one completed lap).
  auto hook = [&](double, const std::vector<Visit>& visits) {
    if (!switched && !visits.empty() && visits.back().lap == 1 && visits.back().valve == tour.order[1] &&
        visits.back().duration_s > 1.0) {
      controller.SetWeights(after);
      switched = true;
    }
  };
  const auto visits = Simulate(controller, 240.0, 0.05, hook);
  ASSERT_TRUE(switched);
  int old_checked = 0, new_checked = 0;
  for (const Visit& visit : visits) {
    if (visit.lap <= 1) {
      EXPECT_NEAR(visit.duration_s, wait_per_lap_s * before[visit.valve], 0.7) << "lap " << visit.lap;
      old_checked += visit.lap == 1;
    } else if (visit.lap == 2) {
      EXPECT_NEAR(visit.duration_s, wait_per_lap_s * after[visit.valve], 0.7) << "valve " << visit.valve;
      ++new_checked;
    }
  }
  EXPECT_EQ(old_checked, 4);
  EXPECT_EQ(new_checked, 4);
}

// Valves on either side of an XT: the vehicle goes around it, never inside its footprint.
TEST(TourController, GoesAroundStructures) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const std::vector<Eigen::Vector2d> valves = {{4.55, 5.05}, {7.45, 5.05}};
  const Tour tour = PlanTour(grid, valves);
  ASSERT_TRUE(tour.ok);
  EXPECT_GT(tour.length_m, 2.0 * (7.45 - 4.55) + 0.5);  // a detour each way
  TourController controller(tour, grid, kSpeed, 2.0, Eigen::Vector2d(0.5, 0.5));
  VehicleState state;
  state.position_m = Eigen::Vector2d(6.0, 0.5);
  for (int n = 0; n < 1500; ++n) {
    state.position_m += controller.Command(state, n * kDt) * kDt;
    const Eigen::Vector2d p = state.position_m;
    ASSERT_FALSE(p.x() > 5.25 && p.x() < 6.75 && p.y() > 4.25 && p.y() < 5.75) << "inside the XT at t = " << n * kDt;
  }
  EXPECT_GE(controller.laps_completed(), 3);
}

// Invalid input is rejected at construction.
TEST(TourController, RejectsInvalidTourAndWeights) {
  const maps::OccupancyGrid grid = SquareSiteGrid();
  const Tour tour = PlanTour(grid, kValves);
  EXPECT_THROW(TourController(Tour{}, grid, kSpeed, 2.0, Eigen::Vector4d::Ones()), std::invalid_argument);
  EXPECT_THROW(TourController(tour, grid, kSpeed, 2.0, Eigen::Vector3d::Ones()), std::invalid_argument);
  EXPECT_THROW(TourController(tour, grid, 0.0, 2.0, Eigen::Vector4d::Ones()), std::invalid_argument);
  TourController controller(tour, grid, kSpeed, 2.0, Eigen::Vector4d::Ones());
  EXPECT_THROW(controller.SetWeights(Eigen::Vector4d::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace sage::agents
