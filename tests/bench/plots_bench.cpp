// The run directory's charts at fleet scale: what drawing them costs at the end of a mission and
// how large the files are, on fields generated as `sage bench scale` does (N XTs, 3.5 N valves,
// N vehicles; arg: N). The trajectory is what RunDirectory keeps for the plots: a PlotRecord at its
// default budget (200,000 samples, thinned evenly), fed 600 cycles of every vehicle walking at
// random from its start.
//  - BM_FieldPlot: plot.svg alone (the raster, labels, markers).
//  - BM_MissionPlotFiles: the six files (plot, metric, revisits; SVG and PNG through librsvg);
//    counters: each file's size in bytes.
// Figures only: nothing here asserts on time (the machine is shared).
// Run: build/bin/sage_bench_plots   (figures also go to sage_bench_plots.json)
#include <map>
#include <memory>
#include <random>
#include <string>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "maps/scenario/field_generator.h"
#include "server/report/plots/mission_plots.h"
#include "server/report/plots/plot_record.h"
#include "tests/bench/bench_main.h"

namespace {

using namespace sage;

struct Fleet {
  maps::Scenario field;
  std::unique_ptr<server::plots::PlotRecord> record;
  server::MissionMetrics metrics;
  server::plots::MissionPlotInput Input() const {
    return {&field, &metrics, &record->trajectory(), record->Events(), record->events_not_kept(), field.name};
  }
};

const Fleet& FleetOf(int n) {
  static std::map<int, std::unique_ptr<Fleet>> fleets;
  std::unique_ptr<Fleet>& f = fleets[n];
  if (f) return *f;
  f = std::make_unique<Fleet>();
  maps::FieldOptions options;
  options.xts = n;
  options.valves = static_cast<int>(3.5 * n);
  options.vehicles = n;
  f->field = maps::GenerateField(options);
  f->record = std::make_unique<server::plots::PlotRecord>(f->field);
  std::mt19937 rng(1);
  std::normal_distribution<double> step(0.0, 0.05);
  std::vector<Eigen::Vector2d> at;
  std::vector<std::string> names;
  for (const maps::VehicleSpec& v : f->field.vehicles) {
    at.push_back(v.start_m);
    names.push_back(v.name);
  }
  for (int cycle = 0; cycle < 600; ++cycle) {
    for (int v = 0; v < n; ++v) {
      at[v] += Eigen::Vector2d(step(rng), step(rng));
      f->record->OnSample({cycle / f->field.control_rate_hz, v, at[v]}, names[v]);
    }
  }
  const std::vector<maps::Valve> valves = f->field.AllValves();
  const maps::RiskProfile* profile = f->field.FindProfile(f->field.default_profile);
  double sum = 0.0;
  for (const maps::Valve& v : valves) sum += profile->weights.at(v.name);
  for (const maps::Valve& v : valves) {
    server::ValveMetrics m;
    m.name = v.name;
    m.weight = profile->weights.at(v.name) / sum;
    m.visits = 3;
    m.mean_interval_s = 20.0;
    m.max_gap_s = 40.0 + static_cast<double>(m.name.size());
    f->metrics.valves.push_back(m);
  }
  f->metrics.duration_s = 60.0;
  for (int t = 0; t <= 60; ++t) f->metrics.metric_over_time.push_back({1.0 * t, 1e-2 / (1.0 + t)});
  return *f;
}

void BM_FieldPlot(benchmark::State& state) {
  const Fleet& fleet = FleetOf(static_cast<int>(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string svg = server::plots::FieldPlotSvg(fleet.Input());
    bytes = svg.size();
    benchmark::DoNotOptimize(svg.data());
  }
  state.counters["plot_svg_bytes"] = static_cast<double>(bytes);
  state.counters["samples_kept"] = static_cast<double>(fleet.record->trajectory().samples.size());
}
BENCHMARK(BM_FieldPlot)->Arg(4)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_MissionPlotFiles(benchmark::State& state) {
  const Fleet& fleet = FleetOf(static_cast<int>(state.range(0)));
  std::vector<server::plots::PlotFile> files;
  for (auto _ : state) {
    files = server::plots::MissionPlotFiles(fleet.Input());
    benchmark::DoNotOptimize(files.data());
  }
  for (const server::plots::PlotFile& f : files) {
    std::string key = f.name;
    for (char& c : key)
      if (c == '.') c = '_';
    state.counters[key + "_bytes"] = static_cast<double>(f.bytes.size());
  }
}
BENCHMARK(BM_MissionPlotFiles)->Arg(4)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "sage_bench_plots.json"); }
