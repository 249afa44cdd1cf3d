#include "maps/perception/sensor_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sage::maps {

SensorModel::SensorModel(const SensorSpec& spec, const OccupancyGrid& obstacles, double control_rate_hz)
    : spec_(spec), obstacles_(obstacles) {
  if (!(control_rate_hz > 0.0) || !(spec.rate_hz > 0.0) || !(spec.range_m > 0.0) || !(spec.fov_deg > 0.0)) {
    throw std::invalid_argument("SensorModel: sensor " + spec.name + " needs positive rates, range and field of view");
  }
  every_ = ScanEveryCycles(control_rate_hz, spec.rate_hz);
  period_s_ = every_ / control_rate_hz;
  half_fov_rad_ = 0.5 * std::min(spec.fov_deg, 360.0) * M_PI / 180.0;
  cos_half_fov_ = std::cos(half_fov_rad_);
  area_m2_ = half_fov_rad_ * spec.range_m * spec.range_m;
}

bool SensorModel::InSector(const Eigen::Vector2d& from, double heading_rad, const Eigen::Vector2d& y) const {
  return InSectorAlong(from, Eigen::Vector2d(std::cos(heading_rad), std::sin(heading_rad)), y);
}

bool SensorModel::InSectorAlong(const Eigen::Vector2d& from, const Eigen::Vector2d& heading_unit,
                                const Eigen::Vector2d& y) const {
  const Eigen::Vector2d d = y - from;
  const double r2 = d.squaredNorm();
  if (r2 > spec_.range_m * spec_.range_m) return false;
  if (spec_.fov_deg >= 360.0 || r2 == 0.0) return true;
  // The bearing within half the opening of the heading: cos(angle) >= cos(half fov).
  return d.dot(heading_unit) >= cos_half_fov_ * std::sqrt(r2);
}

bool SensorModel::ClearAround(const Eigen::Vector2d& from) const {
  const Eigen::Vector2d reach = Eigen::Vector2d::Constant(spec_.range_m);
  const Eigen::Vector2i lo = obstacles_.CellOf(from - reach), hi = obstacles_.CellOf(from + reach);
  return obstacles_.RectangleFree(lo, hi);
}

bool SensorModel::LineOfSight(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const {
  // Amanatides & Woo's traversal of the grid cells the segment crosses.
  const double r = obstacles_.resolution_m();
  int i = static_cast<int>(std::floor(from.x() / r)), j = static_cast<int>(std::floor(from.y() / r));
  const int i_end = static_cast<int>(std::floor(to.x() / r)), j_end = static_cast<int>(std::floor(to.y() / r));
  if (!obstacles_.InBounds(i_end, j_end)) return false;
  const Eigen::Vector2d d = to - from;
  const int step_i = d.x() > 0 ? 1 : -1, step_j = d.y() > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  double t_max_x = d.x() != 0.0 ? ((step_i > 0 ? (i + 1) * r : i * r) - from.x()) / d.x() : inf;
  double t_max_y = d.y() != 0.0 ? ((step_j > 0 ? (j + 1) * r : j * r) - from.y()) / d.y() : inf;
  const double t_dx = d.x() != 0.0 ? r / std::abs(d.x()) : inf;
  const double t_dy = d.y() != 0.0 ? r / std::abs(d.y()) : inf;
  // At most the cells a segment of this length can cross (a guard against rounding at corners).
  const int most = std::abs(i_end - i) + std::abs(j_end - j) + 2;
  for (int n = 0; n < most && (i != i_end || j != j_end); ++n) {
    if (t_max_x < t_max_y) {
      i += step_i;
      t_max_x += t_dx;
    } else {
      j += step_j;
      t_max_y += t_dy;
    }
    if (obstacles_.Occupied(i, j)) return false;
  }
  return !obstacles_.Occupied(i_end, j_end);
}

double SensorModel::DetectionProbability(double distance_m, double strength) const {
  if (!(distance_m <= spec_.range_m) || !(strength > 0.0)) return 0.0;
  const double x = distance_m / (spec_.half_range_m * std::sqrt(strength));
  return spec_.p_detect * std::exp2(-x * x);
}

double SensorModel::PositionDensity(const Eigen::Vector2d& z, const Eigen::Vector2d& y) const {
  const double s2 = spec_.position_sigma_m * spec_.position_sigma_m;
  return std::exp(-0.5 * (z - y).squaredNorm() / s2) / (2.0 * M_PI * s2);
}

}  // namespace sage::maps
