// Fleet inspection tours: k-medoids on grid distance, min-max local search, A* legs (see the
// header for the method, the math and the complexity).
#include "agents/fleet_tour_planner.h"
#include "agents/grid_steps.h"
#include "agents/greedy_match.h"
#include "agents/matching.h"
#include "maps/nearby_points.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace sage::agents {
namespace {
// A named namespace inside the anonymous one: main builds each library as unity batches
// (cmake/SageLibrary.cmake), where this file shares a translation unit with tour_planner.cpp,
// whose anonymous namespace has a kInf of its own.
namespace fleet_tours {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Grid distance (m) between valves with no path between them: finite, so that the search still
// compares tours holding such a pair, and splits them where it has the vehicles to.
constexpr double kUnreachable = 1e9;
constexpr int kExactTourSize = 8;  // Held-Karp per priced tour: 2^7 x 8 x 8 steps at most
constexpr double kTolerance = 1e-9;  // changes smaller than this (s, m) are rounding, not moves
constexpr int kMedoidCandidates = 4;  // members nearest the centroid tried as the next medoid

using Points = std::vector<Eigen::Vector2d>;
using Clock = std::chrono::steady_clock;

// Cell index (i * rows + j, the grid's own order) of x_m, or of the nearest free cell: the first
// Chebyshev ring around x_m's cell that has a free cell, its centre closest to x_m (PlanGridPath's
// rule). -1 if the grid has no free cell.
int SnapCell(const maps::OccupancyGrid& grid, const Eigen::Vector2d& x_m) {
  const Eigen::Vector2i c = grid.CellOf(x_m);
  for (int ring = 0; ring <= std::max(grid.cols(), grid.rows()); ++ring) {
    int best = -1;
    double best_d2 = kInf;
    for (int i = c.x() - ring; i <= c.x() + ring; ++i) {
      const int step = (i == c.x() - ring || i == c.x() + ring) ? 1 : 2 * ring;  // the ring only
      for (int j = c.y() - ring; j <= c.y() + ring; j += std::max(step, 1)) {
        if (grid.Occupied(i, j)) continue;
        const double d2 = (grid.CenterOf({i, j}) - x_m).squaredNorm();
        if (d2 < best_d2) best = i * grid.rows() + j, best_d2 = d2;
      }
    }
    if (best >= 0) return best;
  }
  return -1;
}

// A hash map without a node per entry: open addressing, linear probing, at most half full,
// `empty` the key no entry has. The planner's tables hold up to a million small entries, each
// looked up many times (std::unordered_map and std::map: a cache miss or two and an allocation
// per entry; the pair look-ups alone were 8 % of a 10,000-vehicle split). Hash(key) mixes all 64 bits; the slot is
// its top bits.
template <class Key, class Value, class Hash>
class FlatMap {
 public:
  explicit FlatMap(const Key& empty) : empty_(empty) {}
  // The slot of key's value and whether it was just added (its value then Value{}).
  std::pair<Value*, bool> FindOrAdd(const Key& key) {
    if (2 * (size_ + 1) > slots_.size()) Grow();
    for (std::size_t at = Home(key);; at = (at + 1) & mask_) {
      Slot& slot = slots_[at];
      if (slot.key == key) return {&slot.value, false};
      if (slot.key == empty_) {
        slot.key = key, ++size_;
        return {&slot.value, true};
      }
    }
  }

 private:
  struct Slot {
    Key key;
    Value value;
  };
  std::size_t Home(const Key& key) const { return static_cast<std::size_t>(Hash{}(key) >> shift_); }
  void Grow() {
    std::vector<Slot> old = std::exchange(slots_, std::vector<Slot>(std::max<std::size_t>(64, 2 * slots_.size()), Slot{empty_, Value{}}));
    mask_ = slots_.size() - 1;
    shift_ = 64 - std::countr_zero(slots_.size());
    for (Slot& slot : old) {
      if (slot.key == empty_) continue;
      std::size_t at = Home(slot.key);
      while (!(slots_[at].key == empty_)) at = (at + 1) & mask_;
      slots_[at] = std::move(slot);
    }
  }
  Key empty_;
  std::vector<Slot> slots_;
  std::size_t size_ = 0, mask_ = 0;
  int shift_ = 64;
};

constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ull;  // 2^64 / phi: Fibonacci hashing
struct PairHash {
  std::uint64_t operator()(std::uint64_t key) const { return key * kGolden; }
};
// A set of at most kExactTourSize valves, ascending, padded with -1.
using ValveSet = std::array<int, kExactTourSize>;
struct ValveSetHash {
  std::uint64_t operator()(const ValveSet& set) const {
    std::uint64_t h = 0;
    for (const int v : set) h = (h ^ static_cast<std::uint32_t>(v)) * kGolden;
    return h;
  }
};

// Valve-to-valve grid distances: A* between the valves' cells on the graph and costs of
// PlanGridPath's (8-connected, no corner cutting, octile heuristic, so the cost is exact), ties
// in f to the deeper cell so that open water costs O(L / r) cells; cached per pair. Valves in
// different 4-connected components of the free cells (the same connectivity: a diagonal needs
// both orthogonal cells) are kUnreachable apart without a search.
class ValveDistances {
 public:
  ValveDistances(const maps::OccupancyGrid& grid, const Points& valves, const std::atomic<bool>* cancel = nullptr)
      : cancel_(cancel), grid_(grid), pad_rows_(grid.rows() + 2), r_(grid.resolution_m()), cells_((grid.cols() + 2) * pad_rows_),
        free_(cells_, 0), component_(cells_, -1) {
    // One cell of occupied padding: no bounds checks in the searches.
    for (int i = 0; i < grid.cols(); ++i) {
      for (int j = 0; j < grid.rows(); ++j) free_[(i + 1) * pad_rows_ + j + 1] = !grid.Occupied(i, j);
    }
    for (const Eigen::Vector2d& x : valves) {
      const int cell = SnapCell(grid, x);
      cell_.push_back(cell < 0 ? -1 : (cell / grid.rows() + 1) * pad_rows_ + cell % grid.rows() + 1);
      centre_.push_back(cell < 0 ? x : grid.CenterOf({cell / grid.rows(), cell % grid.rows()}));
      if (cell_.back() >= 0 && component_[cell_.back()] < 0) Label(cell_.back(), cell_.back());
    }
  }

  double operator()(int i, int j) {
    if (cell_[i] < 0 || cell_[j] < 0 || component_[cell_[i]] != component_[cell_[j]]) return kUnreachable;
    if (cell_[i] == cell_[j]) return 0.0;
    const auto key = static_cast<std::uint64_t>(std::min(i, j)) << 32 | static_cast<std::uint32_t>(std::max(i, j));
    const auto [value, added] = cache_.FindOrAdd(key);
    if (added) *value = Search(cell_[std::min(i, j)], cell_[std::max(i, j)]);
    return *value;
  }
  /// Centre of valve i's cell (m): straight lines between centres bound d from below.
  const Eigen::Vector2d& centre(int i) const { return centre_[i]; }

 private:
  struct Step {
    int offset, side_a, side_b;  // to the neighbour; the two cells a diagonal passes (0: none)
    GridSteps cost;
    int dx, dy;  // the neighbour's coordinates less the cell's
  };
  // A grid for one search: cell (x, y) at x * stride + y, free[c] != 0 for a free cell, every
  // cell a path may reach has all eight neighbours in it (a border of blocked cells).
  struct Space {
    const char* free;
    int stride;
    std::uint32_t* stamp;  // g[c] is valid iff stamp[c] == generation_
    GridSteps* g;
  };
  // Padded cells [lo, hi] (inclusive), x the grid's column.
  struct Window {
    Eigen::Vector2i lo, hi;
    bool Contains(const Window& w) const { return (lo.array() <= w.lo.array()).all() && (w.hi.array() <= hi.array()).all(); }
  };

  void Label(int seed, int label) {  // flood fill of seed's component
    std::vector<int> stack{seed};
    component_[seed] = label;
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      for (const int k : {c - 1, c + 1, c - pad_rows_, c + pad_rows_}) {
        if (free_[k] && component_[k] < 0) component_[k] = label, stack.push_back(k);
      }
    }
  }

  // The grid distance between two padded cells: the octile cost at once when their rectangle is
  // free (no shortest path leaves it; most pairs of a field's valves), else by A* in a window of
  // the grid around the pair (the pair's rectangle and a margin of half its longer side), copied
  // out: its search state is a few kB kept between searches, where the whole grid's was 220 MB
  // on the 10,000-vehicle field, made for every plan. The window's answer
  // c0 is a path, so the shortest is no longer; any cell x on a path no longer than c0 has
  // cheb(s, x) + cheb(x, g) <= c0 (octile >= Chebyshev), a box (Reach). If the window holds that
  // box, its search found the shortest; else a search in the box does. Only when no path stays
  // in the first window is the whole grid searched.
  double Search(int start, int goal) {
    const Eigen::Vector2i s(start / pad_rows_, start % pad_rows_), g(goal / pad_rows_, goal % pad_rows_);
    const Eigen::Vector2i one(1, 1);
    if (grid_.RectangleFree(s - one, g - one)) return Octile(g.x() - s.x(), g.y() - s.y()).Metres(r_);
    ThrowIfCancelled();
    const int margin = kWindowMargin + (s - g).cwiseAbs().maxCoeff() / 2;
    const Window first = Clip({s.cwiseMin(g) - margin * one, s.cwiseMax(g) + margin * one});
    if (const std::optional<GridSteps> c0 = WindowAStar(first, start, goal)) {
      const Window reach = Clip(Reach(s, g, *c0));
      if (first.Contains(reach)) return c0->Metres(r_);
      if (const std::optional<GridSteps> c = WindowAStar(reach, start, goal)) return c->Metres(r_);
    }
    if (whole_stamp_.empty()) whole_stamp_.assign(cells_, 0), whole_g_.resize(cells_);  // first need only
    const std::optional<GridSteps> c = AStar({free_.data(), pad_rows_, whole_stamp_.data(), whole_g_.data()}, start, goal);
    return c ? c->Metres(r_) : kUnreachable;  // not reached: the component check comes first
  }

  // The box of cells x with cheb(s, x) + cheb(x, g) <= c (cells), one cell wider each way for
  // c's rounding: per axis |x - s| + |x - g| <= c.
  static Window Reach(const Eigen::Vector2i& s, const Eigen::Vector2i& g, const GridSteps& c) {
    const double length = c.a + kSqrt2 * c.b;
    Window w;
    for (int k = 0; k < 2; ++k) {
      w.lo[k] = static_cast<int>(std::floor((s[k] + g[k] - length) / 2.0)) - 1;
      w.hi[k] = static_cast<int>(std::ceil((s[k] + g[k] + length) / 2.0)) + 1;
    }
    return w;
  }
  Window Clip(Window w) const {
    const Eigen::Vector2i last(static_cast<int>(cells_ / static_cast<std::size_t>(pad_rows_)) - 1, pad_rows_ - 1);
    return {w.lo.cwiseMax(Eigen::Vector2i::Zero()), w.hi.cwiseMin(last)};
  }

  // A* in window w of the padded grid, its cells copied out with a blocked border: the shortest
  // path that stays in w, or none.
  std::optional<GridSteps> WindowAStar(const Window& w, int start, int goal) {
    const int stride = w.hi.y() - w.lo.y() + 3, columns = w.hi.x() - w.lo.x() + 3;
    const auto cells = static_cast<std::size_t>(stride) * static_cast<std::size_t>(columns);
    window_free_.assign(cells, 0);
    if (window_stamp_.size() < cells) window_stamp_.resize(cells, 0), window_g_.resize(cells);
    const auto rows = static_cast<std::size_t>(w.hi.y() - w.lo.y() + 1);
    for (int x = w.lo.x(); x <= w.hi.x(); ++x) {
      std::memcpy(&window_free_[static_cast<std::size_t>(x - w.lo.x() + 1) * stride + 1],
                  &free_[static_cast<std::size_t>(x) * pad_rows_ + w.lo.y()], rows);
    }
    const auto local = [&](int c) { return (c / pad_rows_ - w.lo.x() + 1) * stride + c % pad_rows_ - w.lo.y() + 1; };
    return AStar({window_free_.data(), stride, window_stamp_.data(), window_g_.data()}, local(start), local(goal));
  }

  // Asked at each search and every kPopsBetweenChecks cells of one (a search across a large field
  // pops millions).
  void ThrowIfCancelled() const {
    if (cancel_ != nullptr && cancel_->load(std::memory_order_relaxed)) throw PlanCancelled();
  }
  static constexpr std::uint32_t kPopsBetweenChecks = 1u << 16;
  static constexpr int kWindowMargin = 4;  // cells around a pair's rectangle, besides half its side

  // A* from start to goal on space. A popped cell's coordinates are worked out once and its
  // neighbours' from them, so that the heuristic costs no division (two per neighbour were most
  // of a search's time); an open entry holds its keys and cell only (its exact g is space.g's
  // when it is not stale). A neighbour with the popped cell's own f (a step straight on towards
  // the goal, most steps) goes on a stack that is popped before the heap: the heap holds nothing
  // below that f (the heuristic is consistent), so it is a least-f cell as the heap's would be,
  // without the heap's sifting. Which of equal-f cells comes first changes the path, not its
  // cost, and only the cost is kept.
  std::optional<GridSteps> AStar(const Space& space, int start, int goal) {
    ThrowIfCancelled();
    std::uint32_t pops = 0;
    ++generation_;
    const int stride = space.stride, gx = goal / stride, gy = goal % stride;
    std::array<Step, 8> steps;
    std::size_t n = 0;
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        const bool diagonal = di != 0 && dj != 0;
        if (di != 0 || dj != 0) {
          steps[n++] = {di * stride + dj, diagonal ? di * stride : 0, diagonal ? dj : 0,
                        diagonal ? GridSteps{0, 1} : GridSteps{1, 0}, di, dj};
        }
      }
    }
    const auto passable = [&](int c, const Step& step) {
      return space.free[c + step.offset] && space.free[c + step.side_a] && space.free[c + step.side_b];
    };
    // The open list is ordered on doubles, a + b sqrt 2, where Compare's branches were a fifth of
    // a 10,000-vehicle split: two different costs of at most N steps differ by at least
    // 1 / (N (1 + sqrt 2)) (p^2 - 2 q^2 is a nonzero integer), and each double is within
    // N 2^-52 of its cost, so below N = 3 10^7 steps (any path on a grid of fewer cells; the
    // 10,000-vehicle field's has 1.3 10^7) the order is Compare's exactly: least f first, ties to
    // the deeper cell (beyond, two costs within rounding of each other might swap: the answer
    // could then be a path longer by a rounding error). g stays exact for the answer.
    const auto key = [](const GridSteps& x) { return x.a + kSqrt2 * x.b; };
    const auto later = [](const OpenEntry& x, const OpenEntry& y) { return x.f > y.f || (x.f == y.f && x.g < y.g); };
    open_.clear();  // its capacity stays: no allocation per search
    straight_on_.clear();
    double f_popped = -1.0;
    const auto push = [&](const GridSteps& g, int cell, int x, int y) {
      const OpenEntry entry{key(g + Octile(x - gx, y - gy)), key(g), cell};
      if (entry.f == f_popped) {
        straight_on_.push_back(entry);
        return;
      }
      open_.push_back(entry);
      std::push_heap(open_.begin(), open_.end(), later);
    };
    space.stamp[start] = generation_, space.g[start] = GridSteps{};
    push(GridSteps{}, start, start / stride, start % stride);
    while (!open_.empty() || !straight_on_.empty()) {
      OpenEntry e;
      if (!straight_on_.empty()) {
        e = straight_on_.back();
        straight_on_.pop_back();
      } else {
        std::pop_heap(open_.begin(), open_.end(), later);
        e = open_.back();
        open_.pop_back();
      }
      f_popped = e.f;
      if (++pops % kPopsBetweenChecks == 0) ThrowIfCancelled();
      const GridSteps at = space.g[e.cell];
      if (e.g > key(at)) continue;  // stale entry
      if (e.cell == goal) return at;
      const int x = e.cell / stride, y = e.cell % stride;
      for (const Step& step : steps) {
        const int k = e.cell + step.offset;
        const GridSteps g = at + step.cost;
        if (!passable(e.cell, step) || (space.stamp[k] == generation_ && Compare(g, space.g[k]) >= 0)) continue;
        space.stamp[k] = generation_, space.g[k] = g;
        push(g, k, x + step.dx, y + step.dy);
      }
    }
    return std::nullopt;
  }

  const std::atomic<bool>* cancel_;
  const maps::OccupancyGrid& grid_;
  int pad_rows_;
  double r_;
  std::size_t cells_;
  std::vector<char> free_;  // padded grid: cell (i, j) at (i + 1) * pad_rows_ + j + 1
  std::vector<int> component_;
  // The whole grid's search state, made at the first search no window held (none on most fields).
  std::vector<std::uint32_t> whole_stamp_;
  std::vector<GridSteps> whole_g_;
  std::vector<char> window_free_;  // a window's cells (WindowAStar), kept between searches
  std::vector<std::uint32_t> window_stamp_;
  std::vector<GridSteps> window_g_;
  struct OpenEntry {
    double f, g;      // keys: f = g + h and g, as a + b sqrt 2
    int cell;
  };
  static constexpr double kSqrt2 = 1.4142135623730951;
  std::vector<OpenEntry> open_;  // AStar's open list (a binary heap), kept between searches
  std::vector<OpenEntry> straight_on_;  // AStar's entries at the popped cell's f
  std::uint32_t generation_ = 0;
  std::vector<int> cell_;
  Points centre_;
  // The distances found, by pair key (never 0: two different valves, the smaller index in the
  // high word).
  FlatMap<std::uint64_t, double, PairHash> cache_{0};
};

// The larger side of the points' bounding box (m; at least 1e-6): what a bucket index's cell size
// and its search radii scale with.
double Span(const Points& p) {
  Eigen::Vector2d lo = p[0], hi = p[0];
  for (const Eigen::Vector2d& x : p) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  return std::max((hi - lo).maxCoeff(), 1e-6);
}

// Each valve's `count` nearest other valves in straight line (the search's candidate moves; each
// move is then priced on the grid), nearest first, ties by index. Bucketed: a valve looks at the
// valves within a radius that doubles until it holds `count` of them (all M against all M was
// 1.2e9 distances on a 35,000-valve field).
std::vector<std::vector<int>> NearestValves(const Points& p, int count) {
  const int m = static_cast<int>(p.size());
  std::vector<std::vector<int>> near(m);
  if (m < 2) return near;
  const int want = std::min(count, m - 1);
  const double span = Span(p);
  const double cell = std::max(span * std::sqrt((want + 1.0) / m), 1e-6);  // ~ want valves a cell
  const maps::NearbyPoints index(p, cell);
  std::vector<int> within;
  std::vector<std::pair<double, int>> by_distance;
  for (int v = 0; v < m; ++v) {
    for (double radius = cell;; radius *= 2.0) {
      index.Within(p[v], radius, within);
      by_distance.clear();
      for (int u : within)
        if (u != v) by_distance.emplace_back((p[u] - p[v]).squaredNorm(), u);
      const auto last = by_distance.begin() + std::min<std::size_t>(want, by_distance.size());
      std::partial_sort(by_distance.begin(), last, by_distance.end());
      // Done when the want-th nearest lies well inside the radius (nothing outside is nearer) or
      // the radius holds every valve.
      const bool enough = static_cast<int>(by_distance.size()) >= want &&
                          std::sqrt(by_distance[want - 1].first) < radius * (1.0 - 1e-9);
      if (enough || radius > 2.0 * span) {
        for (auto it = by_distance.begin(); it != last; ++it) near[v].push_back(it->second);
        break;
      }
    }
  }
  return near;
}

// The medoid nearest to v by grid distance: medoids in ascending straight line between cell
// centres (a lower bound of d; ties by index) until that line reaches the best d found. The
// medoids come from a bucket index in bands of doubling radius, so a valve looks at the medoids
// near it and not at all k (35,000 valves x 10,000 medoids a round on a 10,000-vehicle field).
class NearestMedoid {
 public:
  NearestMedoid(ValveDistances& dist, const std::vector<int>& medoids) : dist_(dist), medoids_(medoids) {
    Points at;
    for (int c : medoids) at.push_back(dist.centre(c));
    span_ = Span(at);
    Eigen::Vector2d lo = at[0], hi = at[0];
    for (const Eigen::Vector2d& x : at) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
    centre_ = 0.5 * (lo + hi);
    half_diagonal_ = 0.5 * (hi - lo).norm();
    cell_ = std::max(span_ / std::sqrt(static_cast<double>(at.size())), 1e-6);  // ~1 medoid a cell
    index_.emplace(at, cell_);
  }

  int operator()(int v) {
    const Eigen::Vector2d& x = dist_.centre(v);
    int best = -1;
    double best_d = kInf;
    std::size_t seen = 0;
    for (double lo = 0.0, radius = cell_;; lo = radius, radius *= 2.0) {
      // The band [lo, radius) of straight-line distances, in ascending (line, medoid) order.
      index_->Within(x, radius, within_);
      band_.clear();
      for (int i : within_) {
        const double line = (dist_.centre(medoids_[i]) - x).norm();
        if (line >= lo && line < radius) band_.emplace_back(line, medoids_[i]);
      }
      std::sort(band_.begin(), band_.end());
      seen += band_.size();
      for (const auto& [line, c] : band_) {
        if (line >= best_d) return best;
        const double d = dist_(v, c);
        if (d < best_d) best = c, best_d = d;
      }
      // Every medoid is within |x - centre| + half a diagonal of their box: past that all were
      // looked at (the bound had been 4 spans, 4 um when the medoids coincide: a valve farther
      // than that from them got no medoid at all, an index of -1; found by the scenario fuzzer).
      if (radius >= best_d || seen == medoids_.size() || lo > (x - centre_).norm() + half_diagonal_ + cell_) return best;
    }
  }

 private:
  ValveDistances& dist_;
  const std::vector<int>& medoids_;
  double span_ = 0.0, cell_ = 0.0;
  Eigen::Vector2d centre_ = Eigen::Vector2d::Zero();
  double half_diagonal_ = 0.0;
  std::optional<maps::NearbyPoints> index_;
  std::vector<int> within_;
  std::vector<std::pair<double, int>> band_;
};

double ClosedLength(ValveDistances& dist, const std::vector<int>& order) {
  double length = 0.0;
  for (std::size_t i = 0; i < order.size(); ++i) length += dist(order[i], order[(i + 1) % order.size()]);
  return length;
}

// Held-Karp over the m <= kExactTourSize valves of order (order[0] stays first):
//   C({j}, j) = d(0, j),  C(S, j) = min_{i in S \ {j}} C(S \ {j}, i) + d(i, j),
//   L = min_j C({1..m-1}, j) + d(j, 0).
// Rewrites order optimally and returns L.
double ExactOrder(ValveDistances& dist, std::vector<int>& order) {
  const int m = static_cast<int>(order.size());
  if (m <= 3) return ClosedLength(dist, order);  // one cyclic order up to direction
  // On the stack: a 10,000-vehicle split prices 0.8 million sets, three allocations each before.
  constexpr int kMost = kExactTourSize, kMostCosts = (1 << (kMost - 1)) * (kMost - 1);
  std::array<double, kMost * kMost> d{};
  for (int a = 0; a < m; ++a) {
    for (int b = a + 1; b < m; ++b) d[a * m + b] = d[b * m + a] = dist(order[a], order[b]);
  }
  const int n = m - 1, subsets = 1 << n;
  std::array<double, kMostCosts> cost;
  std::array<int, kMostCosts> parent;
  std::fill_n(cost.begin(), subsets * n, kInf);
  std::fill_n(parent.begin(), subsets * n, -1);
  for (int j = 0; j < n; ++j) cost[(1 << j) * n + j] = d[j + 1];
  for (int set = 1; set < subsets; ++set) {
    for (int j = 0; j < n; ++j) {
      if (!(set >> j & 1) || cost[set * n + j] == kInf) continue;
      for (int k = 0; k < n; ++k) {
        if (set >> k & 1) continue;
        const int grown = set | 1 << k;
        const double c = cost[set * n + j] + d[(j + 1) * m + k + 1];
        if (c < cost[grown * n + k]) cost[grown * n + k] = c, parent[grown * n + k] = j;
      }
    }
  }
  int last = -1;
  double best = kInf;
  for (int j = 0; j < n; ++j) {
    const double c = cost[(subsets - 1) * n + j] + d[(j + 1) * m];
    if (c < best) best = c, last = j;
  }
  std::vector<int> optimal;
  for (int set = subsets - 1; last != -1;) {
    optimal.push_back(order[last + 1]);
    const int previous = parent[set * n + last];
    set &= ~(1 << last);
    last = previous;
  }
  optimal.push_back(order[0]);
  order.assign(optimal.rbegin(), optimal.rend());
  return best;
}

// 2-opt: reverse order[i..j] while delta = d(a, c) + d(b, e) - d(a, b) - d(c, e) < 0
// (a b ... c e -> a c ... b e). Straight lines bound d(a, c) + d(b, e) from below, so a pair is
// priced on the grid only if it could gain: far pairs are the costly searches.
double TwoOpt(ValveDistances& dist, const Points& p, std::vector<int>& order) {
  const int m = static_cast<int>(order.size());
  for (bool improved = m >= 4; improved;) {
    improved = false;
    for (int i = 1; i + 1 < m; ++i) {
      for (int j = i + 1; j < m; ++j) {
        const int a = order[i - 1], b = order[i], c = order[j], e = order[(j + 1) % m];
        if (e == a) continue;  // reversing all but a: the same tour
        const double removed = dist(a, b) + dist(c, e);
        if ((p[a] - p[c]).norm() + (p[b] - p[e]).norm() >= removed - kTolerance) continue;
        if (dist(a, c) + dist(b, e) < removed - kTolerance) {
          std::reverse(order.begin() + i, order.begin() + j + 1);
          improved = true;
        }
      }
    }
  }
  return ClosedLength(dist, order);
}

// A first tour through `valves`: exact if small, else straight-line nearest neighbour + 2-opt.
double FirstOrder(ValveDistances& dist, const Points& p, std::vector<int>& valves) {
  if (static_cast<int>(valves.size()) <= kExactTourSize) return ExactOrder(dist, valves);
  for (std::size_t k = 1; k < valves.size(); ++k) {
    const auto nearest = std::min_element(valves.begin() + k, valves.end(), [&](int a, int b) {
      return (p[a] - p[valves[k - 1]]).squaredNorm() < (p[b] - p[valves[k - 1]]).squaredNorm();
    });
    std::iter_swap(valves.begin() + k, nearest);
  }
  return TwoOpt(dist, p, valves);
}

double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Per point a value >= 0, with the sum and the largest of every power-of-two run of points kept
// up to date on each change (O(log m)), so that a draw in proportion to the values walks down
// from the root.
class DrawTree {
 public:
  explicit DrawTree(int m) : leaves_(static_cast<int>(std::bit_ceil(static_cast<unsigned>(std::max(m, 1))))) {
    sum_.assign(2 * static_cast<std::size_t>(leaves_), 0.0);
    max_.assign(2 * static_cast<std::size_t>(leaves_), 0.0);
  }
  void Set(int v, double value) {
    int i = leaves_ + v;
    sum_[i] = max_[i] = value;
    for (i /= 2; i >= 1; i /= 2) sum_[i] = sum_[2 * i] + sum_[2 * i + 1], max_[i] = std::max(max_[2 * i], max_[2 * i + 1]);
  }
  double Total() const { return sum_[1]; }
  double Largest() const { return max_[1]; }
  // The point whose run of the cumulative sum holds `draw` (0 <= draw < Total()).
  int Find(double draw) const {
    int i = 1;
    while (i < leaves_) {
      if (draw < sum_[2 * i]) {
        i = 2 * i;
      } else {
        draw -= sum_[2 * i], i = 2 * i + 1;
      }
    }
    return i - leaves_;
  }

 private:
  int leaves_;
  std::vector<double> sum_, max_;
};

// k-means++ seeding: the first medoid at random, each next one drawn with probability in
// proportion to its squared straight-line distance d^2 to the nearest medoid so far. A new medoid
// lowers d^2 only for the valves nearer to it than the largest d^2 of all, which shrinks as
// medoids are drawn: those are looked up in the valves' spatial index, and the draw walks a
// DrawTree of d^2. Every valve against every medoid had been 10,000 x 35,000 x 2 steps on the
// generated 10,000-vehicle field (0.7 s of its split). The same medoids as that scan but for
// rounding of the sums (the tree adds in another order).
std::vector<int> SeedMedoids(const Points& p, int k, std::mt19937_64& rng) {
  const int m = static_cast<int>(p.size());
  std::vector<int> medoids;
  std::vector<char> is_medoid(m, 0);
  std::vector<double> d2(m, kInf);
  DrawTree tree(m);
  const double span = Span(p);
  const maps::NearbyPoints index(p, std::max(span * std::sqrt(4.0 / m), 1e-6));  // ~ four valves a cell
  std::vector<int> near;
  int first_free = 0;
  for (int next = static_cast<int>(rng() % m);;) {
    medoids.push_back(next);
    is_medoid[next] = 1;
    if (static_cast<int>(medoids.size()) == k) break;
    if (medoids.size() == 1) {  // every d^2 is still infinite: every valve
      near.resize(m);
      for (int v = 0; v < m; ++v) near[v] = v;
    } else {
      index.Within(p[next], std::sqrt(tree.Largest()), near);
    }
    for (int v : near) {
      const double d = is_medoid[v] ? 0.0 : (p[v] - p[next]).squaredNorm();
      if (d < d2[v]) d2[v] = d, tree.Set(v, d);
    }
    const double total = tree.Total();
    const double draw = Uniform01(rng) * total;
    if (total > 0.0) {
      // Rounding may walk past the last valve with d^2 > 0, or onto a 0: the nearest one with d^2 > 0.
      const int found = std::min(tree.Find(draw), m - 1);
      const auto drawable = [&](int v) { return !is_medoid[v] && d2[v] > 0.0; };
      next = -1;
      for (int v = found; v >= 0 && next < 0; --v) next = drawable(v) ? v : -1;
      for (int v = found + 1; v < m && next < 0; ++v) next = drawable(v) ? v : -1;
      if (next >= 0) continue;
    }
    while (is_medoid[first_free]) ++first_free;  // coincident valves (total 0): the first free one
    next = first_free;
  }
  return medoids;
}

// k-medoids on grid distance with k-means++ seeding (header, step 1). Returns the clusters.
std::vector<std::vector<int>> Cluster(ValveDistances& dist, const Points& p, int k, int iterations,
                                      std::mt19937_64& rng) {
  const int m = static_cast<int>(p.size());
  std::vector<int> medoids = SeedMedoids(p, k, rng);
  std::vector<char> is_medoid(m, 0);
  for (int v : medoids) is_medoid[v] = 1;
  std::vector<int> label(m), cluster_of(m, -1);
  std::vector<std::vector<int>> clusters(k);
  for (int round = 1;; ++round) {
    for (int c = 0; c < k; ++c) cluster_of[medoids[c]] = c;
    NearestMedoid nearest(dist, medoids);
    for (int v = 0; v < m; ++v) label[v] = cluster_of[is_medoid[v] ? v : nearest(v)];
    for (auto& cluster : clusters) cluster.clear();
    for (int v = 0; v < m; ++v) clusters[label[v]].push_back(v);
    if (round >= iterations) break;
    bool moved = false;
    for (int c = 0; c < k; ++c) {
      const std::vector<int>& members = clusters[c];
      Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
      for (int v : members) centroid += p[v] / static_cast<double>(members.size());
      std::vector<int> candidates = members;
      const auto by_centroid = [&](int a, int b) {  // ties by index: the same order on every library
        return std::pair((p[a] - centroid).squaredNorm(), a) < std::pair((p[b] - centroid).squaredNorm(), b);
      };
      const std::size_t tried = std::min<std::size_t>(kMedoidCandidates, candidates.size());
      std::partial_sort(candidates.begin(), candidates.begin() + tried, candidates.end(), by_centroid);
      candidates.resize(tried);
      candidates.push_back(medoids[c]);
      int best = medoids[c];
      double best_cost = kInf;
      for (int candidate : candidates) {
        double cost = 0.0;
        for (int v : members) cost += dist(candidate, v);
        if (cost < best_cost - kTolerance || (cost <= best_cost + kTolerance && candidate == medoids[c])) {
          best = candidate, best_cost = cost;
        }
      }
      if (best != medoids[c]) {
        is_medoid[medoids[c]] = 0, is_medoid[best] = 1, medoids[c] = best;
        moved = true;
      }
    }
    if (!moved) break;
  }
  return clusters;
}

// The min-max acceptance rule on the laps of the tours a change touches (header, step 3).
bool Better(double new_max, double new_sum, double old_max, double old_sum) {
  return new_max < old_max - kTolerance || (new_max <= old_max && new_sum < old_sum - kTolerance);
}

// The search state: per vehicle its valves in visiting order and that tour's grid length (m).
struct Tours {
  std::vector<std::vector<int>> order;
  std::vector<double> length;
  std::vector<int> owner;             // valve -> vehicle
  std::vector<std::uint64_t> version;  // a new number whenever the tour changes
};

// Min-max local search, split-merge and kicks (header, steps 3 and 4).
class Search {
 public:
  Search(ValveDistances& dist, const Points& p, const std::vector<FleetVehicle>& vehicles, double wait_s,
         const Eigen::VectorXd& weights, const FleetTourOptions& options, std::mt19937_64& rng)
      : dist_(dist), p_(p), near_(NearestValves(p, std::max(1, options.neighbours))), vehicles_(vehicles),
        wait_s_(wait_s), risk_share_(options.risk_share),
        mass_(weights.sum() > 0.0 ? Eigen::VectorXd(weights / weights.sum()) : weights), rng_(rng),
        deadline_(options.time_budget_s > 0.0
                      ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(options.time_budget_s))
                      : Clock::time_point::max()),
        merges_(vehicles.size()) {}

  void Run(Tours& s, int rounds) {
    std::vector<int> all(s.order.size());
    for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
    std::stable_sort(all.begin(), all.end(), [&](int a, int b) { return Lap(s, a) > Lap(s, b); });
    Settle(s, {all.begin(), all.end()});
    auto [best_max, best_sum] = Key(s);
    undo_.saved.assign(s.order.size(), 0);
    for (int round = 0; round < rounds && !OutOfTime(); ++round) {
      undo_.Begin();
      int from = Longest(s);
      std::deque<int> touched{from};
      for (int step = 0; step < 2 && s.order[from].size() > 1; ++step) {  // a chain of two moves
        const int v = s.order[from][rng_() % s.order[from].size()];
        const auto near = Neighbours(s, v);
        if (near.empty()) break;
        const int to = near[rng_() % near.size()].second;
        Apply(s, from, Edit(Of(s, from), v, -1));
        Apply(s, to, Edit(Of(s, to), -1, v));
        touched.push_back(to);
        from = to;
      }
      Settle(s, touched);
      const auto [max, sum] = Key(s);
      if (Better(max, sum, best_max, best_sum)) {
        best_max = max, best_sum = sum;
      } else {
        undo_.Restore(s);
      }
    }
    undo_ = {};
  }

  // The lap the search balances (vehicle k flying a tour of length_m through `order`): travel and
  // waits, times 1 + beta n W for a share holding W of the field's risk
  // (FleetTourOptions::risk_share; beta = 0: the lap itself).
  double Lap(int k, double length_m, const std::vector<int>& order) const {
    const double lap = length_m / vehicles_[k].speed_mps + wait_s_;
    if (risk_share_ <= 0.0) return lap;
    double mass = 0.0;
    for (int v : order) mass += mass_[v];
    return lap * (1.0 + risk_share_ * static_cast<double>(vehicles_.size()) * mass);
  }

 private:
  struct Candidate {
    std::vector<int> order;
    double length = 0.0;
  };
  struct Merge {
    double lap = kInf;  // of u after the merge
    int u = -1;
    std::uint64_t t_version = 0, u_version = 0;
  };
  double Lap(int k, const Candidate& c) const { return Lap(k, c.length, c.order); }
  double Lap(const Tours& s, int k) const { return Lap(k, s.length[k], s.order[k]); }
  bool OutOfTime() const { return Clock::now() > deadline_; }
  static Candidate Of(const Tours& s, int k) { return {s.order[k], s.length[k]}; }
  int Longest(const Tours& s) const {
    int longest = 0;
    for (int k = 1; k < static_cast<int>(s.order.size()); ++k) longest = Lap(s, k) > Lap(s, longest) ? k : longest;
    return longest;
  }
  std::pair<double, double> Key(const Tours& s) const {
    double max = 0.0, sum = 0.0;
    for (std::size_t k = 0; k < s.order.size(); ++k) max = std::max(max, Lap(s, k)), sum += Lap(s, k);
    return {max, sum};
  }

  // (valve u, its tour) for each of v's K nearest valves held by another tour.
  std::vector<std::pair<int, int>> Neighbours(const Tours& s, int v) const {
    std::vector<std::pair<int, int>> out;
    for (int u : near_[v]) {
      if (s.owner[u] != s.owner[v]) out.emplace_back(u, s.owner[u]);
    }
    return out;
  }

  // The shortest closed tour through a set of at most kExactTourSize valves, memoised by the set:
  // the search prices the same few sets again and again (1.9 million times, 0.8 million sets, on
  // the 10,000-vehicle field). A set's tour is kept in exact_ (the set, its tour as positions in
  // it); exact_index_ maps the set's 64-bit hash to the last tour kept with it, whose `next`
  // holds the one before: 16 bytes a set in the table (a std::map of vectors had ~150 and two
  // allocations).
  Candidate Exact(std::vector<int> order) {
    if (static_cast<int>(order.size()) > kExactTourSize) throw std::logic_error("fleet tours: an exact tour of over 8 valves");
    KeptTour tour;
    tour.valves.fill(-1);
    std::copy(order.begin(), order.end(), tour.valves.begin());
    const auto size = static_cast<std::ptrdiff_t>(order.size());
    std::sort(tour.valves.begin(), tour.valves.begin() + size);
    const auto [last, added] = exact_index_.FindOrAdd(ValveSetHash{}(tour.valves) | 1);  // never 0, the empty key
    if (added) *last = kNoTour;  // no tour with this hash yet (so also if ExactOrder throws below)
    for (std::uint32_t k = *last; k != kNoTour; k = exact_[k].next) {
      if (exact_[k].valves == tour.valves) return Unpack(exact_[k], size);
    }
    tour.length = ExactOrder(dist_, order);
    for (std::ptrdiff_t i = 0; i < size; ++i) {
      tour.order[i] = static_cast<std::uint8_t>(
          std::lower_bound(tour.valves.begin(), tour.valves.begin() + size, order[i]) - tour.valves.begin());
    }
    tour.next = *last;
    *last = static_cast<std::uint32_t>(exact_.size());
    exact_.push_back(tour);
    return {std::move(order), tour.length};
  }

  // c without `remove` and with `add` (-1: none), priced exactly if it has at most
  // kExactTourSize valves, else by the removal gain d(p, n) - d(p, v) - d(v, n) and the cheapest
  // insertion d(x, u) + d(u, y) - d(x, y) over its edges (x, y).
  Candidate Edit(Candidate c, int remove, int add) {
    if (remove >= 0) {
      const auto it = std::find(c.order.begin(), c.order.end(), remove);
      const int m = static_cast<int>(c.order.size()), at = static_cast<int>(it - c.order.begin());
      const int prev = c.order[(at + m - 1) % m], next = c.order[(at + 1) % m];
      c.length += dist_(prev, next) - dist_(prev, remove) - dist_(remove, next);
      c.order.erase(it);
    }
    const int m = static_cast<int>(c.order.size());
    if (add >= 0 && m >= kExactTourSize) {
      // Positions by the straight-line lower bound of their cost, priced on the grid until the
      // bound passes the best: a far edge is never searched.
      std::vector<std::pair<double, int>> bounds;
      for (int q = 0; q < m; ++q) {
        const int x = c.order[q], y = c.order[(q + 1) % m];
        bounds.emplace_back((p_[x] - p_[add]).norm() + (p_[add] - p_[y]).norm() - dist_(x, y), q);
      }
      std::sort(bounds.begin(), bounds.end());
      double best = kInf;
      int at = 0;
      for (const auto& [bound, q] : bounds) {
        if (bound >= best) break;
        const int x = c.order[q], y = c.order[(q + 1) % m];
        const double cost = dist_(x, add) + dist_(add, y) - dist_(x, y);
        if (cost < best) best = cost, at = q + 1;
      }
      c.order.insert(c.order.begin() + at, add);
      c.length += best;
    } else if (add >= 0) {
      c.order.push_back(add);
    }
    return static_cast<int>(c.order.size()) <= kExactTourSize ? Exact(std::move(c.order)) : c;
  }

  void Apply(Tours& s, int k, Candidate c) {
    if (static_cast<int>(c.order.size()) > kExactTourSize) c.length = TwoOpt(dist_, p_, c.order);
    undo_.Keep(s, k);
    s.version[k] = ++versions_;
    for (int v : c.order) s.owner[v] = k;
    s.order[k] = std::move(c.order);
    s.length[k] = c.length;
  }

  // Whether changing tours ks to tours of these laps passes the rule.
  bool Passes(const Tours& s, std::initializer_list<int> ks, std::span<const double> new_laps) const {
    double old_max = 0.0, old_sum = 0.0, new_max = 0.0, new_sum = 0.0;
    auto lap = new_laps.begin();
    for (auto k = ks.begin(); k != ks.end(); ++k, ++lap) {
      old_max = std::max(old_max, Lap(s, *k)), old_sum += Lap(s, *k);
      new_max = std::max(new_max, *lap), new_sum += *lap;
    }
    return Better(new_max, new_sum, old_max, old_sum);
  }
  bool Passes(const Tours& s, std::initializer_list<int> ks, std::initializer_list<double> new_laps) const {
    return Passes(s, ks, std::span<const double>(new_laps.begin(), new_laps.size()));
  }

  // Applies the change of tours ks to cs if it passes the rule; 2-opt only shortens, so a change
  // that passed on its price stays an improvement.
  bool Try(Tours& s, std::initializer_list<int> ks, std::initializer_list<Candidate> cs) {
    std::array<double, 3> laps{};  // a move or swap changes two tours, a split-merge three
    if (ks.size() > laps.size()) throw std::logic_error("fleet tours: a change of more than three tours");
    auto c = cs.begin();
    for (std::size_t i = 0; i < ks.size(); ++i, ++c) laps[i] = Lap(ks.begin()[i], *c);
    if (!Passes(s, ks, {laps.data(), ks.size()})) return false;
    c = cs.begin();
    for (auto k = ks.begin(); k != ks.end(); ++k, ++c) Apply(s, *k, *c);
    return true;
  }

  // Takes the first improving move or swap of one of tour a's valves; returns the other tour
  // changed, -1 if none improves. A tour is never emptied.
  int Improve(Tours& s, int a) {
    const std::vector<int> members = s.order[a];
    for (int v : members) {
      std::vector<int> tried;
      for (const auto& [u, b] : Neighbours(s, v)) {
        if (s.order[a].size() > 1 && std::find(tried.begin(), tried.end(), b) == tried.end()) {
          tried.push_back(b);
          if (Try(s, {a, b}, {Edit(Of(s, a), v, -1), Edit(Of(s, b), -1, v)})) return b;
        }
        if (Try(s, {a, b}, {Edit(Of(s, a), v, u), Edit(Of(s, b), u, v)})) return b;
      }
    }
    return -1;
  }

  // Split-merge: moves and swaps cannot change how many vehicles share a group of valves (a
  // tour is never emptied). Tour t merges into a neighbouring tour u, and its vehicle takes part
  // of the longest tour a (the best of every bipartition if a is small, else of 8 cuts of its
  // order into halves); taken by the rule on {a, t, u}. The t are tried cheapest merge first.
  bool SplitMerge(Tours& s, std::deque<int>& touched) {
    const int a = Longest(s), m = static_cast<int>(s.order[a].size());
    if (m < 2) return false;
    std::vector<std::pair<Candidate, Candidate>> splits;  // (stays with a, goes to t), on first need
    const auto add_split = [&](const std::vector<int>& x, const std::vector<int>& y) {
      const auto price = [&](std::vector<int> part) {
        if (static_cast<int>(part.size()) <= kExactTourSize) return Exact(std::move(part));
        const double length = TwoOpt(dist_, p_, part);
        return Candidate{std::move(part), length};
      };
      splits.emplace_back(price(x), price(y));
      splits.emplace_back(splits.back().second, splits.back().first);
    };
    const auto make_splits = [&] {
      const std::vector<int>& order = s.order[a];
      for (int mask = 1; m <= kExactTourSize && mask < 1 << (m - 1); ++mask) {  // order[m - 1] in y: each once
        std::vector<int> x, y;
        for (int q = 0; q < m; ++q) (mask >> q & 1 ? x : y).push_back(order[q]);
        add_split(x, y);
      }
      for (int cut = 0; m > kExactTourSize && cut < 8; ++cut) {
        std::vector<int> rotated(order.begin() + cut * m / 8, order.end());
        rotated.insert(rotated.end(), order.begin(), order.begin() + cut * m / 8);
        add_split({rotated.begin(), rotated.begin() + m / 2}, {rotated.begin() + m / 2, rotated.end()});
      }
    };
    std::vector<std::pair<double, int>> by_merge;  // tours t whose merge keeps u below a's lap
    const double lap_a = Lap(s, a);
    for (int t = 0; t < static_cast<int>(s.order.size()); ++t) {
      if (t != a && BestMerge(s, t).lap < lap_a && merges_[t].u != a) by_merge.emplace_back(merges_[t].lap, t);
    }
    std::sort(by_merge.begin(), by_merge.end());
    // A t's lap depends on it only through its vehicle's speed, so the best split of a is found
    // once per speed; and the merged u's lap is the cached merge's, priced by the same edits. So
    // the rule is checked from laps known already, and a merge is built only where it passes
    // (most listed t do not: every kick's settling ends with a call that finds none).
    std::vector<std::pair<double, std::size_t>> best_split;  // (speed, index in splits)
    for (const auto& [lap, t] : by_merge) {
      const int u = merges_[t].u;
      if (splits.empty()) make_splits();
      const double speed = vehicles_[t].speed_mps;
      auto known = std::find_if(best_split.begin(), best_split.end(), [&](const auto& e) { return e.first == speed; });
      if (known == best_split.end()) {
        const auto best = std::min_element(splits.begin(), splits.end(), [&, t = t](const auto& x, const auto& y) {
          return std::max(Lap(a, x.first), Lap(t, x.second)) < std::max(Lap(a, y.first), Lap(t, y.second));
        });
        known = best_split.insert(best_split.end(), {speed, static_cast<std::size_t>(best - splits.begin())});
      }
      const auto best = splits.begin() + static_cast<std::ptrdiff_t>(known->second);
      if (!Passes(s, {a, t, u}, {Lap(a, best->first), Lap(t, best->second), lap})) continue;
      Candidate merged = Of(s, u);
      for (int v : s.order[t]) merged = Edit(std::move(merged), -1, v);
      if (Try(s, {a, t, u}, {best->first, best->second, merged})) {
        touched = {a, t, u};
        return true;
      }
    }
    return false;
  }

  // Tour t's cheapest merge into a neighbouring tour u (lowest lap of u after it), cached until
  // either tour changes. Only small tours merge: two large ones would make a far longer one.
  const Merge& BestMerge(const Tours& s, int t) {
    Merge& e = merges_[t];
    if (e.u >= 0 && e.t_version == s.version[t] && e.u_version == s.version[e.u]) return e;
    e = Merge{};
    for (int v : s.order[t]) {
      for (const auto& [w, u] : Neighbours(s, v)) {
        if (u == e.u || std::max(s.order[t].size(), s.order[u].size()) > kExactTourSize) continue;
        Candidate merged = Of(s, u);
        for (int x : s.order[t]) merged = Edit(std::move(merged), -1, x);
        if (Lap(u, merged) < e.lap) e = {Lap(u, merged), u, s.version[t], s.version[u]};
      }
    }
    return e;
  }

  // Local search from the queued tours, then split-merge on the longest tour while it helps.
  void Settle(Tours& s, std::deque<int> queue) {
    do {
      std::vector<char> queued(s.order.size(), 0);
      for (int k : queue) queued[k] = 1;
      while (!queue.empty() && !OutOfTime()) {
        const int a = queue.front();
        queue.pop_front();
        queued[a] = 0;
        const int b = Improve(s, a);
        if (b < 0) continue;
        for (int k : {a, b}) {
          if (!queued[k]) queued[k] = 1, queue.push_back(k);
        }
      }
    } while (!OutOfTime() && SplitMerge(s, queue));
  }

  ValveDistances& dist_;
  const Points& p_;
  std::vector<std::vector<int>> near_;
  const std::vector<FleetVehicle>& vehicles_;
  double wait_s_;
  double risk_share_;
  Eigen::VectorXd mass_;  // each valve's share of the field's risk (sums to 1)
  std::mt19937_64& rng_;
  Clock::time_point deadline_;
  static constexpr std::uint32_t kNoTour = 0xFFFFFFFFu;
  struct KeptTour {
    ValveSet valves;                            // ascending, -1 after the last
    std::array<std::uint8_t, kExactTourSize> order{};  // the tour, as positions in valves
    std::uint32_t next = kNoTour;               // the tour kept before it with the same hash
    double length = 0.0;
  };
  static Candidate Unpack(const KeptTour& tour, std::ptrdiff_t size) {
    Candidate c{std::vector<int>(static_cast<std::size_t>(size)), tour.length};
    for (std::ptrdiff_t i = 0; i < size; ++i) c.order[static_cast<std::size_t>(i)] = tour.valves[tour.order[i]];
    return c;
  }
  // The tours a kick's round changed, as they were before it, so that a round that does not pass
  // gives back those few tours (and their valves' owner). It had copied every tour each round to
  // keep the best (10,000 vectors a round, 200 rounds: 0.6 s of the 10,000-vehicle split's 6).
  struct Undo {
    std::vector<char> saved;  // by tour: kept this round (empty: outside the kicks, nothing kept)
    std::vector<int> tours;
    std::vector<Candidate> before;
    std::vector<std::uint64_t> versions;
    void Begin() {
      for (int k : tours) saved[k] = 0;
      tours.clear(), before.clear(), versions.clear();
    }
    void Keep(const Tours& s, int k) {
      if (saved.empty() || saved[k]) return;
      saved[k] = 1;
      tours.push_back(k), before.push_back(Of(s, k)), versions.push_back(s.version[k]);
    }
    // Every valve whose owner the round changed left a kept tour, so setting the owners of the
    // kept tours' valves restores every owner.
    void Restore(Tours& s) {
      for (std::size_t i = 0; i < tours.size(); ++i) {
        const int k = tours[i];
        s.order[k] = std::move(before[i].order), s.length[k] = before[i].length, s.version[k] = versions[i];
      }
      for (int k : tours) {
        for (int v : s.order[k]) s.owner[v] = k;
      }
    }
  };
  Undo undo_;
  std::vector<KeptTour> exact_;
  FlatMap<std::uint64_t, std::uint32_t, PairHash> exact_index_{0};
  std::vector<Merge> merges_;
  std::uint64_t versions_ = 0;
};

// Cluster c -> vehicle, minimising the sum of squared straight-line approach times (the
// Hungarian method, agents/matching.h): a vehicle sent across a crowded field meets every other
// tour on its way, and greedy matching leaves the last vehicles the farthest clusters. Squared,
// because where vehicles and valves are spread unevenly the plain sum is as happy to send one
// vehicle 330 m (a tour unvisited for 8 minutes, measured on a generated 1,000-vehicle field) as a
// chain of vehicles a few metres each. Beyond kHungarianMax clusters (1,000 vehicles: ~1e9 steps)
// by recursive bisection into parts of at most kMatchLeaf clusters, each matched exactly, or with
// spare vehicles (more vehicles than valves) greedily, shortest pair first.
constexpr int kHungarianMax = 1200;
constexpr int kMatchLeaf = 256;

std::vector<int> Match(const Points& centroids, const std::vector<FleetVehicle>& vehicles) {
  const int n = static_cast<int>(centroids.size()), m = static_cast<int>(vehicles.size());  // n <= m
  const auto cost = [&](int c, int k) {
    return (centroids[c] - vehicles[k].position_m).squaredNorm() / (vehicles[k].speed_mps * vehicles[k].speed_mps);
  };
  if (n <= kHungarianMax) return MinCostMatch(n, m, cost);
  std::vector<Eigen::Vector2d> at;
  double fastest = 0.0;
  for (const FleetVehicle& vehicle : vehicles) {
    at.push_back(vehicle.position_m);
    fastest = std::max(fastest, vehicle.speed_mps);
  }
  // With spare vehicles each cluster finds a free one near it, and shortest pair first does
  // better than bisection's quantiles (measured 1.3-1.45x the optimum against 1.5-2.2x).
  if (n < m) return GreedyMatchNear(centroids, at, fastest, cost);
  return BisectedMatch(centroids, at, cost, kMatchLeaf);
}

// The mean position of a share's valves (m); the origin for an empty share.
Eigen::Vector2d Centroid(const std::vector<int>& share, const Points& valves_m) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int v : share) sum += valves_m[v];
  return sum / static_cast<double>(std::max<std::size_t>(1, share.size()));
}

// The search moves valves between tours wherever that shortens the longest lap, so a tour can end
// far from the vehicle it was matched to (on a generated 1,000-vehicle field, 330 m: a tour
// unwatched for 8 minutes): the tours as they came out go to the vehicles again (each tour's
// order, indexed by vehicle). Up to kHungarianMax tours, first on the time by which each vehicle
// has seen every valve of its tour once: its straight-line approach to the tour's nearest valve,
// then one lap, at its speed. The longest such time over the fleet is made least (a bottleneck
// assignment), then among the assignments within it the squared approaches to the tours'
// centroids are (Match's cost), and a tour goes only to a vehicle that flies it within the
// search's longest lap, so the plan's objective stands. Matched per speed and on the centroids
// alone (as above that size still), a 100-vehicle generated field of three speeds sent one
// vehicle 31 m to a region whose last valve then waited 68.7 s for its first look, twice the
// tours' worst gap (its approach 42.7 s; matched so, the fleet's longest approach is 19.7 s and
// the field's longest gap 42.5 s). It costs the 1,000-vehicle split 0.26 s (0.40 -> 0.66 s).
// The longest lap as the search priced it (with beta's risk factor) stands; the sum of the laps,
// the search's tie-break, and the plan's unweighted max_lap_s may rise by a tour's move to a
// slower vehicle within it. s's orders are moved into the result.
std::vector<std::vector<int>> Rematch(Tours& s, const Search& search, const Points& valves_m,
                                      const std::vector<FleetVehicle>& vehicles, double wait_per_lap_s) {
  const int n = static_cast<int>(vehicles.size());
  Points centroids;
  for (int t = 0; t < n; ++t) centroids.push_back(Centroid(s.order[t], valves_m));
  std::vector<std::vector<int>> orders(n);
  if (n > kHungarianMax) {  // among vehicles of one speed (a lap was balanced for its vehicle's speed)
    std::map<double, std::vector<int>> by_speed;
    for (int k = 0; k < n; ++k) by_speed[vehicles[k].speed_mps].push_back(k);
    for (const auto& [speed, group] : by_speed) {
      Points finals;
      std::vector<FleetVehicle> fleet;
      for (int k : group) finals.push_back(centroids[k]), fleet.push_back(vehicles[k]);
      const std::vector<int> rematch = Match(finals, fleet);
      for (std::size_t g = 0; g < group.size(); ++g) orders[group[rematch[g]]] = std::move(s.order[group[g]]);
    }
    return orders;
  }
  double longest_lap = 0.0;
  for (int k = 0; k < n; ++k) longest_lap = std::max(longest_lap, search.Lap(k, s.length[k], s.order[k]));
  // first[t n + k]: vehicle k's first sight of every valve of tour t (s); infinite where k would
  // fly t beyond the longest lap.
  std::vector<double> first(static_cast<std::size_t>(n) * n, kInf);
  for (int t = 0; t < n; ++t) {
    for (int k = 0; k < n; ++k) {
      if (search.Lap(k, s.length[t], s.order[t]) > longest_lap + kTolerance) continue;
      const FleetVehicle& vehicle = vehicles[k];
      double nearest2 = kInf;
      for (int v : s.order[t]) nearest2 = std::min(nearest2, (valves_m[v] - vehicle.position_m).squaredNorm());
      const double travel_m = std::sqrt(nearest2) + s.length[t];  // approach, then one lap
      first[static_cast<std::size_t>(t) * n + k] = travel_m / vehicle.speed_mps + wait_per_lap_s;
    }
  }
  const auto first_of = [&](int t, int k) { return first[static_cast<std::size_t>(t) * n + k]; };
  // Finite when every position is: each tour's own vehicle is within the longest lap. A vehicle
  // reported at no finite place leaves the tours with the vehicles the search gave them.
  const double bound = BottleneckBound(n, n, first_of);
  if (!std::isfinite(bound)) return std::move(s.order);
  const std::vector<int> vehicle_of = MinCostMatch(n, n, [&](int t, int k) {
    if (!(first_of(t, k) <= bound)) return kMaxMatchCost;
    const double speed2 = vehicles[k].speed_mps * vehicles[k].speed_mps;
    return (centroids[t] - vehicles[k].position_m).squaredNorm() / speed2;
  });
  for (int t = 0; t < n; ++t) orders[vehicle_of[t]] = std::move(s.order[t]);
  return orders;
}

FleetTourPlan Plan(const maps::OccupancyGrid& grid, const Points& valves_m, const Eigen::VectorXd& weights,
                   const std::vector<FleetVehicle>& vehicles, double wait_per_lap_s, const FleetTourOptions& options) {
  const int m = static_cast<int>(valves_m.size()), n = static_cast<int>(vehicles.size());
  if (m == 0 || n == 0) throw std::invalid_argument("PlanFleetTours: needs at least one valve and one vehicle");
  if (weights.size() != m || !weights.allFinite() || (weights.array() < 0.0).any()) {
    throw std::invalid_argument("PlanFleetTours: one finite weight >= 0 per valve");
  }
  for (const FleetVehicle& vehicle : vehicles) {
    if (!(vehicle.speed_mps > 0.0) || !std::isfinite(vehicle.speed_mps)) {
      throw std::invalid_argument("PlanFleetTours: vehicle speeds must be finite and > 0");
    }
  }
  if (!(wait_per_lap_s >= 0.0) || !std::isfinite(wait_per_lap_s)) {
    throw std::invalid_argument("PlanFleetTours: wait_per_lap_s must be finite and >= 0");
  }
  if (!(options.weight_exponent >= 0.0) || !std::isfinite(options.weight_exponent)) {
    throw std::invalid_argument("PlanFleetTours: weight_exponent must be finite and >= 0");
  }
  ValveDistances dist(grid, valves_m, options.cancel);
  Points centres;  // the search works on the cells' centres, where d is measured
  for (int v = 0; v < m; ++v) centres.push_back(dist.centre(v));
  std::mt19937_64 rng(options.seed);
  std::vector<std::vector<int>> clusters;
  if (n < m) {
    clusters = Cluster(dist, centres, n, std::max(1, options.medoid_iterations), rng);
  } else {
    for (int v = 0; v < m; ++v) clusters.push_back({v});
  }
  Points centroids;
  for (const auto& cluster : clusters) centroids.push_back(Centroid(cluster, valves_m));
  const std::vector<int> vehicle_of = Match(centroids, vehicles);
  Tours s{std::vector<std::vector<int>>(n), std::vector<double>(n, 0.0), std::vector<int>(m, -1),
          std::vector<std::uint64_t>(n, 0)};
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const int k = vehicle_of[c];
    s.order[k] = clusters[c];
    s.length[k] = FirstOrder(dist, centres, s.order[k]);
    for (int v : s.order[k]) s.owner[v] = k;
  }
  if (n < m) {
    Search search(dist, centres, vehicles, wait_per_lap_s, weights, options, rng);
    search.Run(s, std::max(0, options.perturbation_rounds));
    s.order = Rematch(s, search, valves_m, vehicles, wait_per_lap_s);
  }  // else each valve has a vehicle of its own, and the vehicles left over none: in reserve

  FleetTourPlan plan;
  plan.ok = true;
  for (int k = 0; k < n; ++k) {
    if (s.order[k].empty()) {  // in reserve
      ++plan.reserve;
      plan.vehicles.emplace_back().tour.ok = true;
      continue;
    }
    std::vector<int> order = s.order[k];
    std::rotate(order.begin(), std::min_element(order.begin(), order.end()), order.end());
    VehicleTour out;
    out.valves = order;
    std::sort(out.valves.begin(), out.valves.end());
    const int size = static_cast<int>(order.size());
    out.tour.ok = true;
    for (int q = 0; q < size; ++q) {
      const int from = order[q], to = order[(q + 1) % size];
      out.tour.order.push_back(static_cast<int>(std::lower_bound(out.valves.begin(), out.valves.end(), from) -
                                                out.valves.begin()));
      if (!options.legs) {  // the lap as the search priced it
        const double d = from == to ? 0.0 : dist(from, to);
        out.tour.ok = out.tour.ok && d < kUnreachable;
        out.tour.length_m += d;
        continue;
      }
      out.tour.legs.push_back(PlanGridPath(grid, valves_m[from], valves_m[to]));
      out.tour.ok = out.tour.ok && !out.tour.legs.back().empty();
      out.tour.length_m += PathLength(out.tour.legs.back());
    }
    out.weights = TourWeights(out.valves, weights, options.weight_exponent);
    out.lap_time_s = out.tour.length_m / vehicles[k].speed_mps;
    for (int i = 0; i < size; ++i) out.lap_time_s += wait_per_lap_s * out.weights[i];
    plan.ok = plan.ok && out.tour.ok;
    plan.max_lap_s = std::max(plan.max_lap_s, out.lap_time_s);
    plan.mean_lap_s += out.lap_time_s;
    plan.vehicles.push_back(std::move(out));
  }
  plan.mean_lap_s /= std::max(1, n - plan.reserve);
  return plan;
}

}  // namespace fleet_tours
}  // namespace

Eigen::VectorXd TourWeights(const std::vector<int>& valves, const Eigen::VectorXd& weights, double exponent) {
  // (w_i / max w)^alpha: the same ratios as w_i^alpha, without overflow for raw weights.
  const auto size = static_cast<Eigen::Index>(valves.size());
  Eigen::VectorXd out(size);
  double heaviest = 0.0;
  for (int v : valves) heaviest = std::max(heaviest, weights[v]);
  for (Eigen::Index i = 0; i < size; ++i) {
    out[i] = heaviest > 0.0 ? std::pow(weights[valves[static_cast<std::size_t>(i)]] / heaviest, exponent) : 1.0;
  }
  return out / out.sum();  // the sum is >= 1: the heaviest valve's term is 1, as is 0^0
}

FleetTourPlan PlanFleetTours(const maps::OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& valves_m,
                             const Eigen::VectorXd& weights, const std::vector<FleetVehicle>& vehicles,
                             double wait_per_lap_s, const FleetTourOptions& options) {
  return fleet_tours::Plan(grid, valves_m, weights, vehicles, wait_per_lap_s, options);
}

}  // namespace sage::agents
