// The seabed's columns (see seabed_columns.h).
#include "maps/seabed/seabed_columns.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sage::maps {
namespace {

// The cells whose centre may lie within `reach` of the box [lo, hi] (m): a range of whole cells,
// clipped to the grid, one cell wider than needed on each side.
struct CellRange {
  int i0, i1, j0, j1;
};
CellRange CellsNear(const HeightGrid& grid, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double reach) {
  const double r = grid.resolution_m();
  const auto first = [&](double v) { return static_cast<int>(std::floor((v - reach) / r - 0.5)) - 1; };
  const auto last = [&](double v) { return static_cast<int>(std::ceil((v + reach) / r - 0.5)) + 1; };
  return {std::max(0, first(lo.x())), std::min(grid.cols() - 1, last(hi.x())), std::max(0, first(lo.y())),
          std::min(grid.rows() - 1, last(hi.y()))};
}

void Raise(HeightGrid& top, int i, int j, double height) { top.at(i, j) = std::max(top.at(i, j), height); }

}  // namespace

double DistanceToPolyline(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& p,
                          Eigen::Vector2d* nearest) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < points.size(); ++k) {
    Eigen::Vector2d q = points[k];
    if (k + 1 < points.size()) {
      const Eigen::Vector2d d = points[k + 1] - points[k];
      const double length2 = d.squaredNorm();
      const double t = length2 > 0 ? std::clamp((p - points[k]).dot(d) / length2, 0.0, 1.0) : 0.0;
      q = points[k] + t * d;
    }
    const double distance = (p - q).norm();
    if (distance < best) {
      best = distance;
      if (nearest) *nearest = q;
    }
  }
  return best;
}

SeabedColumns StandOnSeabed(const Scenario& scenario, HeightGrid ground) {
  HeightGrid trend = TrendSurface(ground, scenario.SeabedOrDefault().trend_radius_m);
  HeightGrid top = ground;
  for (const ChristmasTree& structure : scenario.structures) {
    const Eigen::Vector2d lo = structure.center_m - structure.size_m / 2, hi = structure.center_m + structure.size_m / 2;
    const double height = ground.Sample(structure.center_m) + structure.height_m;
    const CellRange cells = CellsNear(ground, lo, hi, 0.0);
    for (int i = cells.i0; i <= cells.i1; ++i) {
      for (int j = cells.j0; j <= cells.j1; ++j) {
        const Eigen::Vector2d c = ground.CenterOf(i, j);
        if ((c.array() >= lo.array()).all() && (c.array() <= hi.array()).all()) Raise(top, i, j, height);
      }
    }
  }
  for (const Boulder& boulder : scenario.boulders) {
    const double radius = boulder.diameter_m / 2, base = ground.Sample(boulder.center_m);
    const CellRange cells = CellsNear(ground, boulder.center_m, boulder.center_m, radius);
    for (int i = cells.i0; i <= cells.i1; ++i) {
      for (int j = cells.j0; j <= cells.j1; ++j) {
        const double d = (ground.CenterOf(i, j) - boulder.center_m).norm();
        if (d < radius) Raise(top, i, j, base + boulder.height_m * std::sqrt(1.0 - (d / radius) * (d / radius)));
      }
    }
  }
  for (const Flowline& flowline : scenario.flowlines) {
    const double radius = flowline.diameter_m / 2;
    for (std::size_t k = 0; k + 1 < flowline.points_m.size(); ++k) {
      const std::vector<Eigen::Vector2d> segment = {flowline.points_m[k], flowline.points_m[k + 1]};
      const CellRange cells = CellsNear(ground, segment[0].cwiseMin(segment[1]), segment[0].cwiseMax(segment[1]), radius);
      for (int i = cells.i0; i <= cells.i1; ++i) {
        for (int j = cells.j0; j <= cells.j1; ++j) {
          Eigen::Vector2d axis;
          const double d = DistanceToPolyline(segment, ground.CenterOf(i, j), &axis);
          if (d < radius) Raise(top, i, j, ground.Sample(axis) + radius + std::sqrt(radius * radius - d * d));
        }
      }
    }
  }
  return {std::move(ground), std::move(trend), std::move(top)};
}

}  // namespace sage::maps
