// The look planner (agents/look_planner.h): its price of a sequence against the integral of the
// unseen onsets computed from their definition on a fine time grid, its search against every
// sequence enumerated, the looks a leg makes against the sensor's fall-off, and, flown closed
// loop on its own model over two_xt, no valve put off for ever.
#include "agents/look_planner.h"

#include <cmath>
#include <algorithm>
#include <functional>
#include <utility>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "maps/perception/sensor_model.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::agents {
namespace {

const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";

struct TwoXt {
  maps::Scenario scenario = maps::LoadScenario(kTwoXtLeaks);
  maps::World world{scenario};
  maps::SensorModel camera{scenario.sensors[0], world.obstacles(), scenario.control_rate_hz};
  LookPlanner Planner(LookPlanner::Options options = {}) const {
    return LookPlanner(world.astar_grid(), scenario.ValvePositions(), camera, scenario.vehicles[0].transit_speed_mps, options);
  }
};

// The integral of S = sum_k w_k U_k over [0, horizon] plus S(horizon) x terminal, from U's
// definition: U_k(t) = U_k(0) prod (1 - p) over the looks at k in (0, t], plus, for each onset s
// in (0, t], prod (1 - p) over the looks at k in (s, t] (piecewise constant in s: summed exactly
// between looks). t on a midpoint grid of `steps`.
double CostFromDefinition(const LookPlanner& planner, int from, const std::vector<int>& sequence, const Eigen::VectorXd& u0,
                          const Eigen::VectorXd& w, double horizon_s, double terminal_s, int steps) {
  struct Seen {
    double t;
    int valve;
    double p;
  };
  std::vector<Seen> looks;
  double start = 0.0;
  int at = from;
  for (int next : sequence) {
    const LookPlanner::Leg& leg = planner.leg(at, next);
    for (const LookPlanner::Look& l : leg.looks) looks.push_back({start + l.time_s, l.valve, l.p});
    start += leg.duration_s;
    at = next;
  }
  const auto unseen = [&](int k, double t) {
    // Onsets before the first look at k in (0, t] and between looks, each scaled by the looks after it.
    std::vector<Seen> at_k;
    for (const Seen& s : looks) {
      if (s.valve == k && s.t <= t) at_k.push_back(s);
    }
    double total = u0[k];
    for (const Seen& s : at_k) total *= 1.0 - s.p;
    double begin = 0.0;
    for (std::size_t i = 0; i <= at_k.size(); ++i) {
      const double end = i < at_k.size() ? at_k[i].t : t;
      double survive = 1.0;
      for (std::size_t j = i; j < at_k.size(); ++j) survive *= 1.0 - at_k[j].p;
      total += (end - begin) * survive;
      begin = end;
    }
    return total;
  };
  const auto s_at = [&](double t) {
    double s = 0.0;
    for (int k = 0; k < w.size(); ++k) s += w[k] * unseen(k, t);
    return s;
  };
  double integral = 0.0;
  const double dt = horizon_s / steps;
  for (int i = 0; i < steps; ++i) integral += s_at((i + 0.5) * dt) * dt;
  return integral + terminal_s * s_at(horizon_s);
}

TEST(LookPlanner, CostIsTheIntegralOfTheUnseenOnsets) {
  const TwoXt two_xt;
  LookPlanner::Options options;
  options.horizon_s = 12.0;
  options.terminal_s = 7.0;
  const LookPlanner planner = two_xt.Planner(options);
  // 2.5 of the longest leg (P2 to P5, ~5.6 s), within the search's depth of average legs.
  double longest = 0.0, sum = 0.0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      if (i == j) continue;
      longest = std::max(longest, planner.leg(i, j).duration_s);
      sum += planner.leg(i, j).duration_s;
    }
  }
  EXPECT_DOUBLE_EQ(planner.horizon_s(), std::max(12.0, std::min(2.5 * longest, planner.depth() * sum / 20.0)));
  EXPECT_GT(planner.horizon_s(), 12.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    Eigen::VectorXd u(5), w(5);
    for (int k = 0; k < 5; ++k) {
      u[k] = 20.0 * uniform(rng);
      w[k] = uniform(rng);
    }
    const int from = trial % 5;
    std::vector<int> sequence;
    for (int at = from; sequence.size() < 6;) {
      const int next = (at + 1 + static_cast<int>(uniform(rng) * 4)) % 5;
      sequence.push_back(next);
      at = next;
    }
    const double cost = planner.Cost(from, sequence, u, w);
    const double reference = CostFromDefinition(planner, from, sequence, u, w, planner.horizon_s(), 7.0, 24'000);
    // The midpoint rule errs by at most the jumps' (sum w p U) x dt / 2 at each look: well under 1e-3.
    EXPECT_NEAR(cost, reference, 1e-3 * reference) << "trial " << trial;
  }
}

TEST(LookPlanner, PlansTheCheapestSequenceOfAllEnumerated) {
  const TwoXt two_xt;
  LookPlanner::Options options;
  options.max_sequences = 300;  // depth 4 over five valves (4^4 = 256)
  const LookPlanner planner = two_xt.Planner(options);
  ASSERT_EQ(planner.depth(), 4);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    Eigen::VectorXd u(5), w(5);
    for (int k = 0; k < 5; ++k) {
      u[k] = 30.0 * uniform(rng);
      w[k] = 0.05 + uniform(rng);
    }
    const int from = trial % 5;
    // Every sequence of four legs, by its first valve and its price.
    std::vector<std::pair<int, double>> priced;
    std::vector<int> sequence;
    const std::function<void(int)> enumerate = [&](int at) {
      if (sequence.size() == 4) {
        priced.emplace_back(sequence.front(), planner.Cost(from, sequence, u, w));
        return;
      }
      for (int next = 0; next < 5; ++next) {
        if (next == at) continue;
        sequence.push_back(next);
        enumerate(next);
        sequence.pop_back();
      }
    };
    enumerate(from);
    const auto cheapest = [&](int avoid) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& [first, cost] : priced) {
        if (first != avoid) best = std::min(best, cost);
      }
      return best;
    };
    const double best = cheapest(-1);
    const std::vector<int> plan = planner.Plan(from, u, w);
    ASSERT_FALSE(plan.empty());
    EXPECT_NE(plan.front(), from);
    EXPECT_NEAR(planner.Cost(from, plan, u, w), best, 1e-9 * best) << "trial " << trial;
    // A valve it could not reach is not flown to first: the best of the sequences that start elsewhere.
    const int avoid = plan.front();
    const double best_elsewhere = cheapest(avoid);
    const std::vector<int> around = planner.Plan(from, u, w, avoid);
    EXPECT_NE(around.front(), avoid);
    EXPECT_NE(around.front(), from);
    EXPECT_NEAR(planner.Cost(from, around, u, w), best_elsewhere, 1e-9 * best_elsewhere) << "trial " << trial;
  }
}

TEST(LookPlanner, ALegLooksAtTheNearestValveWithTheSensorsFallOff) {
  // Open water, three valves: A and B 3 m apart, C 0.5 m off the leg's middle.
  maps::OccupancyGrid grid(6.0, 4.0, 0.05);
  maps::SensorSpec spec;
  spec.range_m = 1.2;
  spec.half_range_m = 0.7;
  spec.p_detect = 0.9;
  spec.rate_hz = 5.0;
  const maps::SensorModel camera(spec, grid, 10.0);
  const Eigen::Vector2d a(1.5, 1.0), b(4.5, 1.0), c(3.0, 1.5);
  LookPlanner::Options options;
  options.turn_s = 0.5;
  const LookPlanner planner(grid, {a, b, c}, camera, 1.0, options);
  const LookPlanner::Leg& leg = planner.leg(0, 1);
  EXPECT_NEAR(leg.duration_s, 3.0 + 0.5, 0.06);  // the grid's path: within a cell of the straight line
  ASSERT_FALSE(leg.looks.empty());
  // The path runs between the cells' centres the ends snap to, straight in open water.
  const Eigen::Vector2d from = grid.CenterOf(grid.CellOf(a)), to = grid.CenterOf(grid.CellOf(b));
  int at_c = 0;
  for (const LookPlanner::Look& look : leg.looks) {
    EXPECT_NEAR(std::remainder(look.time_s, 0.2), 0.0, 1e-9) << "scans every 0.2 s";
    const double along = std::min(look.time_s, leg.duration_s - 0.5);  // 1 m/s
    const Eigen::Vector2d x = from + (to - from).normalized() * along;
    std::vector<std::pair<double, int>> by_distance = {{(a - x).norm(), 0}, {(b - x).norm(), 1}, {(c - x).norm(), 2}};
    std::sort(by_distance.begin(), by_distance.end());
    if (by_distance[1].first - by_distance[0].first > 1e-6) EXPECT_EQ(look.valve, by_distance[0].second) << "at t = " << look.time_s;
    EXPECT_NEAR(look.p, camera.DetectionProbability(by_distance[0].first), 1e-9) << "at t = " << look.time_s;
    at_c += look.valve == 2;
  }
  EXPECT_GE(at_c, 4);  // C is nearest over the leg's middle ~1.5 m: about 7 scans
}

TEST(LookPlanner, FlownOnItsOwnModelPutsNoValveOffForEver) {
  // Closed loop over two_xt's one_extreme risk: plan, fly the first leg as the model has it (its
  // looks scale U, U grows 1 a second), plan again, for 300 s. Every valve is looked at, none
  // left unseen for 40 s, the light P5 (7 % of the risk, the farthest) too: a receding horizon
  // may put a valve off leg after leg, each plan promising it in a later leg it never flies.
  const TwoXt two_xt;
  const LookPlanner planner = two_xt.Planner();
  Eigen::VectorXd w(5);
  w << 0.55, 0.20, 0.10, 0.08, 0.07;
  w = w.array().pow(0.8);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(5), worst = Eigen::VectorXd::Zero(5);
  int at = 1;
  std::vector<int> looked(5, 0);
  for (double t = 0.0; t < 300.0;) {
    const int next = planner.Plan(at, u, w).front();
    const LookPlanner::Leg& leg = planner.leg(at, next);
    double last = 0.0;
    for (const LookPlanner::Look& look : leg.looks) {
      u.array() += look.time_s - last;
      last = look.time_s;
      u[look.valve] *= 1.0 - look.p;
      ++looked[static_cast<std::size_t>(look.valve)];
    }
    u.array() += leg.duration_s - last;
    worst = worst.cwiseMax(u);
    t += leg.duration_s;
    at = next;
  }
  for (int k = 0; k < 5; ++k) {
    EXPECT_GT(looked[static_cast<std::size_t>(k)], 0) << "valve " << k;
    EXPECT_LT(worst[k], 40.0) << "valve " << k;
  }
}

TEST(LookPlanner, RefusesWhatIsNotAPlan) {
  const TwoXt two_xt;
  const LookPlanner planner = two_xt.Planner();
  const Eigen::VectorXd five = Eigen::VectorXd::Ones(5);
  EXPECT_THROW(planner.Plan(5, five, five), std::invalid_argument);
  EXPECT_THROW(planner.Plan(0, Eigen::VectorXd::Ones(4), five), std::invalid_argument);
  Eigen::VectorXd negative = five;
  negative[2] = -1.0;
  EXPECT_THROW(planner.Plan(0, negative, five), std::invalid_argument);
  EXPECT_THROW(planner.Plan(0, five, negative), std::invalid_argument);
  EXPECT_THROW(planner.Cost(0, {0}, five, five), std::invalid_argument);  // no leg from a valve to itself
  EXPECT_THROW(LookPlanner(two_xt.world.astar_grid(), {}, two_xt.camera, 0.8), std::invalid_argument);
  EXPECT_THROW(LookPlanner(two_xt.world.astar_grid(), two_xt.scenario.ValvePositions(), two_xt.camera, 0.0),
               std::invalid_argument);
  // One valve: nowhere else to go.
  const LookPlanner one(two_xt.world.astar_grid(), {two_xt.scenario.ValvePositions()[0]}, two_xt.camera, 0.8);
  EXPECT_EQ(one.Plan(0, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1)), std::vector<int>{0});
}

}  // namespace
}  // namespace sage::agents
