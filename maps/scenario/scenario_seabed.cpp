// The seabed sections of a scenario: flowline geometry (a leak "at FL-A, 12 m along" needs the
// point), the map file's kind, and the map's path resolved and its file checked when loaded.
// Reading the map itself (GDAL, OctoMap) is maps/seabed's work, not the schema's.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <system_error>

#include "maps/scenario/scenario.h"
#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::FormatNumber;
using detail::OneLine;

}  // namespace

double Flowline::Length_m() const {
  double length = 0.0;
  for (std::size_t k = 1; k < points_m.size(); ++k) length += (points_m[k] - points_m[k - 1]).norm();
  return length;
}

Eigen::Vector2d Flowline::PointAt(double s_m) const {
  if (points_m.empty()) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double left = std::max(0.0, s_m);
  for (std::size_t k = 1; k < points_m.size(); ++k) {
    const double segment = (points_m[k] - points_m[k - 1]).norm();
    if (left <= segment && segment > 0.0) return points_m[k - 1] + (left / segment) * (points_m[k] - points_m[k - 1]);
    left -= segment;
  }
  return points_m.back();
}

Eigen::Vector2d Scenario::FlowlinePoint(const std::string& flowline, double s_m) const {
  const std::string where = (source_path.empty() ? std::string("<scenario>") : source_path) + ": ";
  const auto it = std::find_if(flowlines.begin(), flowlines.end(), [&](const Flowline& f) { return f.name == flowline; });
  if (it == flowlines.end()) {
    std::string names;
    for (const Flowline& f : flowlines) names += (names.empty() ? "" : ", ") + f.name;
    throw ScenarioError(OneLine(where + "flowline " + flowline + ": no such flowline (flowlines: " +
                                (names.empty() ? "none" : names) + ")"));
  }
  const double length = it->Length_m();
  if (!(s_m >= 0.0 && s_m <= length)) {
    throw ScenarioError(OneLine(where + "flowline " + flowline + " at s = " + FormatNumber(s_m) +
                                " m: must be in [0, " + FormatNumber(length) + "] m (its length)"));
  }
  return it->PointAt(s_m);
}

const char* ToString(SeabedValues values) {
  switch (values) {
    case SeabedValues::kElevation: return "elevation";
    case SeabedValues::kDepth: return "depth";
  }
  return "unknown";
}

SeabedMapFormat SeabedMapFormatOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".tif" || ext == ".tiff") return SeabedMapFormat::kGeoTiff;
  if (ext == ".xyz" || ext == ".csv") return SeabedMapFormat::kXyz;
  if (ext == ".bt" || ext == ".ot") return SeabedMapFormat::kOctoMap;
  return SeabedMapFormat::kUnknown;
}

namespace detail {

void ResolveSeabedMap(SeabedSettings& seabed, const std::string& source) {
  namespace fs = std::filesystem;
  const std::string file = source.empty() ? "<scenario>" : source;
  const auto fail = [&](const std::string& shown, const std::string& rule) {
    throw ScenarioError(OneLine(file + ": seabed.map = " + shown + ": " + rule));
  };
  if (SeabedMapFormatOf(seabed.map) == SeabedMapFormat::kUnknown) {
    fail(seabed.map, "must end in .tif or .tiff (GeoTIFF), .xyz or .csv (gridded x y z) or .bt or .ot (OctoMap)");
  }
  fs::path path(seabed.map);
  std::error_code error;
  if (path.is_relative()) {
    const fs::path base = source.empty() ? fs::path() : fs::path(source).parent_path();
    path = fs::absolute(base / path, error);
    if (error) fail(seabed.map, "cannot resolve the path: " + error.message());
  }
  path = path.lexically_normal();
  const std::string shown = path.string();
  const fs::file_status status = fs::status(path, error);
  if (error || !fs::exists(status)) fail(shown, "cannot open: no such file");
  if (!fs::is_regular_file(status)) fail(shown, "must be a regular file");
  const auto too_large = [&] {
    fail(shown, "over " + std::to_string(kMaxSeabedMapBytes >> 20) + " MB: too large for a seabed map");
  };
  if (const std::uintmax_t size = fs::file_size(path, error); !error && size > kMaxSeabedMapBytes) too_large();
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> in(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!in) fail(shown, std::string("cannot open: ") + std::strerror(errno));
  // FNV-1a 64 of the bytes, read no further than a map may be.
  std::uint64_t hash = 0xcbf29ce484222325ull;
  std::size_t total = 0, count = 0;
  char buffer[1 << 16];
  while ((count = std::fread(buffer, 1, sizeof buffer, in.get())) > 0) {
    total += count;
    if (total > kMaxSeabedMapBytes) too_large();  // grown since it was measured
    for (std::size_t k = 0; k < count; ++k) hash = (hash ^ static_cast<unsigned char>(buffer[k])) * 0x100000001b3ull;
  }
  if (std::ferror(in.get())) fail(shown, std::string("cannot read: ") + std::strerror(errno));
  if (total == 0) fail(shown, "is empty");
  seabed.map = shown;
  seabed.map_fnv1a = hash;
}

}  // namespace detail
}  // namespace sage::maps
