// Per-step cost of the SAGE engine: one SMC control step of one vehicle (cos/sin tables at the
// position, the coverage update S_k <- decay S_k + dt F_k(x), c_k = (own + fleet sums) /
// (own + fleet time), B = sum_k Lambda_k (c_k - phi_k) grad F_k(x), the direction -B/|B|) at
// K = 10, 20 and 40, as the paper runs it (no forgetting, one vehicle) and as fleet_field runs it
// (60 s forgetting, the rest of the fleet's coverage, a 0.3 m turning radius); and the phi_k
// update after one valve's weight changes (O(M K^2) re-weighting of cached vectors); and the
// region step of 1 to 10,000 vehicles taken in turn (what the caches cost a large fleet).
// The server adding one vehicle sample to the fleet's coverage sum (K = 20 and 64).
// Also one grid path (A*, shortcut) of a vehicle to a valve 10-40 m away on a generated 1,000-XT
// field, and 20-100 m away on a 10,000-XT one, as every vehicle plans when it is sent to its
// region or tour.
// The paper's Python reference takes ~45 us per step; our goal is <= 0.5 us at K = 20.
// Figures only: nothing here asserts on time (the machine is shared; see --benchmark_repetitions).
// Run: build/bin/sage_bench_spectral --benchmark_out=bench_spectral.json
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "agents/ergodic_controller.h"
#include "agents/tour_planner.h"
#include "maps/scenario/field_generator.h"
#include "maps/world.h"
#include "maps/risk_field.h"
#include "tests/bench/bench_main.h"

namespace {

using sage::agents::ErgodicController;
using sage::agents::VehicleState;
using sage::maps::GaussianComponent;
using sage::maps::RiskField;
using sage::maps::SpectralBasis;

std::vector<GaussianComponent> RandomValves(int count, double width, double height) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0.5, width - 0.5), uy(0.5, height - 0.5);
  std::vector<GaussianComponent> valves(count);
  for (auto& v : valves) {
    v.mean_m = {ux(rng), uy(rng)};
    v.covariance_m2 = 0.09 * Eigen::Matrix2d::Identity();
  }
  return valves;
}

// Steps a single integrator along the controller's commands, one SMC step per iteration.
void StepAlong(benchmark::State& state, ErgodicController& controller, const SpectralBasis& basis) {
  VehicleState vehicle;
  vehicle.position_m = {0.6, 0.6};
  double t = 0.0;
  for (auto _ : state) {
    const Eigen::Vector2d u = controller.Command(vehicle, t);
    vehicle.position_m += 0.1 * u;
    t += 0.1;
    benchmark::DoNotOptimize(vehicle.position_m.data());
  }
  state.counters["K"] = basis.order();
  state.counters["coefficients"] = basis.size();
}

void BM_SmcStep(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const SpectralBasis basis(7.0, 5.0, order);
  const RiskField field(basis, RandomValves(5, 7.0, 5.0));
  ErgodicController controller(basis, 0.7);
  controller.SetTarget(field.coefficients());
  StepAlong(state, controller, basis);
}
BENCHMARK(BM_SmcStep)->Arg(10)->Arg(20)->Arg(40);

// The step with everything on, as in fleet_field: forgetting (one exp per step and a decay
// multiply per coefficient), fleet coverage in c_k, the turning-radius limit.
void BM_SmcStepFleet(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const SpectralBasis basis(7.0, 5.0, order);
  const RiskField field(basis, RandomValves(5, 7.0, 5.0));
  ErgodicController controller(basis, 0.7, 60.0, 0.3);
  controller.SetTarget(field.coefficients());
  Eigen::VectorXd fleet_sums = Eigen::VectorXd::Zero(basis.size()), f;
  for (const GaussianComponent& valve : RandomValves(30, 7.0, 5.0)) {  // the others' past positions
    basis.Evaluate(valve.mean_m, f);
    fleet_sums += 0.1 * f;
  }
  controller.SetFleetCoverage(fleet_sums, 3.0);
  StepAlong(state, controller, basis);
}
BENCHMARK(BM_SmcStepFleet)->Arg(10)->Arg(20)->Arg(40);

// The step as a large fleet runs it in regions: N vehicles, each with a basis of its own (a
// 4.5 x 4.5 m box at K = 18, a 10,000-vehicle field's typical region) and 60 s forgetting,
// stepped in turn, one step per iteration. Against N = 1 this is what a vehicle's step pays when
// the fleet's coefficient arrays no longer fit in the caches (at K = 18 a vehicle's coverage,
// target and Lambda/h arrays are 7.8 kB; 10,000 of them are 78 MB): the growth of the mission's
// CPU per vehicle-second from 100 to 10,000 vehicles.
void BM_SmcStepManyVehicles(benchmark::State& state) {
  const int vehicles = static_cast<int>(state.range(0));
  constexpr int kOrder = 18;
  constexpr double kBox_m = 4.5;
  struct Vehicle {
    std::unique_ptr<SpectralBasis> basis;
    std::unique_ptr<ErgodicController> controller;
    VehicleState state;
  };
  std::vector<Vehicle> fleet(static_cast<std::size_t>(vehicles));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (Vehicle& v : fleet) {
    // Boxes a few cm apart in size, as the regions' are: no two vehicles share a basis.
    v.basis = std::make_unique<SpectralBasis>(kBox_m + jitter(rng), kBox_m + jitter(rng), kOrder);
    const RiskField field(*v.basis, RandomValves(3, kBox_m - 0.1, kBox_m - 0.1));
    v.controller = std::make_unique<ErgodicController>(*v.basis, 0.7, 60.0, 0.3);
    v.controller->SetTarget(field.coefficients());
    v.state.position_m = {0.6 + 3.0 * (jitter(rng) + 0.05), 0.6};
  }
  std::size_t next = 0;
  double t = 0.0;
  for (auto _ : state) {
    Vehicle& v = fleet[next];
    const Eigen::Vector2d u = v.controller->Command(v.state, t);
    v.state.position_m += 0.1 * u;
    v.state.position_m = v.state.position_m.cwiseMax(0.1).cwiseMin(kBox_m - 0.2);
    benchmark::DoNotOptimize(v.state.position_m.data());
    if (++next == fleet.size()) next = 0, t += 0.1;
  }
  state.counters["vehicles"] = vehicles;
  state.counters["K"] = kOrder;
}
BENCHMARK(BM_SmcStepManyVehicles)->Arg(1)->Arg(100)->Arg(1000)->Arg(10000);

// The server's fleet metric: every vehicle's sample adds dt F_k(x) to the fleet's coverage sum,
// each cycle (K = 64 on a generated 10,000-vehicle field: 4,096 terms a sample).
void BM_CoverageSample(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const SpectralBasis basis(700.0, 500.0, order);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(basis.size());
  Eigen::Vector2d x(3.1, 2.7);
  for (auto _ : state) {
    basis.AddScaled(x, 0.1, sum);
    x.x() = x.x() > 690.0 ? 3.1 : x.x() + 0.37;
    benchmark::DoNotOptimize(sum.data());
  }
  state.counters["K"] = order;
}
BENCHMARK(BM_CoverageSample)->Arg(20)->Arg(64);

// The same, a cycle's samples at once (AddScaledAll, as the metric's helper thread adds them):
// per sample, against BM_CoverageSample.
void BM_CoverageSamples(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const SpectralBasis basis(700.0, 500.0, order);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(basis.size());
  std::vector<std::pair<Eigen::Vector2d, double>> samples;
  for (int s = 0; s < 1024; ++s) samples.emplace_back(Eigen::Vector2d(3.1 + 0.67 * s, 2.7 + 0.41 * (s % 977)), 0.1);
  for (auto _ : state) {
    basis.AddScaledAll(samples, sum);
    benchmark::DoNotOptimize(sum.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(samples.size()));
  state.counters["K"] = order;
}
BENCHMARK(BM_CoverageSamples)->Arg(20)->Arg(64);

void BM_WeightChange(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const int valves = static_cast<int>(state.range(1));
  const SpectralBasis basis(100.0, 100.0, order);
  RiskField field(basis, RandomValves(valves, 100.0, 100.0));
  int i = 0;
  for (auto _ : state) {
    field.SetWeight(i % valves, 1.0 + (i % 7));
    ++i;
    benchmark::DoNotOptimize(field.coefficients().data());
  }
  state.counters["K"] = order;
  state.counters["valves"] = valves;
}
BENCHMARK(BM_WeightChange)->Args({10, 5})->Args({20, 5})->Args({20, 200});

// Crossings of a generated field at its density (80 m^2 of seabed per XT): each vehicle's start
// to a valve 10-40 m from it, the same pairs every run.
// A generated field of `xts` XTs (3.5 valves and one vehicle each) and its world, made once.
const sage::maps::World& FieldWorld(int xts, const sage::maps::Scenario** field_out) {
  static std::map<int, std::pair<sage::maps::Scenario, std::unique_ptr<sage::maps::World>>> made;
  auto it = made.find(xts);
  if (it == made.end()) {
    sage::maps::FieldOptions options;
    options.xts = xts;
    options.valves = xts * 7 / 2;
    options.vehicles = xts;
    it = made.emplace(xts, std::make_pair(sage::maps::GenerateField(options), nullptr)).first;
    it->second.second = std::make_unique<sage::maps::World>(it->second.first);
  }
  *field_out = &it->second.first;
  return *it->second.second;
}

// Args: XTs of the field, then the shortest and longest path (m) between a vehicle's start and
// a valve: 10-40 m as a vehicle sent to a valve of its region, 20-100 m as one crossing a
// 10,000-vehicle field to its region.
void BM_GridPath(benchmark::State& state) {
  const sage::maps::Scenario* field = nullptr;
  const sage::maps::World& world = FieldWorld(static_cast<int>(state.range(0)), &field);
  const double shortest = static_cast<double>(state.range(1)), longest = static_cast<double>(state.range(2));
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;
  const std::vector<Eigen::Vector2d> valves = field->ValvePositions();
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> pick(0, valves.size() - 1);
  for (std::size_t i = 0; i < field->vehicles.size() && pairs.size() < 1000; ++i) {
    const Eigen::Vector2d& start = field->vehicles[i].start_m;
    for (int tries = 0; tries < 1000; ++tries) {
      const Eigen::Vector2d& goal = valves[pick(rng)];
      const double d = (goal - start).norm();
      if (d >= shortest && d <= longest) {
        pairs.emplace_back(start, goal);
        break;
      }
    }
  }
  std::size_t k = 0, waypoints = 0;
  for (auto _ : state) {
    const auto& [from, to] = pairs[k++ % pairs.size()];
    const std::vector<Eigen::Vector2d> path = sage::agents::PlanGridPath(world.astar_grid(), from, to);
    waypoints += path.size();
    benchmark::DoNotOptimize(path.data());
  }
  state.counters["pairs"] = static_cast<double>(pairs.size());
  state.counters["waypoints"] = benchmark::Counter(static_cast<double>(waypoints), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_GridPath)->Args({1000, 10, 40})->Args({10000, 20, 100})->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "sage_bench_spectral.json"); }
