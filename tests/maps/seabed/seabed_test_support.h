#pragma once
// Shared by the seabed tests: a scratch folder, small scenarios on a map, and bathymetry written
// as gridded XYZ (text) or GeoTIFF (through GDAL) from heights given at pixel centres.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gdal.h>
#include <ogr_srs_api.h>

#include "maps/scenario/scenario.h"

namespace sage::maps::testing {

// A folder of its own for each test process, removed at its end.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string File(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// A raster: cols x rows pixels of `pixel_m`, the south-west corner at (x0, y0) in map
// coordinates, row 0 the northernmost (north-up, as a GeoTIFF is), values z(col, row).
struct Raster {
  int cols = 0, rows = 0;
  double pixel_m = 1.0, x0 = 0.0, y0 = 0.0;
  std::vector<float> values;  // row-major, north row first
  float& at(int col, int row) { return values[static_cast<std::size_t>(row) * cols + col]; }
  float at(int col, int row) const { return values[static_cast<std::size_t>(row) * cols + col]; }
  // Map coordinates of the pixel's centre.
  double X(int col) const { return x0 + (col + 0.5) * pixel_m; }
  double Y(int row) const { return y0 + (rows - row - 0.5) * pixel_m; }
};

// Fills a raster from a height function of map coordinates (values rounded to float, as GDAL
// keeps them).
inline Raster MakeRaster(int cols, int rows, double pixel_m, double x0, double y0,
                         const std::function<double(double, double)>& height) {
  Raster r;
  r.cols = cols, r.rows = rows, r.pixel_m = pixel_m, r.x0 = x0, r.y0 = y0;
  r.values.resize(static_cast<std::size_t>(cols) * rows);
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) r.at(col, row) = static_cast<float>(height(r.X(col), r.Y(row)));
  }
  return r;
}

// Gridded XYZ, as surveys deliver them: "x y z" per node, a header line, rows north to south.
inline void WriteXyz(const Raster& r, const std::string& path, bool skip_one = false) {
  std::ofstream out(path);
  out << "x y z\n";
  char line[128];
  bool skipped = false;
  for (int row = 0; row < r.rows; ++row) {
    for (int col = 0; col < r.cols; ++col) {
      if (skip_one && !skipped && row == r.rows / 2 && col == r.cols / 2) {
        skipped = true;
        continue;
      }
      std::snprintf(line, sizeof line, "%.6f %.6f %.9g\n", r.X(col), r.Y(row), static_cast<double>(r.at(col, row)));
      out << line;
    }
  }
}

// A Float32 GeoTIFF; a geotransform unless `georeferenced` is false; `nodata` declared if given.
inline void WriteGeoTiff(const Raster& r, const std::string& path, bool georeferenced = true,
                         const double* nodata = nullptr, double rotation = 0.0, int epsg = 0) {
  GDALAllRegister();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  GDALDatasetH ds = GDALCreate(driver, path.c_str(), r.cols, r.rows, 1, GDT_Float32, nullptr);
  if (georeferenced) {
    double gt[6] = {r.x0, r.pixel_m, rotation, r.y0 + r.rows * r.pixel_m, 0.0, -r.pixel_m};
    GDALSetGeoTransform(ds, gt);
  }
  if (epsg != 0) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(srs, epsg);
    GDALSetSpatialRef(ds, srs);
    OSRDestroySpatialReference(srs);
  }
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  if (nodata) GDALSetRasterNoDataValue(band, *nodata);
  std::vector<float> copy = r.values;
  if (GDALRasterIO(band, GF_Write, 0, 0, r.cols, r.rows, copy.data(), r.cols, r.rows, GDT_Float32, 0, 0) != CE_None) {
    std::abort();
  }
  GDALClose(ds);
}

// A minimal valid scenario on a workspace of w x h m: one 1 x 1 m XT at `xt`, its valve 1.3 m
// north of it, one BlueROV2 at `start`; A* grid `grid_m`.
inline Scenario SmallScenario(double w, double h, double grid_m, const Eigen::Vector2d& xt = {3.0, 4.0},
                              const Eigen::Vector2d& start = {1.0, 1.0}) {
  Scenario s;
  s.name = "seabed_test";
  s.source_path = "seabed_test.yaml";
  s.workspace = {w, h};
  s.astar.grid_resolution_m = grid_m;
  ChristmasTree tree;
  tree.name = "XT-A";
  tree.center_m = xt;
  tree.size_m = {1.0, 1.0};
  tree.height_m = 2.5;
  Valve valve;
  valve.name = "P1";
  valve.position_m = xt + Eigen::Vector2d(0.0, 1.3);
  tree.valves.push_back(valve);
  s.structures.push_back(tree);
  VehicleSpec vehicle;
  vehicle.name = "rov1";
  vehicle.start_m = start;
  s.vehicles.push_back(vehicle);
  RiskProfile profile;
  profile.name = "equal";
  profile.weights["P1"] = 1.0;
  s.profiles.push_back(profile);
  s.default_profile = "equal";
  return s;
}

}  // namespace sage::maps::testing
