#pragma once
// The example seabed field (`sage field seabed`, scenarios/manifold_slope.yaml): a subsea
// production cluster on a real-looking seabed, deterministic by seed. A manifold with four XTs
// around it, a jumper from each XT to the manifold, an export flowline and an umbilical, on a
// slope of about 3 degrees with sand waves, a rock ridge, a scarp, a pockmark and a boulder
// field; three BlueROV2s flying 0.8-2.0 m above the local seabed. The bathymetry is a gridded
// XYZ file of depths in projected coordinates (UTM-like eastings and northings, 0.5 m nodes),
// written beside the scenario, which names it relative to itself.
#include <cstdint>
#include <string>

#include "maps/scenario/scenario.h"

namespace sage::maps {

struct SeabedExample {
  Scenario scenario;      ///< valid; its seabed.map is the map's file name (beside the scenario)
  std::string yaml;       ///< the scenario file: a header that explains the field, then EmitScenario
  std::string map_xyz;    ///< the bathymetry: "easting northing depth" then one line a node
};

/// The example field for `seed` (boulders, sand-wave phases and the risk profile's weights move
/// with it; the layout does not). `name` names the scenario and, with ".xyz", its map file.
/// The same seed and name give byte-identical texts.
SeabedExample GenerateSeabedExample(std::uint64_t seed, const std::string& name = "manifold_slope");

}  // namespace sage::maps
