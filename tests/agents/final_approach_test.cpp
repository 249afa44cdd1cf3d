#include "agents/final_approach.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "agents/ergodic_controller.h"
#include "maps/distance_field.h"
#include "maps/occupancy_grid.h"
#include "maps/spectral_basis.h"

namespace sage::agents {
namespace {

// A 6 m x 6 m field; `box` puts a structure on [2.5, 3.5] x [0.5, 1.5].
struct Field {
  maps::OccupancyGrid grid{6.0, 6.0, 0.05};
  explicit Field(bool box = false) {
    if (box) grid.FillBox({2.5, 0.5}, {3.5, 1.5});
  }
};

const auto kEvery = [](int, const Eigen::Vector2d&) { return true; };

// The angle (degrees) between two vectors.
double AngleDeg(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::atan2(std::abs(a.x() * b.y() - a.y() * b.x()), a.dot(b)) * 180.0 / std::numbers::pi;
}

// A pass 0.4 m off a valve ahead is turned onto it, at the law's speed.
TEST(FinalApproach, TurnsAPassThatWouldMissAValveOntoIt) {
  Field f;
  const maps::DistanceField clearance(f.grid);
  const FinalApproach approach({{2.0, 1.4}}, clearance, 1.5);
  std::vector<int> scratch;
  const Eigen::Vector2d from(1.0, 1.0), law(0.7, 0.0);
  const Eigen::Vector2d out = approach.Apply(from, law, kEvery, scratch);
  EXPECT_NEAR(out.norm(), 0.7, 1e-12);
  EXPECT_NEAR(AngleDeg(out, Eigen::Vector2d(2.0, 1.4) - from), 0.0, 1e-6);
}

// Off the cone, beyond the radius, at the valve already, or with the radius 0: the law's own
// command, bit for bit.
TEST(FinalApproach, LeavesTheLawAloneWhereNoValveIsAhead) {
  Field f;
  const maps::DistanceField clearance(f.grid);
  std::vector<int> scratch;
  const Eigen::Vector2d from(1.0, 1.0), law(0.7, 0.0);
  // 81.9 degrees off the command (the cone is 80): not ahead; 77.9 degrees: ahead.
  EXPECT_EQ(FinalApproach({{1.2, 2.4}}, clearance, 1.5).Apply(from, law, kEvery, scratch), law);
  EXPECT_NE(FinalApproach({{1.3, 2.4}}, clearance, 1.5).Apply(from, law, kEvery, scratch), law);
  EXPECT_EQ(FinalApproach({{0.5, 1.0}}, clearance, 1.5).Apply(from, law, kEvery, scratch), law);  // behind
  EXPECT_EQ(FinalApproach({{2.6, 1.0}}, clearance, 1.5).Apply(from, law, kEvery, scratch), law);  // 1.6 m
  EXPECT_EQ(FinalApproach({{1.03, 1.0}}, clearance, 1.5).Apply(from, law, kEvery, scratch), law);  // there
  EXPECT_EQ(FinalApproach({{2.0, 1.4}}, clearance, 0.0).Apply(from, law, kEvery, scratch), law);  // off
  EXPECT_EQ(FinalApproach({{2.0, 1.4}}, clearance, 1.5).Apply(from, Eigen::Vector2d::Zero(), kEvery, scratch),
            Eigen::Vector2d::Zero());  // a law at rest stays at rest
  EXPECT_THROW(FinalApproach({}, clearance, -1.0), std::invalid_argument);
}

// A valve behind a structure is not flown at (the straight line would meet the structure); one
// as far on a clear line is.
TEST(FinalApproach, NeverFliesAtAValveThroughAStructure) {
  Field f(true);
  const maps::DistanceField clearance(f.grid);
  std::vector<int> scratch;
  const Eigen::Vector2d from(2.0, 1.0), law(0.7, 0.0);
  const Eigen::Vector2d behind(4.0, 1.0), clear(2.6, 2.6);  // both 2 m or so away, both ahead
  EXPECT_FALSE(FinalApproach({behind}, clearance, 2.5).InSight(from, behind));
  EXPECT_EQ(FinalApproach({behind}, clearance, 2.5).Apply(from, law, kEvery, scratch), law);
  EXPECT_TRUE(FinalApproach({clear}, clearance, 2.5).InSight(from, clear));
  EXPECT_NEAR(AngleDeg(FinalApproach({clear}, clearance, 2.5).Apply(from, law, kEvery, scratch), clear - from), 0.0,
              1e-6);
  // A valve 0.15 m off the structure's face is reached square on (its own clearance halves the margin).
  const Eigen::Vector2d at_face(3.0, 1.65);
  EXPECT_TRUE(FinalApproach({at_face}, clearance, 2.5).InSight(Eigen::Vector2d(3.0, 3.0), at_face));
}

// The choice, against a brute force over every valve: the nearest valve within the radius,
// within 80 degrees of the command and farther than kArrived_m, among those the caller wants.
TEST(FinalApproach, ChoosesAsABruteForceDoes) {
  Field f;
  const maps::DistanceField clearance(f.grid);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> where(0.0, 6.0), turn(-std::numbers::pi, std::numbers::pi);
  std::vector<Eigen::Vector2d> valves;
  for (int i = 0; i < 60; ++i) valves.emplace_back(where(rng), where(rng));
  const double radius = 1.5;
  const FinalApproach approach(valves, clearance, radius);
  const auto wanted = [](int k, const Eigen::Vector2d&) { return k % 3 != 0; };
  std::vector<int> scratch;
  int turned = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Vector2d x(where(rng), where(rng));
    const double a = turn(rng);
    const Eigen::Vector2d law = 0.6 * Eigen::Vector2d(std::cos(a), std::sin(a));
    int best = -1;
    for (int k = 0; k < static_cast<int>(valves.size()); ++k) {
      const double d = (valves[k] - x).norm();
      if (d > radius || d < FinalApproach::kArrived_m || !wanted(k, valves[k])) continue;
      if (AngleDeg(valves[k] - x, law) > FinalApproach::kHalfAngle_deg) continue;
      if (best < 0 || d < (valves[best] - x).norm()) best = k;
    }
    const Eigen::Vector2d out = approach.Apply(x, law, wanted, scratch);
    if (best < 0) {
      EXPECT_EQ(out, law) << trial;
    } else {
      ++turned;
      EXPECT_NEAR(AngleDeg(out, valves[best] - x), 0.0, 1e-6) << trial;
      EXPECT_NEAR(out.norm(), 0.6, 1e-12) << trial;
    }
  }
  EXPECT_GT(turned, 200);  // the draws do exercise the turn
}

// What the approach asks of the law: the target's density at a point, and the coverage's,
// sum_k c_k F_k(x), checked against the coverage summed along the path flown (the kernel
// sum_k F_k(x(t)) F_k(x) at every step, averaged over time), not through the running sums.
TEST(FinalApproach, TheLawsDensitiesMatchThePathFlown) {
  const maps::SpectralBasis basis(6.0, 6.0, 12);
  ErgodicController law(basis, 0.5);
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(basis.size());
  Eigen::VectorXd f;
  basis.Evaluate({2.0, 3.0}, phi);  // a target peaked at (2, 3), as a valve's is
  law.SetTarget(phi);
  std::vector<Eigen::Vector2d> path;
  double t = 0.0;
  VehicleState state;
  state.position_m = {1.0, 1.0};
  for (int i = 0; i < 80; ++i, t += 0.1) {
    path.push_back(state.position_m);
    const Eigen::Vector2d u = law.Command(state, t);
    state.position_m += 0.1 * u;
  }
  const Eigen::Vector2d x(2.0, 3.0);
  Eigen::VectorXd fx;
  basis.Evaluate(x, fx);
  // Rectangle rule as the law integrates: the position at step i stands for the interval before it.
  double kernel_sum = 0.0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    basis.Evaluate(path[i + 1], f);
    kernel_sum += 0.1 * f.dot(fx);
  }
  (void)law.Command(state, t);  // integrates the last position
  basis.Evaluate(state.position_m, f);
  kernel_sum += 0.1 * f.dot(fx);
  const double elapsed = 0.1 * static_cast<double>(path.size());
  const ErgodicController::Densities d = law.DensitiesAt(x);
  EXPECT_NEAR(d.target, phi.dot(fx), 1e-12);
  EXPECT_NEAR(d.covered, kernel_sum / elapsed, 1e-9 * std::abs(kernel_sum / elapsed) + 1e-12);
}

}  // namespace
}  // namespace sage::agents
