// A* grid paths and the shortest closed inspection tour (the SAGE paper's baseline).
#include "agents/tour_planner.h"
#include "agents/grid_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <queue>
#include <unordered_set>

namespace sage::agents {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Held-Karp is O(2^M M^2) time and O(2^M M) memory: exact up to 12 valves (2^11 x 12 states).
constexpr int kMaxExactTourSize = 12;

using Cell = Eigen::Vector2i;

bool Free(const maps::OccupancyGrid& grid, const Cell& c) { return !grid.Occupied(c.x(), c.y()); }

// Nearest free cell to x_m: breadth-first rings (8-connected) out from its cell; among the free
// cells of the first ring that has any, the one whose centre is closest to x_m.
std::optional<Cell> SnapToFree(const maps::OccupancyGrid& grid, const Eigen::Vector2d& x_m) {
  const Cell start = grid.CellOf(x_m);
  if (Free(grid, start)) return start;
  // The cells seen so far, as a set: the rings stay small (a valve's standoff lies a few cells
  // inside a structure's inflation), and a per-cell array was 12.8 MB to clear for each path on a
  // 10,000-vehicle field.
  std::unordered_set<std::int64_t> seen;
  auto index = [&](const Cell& c) { return static_cast<std::int64_t>(c.x()) * grid.rows() + c.y(); };
  auto first_time = [&](const Cell& c) { return seen.insert(index(c)).second; };
  std::vector<Cell> ring{start};
  first_time(start);
  while (!ring.empty()) {
    std::vector<Cell> next;
    std::optional<Cell> best;
    double best_d2 = kInf;
    for (const Cell& c : ring) {
      for (int di = -1; di <= 1; ++di) {
        for (int dj = -1; dj <= 1; ++dj) {
          const Cell nb(c.x() + di, c.y() + dj);
          if (!grid.InBounds(nb.x(), nb.y()) || !first_time(nb)) continue;
          next.push_back(nb);
          const double d2 = (grid.CenterOf(nb) - x_m).squaredNorm();
          if (Free(grid, nb) && d2 < best_d2) best = nb, best_d2 = d2;
        }
      }
    }
    if (best) return best;
    ring = std::move(next);
  }
  return std::nullopt;  // no free cell at all
}

// True if the segment a-b (m) touches only free cells. Exact grid traversal (Amanatides & Woo)
// rather than sampling: sampling at r/2 can clip an occupied cell's corner unseen. Where the
// segment passes exactly through a cell vertex, both side cells must be free too (the same
// no-corner-cutting rule as the A* moves).
bool SegmentFree(const maps::OccupancyGrid& grid, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const double r = grid.resolution_m();
  const Eigen::Vector2d p = a / r, d = (b - a) / r;  // in cell units
  Cell cell(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())));
  const Cell last(static_cast<int>(std::floor(b.x() / r)), static_cast<int>(std::floor(b.y() / r)));
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  // t (fraction of the segment) at the next vertical / horizontal cell boundary.
  auto first_crossing = [](double pos, double dir, int cell_index) {
    if (dir == 0.0) return kInf;
    const double boundary = dir > 0 ? cell_index + 1.0 : static_cast<double>(cell_index);
    return (boundary - pos) / dir;
  };
  double t_x = first_crossing(p.x(), d.x(), cell.x()), t_y = first_crossing(p.y(), d.y(), cell.y());
  const double dt_x = d.x() == 0.0 ? kInf : 1.0 / std::abs(d.x());
  const double dt_y = d.y() == 0.0 ? kInf : 1.0 / std::abs(d.y());
  constexpr double kTie = 1e-9;
  const int max_cells = std::abs(last.x() - cell.x()) + std::abs(last.y() - cell.y()) + 2;
  for (int visited = 0; visited <= max_cells; ++visited) {
    if (!Free(grid, cell)) return false;
    if (cell == last || std::min(t_x, t_y) > 1.0) return true;
    if (std::abs(t_x - t_y) < kTie) {  // through a vertex: the two side cells as well
      if (!Free(grid, Cell(cell.x() + step_x, cell.y())) || !Free(grid, Cell(cell.x(), cell.y() + step_y))) {
        return false;
      }
      cell += Cell(step_x, step_y);
      t_x += dt_x, t_y += dt_y;
    } else if (t_x < t_y) {
      cell.x() += step_x, t_x += dt_x;
    } else {
      cell.y() += step_y, t_y += dt_y;
    }
  }
  return Free(grid, cell);
}

// A* over cells, 8-connected: orthogonal step r, diagonal sqrt(2) r, and a diagonal only if
// both orthogonal cells it passes are free. Octile heuristic
//   h = r (max(dx, dy) + (sqrt(2) - 1) min(dx, dy))
// is the exact obstacle-free cost, hence admissible and consistent.
// Costs are kept exactly, as a + b sqrt(2) steps (agents/grid_steps.h): in doubles the many
// cells of equal f (every cell on some shortest octile path) differ by rounding, and the search
// had expanded them all in effect at random, ~80 cells per cell of path on 20-100 m crossings of
// a 10,000-XT field. Exact ties break toward the goal (least h), then by cell index, so the
// search runs along one shortest path and the result is deterministic.

// The search's per-cell state, kept between searches of one thread and stamped per search, so a
// search costs what it touches: on a 10,000-vehicle field (12.8 million cells) each vehicle's
// first path had cleared 166 MB of per-cell arrays, 10-12 minutes for the fleet. Indexed by the
// searched area's cells (below), and only ever grown: an area's cells are a prefix.
struct AStarScratch {
  std::vector<GridSteps> g;
  std::vector<int> parent;
  std::vector<std::uint32_t> reached, closed;  // == stamp: this search's g/parent, closed
  std::uint32_t stamp = 0;

  void Begin(std::size_t cells) {
    if (g.size() < cells) {
      g.assign(cells, GridSteps{});
      parent.assign(cells, -1);
      reached.assign(cells, 0);
      closed.assign(cells, 0);
      stamp = 0;
    }
    if (++stamp == 0) {  // wrapped: clear the stamps once
      std::fill(reached.begin(), reached.end(), 0u);
      std::fill(closed.begin(), closed.end(), 0u);
      stamp = 1;
    }
  }
};

// A rectangle of the grid's cells, lo and hi included.
struct Area {
  Cell lo, hi;
  bool Contains(const Area& other) const {
    return (other.lo.array() >= lo.array()).all() && (other.hi.array() <= hi.array()).all();
  }
};

// The cells of a shortest path from start to goal through free cells of `area` (empty if none);
// its cost into *cost. start and goal lie in the area.
std::vector<Cell> AStarIn(const maps::OccupancyGrid& grid, const Area& area, const Cell& start, const Cell& goal,
                          GridSteps* cost) {
  // Cells by (x, y) lexicographically, as the whole grid's index orders them: the same ties.
  const int rows = area.hi.y() - area.lo.y() + 1;
  auto index = [&](const Cell& c) { return (c.x() - area.lo.x()) * rows + (c.y() - area.lo.y()); };
  auto cell_of = [&](int k) { return Cell(area.lo.x() + k / rows, area.lo.y() + k % rows); };
  auto free = [&](const Cell& c) {
    return (c.array() >= area.lo.array()).all() && (c.array() <= area.hi.array()).all() && Free(grid, c);
  };
  auto heuristic = [&](const Cell& c) { return Octile(c.x() - goal.x(), c.y() - goal.y()); };
  struct Entry {
    GridSteps f, h;
    int cell;
  };
  // The open list's order: least f, then least h, then least cell index (a heap's "greater").
  const auto later = [](const Entry& x, const Entry& y) {
    if (const int c = Compare(x.f, y.f); c != 0) return c > 0;
    if (const int c = Compare(x.h, y.h); c != 0) return c > 0;
    return x.cell > y.cell;
  };
  thread_local AStarScratch scratch;
  scratch.Begin(static_cast<std::size_t>(area.hi.x() - area.lo.x() + 1) * static_cast<std::size_t>(rows));
  const std::uint32_t stamp = scratch.stamp;
  std::priority_queue<Entry, std::vector<Entry>, decltype(later)> open(later);
  const int start_index = index(start);
  scratch.g[start_index] = GridSteps{};
  scratch.parent[start_index] = -1;
  scratch.reached[start_index] = stamp;
  open.push({heuristic(start), heuristic(start), start_index});
  const int goal_index = index(goal);
  while (!open.empty()) {
    const int current = open.top().cell;
    open.pop();
    if (scratch.closed[current] == stamp) continue;
    scratch.closed[current] = stamp;
    if (current == goal_index) break;
    const Cell c = cell_of(current);
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        if (di == 0 && dj == 0) continue;
        const Cell nb(c.x() + di, c.y() + dj);
        if (!free(nb)) continue;
        const bool diagonal = di != 0 && dj != 0;
        if (diagonal && (!free(Cell(c.x() + di, c.y())) || !free(Cell(c.x(), c.y() + dj)))) continue;
        const int k = index(nb);
        const GridSteps step = scratch.g[current] + (diagonal ? GridSteps{0, 1} : GridSteps{1, 0});
        if (scratch.reached[k] != stamp || Compare(step, scratch.g[k]) < 0) {
          scratch.g[k] = step;
          scratch.parent[k] = current;
          scratch.reached[k] = stamp;
          const GridSteps h = heuristic(nb);
          open.push({step + h, h, k});
        }
      }
    }
  }
  if (scratch.reached[goal_index] != stamp) return {};
  if (cost != nullptr) *cost = scratch.g[goal_index];
  std::vector<Cell> cells;
  for (int k = goal_index; k != -1; k = scratch.parent[k]) cells.push_back(cell_of(k));
  std::reverse(cells.begin(), cells.end());
  return cells;
}

// The cells of the whole grid's shortest path from start to goal (empty if none); its cost into
// *cost. Searched first in a window: the ends' rectangle with a margin of 4 cells and half its
// longer side. A path found there of cost c0 bounds the shortest, c* <= c0, and every cell the
// whole grid's search pops (f = g + h <= c*: Chebyshev <= octile, so per axis
// |x - s| + |x - g| <= c*) lies in the Reach box of c0; a cell outside it has f > c* and is never
// popped, so a search in an area holding that box pops the whole grid's cells in the whole
// grid's order (the same keys, the same ties) and ends on its very path. The window's answer is
// kept when the window holds the box, else the box is searched; the whole grid only when the
// window has no path. A vehicle's transit across a 10,000-vehicle field had searched the whole
// grid's 12.8 million cells' state: 256 MB on each of the host's threads, whose page faults took
// the fleet's first cycle in its regions 2.0 s (a cycle takes 40 ms).
std::vector<Cell> AStar(const maps::OccupancyGrid& grid, const Cell& start, const Cell& goal, GridSteps* cost = nullptr,
                        GridSearch search = GridSearch::kWindowed) {
  const Area whole{Cell(0, 0), Cell(grid.cols() - 1, grid.rows() - 1)};
  const auto clip = [&](const Cell& lo, const Cell& hi) {
    return Area{lo.cwiseMax(whole.lo), hi.cwiseMin(whole.hi)};
  };
  if (search == GridSearch::kWholeGrid) return AStarIn(grid, whole, start, goal, cost);
  const Cell span = (goal - start).cwiseAbs();
  const int margin = 4 + std::max(span.x(), span.y()) / 2;
  const Area window = clip(start.cwiseMin(goal) - Cell::Constant(margin), start.cwiseMax(goal) + Cell::Constant(margin));
  GridSteps c0;
  std::vector<Cell> path = AStarIn(grid, window, start, goal, &c0);
  if (path.empty()) return window.Contains(whole) ? path : AStarIn(grid, whole, start, goal, cost);
  // Reach box of c0, a cell wider each way than its bounds (rounding never narrows it).
  const double c = c0.a + std::numbers::sqrt2 * c0.b;
  const auto low = [&](int s, int g) { return static_cast<int>(std::floor(0.5 * (s + g - c))) - 1; };
  const auto high = [&](int s, int g) { return static_cast<int>(std::ceil(0.5 * (s + g + c))) + 1; };
  const Area reach = clip(Cell(low(start.x(), goal.x()), low(start.y(), goal.y())),
                          Cell(high(start.x(), goal.x()), high(start.y(), goal.y())));
  if (!window.Contains(reach)) return AStarIn(grid, reach, start, goal, cost);
  if (cost != nullptr) *cost = c0;
  return path;
}

// Line-of-sight shortcut ("string pulling"): from the last kept waypoint, skip every following
// waypoint while the straight segment to the one after it is free. Run on the full cell path
// (not only its corners) so a shortcut may also leave an edge part-way; never longer than the
// input by the triangle inequality.
std::vector<Eigen::Vector2d> Shortcut(const maps::OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& path) {
  if (path.size() <= 2) return path;
  std::vector<Eigen::Vector2d> out{path.front()};
  for (std::size_t k = 1; k + 1 < path.size(); ++k) {
    if (!SegmentFree(grid, out.back(), path[k + 1])) out.push_back(path[k]);
  }
  out.push_back(path.back());
  return out;
}

// Drops waypoints that lie on the segment between their neighbours (|cross| ~ 0, same direction).
std::vector<Eigen::Vector2d> RemoveCollinear(const std::vector<Eigen::Vector2d>& path) {
  if (path.size() <= 2) return path;
  std::vector<Eigen::Vector2d> out{path.front()};
  for (std::size_t k = 1; k + 1 < path.size(); ++k) {
    const Eigen::Vector2d in = path[k] - out.back(), next = path[k + 1] - path[k];
    const double cross = in.x() * next.y() - in.y() * next.x();
    if (std::abs(cross) > 1e-9 * in.norm() * next.norm() || in.dot(next) < 0.0) out.push_back(path[k]);
  }
  out.push_back(path.back());
  return out;
}

using DistanceMatrix = std::vector<std::vector<double>>;

double TourLength(const DistanceMatrix& d, const std::vector<int>& order) {
  double length = 0.0;
  for (std::size_t i = 0; i < order.size(); ++i) length += d[order[i]][order[(i + 1) % order.size()]];
  return length;
}

// Held-Karp: C(S, j) = shortest path from 0 through the set S ending at j (0 not in S),
//   C({j}, j) = d(0, j),  C(S, j) = min_{i in S \ {j}} C(S \ {j}, i) + d(i, j),
// tour = min_j C({1..M-1}, j) + d(j, 0). Node k >= 1 is bit k - 1 of S.
std::vector<int> HeldKarpOrder(const DistanceMatrix& d) {
  const int m = static_cast<int>(d.size());
  const int n = m - 1;  // nodes other than 0
  const std::size_t subsets = std::size_t{1} << n;
  std::vector<double> cost(subsets * n, kInf);
  std::vector<int> parent(subsets * n, -1);
  for (int j = 0; j < n; ++j) cost[(std::size_t{1} << j) * n + j] = d[0][j + 1];
  for (std::size_t set = 1; set < subsets; ++set) {
    for (int j = 0; j < n; ++j) {
      if (!(set >> j & 1) || cost[set * n + j] == kInf) continue;
      for (int k = 0; k < n; ++k) {
        if (set >> k & 1) continue;
        const std::size_t grown = set | (std::size_t{1} << k);
        const double c = cost[set * n + j] + d[j + 1][k + 1];
        if (c < cost[grown * n + k]) cost[grown * n + k] = c, parent[grown * n + k] = j;
      }
    }
  }
  const std::size_t full = subsets - 1;
  int last = 0;
  double best = kInf;
  for (int j = 0; j < n; ++j) {
    const double c = cost[full * n + j] + d[j + 1][0];
    if (c < best) best = c, last = j;
  }
  std::vector<int> order;
  for (std::size_t set = full; last != -1;) {
    order.push_back(last + 1);
    const int previous = parent[set * n + last];
    set &= ~(std::size_t{1} << last);
    last = previous;
  }
  order.push_back(0);
  std::reverse(order.begin(), order.end());
  return order;
}

// Nearest neighbour from 0, then 2-opt: reverse order[i..j] while that shortens the tour,
//   delta = d(a, c) + d(b, e) - d(a, b) - d(c, e),  a b ... c e  ->  a c ... b e.
// order[0] never moves (i >= 1). Each accepted move shortens the tour, so it terminates.
std::vector<int> HeuristicOrder(const DistanceMatrix& d) {
  const int m = static_cast<int>(d.size());
  std::vector<int> order{0};
  std::vector<char> used(m, 0);
  used[0] = 1;
  while (static_cast<int>(order.size()) < m) {
    int next = -1;
    for (int k = 0; k < m; ++k) {
      if (!used[k] && (next < 0 || d[order.back()][k] < d[order.back()][next])) next = k;
    }
    used[next] = 1;
    order.push_back(next);
  }
  for (bool improved = true; improved;) {
    improved = false;
    for (int i = 1; i + 1 < m; ++i) {
      for (int j = i + 1; j < m; ++j) {
        const int a = order[i - 1], b = order[i], c = order[j], e = order[(j + 1) % m];
        if (d[a][c] + d[b][e] - d[a][b] - d[c][e] < -1e-12) {
          std::reverse(order.begin() + i, order.begin() + j + 1);
          improved = true;
        }
      }
    }
  }
  return order;
}

}  // namespace

std::vector<Eigen::Vector2d> PlanGridPath(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from,
                                          const Eigen::Vector2d& to, GridSearch search) {
  const std::optional<Cell> start = SnapToFree(grid, from);
  const std::optional<Cell> goal = SnapToFree(grid, to);
  if (!start || !goal) return {};
  // Open water between the ends: every shortest cell path lies in their free rectangle, so the
  // shortcut below would keep only its two ends (every segment between centres in a free
  // rectangle is free). The same result without the search: most of a fleet's legs and transits.
  if (grid.RectangleFree(*start, *goal)) {
    if (*start == *goal) return {grid.CenterOf(*start)};
    return {grid.CenterOf(*start), grid.CenterOf(*goal)};
  }
  const std::vector<Cell> cells = AStar(grid, *start, *goal, nullptr, search);
  if (cells.empty()) return {};
  std::vector<Eigen::Vector2d> path;
  path.reserve(cells.size());
  for (const Cell& c : cells) path.push_back(grid.CenterOf(c));
  return RemoveCollinear(Shortcut(grid, path));
}

double GridDistance(const maps::OccupancyGrid& grid, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                    GridSearch search) {
  const std::optional<Cell> start = SnapToFree(grid, from);
  const std::optional<Cell> goal = SnapToFree(grid, to);
  if (!start || !goal) return kInf;
  if (grid.RectangleFree(*start, *goal)) return Octile(goal->x() - start->x(), goal->y() - start->y()).Metres(grid.resolution_m());
  GridSteps cost;
  if (AStar(grid, *start, *goal, &cost, search).empty()) return kInf;
  return cost.Metres(grid.resolution_m());
}

double PathLength(const std::vector<Eigen::Vector2d>& path) {
  double length = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) length += (path[k] - path[k - 1]).norm();
  return length;
}


Tour PlanTour(const maps::OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points) {
  Tour tour;
  const int m = static_cast<int>(points.size());
  if (m == 0) return tour;
  if (m == 1) {
    tour.order = {0};
    tour.legs = {PlanGridPath(grid, points[0], points[0])};
    tour.ok = !tour.legs[0].empty();
    return tour;
  }
  // Pairwise paths; j -> i is i -> j reversed, so the distance matrix is symmetric (the
  // shortcut pass is greedy and could otherwise differ slightly by direction).
  std::vector<std::vector<std::vector<Eigen::Vector2d>>> paths(m, std::vector<std::vector<Eigen::Vector2d>>(m));
  DistanceMatrix d(m, std::vector<double>(m, 0.0));
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) {
      paths[i][j] = PlanGridPath(grid, points[i], points[j]);
      if (paths[i][j].empty()) return tour;  // a valve unreachable: ok = false
      paths[j][i].assign(paths[i][j].rbegin(), paths[i][j].rend());
      d[i][j] = d[j][i] = PathLength(paths[i][j]);
    }
  }
  tour.order = m <= kMaxExactTourSize ? HeldKarpOrder(d) : HeuristicOrder(d);
  for (int i = 0; i < m; ++i) {
    tour.legs.push_back(paths[tour.order[i]][tour.order[(i + 1) % m]]);
  }
  tour.length_m = TourLength(d, tour.order);
  tour.ok = true;
  return tour;
}

}  // namespace sage::agents
