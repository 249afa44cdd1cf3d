#pragma once
// The seabed map a scenario names, read into heights at the centres of the workspace's cells:
// a GeoTIFF or a gridded XYZ/CSV through GDAL, or an OctoMap (.bt, .ot) through OctoMap. Every
// file is checked at the door, each broken rule one line naming the scenario file, the field
// (seabed.map), the map file, the value and the rule:
//   - kind and size: ParseScenario has checked the extension and the size (kMaxSeabedMapBytes);
//     here the content must be what the extension says (GDAL's GTiff or XYZ driver only, or an
//     OctoMap tree of an occupancy type);
//   - georeferencing: a raster must carry a north-up geotransform; pixels of 1 mm to 10 km;
//   - extent: the map must cover the workspace placed at seabed.origin_m (default the map's
//     south-west corner), and the workspace may span at most kMaxSeabedPixels of its pixels;
//   - values: no pixel the workspace uses may be no-data, NaN or infinite, nor beyond
//     kMaxSeabedElevation_m (an undeclared no-data value such as -32767 or 3.4e38); an OctoMap
//     must hold an occupied voxel over every cell of the workspace.
// The vertical extent against OctoMap's 16-bit keys is checked where the map is voxelised
// (SeabedMap), which knows what stands on the seabed.
#include "maps/scenario/scenario.h"
#include "maps/seabed/height_grid.h"

namespace sage::maps {

/// Raster pixels the workspace may span (a 4 km field at 0.5 m).
inline constexpr double kMaxSeabedPixels = 64e6;
/// Heights and depths beyond this (m) are not a seabed (the deepest is 10,935 m).
inline constexpr double kMaxSeabedElevation_m = 12000.0;

/// The bare seabed under the centres of the workspace's cells of resolution_m (m), in the map's
/// vertical frame (m, up; depths are negated): bilinear between a raster's pixel centres (held
/// flat in the half pixel beyond the outermost ones), or the top of an OctoMap's occupied
/// voxels over each cell. 0 everywhere when the scenario names no map. Throws ScenarioError.
HeightGrid ReadSeabedHeights(const Scenario& scenario, double resolution_m);

}  // namespace sage::maps
