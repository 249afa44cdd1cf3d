// What a seabed model costs, in every process of a mission (each builds its World):
//  - BM_SeabedRead: the example's map (scenarios/manifold_slope.xyz, GDAL's XYZ driver) read
//    into heights on the 0.1 m grid: 600 x 400 cells.
//  - BM_SeabedModel: the whole SeabedMap (read, local seabed, what stands on it, voxelised into
//    the OctoMap, pruned), then BM_OperatingSlice: its projection into the 2-D obstacle grid.
//  - BM_SeabedWorld: the whole maps::World on the example (seabed, distance field, A* grid, risk
//    field, Box2D's rectangles).
//  - BM_SeabedModelLarge/N: SeabedMap on a synthetic N x N m GeoTIFF (slope, ridges and bumps,
//    1 m pixels) at 0.1 m, for how the cost grows with the field (N = 100, 200: 1 and 4 million
//    columns, the last kMaxSeabedColumns).
// Figures only: nothing here asserts on time. Run: build/bin/sage_bench_seabed
// (figures also go to sage_bench_seabed.json)
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <gdal.h>
#include <octomap/OcTree.h>

#include "maps/seabed/seabed_file.h"
#include "maps/seabed_map.h"
#include "maps/world.h"
#include "tests/bench/bench_main.h"

namespace {

using namespace sage::maps;

const std::string kExample = std::string(SAGE_SOURCE_DIR) + "/scenarios/manifold_slope.yaml";

void BM_SeabedRead(benchmark::State& state) {
  const Scenario s = LoadScenario(kExample);
  for (auto _ : state) benchmark::DoNotOptimize(ReadSeabedHeights(s, s.astar.grid_resolution_m));
  state.counters["cells"] = 600.0 * 400.0;
}
BENCHMARK(BM_SeabedRead)->Unit(benchmark::kMillisecond);

void BM_SeabedModel(benchmark::State& state) {
  const Scenario s = LoadScenario(kExample);
  double leaves = 0;
  for (auto _ : state) {
    const SeabedMap map(s, s.astar.grid_resolution_m);
    leaves = static_cast<double>(map.tree().getNumLeafNodes());
  }
  state.counters["leaves"] = leaves;
}
BENCHMARK(BM_SeabedModel)->Unit(benchmark::kMillisecond);

void BM_OperatingSlice(benchmark::State& state) {
  const Scenario s = LoadScenario(kExample);
  const SeabedMap map(s, s.astar.grid_resolution_m);
  int blocked = 0;
  for (auto _ : state) blocked = map.OperatingSlice().OccupiedCount();
  state.counters["blocked_cells"] = blocked;
}
BENCHMARK(BM_OperatingSlice)->Unit(benchmark::kMillisecond);

void BM_SeabedWorld(benchmark::State& state) {
  const Scenario s = LoadScenario(kExample);
  double rectangles = 0;
  for (auto _ : state) {
    const World world(s);
    rectangles = static_cast<double>(world.terrain_blocks().size());
  }
  state.counters["box2d_rectangles"] = rectangles;
}
BENCHMARK(BM_SeabedWorld)->Unit(benchmark::kMillisecond);

// A synthetic seabed of side_m x side_m at 1 m pixels, written once as a GeoTIFF.
std::string LargeMap(int side_m) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("sage_bench_seabed_" + std::to_string(::getpid()) + "_" +
                                                  std::to_string(side_m) + ".tif")).string();
  if (std::filesystem::exists(path)) return path;
  GDALAllRegister();
  const int n = side_m + 2;
  GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), n, n, 1, GDT_Float32, nullptr);
  double gt[6] = {-1.0, 1.0, 0.0, side_m + 1.0, 0.0, -1.0};
  GDALSetGeoTransform(ds, gt);
  std::vector<float> z(static_cast<std::size_t>(n) * n);
  for (int row = 0; row < n; ++row) {
    for (int col = 0; col < n; ++col) {
      const double x = col - 0.5, y = side_m + 0.5 - row;
      z[static_cast<std::size_t>(row) * n + col] = static_cast<float>(
          -300.0 + 0.05 * x + 0.02 * y + 2.0 * std::exp(-std::pow(std::fmod(x + 0.3 * y, 40.0) - 20.0, 2) / 4.0) +
          0.3 * std::sin(0.9 * x) * std::cos(0.7 * y));
    }
  }
  if (GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, n, n, z.data(), n, n, GDT_Float32, 0, 0) != CE_None) {
    std::abort();
  }
  GDALClose(ds);
  return path;
}

void BM_SeabedModelLarge(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  Scenario s = LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  s.workspace = {static_cast<double>(side), static_cast<double>(side)};
  s.astar.grid_resolution_m = 0.1;
  SeabedSettings seabed;
  seabed.map = LargeMap(side);
  s.seabed = seabed;
  double leaves = 0, blocked = 0;
  for (auto _ : state) {
    const SeabedMap map(s, 0.1);
    leaves = static_cast<double>(map.tree().getNumLeafNodes());
    blocked = map.OperatingSlice().OccupiedCount();
  }
  state.counters["columns"] = side * 10.0 * side * 10.0;
  state.counters["leaves"] = leaves;
  state.counters["blocked_cells"] = blocked;
  std::filesystem::remove(seabed.map);
}
BENCHMARK(BM_SeabedModelLarge)->Arg(100)->Arg(200)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

int main(int argc, char** argv) { return sage::bench::RunBenchmarksWritingTo(argc, argv, "sage_bench_seabed.json"); }
