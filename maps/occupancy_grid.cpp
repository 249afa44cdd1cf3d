// 2-D occupancy grid of the workspace at operating depth (see occupancy_grid.h).
#include "maps/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace sage::maps {
namespace {

// Cells needed to cover `extent_m`; the tolerance keeps 7.0 / 0.05 at 140 cells, not 141, when
// the division rounds just above a whole number.
int CellCount(double extent_m, double resolution_m) {
  return std::max(1, static_cast<int>(std::ceil(extent_m / resolution_m - 1e-9)));
}

}  // namespace

OccupancyGrid::OccupancyGrid(double width_m, double height_m, double resolution_m)
    : width_m_(width_m), height_m_(height_m), resolution_m_(resolution_m) {
  if (!(width_m > 0 && height_m > 0 && resolution_m > 0) || !std::isfinite(width_m) || !std::isfinite(height_m) ||
      !std::isfinite(resolution_m)) {
    throw std::invalid_argument("OccupancyGrid: width " + std::to_string(width_m) + " m, height " +
                                std::to_string(height_m) + " m and resolution " + std::to_string(resolution_m) +
                                " m must be finite and > 0");
  }
  cols_ = CellCount(width_m, resolution_m);
  rows_ = CellCount(height_m, resolution_m);
  cells_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_), 0);
}

void OccupancyGrid::SetOccupied(int i, int j, bool occupied) {
  // Out-of-bounds writes are ignored: outside is already "occupied" for every reader.
  if (!InBounds(i, j)) return;
  cells_[static_cast<std::size_t>(i) * rows_ + j] = occupied ? 1 : 0;
}

void OccupancyGrid::FillBox(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m) {
  // Candidate range from the centre formula (i + 1/2) r in [min, max], widened by one cell; the
  // exact test on CenterOf decides, so boundary centres follow the same rule as a brute-force loop.
  const auto first = [&](double lo) { return std::max(0, static_cast<int>(std::floor(lo / resolution_m_ - 0.5)) - 1); };
  const auto last = [&](double hi, int count) {
    return std::min(count - 1, static_cast<int>(std::ceil(hi / resolution_m_ - 0.5)) + 1);
  };
  if (!min_m.allFinite() || !max_m.allFinite()) return;
  for (int i = first(min_m.x()); i <= last(max_m.x(), cols_); ++i) {
    for (int j = first(min_m.y()); j <= last(max_m.y(), rows_); ++j) {
      const Eigen::Vector2d center = CenterOf({i, j});
      if ((center.array() >= min_m.array()).all() && (center.array() <= max_m.array()).all()) SetOccupied(i, j);
    }
  }
}

OccupancyGrid OccupancyGrid::Inflated(double radius_m) const {
  if (radius_m < 0 || std::isnan(radius_m)) {
    throw std::invalid_argument("OccupancyGrid::Inflated: radius " + std::to_string(radius_m) + " m must be >= 0");
  }
  OccupancyGrid out = *this;
  // Offsets (di, dj) of the disc: cells whose centre is within radius_m of the occupied cell's
  // centre; the small tolerance keeps a cell at exactly the radius inside.
  const int reach = static_cast<int>(std::floor(radius_m / resolution_m_ + 1e-9));
  const double limit = (radius_m / resolution_m_) * (radius_m / resolution_m_) + 1e-9;
  std::vector<Eigen::Vector2i> disc;
  for (int di = -reach; di <= reach; ++di) {
    for (int dj = -reach; dj <= reach; ++dj) {
      if (di * di + dj * dj <= limit) disc.emplace_back(di, dj);
    }
  }
  // Only cells with a free 8-neighbour need stamping, and the result is still exact: the occupied
  // cell nearest to any free cell p has a free neighbour, since its neighbour one step towards p
  // is strictly nearer to p (so it cannot be occupied).
  const auto interior = [this](int i, int j) {
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        if (!Occupied(i + di, j + dj)) return false;
      }
    }
    return true;
  };
  for (int i = 0; i < cols_; ++i) {
    for (int j = 0; j < rows_; ++j) {
      if (!Occupied(i, j) || interior(i, j)) continue;
      for (const Eigen::Vector2i& d : disc) out.SetOccupied(i + d.x(), j + d.y());
    }
  }
  return out;
}

Eigen::Vector2i OccupancyGrid::CellOf(const Eigen::Vector2d& x_m) const {
  const auto index = [&](double v, int count) {
    const double cell = std::floor(v / resolution_m_);
    if (!(cell >= 0)) return 0;  // also NaN
    return cell >= count - 1 ? count - 1 : static_cast<int>(cell);
  };
  return {index(x_m.x(), cols_), index(x_m.y(), rows_)};
}

Eigen::Vector2d OccupancyGrid::CenterOf(const Eigen::Vector2i& cell) const {
  return {(cell.x() + 0.5) * resolution_m_, (cell.y() + 0.5) * resolution_m_};
}

bool OccupancyGrid::RectangleFree(const Eigen::Vector2i& lo, const Eigen::Vector2i& hi) const {
  const int i0 = std::min(lo.x(), hi.x()), i1 = std::max(lo.x(), hi.x());
  const int j0 = std::min(lo.y(), hi.y()), j1 = std::max(lo.y(), hi.y());
  if (!InBounds(i0, j0) || !InBounds(i1, j1)) return false;
  const std::size_t length = static_cast<std::size_t>(j1 - j0) + 1;
  for (int i = i0; i <= i1; ++i) {
    const unsigned char* column = cells_.data() + static_cast<std::size_t>(i) * rows_ + j0;
    // Eight cells a word: any nonzero byte makes the word nonzero.
    std::size_t k = 0;
    for (; k + 8 <= length; k += 8) {
      std::uint64_t word;
      std::memcpy(&word, column + k, 8);
      if (word != 0) return false;
    }
    for (; k < length; ++k) {
      if (column[k] != 0) return false;
    }
  }
  return true;
}

int OccupancyGrid::OccupiedCount() const {
  return static_cast<int>(std::count(cells_.begin(), cells_.end(), static_cast<unsigned char>(1)));
}

}  // namespace sage::maps
