// The leak belief's Bayesian update against a hand computation from the sensor's parameters (not
// through SensorModel), the clamps, relaxation to the prior, what is out of view, the valves'
// factors and a checkpoint's round trip.
#include "server/perception/leak_belief.h"

#include <cmath>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

const std::string kTwoXtLeaks = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";

double Logit(double p) { return std::log(p / (1 - p)); }

class LeakBeliefTest : public ::testing::Test {
 protected:
  LeakBeliefTest() : scenario_(maps::LoadScenario(kTwoXtLeaks)), world_(scenario_), belief_(scenario_, world_, 0.2) {}
  // The camera's numbers as the scenario gives them, computed here by hand.
  double P(double d) const {
    const maps::SensorSpec& c = scenario_.sensors[0];
    return c.p_detect * std::pow(2.0, -(d / c.half_range_m) * (d / c.half_range_m));
  }
  double Kappa() const {
    const maps::SensorSpec& c = scenario_.sensors[0];
    const double period = std::round(scenario_.control_rate_hz / c.rate_hz) / scenario_.control_rate_hz;
    return c.false_alarms_per_s * period / (0.5 * c.fov_deg * M_PI / 180.0 * c.range_m * c.range_m);
  }
  double Gauss(const Eigen::Vector2d& z, const Eigen::Vector2d& y) const {
    const double s = scenario_.sensors[0].position_sigma_m;
    return std::exp(-0.5 * (z - y).squaredNorm() / (s * s)) / (2 * M_PI * s * s);
  }
  maps::Scenario scenario_;
  maps::World world_;
  LeakBelief belief_;
};

// One scan from below P1 looking at it, with a detection at P1's leaf: that leaf's log-odds go up
// by ln((1 - p) + p N / kappa), a leaf in view a metre off by ln(1 - p + p N' / kappa) (a miss,
// nearly), one behind the vehicle not at all. 1e-12 relative.
TEST_F(LeakBeliefTest, ScanUpdateMatchesHandComputation) {
  EXPECT_NEAR(belief_.prior_log_odds(), Logit(scenario_.fusion.prior_probability), 1e-12);
  const Eigen::Vector2d pose(2.0, 2.9);
  const LeakBelief::Cell leak = belief_.CellOf({2.0, 3.45});
  const Eigen::Vector2d c = belief_.CentreOf(leak);
  EXPECT_NEAR(c.x(), 2.1, 1e-12);
  EXPECT_NEAR(c.y(), 3.5, 1e-12);
  const Eigen::Vector2d z(2.03, 3.47);
  const int updated = belief_.Fuse(0, pose, M_PI / 2, {z}, 10.0);
  EXPECT_GT(updated, 10);
  const double expected = std::log((1 - P((c - pose).norm())) + P((c - pose).norm()) * Gauss(z, c) / Kappa());
  EXPECT_NEAR(belief_.Evidence(leak, 10.0), expected, 1e-12 * std::abs(expected));
  EXPECT_GT(belief_.Probability(leak, 10.0), scenario_.fusion.alarm_probability) << "one detection raises an alarm";

  const LeakBelief::Cell side = belief_.CellOf({1.5, 3.7});
  const Eigen::Vector2d cs = belief_.CentreOf(side);
  ASSERT_LE((cs - pose).norm(), 1.2);
  const double miss = std::log((1 - P((cs - pose).norm())) + P((cs - pose).norm()) * Gauss(z, cs) / Kappa());
  EXPECT_NEAR(belief_.Evidence(side, 10.0), miss, 1e-12 * std::abs(miss));
  EXPECT_LT(miss, 0.0);
  EXPECT_EQ(belief_.Evidence(belief_.CellOf({2.0, 2.5}), 10.0), 0.0) << "behind the sensor (and inside XT-A)";
  EXPECT_EQ(belief_.positive().count(leak), 1u);
}

// Seeing nothing, scan after scan: down by ln(1 - p) each, held at the floor (min_evidence); a
// detection every scan: up to the ceiling max_log_odds; between scans back to the prior as
// exp(-t / relax_time_s).
TEST_F(LeakBeliefTest, ClampsAndRelaxation) {
  const Eigen::Vector2d pose(2.0, 2.9);
  const LeakBelief::Cell leak = belief_.CellOf({2.0, 3.45});
  const double d = (belief_.CentreOf(leak) - pose).norm();
  belief_.Fuse(0, pose, M_PI / 2, {}, 1.0);
  EXPECT_NEAR(belief_.Evidence(leak, 1.0), std::log(1 - P(d)), 1e-12);
  for (int k = 1; k < 20; ++k) belief_.Fuse(0, pose, M_PI / 2, {}, 1.0);
  EXPECT_DOUBLE_EQ(belief_.Evidence(leak, 1.0), scenario_.fusion.min_evidence);
  const double tau = scenario_.fusion.relax_time_s;
  EXPECT_NEAR(belief_.Evidence(leak, 1.0 + tau), scenario_.fusion.min_evidence / std::exp(1.0), 1e-12);
  // The valve's factor P / P0 < 1 while the evidence is negative.
  const Eigen::VectorXd factors = belief_.ValveFactors(1.0);
  const double p0 = scenario_.fusion.prior_probability;
  const double p = 1.0 / (1.0 + std::exp(-(Logit(p0) + scenario_.fusion.min_evidence)));
  EXPECT_NEAR(factors[0], p / p0, 1e-12);
  EXPECT_EQ(factors[2], 1.0) << "P3 was not looked at";
  for (int k = 0; k < 10; ++k) belief_.Fuse(0, pose, M_PI / 2, {belief_.CentreOf(leak)}, 2.0);
  EXPECT_NEAR(belief_.LogOdds(leak, 2.0), scenario_.fusion.max_log_odds, 1e-12);
}

// regrowth: onset. A leaf looked at and found clean comes back as leaks begin, at the hazard
// P0 / tau: P(t) = P_after + P0 t / tau, linear (not the log-odds' exponential), exactly the prior
// from tau (1 - P_after / P0) on; the valve's factor follows. A detection still relaxes as before.
TEST_F(LeakBeliefTest, OnsetRegrowthIsLinearInProbability) {
  maps::Scenario with_onset = scenario_;  // the fixture's belief keeps relax (it holds scenario_)
  with_onset.fusion.onset_regrowth = true;
  LeakBelief onset(with_onset, world_, 0.2);
  const Eigen::Vector2d pose(2.0, 2.9);
  const LeakBelief::Cell leak = onset.CellOf({2.0, 3.45});
  for (int k = 0; k < 20; ++k) onset.Fuse(0, pose, M_PI / 2, {}, 1.0);
  const double p0 = scenario_.fusion.prior_probability, tau = scenario_.fusion.relax_time_s;
  const double after = 1.0 / (1.0 + std::exp(-(Logit(p0) + scenario_.fusion.min_evidence)));
  for (const double t : {0.0, 5.0, 0.3 * tau, 0.9 * tau * (1 - after / p0)}) {
    SCOPED_TRACE(t);
    const double p = after + p0 * t / tau;
    EXPECT_NEAR(onset.Probability(leak, 1.0 + t), p, 1e-12 * p);
    EXPECT_NEAR(onset.ValveFactors(1.0 + t)[0], p / p0, 1e-9);
  }
  const double back = 1.0 + tau * (1 - after / p0);
  EXPECT_EQ(onset.Evidence(leak, back + 1e-6), 0.0);
  EXPECT_EQ(onset.ValveFactors(back + 1e-6)[0], 1.0);
  // Against relax: the same look, the same floor, a different way back (relax: still below at tau).
  for (int k = 0; k < 20; ++k) belief_.Fuse(0, pose, M_PI / 2, {}, 1.0);
  EXPECT_LT(belief_.Evidence(leak, back + 1e-6), -0.5);
  // A detection's evidence relaxes exponentially under either.
  onset.Fuse(0, pose, M_PI / 2, {onset.CentreOf(leak)}, 200.0);
  const double raised = onset.Evidence(leak, 200.0);
  ASSERT_GT(raised, 0.0);
  EXPECT_NEAR(onset.Evidence(leak, 200.0 + tau), raised / std::exp(1.0), 1e-12 * raised);
}

TEST_F(LeakBeliefTest, CheckpointRoundTrip) {
  belief_.Fuse(0, {2.0, 2.9}, M_PI / 2, {{2.0, 3.45}}, 3.0);
  belief_.Fuse(0, {3.6, 1.6}, -M_PI / 2, {}, 3.2);
  LeakBelief again(scenario_, world_, 0.2);
  again.Restore(belief_.Checkpoint());
  ASSERT_EQ(again.Checkpoint().size(), belief_.Checkpoint().size());
  for (const LeakBelief::Entry& e : belief_.Checkpoint()) {
    EXPECT_EQ(again.Evidence(e.cell, 50.0), belief_.Evidence(e.cell, 50.0));
  }
  EXPECT_EQ(again.positive(), belief_.positive());
  std::vector<LeakBelief::Entry> bad = belief_.Checkpoint();
  bad[0].cell.i = 100000;
  EXPECT_THROW(again.Restore(bad), std::invalid_argument);
}


// Flowline joints (fusion.joint_prior_probability) start at their own prior: a pipe of two_xt_leaks
// from beside P1 to the east, bent once, its first vertex in the camera's view from below P1. The
// joint's leaf is at Pj before any look; a scan that sees nothing lowers its log-odds by the same
// ln(1 - p) as any leaf's (evidence is against the leaf's own prior); it relaxes back to Pj, under
// onset linearly at the hazard Pj / tau; the ceiling max_log_odds holds for l itself; a vertex
// under a structure is no joint; the checkpoint keeps the posterior. Hand computations, 1e-12.
TEST_F(LeakBeliefTest, FlowlineJointsStartAtTheirOwnPrior) {
  const double pj = 0.02, p0 = scenario_.fusion.prior_probability, tau = scenario_.fusion.relax_time_s;
  maps::Scenario with_joints = scenario_;
  with_joints.flowlines.push_back({"FL-T", {{2.3, 3.6}, {4.5, 3.6}, {4.5, 2.0}}, 0.15});
  with_joints.flowlines.push_back({"J-B", {{3.7, 2.0}, {4.5, 2.0}}, 0.15});  // from inside XT-B to the bend
  with_joints.fusion.joint_prior_probability = pj;
  maps::World world(with_joints);
  LeakBelief b(with_joints, world, 0.2);
  const LeakBelief::Cell joint = b.CellOf({2.3, 3.6}), pipe = b.CellOf({3.4, 3.6});
  ASSERT_EQ(b.joints().size(), 3u) << "(2.3, 3.6), (4.5, 3.6), (4.5, 2.0) once; (3.7, 2.0) is inside XT-B";
  EXPECT_EQ(b.joints()[0], joint);
  EXPECT_NEAR(b.Probability(joint, 0.0), pj, 1e-12);
  EXPECT_NEAR(b.Probability(pipe, 0.0), p0, 1e-12) << "straight pipe is open seabed";
  EXPECT_NEAR(b.Probability(b.CellOf({3.7, 2.0}), 0.0), p0, 1e-12);
  EXPECT_EQ(b.prior_log_odds(), belief_.prior_log_odds());

  const Eigen::Vector2d pose(2.0, 2.9);
  const double d = (b.CentreOf(joint) - pose).norm();
  ASSERT_LT(d, 1.2);
  ASSERT_GT(b.Fuse(0, pose, M_PI / 2, {}, 1.0), 0);
  ASSERT_NE(b.Evidence(joint, 1.0), 0.0) << "the joint is in view";
  EXPECT_NEAR(b.Evidence(joint, 1.0), std::log(1 - P(d)), 1e-12);
  EXPECT_NEAR(b.LogOdds(joint, 1.0), Logit(pj) + std::log(1 - P(d)), 1e-12);
  EXPECT_NEAR(b.Evidence(joint, 1.0 + tau), std::log(1 - P(d)) / std::exp(1.0), 1e-12);

  maps::Scenario onset_scenario = with_joints;
  onset_scenario.fusion.onset_regrowth = true;
  LeakBelief onset(onset_scenario, world, 0.2);
  onset.Fuse(0, pose, M_PI / 2, {}, 1.0);
  const double after = 1.0 / (1.0 + std::exp(-(Logit(pj) + std::log(1 - P(d)))));
  for (const double t : {3.0, 0.5 * tau * (1 - after / pj)}) {
    EXPECT_NEAR(onset.Probability(joint, 1.0 + t), after + pj * t / tau, 1e-12);
  }
  EXPECT_EQ(onset.Evidence(joint, 1.0 + tau * (1 - after / pj) + 1e-6), 0.0);

  for (int k = 0; k < 20; ++k) b.Fuse(0, pose, M_PI / 2, {b.CentreOf(joint)}, 2.0);
  EXPECT_NEAR(b.LogOdds(joint, 2.0), scenario_.fusion.max_log_odds, 1e-12);
  LeakBelief again(with_joints, world, 0.2);
  again.Restore(b.Checkpoint());
  EXPECT_EQ(again.Probability(joint, 30.0), b.Probability(joint, 30.0));
  EXPECT_NEAR(again.Probability(b.CellOf({4.5, 2.0}), 30.0), pj, 1e-12) << "a joint not looked at keeps its prior";

  with_joints.fusion.joint_prior_probability = 0.0;
  LeakBelief unweighted(with_joints, world, 0.2);
  EXPECT_TRUE(unweighted.joints().empty());
  EXPECT_NEAR(unweighted.Probability(joint, 0.0), p0, 1e-12);
}

}  // namespace
}  // namespace sage::server
