#include "server/metrics.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "maps/risk_field.h"
#include "maps/spectral_basis.h"

namespace sage::server {
namespace {

// A 12 m x 10 m box with one XT carrying the given valves (covariance 0.25 m^2 I); visit radius
// 0.5 m, re-arm radius 1.0 m. Built in code so these tests do not depend on the YAML loader.
maps::Scenario MakeScenario(const std::vector<Eigen::Vector2d>& valve_positions) {
  maps::Scenario scenario;
  scenario.workspace = {12.0, 10.0};
  maps::ChristmasTree xt;
  xt.name = "XT-A";
  xt.center_m = {6.0, 9.0};
  for (std::size_t i = 0; i < valve_positions.size(); ++i) {
    maps::Valve valve;
    valve.name = fmt::format("P{}", i + 1);  // GCC 12 warns (-Wrestrict, a false positive) on "P" + to_string
    valve.position_m = valve_positions[i];
    xt.valves.push_back(valve);
  }
  scenario.structures = {xt};
  scenario.visit_radius_m = 0.5;
  scenario.rearm_radius_m = 1.0;
  scenario.control_rate_hz = 10.0;
  scenario.ergodic.basis_order = 10;
  return scenario;
}

std::vector<WeightChange> Constant(const Eigen::VectorXd& weights) { return {{0.0, weights}}; }

// One vehicle's path sampled every dt_s from t = 0: position_at(t).
template <typename F>
Trajectory SampledPath(int vehicle, double duration_s, double dt_s, F position_at) {
  Trajectory trajectory;
  for (int k = 0; k * dt_s <= duration_s + 1e-9; ++k) {
    TrajectorySample s;
    s.time_s = k * dt_s;
    s.vehicle = vehicle;
    s.position_m = position_at(s.time_s);
    trajectory.samples.push_back(s);
  }
  return trajectory;
}

// WeightsAt: the last entry at or before t; the first before all; empty throws.
TEST(WeightsAt, PiecewiseConstant) {
  const std::vector<WeightChange> schedule = {{10.0, Eigen::Vector2d(1, 0)}, {20.0, Eigen::Vector2d(0, 1)}};
  EXPECT_EQ(WeightsAt(schedule, 0.0)[0], 1.0);
  EXPECT_EQ(WeightsAt(schedule, 19.999)[0], 1.0);
  EXPECT_EQ(WeightsAt(schedule, 20.0)[1], 1.0);
  EXPECT_EQ(WeightsAt(schedule, 1e9)[1], 1.0);
  EXPECT_THROW(WeightsAt({}, 0.0), std::invalid_argument);
}

// A vehicle entering the valve disc at 2, 7 and 15 s of a 20 s mission: 3 visits at those
// times, mean interval (15 - 2) / 2 = 6.5 s, longest gap 15 - 7 = 8 s; an unvisited valve has
// no interval and a gap of the whole mission. Tolerance 1e-9 s (sample times are k * 0.1).
TEST(ComputeMetrics, ExactVisitsIntervalsAndGaps) {
  const maps::Scenario scenario = MakeScenario({{6, 5}, {2, 8}});
  const Trajectory path = SampledPath(0, 20.0, 0.1, [](double t) {
    const bool at_valve = (t >= 2 - 1e-9 && t < 2.5) || (t >= 7 - 1e-9 && t < 7.5) || (t >= 15 - 1e-9 && t < 15.5);
    return at_valve ? Eigen::Vector2d(6.1, 5.0) : Eigen::Vector2d(10.0, 2.0);
  });
  const MissionMetrics m = ComputeMetrics(path, scenario, Constant(Eigen::Vector2d(0.5, 0.5)), 20.0);
  ASSERT_EQ(m.valves.size(), 2u);
  const ValveMetrics& p1 = m.valves[0];
  EXPECT_EQ(p1.name, "P1");
  ASSERT_EQ(p1.visits, 3);
  EXPECT_NEAR(p1.visit_times_s[0], 2.0, 1e-9);
  EXPECT_NEAR(p1.visit_times_s[1], 7.0, 1e-9);
  EXPECT_NEAR(p1.visit_times_s[2], 15.0, 1e-9);
  EXPECT_NEAR(p1.mean_interval_s, 6.5, 1e-9);
  EXPECT_NEAR(p1.max_gap_s, 8.0, 1e-9);
  EXPECT_NEAR(p1.time_near_s, 1.5, 1e-9);  // 3 x 5 samples x 0.1 s
  EXPECT_EQ(m.valves[1].visits, 0);
  EXPECT_TRUE(std::isnan(m.valves[1].mean_interval_s));
  EXPECT_EQ(m.valves[1].max_gap_s, 20.0);
  EXPECT_EQ(m.vehicle_count, 1);
  EXPECT_EQ(m.controller, "recorded");
}

// Jitter across the visit radius that stays inside the re-arm radius is one visit; leaving the
// re-arm radius and coming back is a second.
TEST(VisitTracker, JitterInsideRearmRadiusCountsOnce) {
  VisitTracker tracker({Eigen::Vector2d(0, 0)}, 0.5, 1.0);
  const double distances[] = {2.0, 0.45, 0.55, 0.45, 0.9, 0.3, 0.99, 0.49, 1.5, 0.4};
  int visits = 0;
  for (int k = 0; k < 10; ++k) {
    visits += static_cast<int>(tracker.Update(0, {distances[k], 0.0}, k).size());
  }
  EXPECT_EQ(visits, 2);
  ASSERT_EQ(tracker.visits()[0].recent.size(), 2u);
  EXPECT_EQ(tracker.visits()[0].recent[0], 1.0);
  EXPECT_EQ(tracker.visits()[0].count, 2u);
  EXPECT_EQ(tracker.LastVisit(0), 9.0);
}

// Two vehicles (ids 5 and 2, arriving in that order) in the disc at once each count a visit;
// Forget re-arms one vehicle only.
TEST(VisitTracker, VehiclesCountSeparately) {
  VisitTracker tracker({Eigen::Vector2d(0, 0)}, 0.5, 1.0);
  EXPECT_EQ(tracker.LastVisit(0), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(tracker.Update(5, {0.1, 0.0}, 1.0).size(), 1u);
  EXPECT_EQ(tracker.Update(2, {0.0, 0.2}, 3.0).size(), 1u);
  EXPECT_EQ(tracker.Update(5, {0.1, 0.0}, 4.0).size(), 0u);  // still disarmed
  tracker.Forget(5);
  EXPECT_EQ(tracker.Update(5, {0.1, 0.0}, 5.0).size(), 1u);
  EXPECT_EQ(tracker.Update(2, {0.0, 0.2}, 6.0).size(), 0u);
  EXPECT_EQ(tracker.visits()[0].count, 3u);
}

// Visits counted from each vehicle's disarmed valves and the valves near it equal the rule run
// on every (vehicle, valve) pair: random walks of 6 vehicles among 300 clustered valves.
TEST(VisitTracker, AgreesWithEveryPairScanned) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> where(0.0, 30.0), step(-0.35, 0.35);
  std::vector<Eigen::Vector2d> valves;
  for (int c = 0; c < 60; ++c) {
    const Eigen::Vector2d centre(where(rng), where(rng));
    for (int k = 0; k < 5; ++k) valves.push_back(centre + Eigen::Vector2d(step(rng), step(rng)));
  }
  const double visit = 0.5, rearm = 1.0;
  VisitTracker tracker(valves, visit, rearm);
  std::vector<std::vector<bool>> armed(6, std::vector<bool>(valves.size(), true));
  std::vector<std::vector<double>> times(valves.size());
  std::vector<Eigen::Vector2d> at(6);
  for (auto& x : at) x = {where(rng), where(rng)};
  std::size_t visits = 0;
  for (int t = 0; t < 4000; ++t) {
    const int v = t % 6;
    at[v] += Eigen::Vector2d(step(rng), step(rng));
    at[v] = at[v].cwiseMax(0.0).cwiseMin(30.0);
    std::vector<int> expected;
    for (std::size_t i = 0; i < valves.size(); ++i) {
      const double d = (at[v] - valves[i]).norm();
      if (armed[v][i] && d <= visit) {
        armed[v][i] = false;
        times[i].push_back(0.1 * t);
        expected.push_back(static_cast<int>(i));
      } else if (!armed[v][i] && d > rearm) {
        armed[v][i] = true;
      }
    }
    ASSERT_EQ(tracker.Update(v, at[v], 0.1 * t), expected) << "sample " << t;
    visits += expected.size();
  }
  for (std::size_t i = 0; i < valves.size(); ++i) {
    EXPECT_EQ(tracker.visits()[i].count, times[i].size());
    EXPECT_EQ(tracker.visits()[i].recent, times[i]) << "valve " << i;  // fewer than kRecentVisits each
    // The last visit, as kept for the age weighting, and the same in a restored copy.
    EXPECT_EQ(tracker.LastVisit(static_cast<int>(i)),
              times[i].empty() ? -std::numeric_limits<double>::infinity() : times[i].back()) << "valve " << i;
  }
  EXPECT_GT(visits, 50u);  // the walks do pass valves
  // A checkpoint's arming state restores to the same counting, and the same last visits.
  VisitTracker restored(valves, visit, rearm);
  restored.Restore(tracker.disarmed(), tracker.visits(), tracker.watches());
  for (std::size_t i = 0; i < valves.size(); ++i) {
    EXPECT_EQ(restored.LastVisit(static_cast<int>(i)), tracker.LastVisit(static_cast<int>(i))) << "valve " << i;
  }
  for (int v = 0; v < 6; ++v) EXPECT_EQ(restored.Update(v, at[v], 400.0), tracker.Update(v, at[v], 400.0));
  EXPECT_THROW(restored.Restore({{3, 2}}, tracker.visits(), {}), std::invalid_argument);
}

// Through ComputeMetrics too: two vehicles, one entry each, are two visits and vehicle_count 2.
TEST(ComputeMetrics, TwoVehiclesEachVisit) {
  const maps::Scenario scenario = MakeScenario({{6, 5}});
  Trajectory a = SampledPath(0, 10.0, 0.1, [](double t) { return Eigen::Vector2d(1.0 + t, 5.0); });
  const Trajectory b = SampledPath(1, 10.0, 0.1, [](double t) { return Eigen::Vector2d(6.0, 9.5 - 0.8 * t); });
  a.samples.insert(a.samples.end(), b.samples.begin(), b.samples.end());
  const MissionMetrics m = ComputeMetrics(a, scenario, Constant(Eigen::VectorXd::Ones(1)), 10.0);
  EXPECT_EQ(m.valves[0].visits, 2);
  EXPECT_EQ(m.vehicle_count, 2);
}

// A straight pass 0.3 m from the valve at 0.5 m/s crosses the 0.5 m disc along a chord of
// 2 sqrt(0.5^2 - 0.3^2) = 0.8 m, so 1.6 s near it; within one sample period (0.1 s).
TEST(ComputeMetrics, TimeNearIsChordOverSpeed) {
  const maps::Scenario scenario = MakeScenario({{6, 5}});
  const Trajectory pass = SampledPath(0, 20.0, 0.1, [](double t) { return Eigen::Vector2d(1.0 + 0.5 * t, 5.3); });
  const MissionMetrics m = ComputeMetrics(pass, scenario, Constant(Eigen::VectorXd::Ones(1)), 20.0);
  EXPECT_NEAR(m.valves[0].time_near_s, 1.6, 0.1);
  EXPECT_EQ(m.valves[0].visits, 1);
}

// Pearson against hand computations (tolerance 1e-12); NaN whenever a side is constant.
TEST(PearsonCorrelation, MatchesHandComputation) {
  EXPECT_NEAR(PearsonCorrelation({1, 2, 3}, {2, 4, 6}), 1.0, 1e-12);
  EXPECT_NEAR(PearsonCorrelation({1, 2, 3}, {3, 2, 1}), -1.0, 1e-12);
  // a = {1,2,3,4}, b = {1,3,2,5}: sum da db = 5.5, sum da^2 = 5, sum db^2 = 8.75.
  EXPECT_NEAR(PearsonCorrelation({1, 2, 3, 4}, {1, 3, 2, 5}), 5.5 / std::sqrt(5.0 * 8.75), 1e-12);
  EXPECT_TRUE(std::isnan(PearsonCorrelation({1, 2, 3}, {0.2, 0.2, 0.2})));
  EXPECT_TRUE(std::isnan(PearsonCorrelation({37, 37, 37, 37, 37}, {0.55, 0.2, 0.1, 0.08, 0.07})));
  EXPECT_TRUE(std::isnan(PearsonCorrelation({1}, {2})));
  // Equal weights off by rounding (as time averages produce) are still constant.
  EXPECT_TRUE(std::isnan(PearsonCorrelation({1, 2, 3}, {0.2, 0.2 + 1e-17, 0.19999999999999998})));
  EXPECT_THROW(PearsonCorrelation({1, 2}, {1, 2, 3}), std::invalid_argument);
}

// Nearest rank on known samples: the p99 of 1..100 is 99 and of 1..600 is 594 (six above it),
// q = 1 is the maximum, a tiny q the minimum, order does not matter, nothing is NaN.
TEST(NearestRankPercentile, KnownSamples) {
  std::vector<double> hundred, six_hundred;
  for (int i = 100; i >= 1; --i) hundred.push_back(i);  // descending: the input order is irrelevant
  for (int i = 1; i <= 600; ++i) six_hundred.push_back(i);
  EXPECT_EQ(NearestRankPercentile(hundred, 0.99), 99.0);
  EXPECT_EQ(NearestRankPercentile(hundred, 0.5), 50.0);
  EXPECT_EQ(NearestRankPercentile(six_hundred, 0.99), 594.0);
  EXPECT_EQ(NearestRankPercentile(six_hundred, 1.0), 600.0);
  EXPECT_EQ(NearestRankPercentile(six_hundred, 1e-6), 1.0);
  EXPECT_EQ(NearestRankPercentile({7.0}, 0.99), 7.0);
  // One slow cycle in 100 is the p99's own value; two are above the p98.
  std::vector<double> cycles(98, 1.0);
  cycles.push_back(50.0);
  cycles.push_back(40.0);
  EXPECT_EQ(NearestRankPercentile(cycles, 0.99), 40.0);
  EXPECT_EQ(NearestRankPercentile(cycles, 0.98), 1.0);
  EXPECT_TRUE(std::isnan(NearestRankPercentile({}, 0.99)));
}

// Samples drawn from the target mixture itself give a far smaller ergodic metric than uniform
// coverage (100x) and than a vehicle parked in a corner (1000x; measured: 9e-8, 3e-3, 4e-2), and
// the metric is reported every second to the end.
TEST(ComputeMetrics, ErgodicMetricRewardsMatchingTheTarget) {
  const maps::Scenario scenario = MakeScenario({{3, 3}, {9, 3}, {6, 7}});
  const Eigen::Vector3d weights(0.6, 0.3, 0.1);
  const double duration = 200.0, dt = 0.01;
  std::mt19937 rng(7);
  std::discrete_distribution<int> pick({0.6, 0.3, 0.1});
  std::normal_distribution<double> normal;
  const std::vector<maps::Valve> valves = scenario.AllValves();
  const Trajectory matched = SampledPath(0, duration, dt, [&](double) {
    const maps::Valve& valve = valves[pick(rng)];
    const Eigen::Matrix2d root = valve.covariance_m2.llt().matrixL();
    return Eigen::Vector2d(valve.position_m + root * Eigen::Vector2d(normal(rng), normal(rng)));
  });
  std::uniform_real_distribution<double> uniform;
  const Trajectory spread = SampledPath(0, duration, dt, [&](double) {
    return Eigen::Vector2d(12.0 * uniform(rng), 10.0 * uniform(rng));
  });
  const Trajectory parked = SampledPath(0, duration, dt, [](double) { return Eigen::Vector2d(0.1, 0.1); });
  const MissionMetrics good = ComputeMetrics(matched, scenario, Constant(weights), duration);
  const MissionMetrics flat = ComputeMetrics(spread, scenario, Constant(weights), duration);
  const MissionMetrics bad = ComputeMetrics(parked, scenario, Constant(weights), duration);
  EXPECT_LT(good.ergodic_metric, flat.ergodic_metric / 100.0) << good.ergodic_metric << " vs " << flat.ergodic_metric;
  EXPECT_LT(good.ergodic_metric, bad.ergodic_metric / 1000.0) << good.ergodic_metric << " vs " << bad.ergodic_metric;
  ASSERT_EQ(good.metric_over_time.size(), 200u);
  EXPECT_EQ(good.metric_over_time.front().time_s, 1.0);
  EXPECT_EQ(good.metric_over_time.back().time_s, duration);
  EXPECT_EQ(good.metric_over_time.back().ergodic_metric, good.ergodic_metric);
}

// c_k is weighted by time, not by sample count, and a sample running past a checkpoint counts
// only up to it: at A until 1.5 s and B until 150 s (samples every 0.3 s), then at A again
// (samples every 0.05 s). At t = 2 s the coverage is (1.5 F(A) + 0.5 F(B)) / 2; at the end
// (151.5 F(A) + 148.5 F(B)) / 300, although A has six times B's samples per second.
// Relative tolerance 1e-9.
TEST(ComputeMetrics, CoverageIsTheTimeAverageUpToEachCheckpoint) {
  const maps::Scenario scenario = MakeScenario({{3, 5}, {9, 5}});
  const Eigen::Vector2d a(2, 2), b(10, 8);
  Trajectory path;
  for (int k = 0; k * 0.3 < 1.5 - 1e-9; ++k) path.samples.push_back({k * 0.3, 0, a});
  for (int k = 5; k * 0.3 < 150 - 1e-9; ++k) path.samples.push_back({k * 0.3, 0, b});
  for (int k = 0; 150 + k * 0.05 < 300; ++k) path.samples.push_back({150 + k * 0.05, 0, a});
  const maps::SpectralBasis basis(12, 10, scenario.ergodic.basis_order);
  maps::RiskField field(basis, {{Eigen::Vector2d(3, 5), 0.25 * Eigen::Matrix2d::Identity()},
                                {Eigen::Vector2d(9, 5), 0.25 * Eigen::Matrix2d::Identity()}});
  const Eigen::VectorXd& phi = field.coefficients();  // equal weights
  Eigen::VectorXd fa, fb;
  basis.Evaluate(a, fa);
  basis.Evaluate(b, fb);
  const MissionMetrics m = ComputeMetrics(path, scenario, Constant(Eigen::Vector2d(1, 1)), 300.0);
  const double at_2 = basis.Metric((1.5 * fa + 0.5 * fb) / 2.0 - phi);
  const double at_end = basis.Metric((151.5 * fa + 148.5 * fb) / 300.0 - phi);
  ASSERT_EQ(m.metric_over_time[1].time_s, 2.0);
  EXPECT_NEAR(m.metric_over_time[1].ergodic_metric, at_2, 1e-9 * at_2);
  EXPECT_NEAR(m.ergodic_metric, at_end, 1e-9 * at_end);
}

// A fleet's samples with the coverage added on the helper thread a cycle at a time
// (LaunchCoverage, batches over kCoverageBatch) and read mid-way (a checkpoint's state, a
// partial result) give bit for bit the figures of adding each sample at once: the sums, the
// metric over time and the final metric, exactly equal.
TEST(MetricsAccumulator, CoverageOnTheHelperThreadIsBitForBitTheSame) {
  const maps::Scenario scenario = MakeScenario({{3, 5}, {9, 5}, {6, 2}});
  const maps::SpectralBasis basis(12, 10, 20);
  const maps::RiskField field = maps::RiskField::ForScenario(scenario, basis);
  MetricsAccumulator launched(scenario, basis, field), inline_(scenario, basis, field);
  for (MetricsAccumulator* m : {&launched, &inline_}) m->OnWeights(0.0, Eigen::Vector3d(0.5, 0.3, 0.2));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> x(0.0, 12.0), y(0.0, 10.0);
  const int vehicles = static_cast<int>(MetricsAccumulator::kCoverageBatch) + 100;
  for (int cycle = 0; cycle < 40; ++cycle) {
    const double t = 0.1 * cycle;
    for (int v = 0; v < vehicles; ++v) {
      const TrajectorySample sample{t, v, Eigen::Vector2d(x(rng), y(rng))};
      launched.Add(sample);
      inline_.Add(sample);
    }
    launched.LaunchCoverage();
    for (MetricsAccumulator* m : {&launched, &inline_}) m->Advance(t);
    if (cycle == 17) {
      const MetricsAccumulator::State& a = launched.state();
      const MetricsAccumulator::State& b = inline_.state();
      ASSERT_EQ(a.sum_f.size(), b.sum_f.size());
      for (Eigen::Index k = 0; k < a.sum_f.size(); ++k) ASSERT_EQ(a.sum_f[k], b.sum_f[k]) << "k " << k;
      EXPECT_EQ(launched.Result(1.7).ergodic_metric, inline_.Result(1.7).ergodic_metric);
    }
  }
  const MissionMetrics a = launched.Result(4.0), b = inline_.Result(4.0);
  ASSERT_EQ(a.metric_over_time.size(), b.metric_over_time.size());
  ASSERT_GE(a.metric_over_time.size(), 3u);
  for (std::size_t i = 0; i < a.metric_over_time.size(); ++i)
    EXPECT_EQ(a.metric_over_time[i].ergodic_metric, b.metric_over_time[i].ergodic_metric) << "checkpoint " << i;
  EXPECT_EQ(a.ergodic_metric, b.ergodic_metric);
  EXPECT_GT(a.ergodic_metric, 0.0);
}

// A fleet's cycles through AddCycle (visits at once, holds and checkpoints on the helper thread
// over kHoldBatch samples, a small cycle inline) give bit for bit what Add gives sample by sample:
// with samples refused (out of order, not finite, before 0), a vehicle retired and back, a weight
// change, the visits read while the helper runs and the state read mid-way.
TEST(MetricsAccumulator, CycleOfSamplesOnTheHelperIsBitForBitAdd) {
  const maps::Scenario scenario = MakeScenario({{3, 5}, {9, 5}, {6, 2}});
  const maps::SpectralBasis basis(12, 10, 16);
  const maps::RiskField field = maps::RiskField::ForScenario(scenario, basis);
  MetricsAccumulator cycles(scenario, basis, field), single(scenario, basis, field);
  for (MetricsAccumulator* m : {&cycles, &single}) m->OnWeights(0.0, Eigen::Vector3d(0.5, 0.3, 0.2));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> x(0.0, 12.0), y(0.0, 10.0);
  const int fleet = static_cast<int>(MetricsAccumulator::kHoldBatch) + 60;
  for (int cycle = 0; cycle < 50; ++cycle) {
    const double t = 0.1 * cycle;
    // Cycles 20-29 small (a fleet of 40: inline), the others over kHoldBatch (the helper).
    const int vehicles = cycle >= 20 && cycle < 30 ? 40 : fleet;
    std::vector<TrajectorySample> samples;
    for (int v = 0; v < vehicles; ++v) samples.push_back({t, v, Eigen::Vector2d(x(rng), y(rng))});
    samples.push_back({t, 7, Eigen::Vector2d(1, 1)});                     // again at the same time: refused
    samples.push_back({t, 8, Eigen::Vector2d(std::nan(""), 1)});          // not finite: refused
    if (cycle == 3) samples.push_back({-1.0, 9, Eigen::Vector2d(1, 1)});  // before 0: refused
    for (const TrajectorySample& s : samples) single.Add(s);
    cycles.AddCycle(samples);
    EXPECT_EQ(cycles.refused_samples(), single.refused_samples()) << "cycle " << cycle;
    for (int valve = 0; valve < 3; ++valve)  // the visits, while the helper may still run
      ASSERT_EQ(cycles.visits().LastVisit(valve), single.visits().LastVisit(valve)) << "cycle " << cycle;
    if (cycle == 12) {
      for (MetricsAccumulator* m : {&cycles, &single}) m->Retire(5);
    }
    if (cycle == 33) {
      for (MetricsAccumulator* m : {&cycles, &single}) m->OnWeights(t, Eigen::Vector3d(0.2, 0.2, 0.6));
    }
    for (MetricsAccumulator* m : {&cycles, &single}) m->Advance(t);
    if (cycle == 17) {
      const MetricsAccumulator::State& a = cycles.state();
      const MetricsAccumulator::State& b = single.state();
      ASSERT_EQ(a.pending.size(), b.pending.size());
      for (Eigen::Index k = 0; k < a.sum_f.size(); ++k) ASSERT_EQ(a.sum_f[k], b.sum_f[k]) << "k " << k;
      EXPECT_EQ(a.time_near_s, b.time_near_s);
      EXPECT_EQ(cycles.Result(1.7).ergodic_metric, single.Result(1.7).ergodic_metric);
    }
  }
  EXPECT_EQ(cycles.refused_samples(), 50u * 2u + 1u);
  const MissionMetrics a = cycles.Result(5.0), b = single.Result(5.0);
  ASSERT_EQ(a.metric_over_time.size(), b.metric_over_time.size());
  ASSERT_GE(a.metric_over_time.size(), 4u);
  for (std::size_t i = 0; i < a.metric_over_time.size(); ++i)
    EXPECT_EQ(a.metric_over_time[i].ergodic_metric, b.metric_over_time[i].ergodic_metric) << "checkpoint " << i;
  EXPECT_EQ(a.ergodic_metric, b.ergodic_metric);
  EXPECT_EQ(a.time_outside_s, b.time_outside_s);
  ASSERT_EQ(a.valves.size(), b.valves.size());
  for (std::size_t v = 0; v < a.valves.size(); ++v) {
    EXPECT_EQ(a.valves[v].visits, b.valves[v].visits);
    EXPECT_EQ(a.valves[v].time_near_s, b.valves[v].time_near_s);
  }
  EXPECT_GT(a.ergodic_metric, 0.0);
  // A sample of a vehicle < 0 is refused at the door with an error, changing nothing.
  EXPECT_THROW(cycles.AddCycle({{6.0, -1, Eigen::Vector2d(1, 1)}}), std::invalid_argument);
}

// 1 s in the middle, 2 s beyond the left edge, 3 s 0.1 m from the right edge, 0.5 s above the
// top: 2.5 s outside and 3 s pinned (margin 0.2 m); a sample after the end does not count.
// Tolerance 1e-9 s.
TEST(ComputeMetrics, TimeOutsideAndPinned) {
  const maps::Scenario scenario = MakeScenario({{6, 5}});
  Trajectory path = SampledPath(0, 6.4, 0.1, [](double t) {
    if (t < 1 - 1e-9) return Eigen::Vector2d(6, 5);
    if (t < 3 - 1e-9) return Eigen::Vector2d(-0.5, 5);
    if (t < 6 - 1e-9) return Eigen::Vector2d(11.9, 5);
    return Eigen::Vector2d(6, 10.1);
  });
  path.samples.push_back({7.0, 0, Eigen::Vector2d(-5, -5)});
  const MissionMetrics m = ComputeMetrics(path, scenario, Constant(Eigen::VectorXd::Ones(1)), 6.5);
  EXPECT_NEAR(m.time_outside_s, 2.5, 1e-9);
  EXPECT_NEAR(m.time_pinned_s, 3.0, 1e-9);
}

// Equal raw weights for 150 s, then 0.1 / 0.9: the 300 s averages are 0.3 / 0.7 (within 1e-12);
// the ergodic metric switches to the new target at the change (a vehicle at P2 matches the
// second target better than the first).
TEST(ComputeMetrics, WeightsTimeAverageAcrossScheduleChange) {
  const maps::Scenario scenario = MakeScenario({{3, 5}, {9, 5}});
  const std::vector<WeightChange> schedule = {{0.0, Eigen::Vector2d(1, 1)}, {150.0, Eigen::Vector2d(0.1, 0.9)}};
  const Trajectory at_p2 = SampledPath(0, 300.0, 0.1, [](double) { return Eigen::Vector2d(9, 5); });
  const MissionMetrics m = ComputeMetrics(at_p2, scenario, schedule, 300.0);
  EXPECT_NEAR(m.valves[0].weight, 0.3, 1e-12);
  EXPECT_NEAR(m.valves[1].weight, 0.7, 1e-12);
  const double before = m.metric_over_time[148].ergodic_metric;  // t = 149 s
  const double after = m.metric_over_time[150].ergodic_metric;   // t = 151 s
  EXPECT_LT(after, before);
  EXPECT_THROW(ComputeMetrics(at_p2, scenario, {{0.0, Eigen::Vector3d(1, 1, 1)}}, 300.0), std::invalid_argument);
}

// The fleet figures against a hand computation: valve A (w 0.75) unwatched for stretches of 2, 5,
// 8 and 5 s of 20 s, so a leak starting at a random moment waits (4 + 25 + 64 + 25) / 40 = 2.95 s;
// valve B (w 0.25) never watched waits 400 / 40 = 10 s. Risk-weighted: 0.75 * 2.95 + 0.25 * 10 s.
// Intervals T / n: 20/3 and 20/1 -> 0.75 * 20/3 + 0.25 * 20 = 10 s. Regular stretches of 5 s
// (four of them in 20 s) wait 100 / 40 = 2.5 s: half the interval.
TEST(SummariseGaps, DetectionDelayAndIntervalsByHand) {
  MissionMetrics m;
  m.duration_s = 20.0;
  ValveMetrics a, b;
  a.name = "A";
  a.weight = 0.75;
  a.visit_times_s = {2.0, 7.0, 15.0};
  a.visits = 3;
  a.max_gap_s = 8.0;
  a.longest_unwatched_s = 8.0;
  a.unwatched_squares_s2 = 4 + 25 + 64 + 25;
  b.name = "B";
  b.weight = 0.25;
  b.max_gap_s = 20.0;
  b.longest_unwatched_s = 20.0;
  b.unwatched_squares_s2 = 400.0;
  m.valves = {a, b};
  SummariseGaps(m);
  EXPECT_NEAR(m.expected_detection_delay_s, 0.75 * 2.95 + 0.25 * 10.0, 1e-12);
  EXPECT_NEAR(m.risk_weighted_interval_s, 0.75 * 20.0 / 3.0 + 0.25 * 20.0, 1e-12);
  EXPECT_NEAR(m.dominant_interval_s, 20.0 / 3.0, 1e-12);
  EXPECT_EQ(m.unvisited_valves, 1);
  EXPECT_EQ(m.longest_gap_max_s, 20.0);
  EXPECT_EQ(m.longest_gap_median_s, 20.0);  // nearest rank of two: the upper one

  MissionMetrics regular;
  regular.duration_s = 20.0;
  ValveMetrics r;
  r.weight = 1.0;
  r.visit_times_s = {0.0, 5.0, 10.0, 15.0};
  r.visits = 4;
  r.unwatched_squares_s2 = 4 * 25.0;
  regular.valves = {r};
  SummariseGaps(regular);
  EXPECT_NEAR(regular.expected_detection_delay_s, 2.5, 1e-12);  // I / 2 with I = 5 s
}

// Unwatched stretches come from the trajectory: a vehicle holding station on the valve from
// t = 2 s watches it to the end (one visit, a visit gap of 18 s, but unwatched only the first
// 2 s); one that passes through the disc at 0.5 m/s from t = 10 s (inside over [12, 14] s, at
// 0.1 s samples) leaves it unwatched for 12 s and 6 s of a 20 s mission.
TEST(ComputeMetrics, UnwatchedStretchesFromPresence) {
  const maps::Scenario scenario = MakeScenario({Eigen::Vector2d(3.0, 3.0)});
  const Trajectory holding = SampledPath(0, 20.0, 0.1, [](double t) {
    return t < 2.0 - 1e-9 ? Eigen::Vector2d(6.0, 3.0) : Eigen::Vector2d(3.1, 3.0);
  });
  const MissionMetrics h = ComputeMetrics(holding, scenario, Constant(Eigen::VectorXd::Ones(1)), 20.0);
  ASSERT_EQ(h.valves[0].visits, 1);
  EXPECT_NEAR(h.valves[0].max_gap_s, 18.0, 1e-9);
  EXPECT_NEAR(h.valves[0].longest_unwatched_s, 2.0, 1e-9);
  EXPECT_NEAR(h.expected_detection_delay_s, 4.0 / 40.0, 1e-9);

  const Trajectory pass = SampledPath(0, 20.0, 0.1, [](double t) {
    return Eigen::Vector2d(1.5 + 0.5 * std::max(0.0, t - 10.0), 3.0);  // within 0.5 m for t in [12, 14]
  });
  const MissionMetrics p = ComputeMetrics(pass, scenario, Constant(Eigen::VectorXd::Ones(1)), 20.0);
  // Presence is sampled: each stretch is known to a sample (0.1 s).
  EXPECT_NEAR(p.valves[0].longest_unwatched_s, 12.0, 0.1 + 1e-9);
  EXPECT_NEAR(p.valves[0].unwatched_squares_s2, 12.0 * 12.0 + 6.0 * 6.0, 2 * 0.1 * 18.0);
}

// A valve's record stays kRecentVisits long however many visits come, and what it reports
// (count, first, last, longest gap, mean interval) equals what every visit time kept would give:
// a valve visited 5,000 times at uneven gaps, some of them arriving out of order.
TEST(VisitTracker, RecordStaysBoundedAndItsFiguresExact) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> gap(0.5, 12.0);
  std::vector<double> times;
  for (double t = 3.0; times.size() < 5000; t += gap(rng)) times.push_back(t);
  times[2500] += 40.0;  // one long gap
  std::sort(times.begin(), times.end());
  VisitTracker::ValveVisits record;
  std::vector<double> order = times;
  for (std::size_t i = 0; i + 1 < order.size(); i += 7) std::swap(order[i], order[i + 1]);  // a late host
  for (const double t : order) record.Add(t);
  EXPECT_EQ(record.count, times.size());
  EXPECT_EQ(record.recent.size(), VisitTracker::kRecentVisits);
  EXPECT_TRUE(std::equal(record.recent.begin(), record.recent.end(), times.end() - VisitTracker::kRecentVisits));
  EXPECT_EQ(record.first_s, times.front());
  double longest = 0.0;
  for (std::size_t i = 1; i + VisitTracker::kRecentVisits < times.size(); ++i) longest = std::max(longest, times[i] - times[i - 1]);
  EXPECT_EQ(record.folded_max_gap_s, longest);
  EXPECT_EQ(record.folded_last_s, times[times.size() - VisitTracker::kRecentVisits - 1]);
}

// Through the metrics: a vehicle circling one valve for 20,000 s, 2,000 visits: metrics.json's
// figures are the same as of the whole list (computed here from the visit times), its list the
// latest kRecentVisits, and the metric over time thinned to at most about kMetricSamplesKept.
TEST(MetricsAccumulator, LongMissionsKeepTheirFiguresInBoundedMemory) {
  maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  const maps::SpectralBasis basis(s.workspace.width_m, s.workspace.height_m, s.ergodic.basis_order);
  const maps::RiskField field = maps::RiskField::ForScenario(s, basis);
  MetricsAccumulator metrics(s, basis, field);
  metrics.OnWeights(0.0, Eigen::VectorXd::Ones(s.ValveCount()));
  const Eigen::Vector2d valve = s.ValvePositions()[0];
  std::vector<double> visits;
  const double duration = 20000.0;
  for (int k = 0; k <= static_cast<int>(duration * 10); ++k) {
    const double t = k / 10.0;
    // In the disc for 1 s of every 10 s, one 300 s absence (the longest gap).
    const bool near = std::fmod(t, 10.0) < 1.0 && !(t > 7000.0 && t < 7300.0);
    const Eigen::Vector2d at = near ? valve : Eigen::Vector2d(valve + Eigen::Vector2d(2.0, 0.0));
    TrajectorySample sample;
    sample.time_s = t;
    sample.position_m = at;
    const std::vector<int> visited = metrics.Add(sample);
    if (std::find(visited.begin(), visited.end(), 0) != visited.end()) visits.push_back(t);
    metrics.Advance(t);
  }
  ASSERT_GT(visits.size(), 1900u);
  EXPECT_LE(metrics.state().metric_over_time.size(), MetricsAccumulator::kMetricSamplesKept);
  EXPECT_GE(metrics.state().metric_over_time.size(), MetricsAccumulator::kMetricSamplesKept / 2);
  const MissionMetrics m = metrics.Result(duration);
  const ValveMetrics& p = m.valves[0];
  EXPECT_EQ(p.visits, static_cast<int>(visits.size()));
  EXPECT_EQ(p.visit_times_s.size(), VisitTracker::kRecentVisits);
  EXPECT_EQ(p.visit_times_s.back(), visits.back());
  double longest = std::max(visits.front(), duration - visits.back());
  for (std::size_t i = 1; i < visits.size(); ++i) longest = std::max(longest, visits[i] - visits[i - 1]);
  EXPECT_EQ(p.max_gap_s, longest);
  EXPECT_NEAR(longest, 300.0, 1e-6);  // the absence: visits at 7,000 s and 7,300 s
  EXPECT_DOUBLE_EQ(p.mean_interval_s, (visits.back() - visits.front()) / static_cast<double>(visits.size() - 1));
  // Evenly thinned, in order, and the end's metric last.
  const auto& over = m.metric_over_time;
  for (std::size_t i = 1; i < over.size(); ++i) ASSERT_GT(over[i].time_s, over[i - 1].time_s);
  EXPECT_EQ(over.back().time_s, duration);
  EXPECT_EQ(metrics.latest_metric(), metrics.state().metric_over_time.back().ergodic_metric);
}

// A risk event's response from its watch equals the one from every visit time: next visit,
// intervals before and after, with visits long past the event folded away.
TEST(VisitTracker, WatchesAnswerEventsAsTheWholeListWould) {
  VisitTracker tracker({Eigen::Vector2d(0, 0)}, 0.5, 1.0);
  std::vector<double> times;
  const auto visit = [&](double t) {
    tracker.Update(0, {0.0, 0.0}, t);
    tracker.Update(0, {3.0, 0.0}, t + 0.05);
    times.push_back(t);
  };
  for (double t = 1.0; t < 100.0; t += 3.0) visit(t);
  tracker.WatchAround(0, 100.0);
  for (double t = 101.5; t < 1000.0; t += 2.0) visit(t);
  MissionMetrics m;
  m.events.push_back({100.0, "P1", 1.0});
  FillEventResponses(tracker, m);
  std::vector<double> before, after;
  for (double t : times) (t < 100.0 ? before : after).push_back(t);
  EXPECT_DOUBLE_EQ(m.events[0].time_to_next_visit_s, after.front() - 100.0);
  EXPECT_DOUBLE_EQ(m.events[0].interval_before_s, (before.back() - before.front()) / (before.size() - 1));
  EXPECT_DOUBLE_EQ(m.events[0].interval_after_s, (after.back() - after.front()) / (after.size() - 1));
  EXPECT_EQ(tracker.visits()[0].count, times.size());
  EXPECT_GT(times.size(), 2 * VisitTracker::kRecentVisits);
}

}  // namespace
}  // namespace sage::server
