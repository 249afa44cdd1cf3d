#pragma once
// A 2-D occupancy grid of the workspace at the vehicles' operating depth: what the A* tour
// plans on and what keeps vehicles clear of structures. Cell (i, j) covers
// [i r, (i+1) r) x [j r, (j+1) r), r = resolution.
#include <vector>

#include <Eigen/Core>

namespace sage::maps {

class OccupancyGrid {
 public:
  OccupancyGrid(double width_m, double height_m, double resolution_m);

  int cols() const { return cols_; }
  int rows() const { return rows_; }
  double resolution_m() const { return resolution_m_; }
  double width_m() const { return width_m_; }
  double height_m() const { return height_m_; }

  bool InBounds(int i, int j) const { return i >= 0 && j >= 0 && i < cols_ && j < rows_; }
  /// Out of bounds counts as occupied, so planners never leave the workspace. Inline: the A*
  /// and the vehicles' guidance ask it for every neighbour of every cell they look at.
  bool Occupied(int i, int j) const {
    return !InBounds(i, j) || cells_[static_cast<std::size_t>(i) * rows_ + j] != 0;
  }
  void SetOccupied(int i, int j, bool occupied = true);
  /// Marks every cell whose centre lies in the axis-aligned box [min, max] (m).
  void FillBox(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m);
  /// A copy with every occupied cell grown by radius_m (disc).
  OccupancyGrid Inflated(double radius_m) const;

  Eigen::Vector2i CellOf(const Eigen::Vector2d& x_m) const;    ///< clamped into the grid
  Eigen::Vector2d CenterOf(const Eigen::Vector2i& cell) const;  ///< cell centre (m)
  int OccupiedCount() const;
  /// True if every cell (i, j) with lo.x() <= i <= hi.x() and lo.y() <= j <= hi.y() is free (false
  /// if any is out of bounds); the corners may come in any order. O(cells of the rectangle), a
  /// byte scan per column with an early exit. A shortest 8-connected path never leaves the
  /// rectangle of its two end cells (leaving adds steps, and the octile cost grows strictly with
  /// either step count), so a free rectangle means the obstacle-free octile path is the shortest.
  bool RectangleFree(const Eigen::Vector2i& lo, const Eigen::Vector2i& hi) const;

 private:
  double width_m_;
  double height_m_;
  double resolution_m_;
  int cols_;
  int rows_;
  std::vector<unsigned char> cells_;  // column-major by (i, j): i * rows_ + j
};

}  // namespace sage::maps
