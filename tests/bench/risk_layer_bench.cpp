// The risk layer's costs (issue 9's acceptance figures), on a 50 x 50 m workspace (fleet_large
// is 49 m) at 0.2 m leaves: 62,500 seabed leaves.
//  - BM_RiskLayerLeafUpdates: setting the excess of random leaves, in batches of 10,000
//    (arg 0: every leaf new to the tree, so OctoMap creates it; arg 1: leaves that exist). The
//    phi_k share of the changes is paid at the next coefficients(), outside the timing here.
//    Acceptance: >= 200,000 leaf updates/s (OctoMap's own updateNode: 205k/s at 0.2 m).
//  - BM_RiskLayerLeafUpdatesWithRefresh: the same batches followed by the phi_k refresh at K = 20:
//    the whole cost per leaf.
//  - BM_RiskLayerThousandLeafUpdate: 1,000 leaves changed then phi_k refreshed at K = 20, on a layer
//    holding 40,000 leaves already (arg 0: scattered over the workspace; arg 1: one detection, a
//    disc of radius 3.57 m, ~1,000 leaves). Acceptance: <= 10 ms.
// Figures only: nothing here asserts on time (the machine is shared; see --benchmark_repetitions).
// Run: build/bin/sage_bench_risk_layer   (figures also go to sage_bench_risk_layer.json)
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "maps/risk_field.h"
#include "maps/risk_layer.h"
#include "maps/spectral_basis.h"
#include "tests/bench/bench_main.h"

namespace {

using sage::maps::GaussianComponent;
using sage::maps::RiskField;
using sage::maps::RiskLayer;
using sage::maps::SpectralBasis;

constexpr double kSide_m = 50.0;
constexpr double kResolution_m = 0.2;
constexpr int kBatch = 10000;

std::unique_ptr<RiskLayer> MakeLayer(int order) {
  const SpectralBasis basis(kSide_m, kSide_m, order);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(2.0, kSide_m - 2.0);
  std::vector<GaussianComponent> valves(40);
  for (GaussianComponent& v : valves) {
    v.mean_m = {u(rng), u(rng)};
    v.covariance_m2 = 0.1225 * Eigen::Matrix2d::Identity();  // sigma 0.35 m, as the scenarios
  }
  return std::make_unique<RiskLayer>(basis, RiskField(basis, valves),
                                     sage::maps::RiskLayerOptions{.resolution_m = kResolution_m});
}

std::vector<Eigen::Vector2d> RandomPoints(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, kSide_m);
  std::vector<Eigen::Vector2d> points(count);
  for (Eigen::Vector2d& p : points) p = {u(rng), u(rng)};
  return points;
}

// Every leaf of the workspace, so that later updates find existing leaves.
void FillEveryLeaf(RiskLayer& layer) {
  const int cells = static_cast<int>(std::round(kSide_m / kResolution_m));
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) layer.SetExcess({(i + 0.5) * kResolution_m, (j + 0.5) * kResolution_m}, 0.01);
  }
  layer.coefficients();
}

void BM_RiskLayerLeafUpdates(benchmark::State& state) {
  const bool existing = state.range(0) == 1;
  const std::vector<Eigen::Vector2d> points = RandomPoints(kBatch, 2);
  std::unique_ptr<RiskLayer> layer = MakeLayer(20);
  if (existing) FillEveryLeaf(*layer);
  std::int64_t round = 0;
  for (auto _ : state) {
    if (!existing) {
      state.PauseTiming();
      layer = MakeLayer(20);  // a fresh tree: every leaf of the batch is created by OctoMap
      state.ResumeTiming();
    }
    const double value = 0.1 + 0.01 * static_cast<double>(++round % 50);
    for (const Eigen::Vector2d& p : points) layer->SetExcess(p, value);
    state.PauseTiming();
    layer->coefficients();  // the pending changes go into the caches, outside the timing
    state.ResumeTiming();
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.counters["leaves"] = static_cast<double>(layer->leaf_count());
}
BENCHMARK(BM_RiskLayerLeafUpdates)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_RiskLayerLeafUpdatesWithRefresh(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  const std::vector<Eigen::Vector2d> points = RandomPoints(kBatch, 3);
  std::unique_ptr<RiskLayer> layer = MakeLayer(order);
  FillEveryLeaf(*layer);
  std::int64_t round = 0;
  for (auto _ : state) {
    const double value = 0.1 + 0.01 * static_cast<double>(++round % 50);
    for (const Eigen::Vector2d& p : points) layer->SetExcess(p, value);
    benchmark::DoNotOptimize(layer->coefficients().data());
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.counters["K"] = order;
}
BENCHMARK(BM_RiskLayerLeafUpdatesWithRefresh)->Arg(20)->Unit(benchmark::kMillisecond);

void BM_RiskLayerThousandLeafUpdate(benchmark::State& state) {
  const bool disc = state.range(0) == 1;
  std::unique_ptr<RiskLayer> layer = MakeLayer(20);
  for (const Eigen::Vector2d& p : RandomPoints(60000, 4)) layer->SetExcess(p, 0.02);  // ~40,000 leaves
  layer->coefficients();
  const std::vector<Eigen::Vector2d> points = RandomPoints(1000 * 64, 5);
  const double radius_m = std::sqrt(1000.0 / M_PI) * kResolution_m;  // a disc of ~1,000 leaves
  std::size_t next = 0;
  std::int64_t changed = 0;
  for (auto _ : state) {
    if (disc) {
      const Eigen::Vector2d centre = points[next++ % points.size()].cwiseMax(radius_m).cwiseMin(kSide_m - radius_m);
      changed += layer->Raise(centre, radius_m, 0.05);
    } else {
      for (int n = 0; n < 1000; ++n) layer->AddExcess(points[next++ % points.size()], 0.05);
      changed += 1000;
    }
    benchmark::DoNotOptimize(layer->coefficients().data());
  }
  state.counters["leaves_changed"] = benchmark::Counter(static_cast<double>(changed), benchmark::Counter::kAvgIterations);
  state.counters["leaves"] = static_cast<double>(layer->leaf_count());
  state.counters["K"] = 20;
}
BENCHMARK(BM_RiskLayerThousandLeafUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "sage_bench_risk_layer.json"); }
