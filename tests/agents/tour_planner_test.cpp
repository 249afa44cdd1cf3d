// A* grid paths (optimal length, obstacle-free segments, snapping, unreachable goals) and the
// closed tour (Held-Karp exact against brute force; 2-opt beyond 12 valves).
#include "agents/tour_planner.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <limits>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "tests/support/grid_traps.h"

namespace sage::agents {
namespace {

using maps::OccupancyGrid;

// Every point of every segment (sampled at r/50) lies in a free cell.
void ExpectPathOnFreeCells(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& path) {
  const double r = grid.resolution_m();
  for (std::size_t k = 1; k < path.size(); ++k) {
    const int samples = static_cast<int>(std::ceil((path[k] - path[k - 1]).norm() / (r / 50.0))) + 1;
    for (int s = 0; s <= samples; ++s) {
      const Eigen::Vector2d x = path[k - 1] + (path[k] - path[k - 1]) * (static_cast<double>(s) / samples);
      const Eigen::Vector2i cell(static_cast<int>(std::floor(x.x() / r)), static_cast<int>(std::floor(x.y() / r)));
      ASSERT_FALSE(grid.Occupied(cell.x(), cell.y())) << "segment " << k << " at " << x.transpose();
    }
  }
}

// Free cell centres drawn uniformly.
std::vector<Eigen::Vector2d> RandomFreePoints(const OccupancyGrid& grid, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> col(0, grid.cols() - 1), row(0, grid.rows() - 1);
  std::vector<Eigen::Vector2d> points;
  while (static_cast<int>(points.size()) < count) {
    const Eigen::Vector2i cell(col(rng), row(rng));
    if (!grid.Occupied(cell.x(), cell.y())) points.push_back(grid.CenterOf(cell));
  }
  return points;
}

OccupancyGrid GridWithTwoBlocks() {
  OccupancyGrid grid(12.0, 10.0, 0.2);
  grid.FillBox({3.0, 2.0}, {4.5, 6.0});
  grid.FillBox({7.0, 4.0}, {9.0, 8.5});
  return grid;
}

// Symmetric distance matrix the way PlanTour defines it (path i -> j for i < j).
std::vector<std::vector<double>> Distances(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points) {
  const std::size_t m = points.size();
  std::vector<std::vector<double>> d(m, std::vector<double>(m, 0.0));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) d[i][j] = d[j][i] = PathLength(PlanGridPath(grid, points[i], points[j]));
  }
  return d;
}

double ClosedLength(const std::vector<std::vector<double>>& d, const std::vector<int>& order) {
  double length = 0.0;
  for (std::size_t i = 0; i < order.size(); ++i) length += d[order[i]][order[(i + 1) % order.size()]];
  return length;
}

// order is a permutation of 0..M-1 starting at 0; legs chain valve to valve; length adds up.
void ExpectValidTour(const Tour& tour, const std::vector<Eigen::Vector2d>& points) {
  const int m = static_cast<int>(points.size());
  ASSERT_TRUE(tour.ok);
  ASSERT_EQ(static_cast<int>(tour.order.size()), m);
  ASSERT_EQ(static_cast<int>(tour.legs.size()), m);
  EXPECT_EQ(tour.order[0], 0);
  std::vector<int> sorted = tour.order;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < m; ++i) EXPECT_EQ(sorted[i], i);
  double sum = 0.0;
  for (int i = 0; i < m; ++i) {
    EXPECT_TRUE(tour.legs[i].front().isApprox(points[tour.order[i]]));
    EXPECT_TRUE(tour.legs[i].back().isApprox(points[tour.order[(i + 1) % m]]));
    sum += PathLength(tour.legs[i]);
  }
  EXPECT_NEAR(tour.length_m, sum, 1e-9);
}

// On an empty grid the path is the straight segment between the two cell centres.
TEST(GridPath, StraightLineOnEmptyGrid) {
  const OccupancyGrid grid(10.0, 8.0, 0.1);
  const Eigen::Vector2d from(1.05, 1.05), to(8.95, 4.35);
  const auto path = PlanGridPath(grid, from, to);
  ASSERT_GE(path.size(), 2u);
  EXPECT_TRUE(path.front().isApprox(from));
  EXPECT_TRUE(path.back().isApprox(to));
  EXPECT_NEAR(PathLength(path), (to - from).norm(), grid.resolution_m());
  EXPECT_EQ(path.size(), 2u);  // shortcut pass leaves no staircase
}

// A wall [4.9, 5.1] x [0, 6] forces a detour over its top; the length matches the taut string
// around its two top corners within 2 cells.
TEST(GridPath, WallForcesDetourOfAnalyticLength) {
  OccupancyGrid grid(10.0, 10.0, 0.1);
  grid.FillBox({4.9, 0.0}, {5.1, 6.0});
  const Eigen::Vector2d from(2.05, 3.05), to(8.05, 3.05);
  const auto path = PlanGridPath(grid, from, to);
  ASSERT_FALSE(path.empty());
  const Eigen::Vector2d corner_left(4.9, 6.0), corner_right(5.1, 6.0);
  const double analytic = (corner_left - from).norm() + 0.2 + (to - corner_right).norm();
  EXPECT_GE(PathLength(path), analytic - 1e-9);
  EXPECT_NEAR(PathLength(path), analytic, 2.0 * grid.resolution_m());
  ExpectPathOnFreeCells(grid, path);
}

// Random obstacle fields and endpoints (some inside obstacles, then snapped): no segment of a
// returned path crosses or clips an occupied cell.
TEST(GridPath, NoSegmentCrossesOccupiedCell) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(0.0, 12.0), y(0.0, 10.0), size(0.3, 2.0);
  for (int field = 0; field < 5; ++field) {
    OccupancyGrid grid(12.0, 10.0, 0.1);
    for (int b = 0; b < 8; ++b) {
      const Eigen::Vector2d corner(x(rng), y(rng));
      grid.FillBox(corner, corner + Eigen::Vector2d(size(rng), size(rng)));
    }
    for (int trial = 0; trial < 10; ++trial) {
      const auto path = PlanGridPath(grid, {x(rng), y(rng)}, {x(rng), y(rng)});
      if (path.empty()) continue;  // walled off: allowed
      ExpectPathOnFreeCells(grid, path);
    }
  }
}

// The A*'s cost against Dijkstra over the same moves (8-connected, no corner cutting), written
// here on its own: random obstacle fields of boxes and single cells, random ends (snapped as the
// planner snaps them: both ends are chosen free here), 1e-9 m; unreachable pairs agree too. The
// shortcut path is never longer than the cell path.
TEST(GridPath, CostEqualsDijkstra) {
  std::mt19937 rng(19);
  for (int field = 0; field < 6; ++field) {
    OccupancyGrid grid(9.0, 7.0, 0.1);
    std::uniform_real_distribution<double> x(0.0, 9.0), y(0.0, 7.0), size(0.2, 2.5);
    for (int b = 0; b < 6 + 2 * field; ++b) {
      const Eigen::Vector2d corner(x(rng), y(rng));
      grid.FillBox(corner, corner + Eigen::Vector2d(size(rng), 0.3 * size(rng)));
    }
    for (int c = 0; c < 150; ++c) grid.SetOccupied(static_cast<int>(x(rng) * 10), static_cast<int>(y(rng) * 10));
    const int cols = grid.cols(), rows = grid.rows();
    for (int trial = 0; trial < 8; ++trial) {
      Eigen::Vector2i a, b;
      do a = grid.CellOf({x(rng), y(rng)}); while (grid.Occupied(a.x(), a.y()));
      do b = grid.CellOf({x(rng), y(rng)}); while (grid.Occupied(b.x(), b.y()));
      std::vector<double> d(static_cast<std::size_t>(cols) * rows, std::numeric_limits<double>::infinity());
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
      d[a.x() * rows + a.y()] = 0.0;
      queue.emplace(0.0, a.x() * rows + a.y());
      while (!queue.empty()) {
        const auto [dist, k] = queue.top();
        queue.pop();
        if (dist > d[k]) continue;
        const int i = k / rows, j = k % rows;
        for (int di = -1; di <= 1; ++di)
          for (int dj = -1; dj <= 1; ++dj) {
            if ((di == 0 && dj == 0) || grid.Occupied(i + di, j + dj)) continue;
            if (di != 0 && dj != 0 && (grid.Occupied(i + di, j) || grid.Occupied(i, j + dj))) continue;
            const double next = dist + (di != 0 && dj != 0 ? std::sqrt(2.0) : 1.0) * grid.resolution_m();
            const int n = (i + di) * rows + j + dj;
            if (next < d[n]) d[n] = next, queue.emplace(next, n);
          }
      }
      const double expected = d[b.x() * rows + b.y()];
      const double got = GridDistance(grid, grid.CenterOf(a), grid.CenterOf(b));
      if (std::isinf(expected)) {
        EXPECT_TRUE(std::isinf(got)) << "field " << field << " trial " << trial;
        EXPECT_TRUE(PlanGridPath(grid, grid.CenterOf(a), grid.CenterOf(b)).empty());
        continue;
      }
      EXPECT_NEAR(got, expected, 1e-9) << "field " << field << " trial " << trial;
      EXPECT_LE(PathLength(PlanGridPath(grid, grid.CenterOf(a), grid.CenterOf(b))), got + 1e-9);
    }
  }
}

// A search looks in a window round its ends first, then in the box every path no longer than the
// window's answer keeps to, and over the whole grid only when the window holds no path: each
// answer must be the whole grid's search's, waypoint for waypoint and cost for cost (==). Fields:
// - far gap: ends either side of the foot of a long wall whose only gap is 11 m up (no path in
//   the window: the whole grid);
// - trap: ends 2 m apart either side of a wall with two gaps, the near one (in the window)
//   reached from one side only through a pocket, the far one just outside the window and
//   shorter: the window's own path is not the grid's (taking it unchecked fails here);
// - random blocks and speckle on three seeds, 40 pairs each.
TEST(GridPath, WindowedSearchIsTheWholeGridsSearch) {
  OccupancyGrid far_gap(40.0, 14.0, 0.1);
  far_gap.FillBox({19.8, 0.0}, {20.2, 12.0});
  far_gap = far_gap.Inflated(0.3);
  const auto make_trap = sage::testing::WallTrap;
  const OccupancyGrid trap = make_trap(true);
  const Eigen::Vector2d trap_from(10.05, 6.35), trap_to(12.05, 6.35);
  // The trap holds: by the far gap is shorter than through the pocket (the far gap closed).
  ASSERT_LT(GridDistance(trap, trap_from, trap_to, GridSearch::kWholeGrid) + 0.1,
            GridDistance(make_trap(false), trap_from, trap_to, GridSearch::kWholeGrid));
  struct Pair {
    const OccupancyGrid* grid;
    Eigen::Vector2d from, to;
  };
  std::vector<Pair> pairs = {{&far_gap, {19.05, 1.05}, {21.05, 1.05}}, {&trap, trap_from, trap_to}, {&trap, trap_to, trap_from}};
  std::vector<OccupancyGrid> fields;
  for (const unsigned seed : {31u, 32u, 33u}) {
    std::mt19937 rng(seed);
    OccupancyGrid grid(30.0, 20.0, 0.1);
    std::uniform_real_distribution<double> x(0.0, 30.0), y(0.0, 20.0), size(0.3, 4.0);
    for (int b = 0; b < 25; ++b) {
      const Eigen::Vector2d corner(x(rng), y(rng));
      grid.FillBox(corner, corner + (seed % 2 == 0 ? Eigen::Vector2d(size(rng), 0.2) : Eigen::Vector2d(0.2, size(rng))));
    }
    for (int c = 0; c < 300; ++c) grid.SetOccupied(static_cast<int>(x(rng) * 10), static_cast<int>(y(rng) * 10));
    fields.push_back(std::move(grid));
  }
  for (std::size_t f = 0; f < fields.size(); ++f) {
    std::mt19937 rng(40 + static_cast<unsigned>(f));
    std::uniform_real_distribution<double> x(0.0, 30.0), y(0.0, 20.0);
    for (int k = 0; k < 40; ++k) pairs.push_back({&fields[f], {x(rng), y(rng)}, {x(rng), y(rng)}});
  }
  int found = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Pair& p = pairs[k];
    const std::vector<Eigen::Vector2d> windowed = PlanGridPath(*p.grid, p.from, p.to);
    const std::vector<Eigen::Vector2d> whole = PlanGridPath(*p.grid, p.from, p.to, GridSearch::kWholeGrid);
    ASSERT_EQ(windowed.size(), whole.size()) << "pair " << k;
    for (std::size_t w = 0; w < whole.size(); ++w) EXPECT_EQ(windowed[w], whole[w]) << "pair " << k << " waypoint " << w;
    EXPECT_EQ(GridDistance(*p.grid, p.from, p.to), GridDistance(*p.grid, p.from, p.to, GridSearch::kWholeGrid)) << "pair " << k;
    found += whole.empty() ? 0 : 1;
  }
  EXPECT_GE(found, 100);
  // The far gap's path does go round the wall's end, the trap's through the far gap.
  EXPECT_GT(GridDistance(far_gap, pairs[0].from, pairs[0].to), 20.0);
  EXPECT_LT(GridDistance(trap, trap_from, trap_to), GridDistance(make_trap(false), trap_from, trap_to) - 0.1);
}

// A start inside an obstacle snaps to the nearest free cell centre.
TEST(GridPath, SnapsEndpointsToNearestFreeCell) {
  OccupancyGrid grid(10.0, 10.0, 0.1);
  grid.FillBox({4.0, 4.0}, {6.0, 6.0});  // cells with centres 4.05 .. 5.95
  const auto path = PlanGridPath(grid, {4.32, 5.0}, {1.05, 5.05});
  ASSERT_FALSE(path.empty());
  EXPECT_NEAR(path.front().x(), 3.95, 1e-9);  // left face is nearest (0.37 m)
  EXPECT_NEAR(path.front().y(), 4.95, 0.1 + 1e-9);
}

// A goal enclosed by a ring of occupied cells is unreachable: empty path.
TEST(GridPath, UnreachableGoalGivesEmptyPath) {
  OccupancyGrid grid(10.0, 10.0, 0.1);
  grid.FillBox({6.0, 6.0}, {8.0, 6.2});
  grid.FillBox({6.0, 7.8}, {8.0, 8.0});
  grid.FillBox({6.0, 6.0}, {6.2, 8.0});
  grid.FillBox({7.8, 6.0}, {8.0, 8.0});
  EXPECT_TRUE(PlanGridPath(grid, {1.05, 1.05}, {7.05, 7.05}).empty());
  const Tour tour = PlanTour(grid, {{1.05, 1.05}, {3.05, 1.05}, {7.05, 7.05}});
  EXPECT_FALSE(tour.ok);
}

// A search reuses its thread's per-cell state from earlier searches (stamped per search): paths
// planned after many others, on grids of other sizes and after an unreachable search that
// reached every free cell, equal the same paths planned each on a fresh thread.
TEST(GridPath, EarlierSearchesLeaveNoTrace) {
  std::mt19937 rng(11);
  std::vector<OccupancyGrid> grids;
  for (int field = 0; field < 3; ++field) {
    OccupancyGrid grid(12.0 + 2.0 * field, 10.0, 0.1);
    std::uniform_real_distribution<double> x(0.0, grid.width_m()), y(0.0, 10.0), size(0.3, 2.0);
    for (int b = 0; b < 8; ++b) {
      const Eigen::Vector2d corner(x(rng), y(rng));
      grid.FillBox(corner, corner + Eigen::Vector2d(size(rng), size(rng)));
    }
    grids.push_back(std::move(grid));
  }
  OccupancyGrid walled(12.0, 10.0, 0.1);  // the size of grids[0]; the goal fenced in
  walled.FillBox({6.0, 6.0}, {8.0, 6.2});
  walled.FillBox({6.0, 7.8}, {8.0, 8.0});
  walled.FillBox({6.0, 6.0}, {6.2, 8.0});
  walled.FillBox({7.8, 6.0}, {8.0, 8.0});
  std::uniform_real_distribution<double> x(0.0, 12.0), y(0.0, 10.0);
  int compared = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const OccupancyGrid& grid = grids[trial % grids.size()];
    const Eigen::Vector2d from(x(rng), y(rng)), to(x(rng), y(rng));
    if (trial % 4 == 0) {
      ASSERT_TRUE(PlanGridPath(walled, {1.05, 1.05}, {7.05, 7.05}).empty());
    }
    const std::vector<Eigen::Vector2d> reused = PlanGridPath(grid, from, to);
    std::vector<Eigen::Vector2d> fresh;
    std::thread([&] { fresh = PlanGridPath(grid, from, to); }).join();
    ASSERT_EQ(reused.size(), fresh.size()) << "trial " << trial;
    for (std::size_t k = 0; k < reused.size(); ++k) EXPECT_EQ(reused[k], fresh[k]) << "trial " << trial << " point " << k;
    compared += reused.empty() ? 0 : 1;
  }
  EXPECT_GE(compared, 20);
}

// Held-Karp equals the brute-force optimum over all (M-1)! orders (1e-9 m), M = 6 and 8.
TEST(TourPlanner, ExactTourMatchesBruteForce) {
  const OccupancyGrid grid = GridWithTwoBlocks();
  for (int m : {6, 8}) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const auto points = RandomFreePoints(grid, m, seed);
      const Tour tour = PlanTour(grid, points);
      ExpectValidTour(tour, points);
      const auto d = Distances(grid, points);
      std::vector<int> order(m);
      std::iota(order.begin(), order.end(), 0);
      double best = 1e300;
      do best = std::min(best, ClosedLength(d, order));
      while (std::next_permutation(order.begin() + 1, order.end()));
      EXPECT_NEAR(tour.length_m, best, 1e-9) << "M = " << m << ", seed " << seed;
    }
  }
}

// Beyond 12 valves: a valid tour no longer than nearest neighbour (M = 14).
TEST(TourPlanner, TwoOptTourIsValidAndNoLongerThanNearestNeighbour) {
  const OccupancyGrid grid = GridWithTwoBlocks();
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const auto points = RandomFreePoints(grid, 14, seed);
    const Tour tour = PlanTour(grid, points);
    ExpectValidTour(tour, points);
    const auto d = Distances(grid, points);
    std::vector<int> nearest{0};
    std::vector<bool> used(points.size(), false);
    used[0] = true;
    while (nearest.size() < points.size()) {
      int next = -1;
      for (int k = 0; k < static_cast<int>(points.size()); ++k) {
        if (!used[k] && (next < 0 || d[nearest.back()][k] < d[nearest.back()][next])) next = k;
      }
      used[next] = true;
      nearest.push_back(next);
    }
    EXPECT_LE(tour.length_m, ClosedLength(d, nearest) + 1e-9);
  }
}

// Degenerate sizes: one valve is a zero-length tour; two valves go there and back.
TEST(TourPlanner, OneAndTwoValves) {
  const OccupancyGrid grid(10.0, 10.0, 0.1);
  const Tour one = PlanTour(grid, {{2.05, 2.05}});
  ExpectValidTour(one, {{2.05, 2.05}});
  EXPECT_DOUBLE_EQ(one.length_m, 0.0);
  const Tour two = PlanTour(grid, {{2.05, 2.05}, {5.05, 6.05}});
  ExpectValidTour(two, {{2.05, 2.05}, {5.05, 6.05}});
  EXPECT_NEAR(two.length_m, 10.0, 1e-9);
  EXPECT_FALSE(PlanTour(grid, {}).ok);
}

}  // namespace
}  // namespace sage::agents
