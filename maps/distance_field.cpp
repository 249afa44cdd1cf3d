#include "maps/distance_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "maps/prefetch.h"

namespace sage::maps {
namespace {

constexpr double kFar = 1e20;  // "no obstacle" in squared cell units; finite so the parabolas work

// 1-D squared distance transform of f (Felzenszwalb & Huttenlocher): d[q] = min_p (q-p)^2 + f[p],
// by the lower envelope of parabolas rooted at each p. O(n).
void Transform1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  int k = 0;
  v[0] = 0;
  z[0] = -std::numeric_limits<double>::infinity();
  z[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    while (s <= z[k]) {
      --k;
      s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = (q - v[k]) * (q - v[k]) + f[v[k]];
  }
}

}  // namespace

DistanceField::DistanceField(const OccupancyGrid& grid)
    : cols_(grid.cols()), rows_(grid.rows()), resolution_m_(grid.resolution_m()), distance_m_(cols_ * rows_) {
  const int longest = std::max(cols_, rows_);
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> v(longest);
  std::vector<double> squared(cols_ * rows_);
  bool any = false;
  // Pass 1: along y (j) for each column i.
  f.resize(rows_);
  d.resize(rows_);
  for (int i = 0; i < cols_; ++i) {
    for (int j = 0; j < rows_; ++j) {
      const bool occupied = grid.Occupied(i, j);
      any = any || occupied;
      f[j] = occupied ? 0.0 : kFar;
    }
    Transform1d(f, d, v, z);
    for (int j = 0; j < rows_; ++j) squared[i * rows_ + j] = d[j];
  }
  // Pass 2: along x (i) for each row j.
  f.resize(cols_);
  d.resize(cols_);
  for (int j = 0; j < rows_; ++j) {
    for (int i = 0; i < cols_; ++i) f[i] = squared[i * rows_ + j];
    Transform1d(f, d, v, z);
    for (int i = 0; i < cols_; ++i) {
      distance_m_[static_cast<std::size_t>(j) * cols_ + i] =
          any ? std::sqrt(d[i]) * resolution_m_ : std::numeric_limits<double>::infinity();
    }
  }
  // The blocks' least distances, over the cells a point in the block interpolates between.
  if (cols_ <= 0 || rows_ <= 0) return;
  block_cols_ = (cols_ + kBlockCells - 1) / kBlockCells;
  const int block_rows = (rows_ + kBlockCells - 1) / kBlockCells;
  block_least_m_.assign(static_cast<std::size_t>(block_cols_) * block_rows, std::numeric_limits<float>::infinity());
  for (int bj = 0; bj < block_rows; ++bj) {
    for (int bi = 0; bi < block_cols_; ++bi) {
      double least = std::numeric_limits<double>::infinity();
      for (int i = bi * kBlockCells; i <= std::min((bi + 1) * kBlockCells, cols_ - 1); ++i) {
        for (int j = bj * kBlockCells; j <= std::min((bj + 1) * kBlockCells, rows_ - 1); ++j) {
          least = std::min(least, At(i, j));
        }
      }
      float rounded = static_cast<float>(least);
      if (static_cast<double>(rounded) > least) rounded = std::nextafter(rounded, -std::numeric_limits<float>::infinity());
      block_least_m_[static_cast<std::size_t>(bj) * block_cols_ + bi] = rounded;
    }
  }
}

bool DistanceField::FartherThan(const Eigen::Vector2d& x_m, double d) const {
  if (block_least_m_.empty() || !x_m.allFinite()) return false;
  // The cells Distance interpolates between: floor(g) and the next, clamped to the grid.
  const double gx = std::clamp(x_m.x() / resolution_m_ - 0.5, -1.0, static_cast<double>(cols_));
  const double gy = std::clamp(x_m.y() / resolution_m_ - 0.5, -1.0, static_cast<double>(rows_));
  const int i = std::clamp(static_cast<int>(std::floor(gx)), 0, cols_ - 1);
  const int j = std::clamp(static_cast<int>(std::floor(gy)), 0, rows_ - 1);
  const double least = block_least_m_[static_cast<std::size_t>(j / kBlockCells) * block_cols_ + i / kBlockCells];
  // A bilinear mean of values >= least is >= least up to a few ulps of rounding.
  return least * (1.0 - 1e-9) >= d;
}

void DistanceField::Prefetch(const Eigen::Vector2d& x_m, double d) const {
  if (!x_m.allFinite() || FartherThan(x_m, d)) return;
  // Distance's stencil is cells i..i+1 by j..j+1; AwayFromObstacle's central differences, one
  // cell either way of x, widen it to i-1..i+2 by j-1..j+2 (a row's four cells are adjacent).
  const int i = static_cast<int>(std::floor(std::clamp(x_m.x() / resolution_m_ - 0.5, -2.0, double(cols_))));
  const int j = static_cast<int>(std::floor(std::clamp(x_m.y() / resolution_m_ - 0.5, -2.0, double(rows_))));
  const int i0 = std::clamp(i - 1, 0, cols_ - 1), i1 = std::clamp(i + 2, 0, cols_ - 1);
  for (int r = std::max(j - 1, 0); r <= std::min(j + 2, rows_ - 1); ++r) {
    PrefetchBytes(&distance_m_[static_cast<std::size_t>(r) * cols_ + i0], sizeof(double) * (i1 - i0 + 1));
  }
}

double DistanceField::At(int i, int j) const {
  i = std::clamp(i, 0, cols_ - 1);
  j = std::clamp(j, 0, rows_ - 1);
  return distance_m_[static_cast<std::size_t>(j) * cols_ + i];
}

double DistanceField::Distance(const Eigen::Vector2d& x_m) const {
  // Cell centres sit at (i + 1/2) r: interpolate bilinearly between the four around x.
  const double gx = x_m.x() / resolution_m_ - 0.5;
  const double gy = x_m.y() / resolution_m_ - 0.5;
  const int i = static_cast<int>(std::floor(gx));
  const int j = static_cast<int>(std::floor(gy));
  const double fx = std::clamp(gx - i, 0.0, 1.0);
  const double fy = std::clamp(gy - j, 0.0, 1.0);
  const double d00 = At(i, j), d10 = At(i + 1, j), d01 = At(i, j + 1), d11 = At(i + 1, j + 1);
  if (!std::isfinite(d00)) return d00;
  return (1 - fx) * (1 - fy) * d00 + fx * (1 - fy) * d10 + (1 - fx) * fy * d01 + fx * fy * d11;
}

Eigen::Vector2d DistanceField::AwayFromObstacle(const Eigen::Vector2d& x_m) const {
  const double h = resolution_m_;
  const Eigen::Vector2d gradient((Distance(x_m + Eigen::Vector2d(h, 0)) - Distance(x_m - Eigen::Vector2d(h, 0))) / (2 * h),
                                 (Distance(x_m + Eigen::Vector2d(0, h)) - Distance(x_m - Eigen::Vector2d(0, h))) / (2 * h));
  const double norm = gradient.norm();
  if (!std::isfinite(norm) || norm < 1e-9) return Eigen::Vector2d::Zero();
  return gradient / norm;
}

}  // namespace sage::maps
