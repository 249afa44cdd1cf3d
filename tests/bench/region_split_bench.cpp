// What the regions' split costs as the field grows (issue 8, weak scaling: 3.5 valves and one XT a
// vehicle, `sage field generate --xts N --valves 3.5N --vehicles N --seed 1`): the planned split
// (PlanRegionSplit: k-medoids, min-max local search and split-merge over the valves' grid
// distances, then each region's box and basis) and the provisional one a large field flies until
// the planned split is due (QuickRegionSplit: each valve to its nearest vehicle). Besides the time,
// each row reports what the split gives the fleet: the longest and the mean lap of a share (s) and
// the valves of the largest share, so a faster planner is seen not to give a worse split.
// Figures only: nothing here asserts on time (the machine is shared).
// Also the field's own risk on its global basis, which World builds before the first cycle.
// Run: build/bin/sage_bench_region_split [--benchmark_filter=Planned/10000]
#include <algorithm>
#include <map>
#include <memory>

#include <benchmark/benchmark.h>

#include "maps/scenario/field_generator.h"
#include "maps/world.h"
#include "server/region_split.h"
#include "tests/bench/bench_main.h"

namespace {

using sage::server::RegionSplit;
using sage::server::RegionSplitInput;

// A generated field of n vehicles, its World (grids) and the split's input at the start: every
// vehicle where the scenario starts it, the default profile's weights, the default risk share.
struct Field {
  sage::maps::Scenario scenario;
  std::unique_ptr<sage::maps::World> world;
  RegionSplitInput input;
};

const Field& FieldOf(int vehicles) {
  static std::map<int, std::unique_ptr<Field>> fields;
  auto& field = fields[vehicles];
  if (!field) {
    field = std::make_unique<Field>();
    sage::maps::FieldOptions options;
    options.xts = vehicles;
    options.valves = vehicles * 7 / 2;
    options.vehicles = vehicles;
    options.seed = 1;
    field->scenario = sage::maps::GenerateField(options);
    field->world = std::make_unique<sage::maps::World>(field->scenario);
    for (int k = 0; k < vehicles; ++k) {
      field->input.vehicle_ids.push_back(k);
      const auto& spec = field->scenario.vehicles[static_cast<std::size_t>(k)];
      field->input.vehicles.push_back({spec.start_m, spec.transit_speed_mps});
    }
    field->input.weights = field->scenario.ProfileWeights(field->scenario.ProfileOrThrow(""));
    field->input.risk_share = field->scenario.fleet.risk_share;
  }
  return *field;
}

void Report(benchmark::State& state, const RegionSplit& split) {
  double longest = 0.0, sum = 0.0;
  std::size_t largest = 0;
  for (const auto& region : split.regions) {
    longest = std::max(longest, region.lap_time_s);
    sum += region.lap_time_s;
    largest = std::max(largest, region.valves.size());
  }
  state.counters["vehicles"] = static_cast<double>(split.regions.size());
  state.counters["longest_lap_s"] = longest;
  state.counters["mean_lap_s"] = split.regions.empty() ? 0.0 : sum / static_cast<double>(split.regions.size());
  state.counters["largest_share"] = static_cast<double>(largest);
}

void BM_PlannedSplit(benchmark::State& state) {
  const Field& field = FieldOf(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const RegionSplit split = sage::server::PlanRegionSplit(field.world->astar_grid(), field.world->blocked(),
                                                            field.scenario, field.input);
    state.PauseTiming();
    Report(state, split);
    state.ResumeTiming();
  }
}
BENCHMARK(BM_PlannedSplit)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_ProvisionalSplit(benchmark::State& state) {
  const Field& field = FieldOf(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const RegionSplit split = sage::server::QuickRegionSplit(field.world->blocked(), field.scenario, field.input);
    state.PauseTiming();
    Report(state, split);
    state.ResumeTiming();
  }
}
BENCHMARK(BM_ProvisionalSplit)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(1);

// The field's risk on its global basis (RiskField::ForValves, as World builds it before the first
// cycle): each valve's closed-form coefficients at the field's K (64 on these fields) with the
// water no hull can be in taken out; on two threads from 2,000 valves (risk_field.cpp), so the
// time is the wall's.
void BM_FieldRisk(benchmark::State& state) {
  const Field& field = FieldOf(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const sage::maps::RiskField risk =
        sage::maps::RiskField::ForValves(field.scenario, field.world->basis(), field.world->blocked());
    benchmark::DoNotOptimize(risk.blocked_mass().data());
  }
  state.counters["valves"] = static_cast<double>(field.scenario.ValveCount());
}
BENCHMARK(BM_FieldRisk)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "bench_region_split.json"); }
