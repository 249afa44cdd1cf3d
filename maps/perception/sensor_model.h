#pragma once
// A leak sensor's model, one for the vehicles that simulate it (agents/perception) and the server
// that fuses its scans (server/perception): what is in view from a pose, how likely a leak there
// is to be seen, and how many false alarms a scan brings. Both sides answer with this same code,
// so the server's Bayesian update uses exactly the geometry the simulated sensor has.
//
// In view of a sensor at x with heading psi: |y - x| <= range, the bearing of y within fov / 2 of
// psi, and the straight line from x to y crosses no occupied cell of the seabed map's obstacle
// grid at the operating depth (the structures; occlusion). Detection probability of a leak of
// strength s at distance d (maps/scenario/perception.h):
//   p(d) = p_detect 2^(-(d / (half_range sqrt(s)))^2).
// False alarms: Poisson with mean false_alarms_per_s * T per scan (T the scan period), uniform
// over the view's sector of area (fov / 2) range^2.
#include <cstdint>

#include <Eigen/Core>

#include "maps/occupancy_grid.h"
#include "maps/scenario/perception.h"

namespace sage::maps {

class SensorModel {
 public:
  /// spec: validated; obstacles: the grid occlusion is checked on (outlives the model);
  /// control_rate_hz: scans fall on whole control cycles.
  SensorModel(const SensorSpec& spec, const OccupancyGrid& obstacles, double control_rate_hz);

  const SensorSpec& spec() const { return spec_; }
  /// A scan every this many control cycles (control rate / rate_hz, rounded, >= 1), on cycles
  /// 0, n, 2n, ...
  int scan_every_cycles() const { return every_; }
  bool ScansAt(std::int64_t cycle) const { return cycle >= 0 && cycle % every_ == 0; }
  double scan_period_s() const { return period_s_; }

  /// Within range and the field of view (no occlusion).
  bool InSector(const Eigen::Vector2d& from, double heading_rad, const Eigen::Vector2d& y) const;
  /// No occupied obstacle cell on the segment from -> to, the cell of `to` included and that of
  /// `from` not (the vehicle is in open water); points off the grid are not seen.
  bool LineOfSight(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const;
  bool InView(const Eigen::Vector2d& from, double heading_rad, const Eigen::Vector2d& y) const {
    return InSector(from, heading_rad, y) && LineOfSight(from, y);
  }
  /// InSector with the heading as a unit vector (cos, sin), for many points of one scan.
  bool InSectorAlong(const Eigen::Vector2d& from, const Eigen::Vector2d& heading_unit, const Eigen::Vector2d& y) const;
  /// No obstacle cell at all in the box around the sensor's reach (from +- range): every point in
  /// the sector is in view, no line of sight to walk.
  bool ClearAround(const Eigen::Vector2d& from) const;
  /// p(d) above; 0 beyond the range. strength > 0 (1 = nominal).
  double DetectionProbability(double distance_m, double strength = 1.0) const;
  /// Area (m^2) of the view's sector, occlusion ignored.
  double view_area_m2() const { return area_m2_; }
  /// Mean false alarms per scan.
  double false_alarms_per_scan() const { return spec_.false_alarms_per_s * period_s_; }
  /// False alarms per scan per m^2 of view (the clutter density of the Bayesian update).
  double clutter_density() const { return false_alarms_per_scan() / area_m2_; }
  /// Density (1/m^2) of a detection reported at z for a leak at y: the isotropic Gaussian of
  /// position_sigma_m.
  double PositionDensity(const Eigen::Vector2d& z, const Eigen::Vector2d& y) const;

 private:
  SensorSpec spec_;
  const OccupancyGrid& obstacles_;
  int every_ = 1;
  double period_s_ = 0.1;
  double half_fov_rad_ = 0.0;
  double cos_half_fov_ = 0.0;
  double area_m2_ = 0.0;
};

}  // namespace sage::maps
