// Reading a seabed map (see seabed_file.h). GDAL and OctoMap's readers are used only here.
#include "maps/seabed/seabed_file.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include "maps/quiet_stderr.h"
#include "maps/scenario/printable_text.h"

namespace sage::maps {
namespace {

// Where a message comes from and what it is about: "scenarios/x.yaml: seabed.map = /abs/map.tif: ".
class MapErrors {
 public:
  MapErrors(const Scenario& scenario, std::string map)
      : prefix_((scenario.source_path.empty() ? std::string("<scenario>") : scenario.source_path) +
                ": seabed.map = " + std::move(map) + ": ") {}
  [[noreturn]] void Fail(const std::string& rule) const {
    std::string text = prefix_ + rule;
    std::replace_if(text.begin(), text.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    throw ScenarioError(text);
  }

 private:
  std::string prefix_;
};

std::string Coordinates(double x, double y) { return fmt::format("({:.10g}, {:.10g})", x, y); }

// The workspace placed on the map: its corner (0, 0) at `origin`, which must lie in [lo, hi].
void CheckCovers(const MapErrors& errors, const Scenario& s, const Eigen::Vector2d& origin, const Eigen::Vector2d& lo,
                 const Eigen::Vector2d& hi) {
  const Eigen::Vector2d far = origin + Eigen::Vector2d(s.workspace.width_m, s.workspace.height_m);
  // A hair of tolerance for coordinates written in decimal (a corner given as the map's own edge).
  const double tolerance = 1e-9 * std::max({1.0, lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()});
  if ((origin.array() >= lo.array() - tolerance).all() && (far.array() <= hi.array() + tolerance).all()) return;
  errors.Fail(fmt::format("covers x in [{:.10g}, {:.10g}], y in [{:.10g}, {:.10g}] (map coordinates); the workspace at "
                          "origin {} needs x in [{:.10g}, {:.10g}], y in [{:.10g}, {:.10g}]: the map must cover the workspace",
                          lo.x(), hi.x(), lo.y(), hi.y(), Coordinates(origin.x(), origin.y()), origin.x(), far.x(),
                          origin.y(), far.y()));
}

// ---- GDAL: GeoTIFF and gridded XYZ --------------------------------------------------------

struct GdalCloser {
  void operator()(void* dataset) const { GDALClose(dataset); }
};

// GDAL's messages for this thread go to a string instead of stderr while it lives.
class GdalMessages {
 public:
  GdalMessages() {
    CPLPushErrorHandlerEx(&GdalMessages::Handle, this);
  }
  ~GdalMessages() { CPLPopErrorHandler(); }
  GdalMessages(const GdalMessages&) = delete;
  GdalMessages& operator=(const GdalMessages&) = delete;
  bool empty() const { return last_.empty(); }
  std::string Last() const { return last_.empty() ? std::string("GDAL gave no reason") : last_; }

 private:
  static void CPL_STDCALL Handle(CPLErr level, CPLErrorNum, const char* message) {
    auto* self = static_cast<GdalMessages*>(CPLGetErrorHandlerUserData());
    if (self && level >= CE_Failure && message) self->last_ = message;
  }
  std::string last_;
};

// GDAL's XYZ driver reads a field that is not a number as 0 (a new user's "3.0,1.5,abc" among
// depths near -100 m had become a pillar, reported only as a valve "on blocked seabed" far off;
// at a corner it passed unseen). Every data line is checked here first, the line named: numbers
// only (nan is a number here, and is refused with its node's position later), x y z at least;
// the first line may be a header of names.
void CheckXyzNumbers(const std::string& path, const MapErrors& errors) {
  std::ifstream in(path);
  if (!in) return;  // GDAL's open says why
  std::string line;
  std::size_t number = 0;
  bool first = true;
  std::vector<std::string_view> fields;
  while (std::getline(in, line)) {
    ++number;
    fields.clear();
    std::string_view rest(line);
    while (!rest.empty()) {
      const std::size_t start = rest.find_first_not_of(" \t,;\r");
      if (start == std::string_view::npos) break;
      rest.remove_prefix(start);
      const std::size_t end = std::min(rest.find_first_of(" \t,;\r"), rest.size());
      fields.push_back(rest.substr(0, end));
      rest.remove_prefix(end);
    }
    if (fields.empty()) continue;
    std::string_view bad;
    for (std::string_view f : fields) {
      std::string_view digits = f.starts_with('+') ? f.substr(1) : f;
      double value = 0.0;
      const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
      if (error != std::errc() || end != digits.data() + digits.size()) {
        bad = f;
        break;
      }
    }
    const bool header = std::exchange(first, false) && !bad.empty();
    if (header) continue;
    if (!bad.empty()) {
      errors.Fail(fmt::format("line {}: '{}' is not a number (a gridded XYZ file holds x y z numbers on every line after "
                              "an optional header)",
                              number, PrintableUtf8(bad, 40)));  // a binary file's bytes shown as ?
    }
    if (fields.size() < 3) {
      errors.Fail(fmt::format("line {}: {} field{}; a gridded XYZ file holds x y z on every line", number, fields.size(),
                              fields.size() == 1 ? "" : "s"));
    }
  }
}

HeightGrid ReadRaster(const Scenario& s, const SeabedSettings& seabed, SeabedMapFormat format, double r,
                      const MapErrors& errors) {
  if (format == SeabedMapFormat::kXyz) CheckXyzNumbers(seabed.map, errors);
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  GdalMessages messages;
  // Only the driver the extension names may open it: a .tif is read as a GeoTIFF or not at all.
  const char* const geotiff[] = {"GTiff", nullptr};
  const char* const xyz[] = {"XYZ", nullptr};
  const std::unique_ptr<void, GdalCloser> dataset(
      GDALOpenEx(seabed.map.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY,
                 format == SeabedMapFormat::kGeoTiff ? geotiff : xyz, nullptr, nullptr));
  const char* kind = format == SeabedMapFormat::kGeoTiff ? "a GeoTIFF" : "a gridded XYZ file (x y z, one line a grid node)";
  if (!dataset) {
    errors.Fail(fmt::format("cannot be read as {}: {}", kind,
                            messages.empty() ? std::string("GDAL's ") + (format == SeabedMapFormat::kGeoTiff ? "GTiff" : "XYZ") +
                                                   " driver does not recognise it"
                                             : messages.Last()));
  }
  const int cols = GDALGetRasterXSize(dataset.get()), rows = GDALGetRasterYSize(dataset.get());
  if (GDALGetRasterCount(dataset.get()) < 1 || cols < 1 || rows < 1) errors.Fail("holds no raster band");
  double gt[6];
  if (GDALGetGeoTransform(dataset.get(), gt) != CE_None) {
    errors.Fail("has no georeferencing (geotransform): a seabed map must say where its pixels lie");
  }
  // Coordinates in metres: a raster in latitude and longitude (GEBCO, EMODnet) has pixels of a
  // few millionths of a degree and a workspace in metres would land anywhere on it. A raster
  // without a reference system (an XYZ file) is taken to be in metres.
  if (OGRSpatialReferenceH srs = GDALGetSpatialRef(dataset.get())) {
    char* unit_name = nullptr;
    if (OSRIsGeographic(srs)) {
      errors.Fail("is in geographic coordinates (degrees): a seabed map must be in a projected reference system in "
                  "metres (e.g. gdalwarp -t_srs EPSG:32631 for UTM zone 31N)");
    }
    if (const double metres = OSRGetLinearUnits(srs, &unit_name); OSRIsProjected(srs) && std::abs(metres - 1.0) > 1e-9) {
      errors.Fail(fmt::format("is in {} ({} m each): a seabed map's coordinates must be in metres",
                              unit_name ? unit_name : "a unit other than metres", metres));
    }
  }
  if (gt[2] != 0.0 || gt[4] != 0.0) {
    errors.Fail(fmt::format("geotransform rotation = ({:.6g}, {:.6g}): must be a north-up raster (rotation 0)", gt[2], gt[4]));
  }
  const double dx = gt[1], dy = gt[5];
  for (const double step : {dx, dy}) {
    if (!std::isfinite(step) || std::abs(step) < 1e-3 || std::abs(step) > 1e4) {
      errors.Fail(fmt::format("pixel size = {:.6g} x {:.6g} m: must be in [0.001, 10000] m", dx, std::abs(dy)));
    }
  }
  if (!(dx > 0)) errors.Fail(fmt::format("pixel width = {:.6g}: must be > 0 (columns run east)", dx));
  if (!std::isfinite(gt[0]) || !std::isfinite(gt[3])) errors.Fail("geotransform origin: must be finite");
  const Eigen::Vector2d lo(gt[0], std::min(gt[3], gt[3] + rows * dy)), hi(gt[0] + cols * dx, std::max(gt[3], gt[3] + rows * dy));
  const Eigen::Vector2d origin = seabed.origin_m.value_or(lo);
  CheckCovers(errors, s, origin, lo, hi);

  // The workspace's cell centres in pixel coordinates (centres at whole numbers): u along the
  // columns, v along the rows (v grows southward when dy < 0).
  const int grid_cols = std::max(1, static_cast<int>(std::ceil(s.workspace.width_m / r - 1e-9)));
  const int grid_rows = std::max(1, static_cast<int>(std::ceil(s.workspace.height_m / r - 1e-9)));
  const auto u_of = [&](int i) { return (origin.x() + (i + 0.5) * r - gt[0]) / dx - 0.5; };
  const auto v_of = [&](int j) { return (origin.y() + (j + 0.5) * r - gt[3]) / dy - 0.5; };
  const auto clamp_u = [&](double u) { return std::clamp(u, 0.0, static_cast<double>(cols - 1)); };
  const auto clamp_v = [&](double v) { return std::clamp(v, 0.0, static_cast<double>(rows - 1)); };
  const double u_lo = clamp_u(std::min(u_of(0), u_of(grid_cols - 1))), u_hi = clamp_u(std::max(u_of(0), u_of(grid_cols - 1)));
  const double v_lo = clamp_v(std::min(v_of(0), v_of(grid_rows - 1))), v_hi = clamp_v(std::max(v_of(0), v_of(grid_rows - 1)));
  const int c0 = static_cast<int>(std::floor(u_lo)), c1 = std::min(cols - 1, static_cast<int>(std::floor(u_hi)) + 1);
  const int r0 = static_cast<int>(std::floor(v_lo)), r1 = std::min(rows - 1, static_cast<int>(std::floor(v_hi)) + 1);
  const int window_cols = c1 - c0 + 1, window_rows = r1 - r0 + 1;
  if (static_cast<double>(window_cols) * window_rows > kMaxSeabedPixels) {
    errors.Fail(fmt::format("the workspace spans {} x {} of its pixels: at most {:.0f} million (resample the map coarser)",
                            window_cols, window_rows, kMaxSeabedPixels / 1e6));
  }
  std::vector<double> pixels(static_cast<std::size_t>(window_cols) * window_rows);
  GDALRasterBandH band = GDALGetRasterBand(dataset.get(), 1);
  if (GDALRasterIO(band, GF_Read, c0, r0, window_cols, window_rows, pixels.data(), window_cols, window_rows,
                   GDT_Float64, 0, 0) != CE_None) {
    errors.Fail("cannot read its pixels: " + messages.Last());
  }
  int has_nodata = 0, has_scale = 0, has_offset = 0;
  const double nodata = GDALGetRasterNoDataValue(band, &has_nodata);
  // Integer rasters often store metres as value * scale + offset (decimetres in an Int16 band).
  const double scale = GDALGetRasterScale(band, &has_scale), offset = GDALGetRasterOffset(band, &has_offset);
  const double sign = seabed.values == SeabedValues::kDepth ? -1.0 : 1.0;
  for (int row = 0; row < window_rows; ++row) {
    for (int col = 0; col < window_cols; ++col) {
      double& value = pixels[static_cast<std::size_t>(row) * window_cols + col];
      const auto where = [&] {
        return fmt::format("pixel (column {}, row {}) at {}", c0 + col, r0 + row,
                           Coordinates(gt[0] + (c0 + col + 0.5) * dx, gt[3] + (r0 + row + 0.5) * dy));
      };
      if ((has_nodata && (value == nodata || (std::isnan(nodata) && std::isnan(value)))) || !std::isfinite(value)) {
        errors.Fail(fmt::format("{} is no-data ({}): the map must cover the workspace without holes", where(),
                                std::isfinite(value) ? fmt::format("{:.6g}", value) : std::string("not a number")));
      }
      if (has_scale || has_offset) value = value * (has_scale ? scale : 1.0) + (has_offset ? offset : 0.0);
      if (std::abs(value) > kMaxSeabedElevation_m) {
        errors.Fail(fmt::format("{} = {:.6g} m: a seabed lies within {:.0f} m of the surface (an undeclared no-data value?)",
                                where(), value, kMaxSeabedElevation_m));
      }
      value *= sign;
    }
  }
  const auto pixel = [&](int col, int row) { return pixels[static_cast<std::size_t>(row - r0) * window_cols + (col - c0)]; };
  HeightGrid heights(grid_cols, grid_rows, r);
  for (int i = 0; i < grid_cols; ++i) {
    const double u = clamp_u(u_of(i));
    const int a0 = std::min(static_cast<int>(u), c1), a1 = std::min(a0 + 1, c1);
    const double fu = u - a0;
    for (int j = 0; j < grid_rows; ++j) {
      const double v = clamp_v(v_of(j));
      const int b0 = std::min(static_cast<int>(v), r1), b1 = std::min(b0 + 1, r1);
      const double fv = v - b0;
      heights.at(i, j) = (1 - fu) * ((1 - fv) * pixel(a0, b0) + fv * pixel(a0, b1)) +
                         fu * ((1 - fv) * pixel(a1, b0) + fv * pixel(a1, b1));
    }
  }
  return heights;
}

// ---- OctoMap: the top of the occupied voxels in each column ---------------------------------

template <typename Tree>
HeightGrid TopOfTree(const Tree& tree, const Scenario& s, const SeabedSettings& seabed, double r, const MapErrors& errors) {
  const double resolution = tree.getResolution();
  if (!(resolution >= 1e-3 && resolution <= 1e3)) {
    errors.Fail(fmt::format("resolution = {:.6g} m: must be in [0.001, 1000] m", resolution));
  }
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double half = it.getSize() / 2;
    lo = lo.cwiseMin(Eigen::Vector2d(it.getX() - half, it.getY() - half));
    hi = hi.cwiseMax(Eigen::Vector2d(it.getX() + half, it.getY() + half));
  }
  if (!lo.allFinite()) errors.Fail("holds no occupied voxel: an OctoMap seabed is its occupied voxels");
  const Eigen::Vector2d origin = seabed.origin_m.value_or(lo);
  CheckCovers(errors, s, origin, lo, hi);
  const int grid_cols = std::max(1, static_cast<int>(std::ceil(s.workspace.width_m / r - 1e-9)));
  const int grid_rows = std::max(1, static_cast<int>(std::ceil(s.workspace.height_m / r - 1e-9)));
  const double unset = -std::numeric_limits<double>::infinity();
  HeightGrid top(grid_cols, grid_rows, r, unset);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // The cells the voxel's footprint overlaps with positive area (the shrink keeps float noise
    // on shared edges out), in workspace coordinates.
    const double half = it.getSize() / 2, shrink = 1e-6 * std::min(r, it.getSize());
    const auto span = [&](double center, double offset, int count) {
      const int first = static_cast<int>(std::floor((center - offset - half + shrink) / r));
      const int last = static_cast<int>(std::floor((center - offset + half - shrink) / r));
      return std::pair<int, int>(std::max(first, 0), std::min(last, count - 1));
    };
    const auto [i0, i1] = span(it.getX(), origin.x(), grid_cols);
    const auto [j0, j1] = span(it.getY(), origin.y(), grid_rows);
    const double z = it.getZ() + half;
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) top.at(i, j) = std::max(top.at(i, j), z);
    }
  }
  for (int i = 0; i < grid_cols; ++i) {
    for (int j = 0; j < grid_rows; ++j) {
      if (top.at(i, j) != unset) continue;
      const Eigen::Vector2d c = top.CenterOf(i, j);
      errors.Fail(fmt::format("no occupied voxel under workspace point {} (map {}): the map must cover the workspace "
                              "without holes",
                              Coordinates(c.x(), c.y()), Coordinates(c.x() + origin.x(), c.y() + origin.y())));
    }
  }
  if (std::abs(top.Min()) > kMaxSeabedElevation_m || std::abs(top.Max()) > kMaxSeabedElevation_m) {
    errors.Fail(fmt::format("seabed from {:.6g} to {:.6g} m: a seabed lies within {:.0f} m of the surface", top.Min(),
                            top.Max(), kMaxSeabedElevation_m));
  }
  return top;
}

HeightGrid ReadOctoMap(const Scenario& s, const SeabedSettings& seabed, double r, const MapErrors& errors) {
  std::ifstream in(seabed.map, std::ios::binary);
  if (!in) errors.Fail("cannot open");
  std::string extension = std::filesystem::path(seabed.map).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  const bool binary = extension == ".bt";
  detail::QuietStderr quiet;  // Debian's OctoMap prints while it reads
  if (binary) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(in)) errors.Fail("is not an OctoMap binary tree (.bt)");
    return TopOfTree(tree, s, seabed, r, errors);
  }
  const std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
  if (!tree) errors.Fail("is not an OctoMap tree (.ot)");
  if (const auto* t = dynamic_cast<const octomap::OcTree*>(tree.get())) return TopOfTree(*t, s, seabed, r, errors);
  if (const auto* t = dynamic_cast<const octomap::ColorOcTree*>(tree.get())) return TopOfTree(*t, s, seabed, r, errors);
  if (const auto* t = dynamic_cast<const octomap::OcTreeStamped*>(tree.get())) return TopOfTree(*t, s, seabed, r, errors);
  errors.Fail("is an OctoMap of type " + tree->getTreeType() +
              ": a seabed map must be an occupancy tree (OcTree, ColorOcTree or OcTreeStamped)");
}

}  // namespace

HeightGrid ReadSeabedHeights(const Scenario& scenario, double resolution_m) {
  const int cols = std::max(1, static_cast<int>(std::ceil(scenario.workspace.width_m / resolution_m - 1e-9)));
  const int rows = std::max(1, static_cast<int>(std::ceil(scenario.workspace.height_m / resolution_m - 1e-9)));
  if (!scenario.seabed || scenario.seabed->map.empty()) return HeightGrid(cols, rows, resolution_m, 0.0);
  const SeabedSettings& seabed = *scenario.seabed;
  const MapErrors errors(scenario, seabed.map);
  const SeabedMapFormat format = SeabedMapFormatOf(seabed.map);
  switch (format) {
    case SeabedMapFormat::kGeoTiff:
    case SeabedMapFormat::kXyz: return ReadRaster(scenario, seabed, format, resolution_m, errors);
    case SeabedMapFormat::kOctoMap: return ReadOctoMap(scenario, seabed, resolution_m, errors);
    case SeabedMapFormat::kUnknown: break;
  }
  errors.Fail("must end in .tif or .tiff (GeoTIFF), .xyz or .csv (gridded x y z) or .bt or .ot (OctoMap)");
}

}  // namespace sage::maps
