// The live view's own costs on the 1,000-vehicle field: 300
// XTs, 1,000 valves and 1,000 vehicles (sage field generate --xts 300 --valves 1000 --vehicles
// 1000 --seed 1), every vehicle heard:
//  - BM_MissionFrame: the copy of the mission core's state the server's loop makes for a frame
//    (what a frame costs the mission's cycle);
//  - BM_FrameJson: a frame's JSON as the view's thread writes it once for every page (arg 1: with
//    every vehicle's 8-point trail, a page's first frame);
//  - BM_RiskDensityGrid: the heat map, 160 cells along the long side (made again when the risk
//    changes, at most twice a second).
// Figures only: nothing here asserts on time (the machine is shared).
// Run: build/bin/sage_bench_live_view   (figures also go to sage_bench_live_view.json)
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "maps/scenario/field_generator.h"
#include "maps/world.h"
#include "server/live/frame_json.h"
#include "server/live/heat_grid.h"
#include "server/live/mission_frames.h"
#include "server/mission_core.h"
#include "tests/bench/bench_main.h"

namespace {

using namespace sage;

struct Field {
  maps::Scenario scenario;
  std::unique_ptr<maps::World> world;
  std::unique_ptr<server::MissionCore> core;
};

Field& TheField() {
  static Field* field = [] {
    auto* f = new Field;
    maps::FieldOptions options;
    options.xts = 300;
    options.valves = 1000;
    options.vehicles = 1000;
    options.seed = 1;
    f->scenario = maps::GenerateField(options);
    f->world = std::make_unique<maps::World>(f->scenario);
    f->core = std::make_unique<server::MissionCore>(*f->world, f->scenario, "", server::ControllerKind::kErgodic);
    for (std::int64_t cycle = 0; cycle < 3; ++cycle) {
      for (int id = 0; id < static_cast<int>(f->scenario.vehicles.size()); ++id) {
        agents::StateReport s;
        s.id = id;
        s.name = f->scenario.vehicles[id].name;
        s.cycle = cycle;
        s.time_s = static_cast<double>(cycle) / f->scenario.control_rate_hz;
        s.state.position_m = f->scenario.vehicles[id].start_m;
        f->core->OnState(s);
      }
      f->core->Cycle(cycle);
    }
    return f;
  }();
  return *field;
}

void BM_MissionFrame(benchmark::State& state) {
  Field& f = TheField();
  const live::MissionFrameMaker maker(f.scenario);
  for (auto _ : state) benchmark::DoNotOptimize(maker.Make(*f.core, 1.0, false));
  state.counters["vehicles"] = static_cast<double>(f.scenario.vehicles.size());
}
BENCHMARK(BM_MissionFrame)->Unit(benchmark::kMicrosecond);

void BM_FrameJson(benchmark::State& state) {
  Field& f = TheField();
  live::LiveFrame frame = live::MissionFrameMaker(f.scenario).Make(*f.core, 1.0, false);
  frame.trails.assign(frame.vehicles.size(), std::vector<float>(16, 12.34f));
  std::vector<live::LoggedEvent> events(50, live::LoggedEvent{1, {1.0, "joined", "rov12 (id 11) joined"}});
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string json = live::FrameJson(frame, 7, events, 50, 1, state.range(0) == 1);
    bytes = json.size();
    benchmark::DoNotOptimize(json.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_FrameJson)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_RiskDensityGrid(benchmark::State& state) {
  Field& f = TheField();
  const live::LiveScene scene = live::SceneOf(f.scenario);
  std::vector<double> shares(scene.valves.size(), 1.0);
  for (auto _ : state) benchmark::DoNotOptimize(live::RiskDensityGrid(scene, shares));
}
BENCHMARK(BM_RiskDensityGrid)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "sage_bench_live_view.json"); }
