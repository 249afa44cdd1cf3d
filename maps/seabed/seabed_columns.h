#pragma once
// What stands in each column of the workspace's grid: the bare seabed, the local seabed the
// vehicles' altitude band is measured from, and the top of the solid (the ground, or a
// structure, boulder or flowline standing on it). SeabedMap voxelises these columns into the
// OctoMap; nothing here reads a file or knows OctoMap.
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"
#include "maps/seabed/height_grid.h"

namespace sage::maps {

/// Horizontal distance (m) from p to the polyline through `points` (its segments); the nearest
/// point of the polyline in *nearest if given. +infinity for no point.
double DistanceToPolyline(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& p,
                          Eigen::Vector2d* nearest = nullptr);

/// Heights (m) in the map's vertical frame, at each cell centre.
struct SeabedColumns {
  HeightGrid ground;  ///< the bare seabed
  HeightGrid trend;   ///< the local seabed: TrendSurface(ground, seabed.trend_radius_m)
  HeightGrid top;     ///< the top of the solid: the ground, or what stands on it
};

/// The columns of the scenario's seabed over `ground` (the bare seabed at the cells' centres):
/// - a structure fills the cells whose centre lies in its footprint (edges included) up to the
///   ground under its centre plus its height (it stands level on its foundation);
/// - a boulder is half an ellipsoid on the ground under its centre g: at distance d < D/2 of
///   its centre it reaches g + H sqrt(1 - (2 d / D)^2);
/// - a flowline is a pipe of diameter D lying on the ground: at distance d < D/2 of its axis it
///   reaches g + D/2 + sqrt(D^2/4 - d^2), g the ground under the nearest point of the axis.
/// Where several stand, the highest top counts.
SeabedColumns StandOnSeabed(const Scenario& scenario, HeightGrid ground);

}  // namespace sage::maps
