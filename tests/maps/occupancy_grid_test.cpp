// OccupancyGrid: box filling, disc inflation and cell/coordinate conversion against brute force.
#include "maps/occupancy_grid.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace sage::maps {
namespace {

// The grid covers the workspace with whole cells, without a spurious extra cell from rounding.
TEST(OccupancyGrid, DimensionsCoverWorkspace) {
  const OccupancyGrid grid(7.0, 5.0, 0.05);
  EXPECT_EQ(grid.cols(), 140);
  EXPECT_EQ(grid.rows(), 100);
  EXPECT_EQ(OccupancyGrid(7.05, 5.0, 0.1).cols(), 71);
  EXPECT_EQ(grid.OccupiedCount(), 0);
  EXPECT_THROW(OccupancyGrid(7.0, 5.0, 0.0), std::invalid_argument);
}

// Out of bounds reads as occupied, so a planner never leaves the workspace.
TEST(OccupancyGrid, OutOfBoundsIsOccupied) {
  OccupancyGrid grid(1.0, 1.0, 0.1);
  EXPECT_TRUE(grid.Occupied(-1, 0));
  EXPECT_TRUE(grid.Occupied(0, 10));
  EXPECT_FALSE(grid.Occupied(0, 0));
  grid.SetOccupied(3, 4);
  EXPECT_TRUE(grid.Occupied(3, 4));
  grid.SetOccupied(3, 4, false);
  EXPECT_FALSE(grid.Occupied(3, 4));
  grid.SetOccupied(-5, 40);  // ignored
  EXPECT_EQ(grid.OccupiedCount(), 0);
}

// FillBox marks exactly the cells whose centres lie in the box (inclusive), cell by cell against
// a brute-force loop, including boxes whose edges pass through cell centres or leave the grid.
TEST(OccupancyGrid, FillBoxMatchesBruteForce) {
  const double res = 0.05;
  const struct { Eigen::Vector2d min, max; } boxes[] = {
      {{1.6, 2.5}, {2.4, 3.3}},      // the two_xt XT-A footprint
      {{1.625, 2.525}, {2.375, 3.275}},  // edges exactly on cell centres
      {{4.21, 1.73}, {4.99, 2.68}},
      {{-1.0, -1.0}, {0.3, 0.2}},    // partly outside the grid
      {{3.0, 3.0}, {3.01, 3.01}},    // smaller than a cell, no centre inside
  };
  for (const auto& box : boxes) {
    OccupancyGrid grid(7.0, 5.0, res);
    grid.FillBox(box.min, box.max);
    int expected = 0;
    for (int i = 0; i < grid.cols(); ++i) {
      for (int j = 0; j < grid.rows(); ++j) {
        const Eigen::Vector2d c = grid.CenterOf({i, j});
        const bool inside = (c.array() >= box.min.array()).all() && (c.array() <= box.max.array()).all();
        expected += inside ? 1 : 0;
        ASSERT_EQ(grid.Occupied(i, j), inside) << "cell " << i << ", " << j;
      }
    }
    EXPECT_EQ(grid.OccupiedCount(), expected);
  }
}

// Inflating one cell by r: cells at r - res are occupied, at r + res free, along x, y and diagonals.
TEST(OccupancyGrid, InflatedGrowsByRadius) {
  const double res = 0.05, radius = 0.3;
  OccupancyGrid grid(5.0, 5.0, res);
  grid.SetOccupied(50, 50);
  const OccupancyGrid inflated = grid.Inflated(radius);
  const Eigen::Vector2d center = grid.CenterOf({50, 50});
  for (double angle = 0; angle < 2 * M_PI; angle += M_PI / 8) {
    const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
    const Eigen::Vector2i near = grid.CellOf(center + (radius - res) * dir);
    const Eigen::Vector2i far = grid.CellOf(center + (radius + res) * dir);
    EXPECT_TRUE(inflated.Occupied(near.x(), near.y())) << "angle " << angle;
    EXPECT_FALSE(inflated.Occupied(far.x(), far.y())) << "angle " << angle;
  }
  EXPECT_TRUE(grid.Inflated(0.0).Occupied(50, 50));
  EXPECT_EQ(grid.Inflated(0.0).OccupiedCount(), 1);
  EXPECT_EQ(grid.OccupiedCount(), 1);  // the original is untouched
}

// Inflation equals the brute-force set of cells within r (centre to centre) of any occupied cell,
// also for a filled box whose interior cells are skipped by the implementation.
TEST(OccupancyGrid, InflatedMatchesBruteForce) {
  OccupancyGrid grid(3.0, 2.0, 0.1);
  grid.FillBox({1.0, 0.5}, {1.8, 1.2});
  grid.SetOccupied(2, 2);
  grid.SetOccupied(29, 0);
  const double radius = 0.25;
  const OccupancyGrid inflated = grid.Inflated(radius);
  for (int i = 0; i < grid.cols(); ++i) {
    for (int j = 0; j < grid.rows(); ++j) {
      bool expected = false;
      for (int a = 0; a < grid.cols() && !expected; ++a) {
        for (int b = 0; b < grid.rows() && !expected; ++b) {
          expected = grid.Occupied(a, b) && (grid.CenterOf({a, b}) - grid.CenterOf({i, j})).norm() <= radius + 1e-9;
        }
      }
      ASSERT_EQ(inflated.Occupied(i, j), expected) << "cell " << i << ", " << j;
    }
  }
}

// CellOf(CenterOf(c)) == c for every cell; points off the grid clamp to the border cells.
TEST(OccupancyGrid, CellOfCenterOfRoundTrip) {
  const OccupancyGrid grid(7.0, 5.0, 0.05);
  for (int i = 0; i < grid.cols(); ++i) {
    for (int j = 0; j < grid.rows(); ++j) {
      const Eigen::Vector2i cell(i, j);
      ASSERT_EQ(grid.CellOf(grid.CenterOf(cell)), cell);
      // Any point strictly inside the cell maps to it.
      ASSERT_EQ(grid.CellOf(grid.CenterOf(cell) + Eigen::Vector2d(0.024, -0.024)), cell);
    }
  }
  EXPECT_EQ(grid.CellOf({-3.0, 2.0}), Eigen::Vector2i(0, 40));
  EXPECT_EQ(grid.CellOf({9.0, 6.0}), Eigen::Vector2i(139, 99));
  EXPECT_EQ(grid.CellOf({7.0, 5.0}), Eigen::Vector2i(139, 99));
  EXPECT_TRUE(grid.CenterOf({0, 0}).isApprox(Eigen::Vector2d(0.025, 0.025)));
}

// RectangleFree against a cell-by-cell check: random sparse grids (a lone occupied cell at a
// column's end or in the middle of an 8-cell word), random rectangles given in either corner
// order, some reaching out of the grid (not free).
TEST(OccupancyGrid, RectangleFreeMatchesCellByCell) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    OccupancyGrid grid(0.1 * (1 + rng() % 40), 0.1 * (1 + rng() % 40), 0.1);
    const int occupied = static_cast<int>(rng() % 6);
    for (int k = 0; k < occupied; ++k) grid.SetOccupied(static_cast<int>(rng() % grid.cols()), static_cast<int>(rng() % grid.rows()));
    for (int q = 0; q < 50; ++q) {
      const Eigen::Vector2i a(static_cast<int>(rng() % (grid.cols() + 2)) - 1, static_cast<int>(rng() % (grid.rows() + 2)) - 1);
      const Eigen::Vector2i b(static_cast<int>(rng() % (grid.cols() + 2)) - 1, static_cast<int>(rng() % (grid.rows() + 2)) - 1);
      bool expected = true;
      for (int i = std::min(a.x(), b.x()); i <= std::max(a.x(), b.x()); ++i)
        for (int j = std::min(a.y(), b.y()); j <= std::max(a.y(), b.y()); ++j) expected = expected && !grid.Occupied(i, j);
      ASSERT_EQ(grid.RectangleFree(a, b), expected) << "trial " << trial << " (" << a.transpose() << ") (" << b.transpose() << ")";
    }
  }
}

}  // namespace
}  // namespace sage::maps
