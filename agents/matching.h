#pragma once
// Tours (clusters) to vehicles: who flies which share of a field (agents/fleet_tour_planner.cpp,
// step 2). The cost of a pair is the squared straight-line approach time, so that a chain of
// vehicles moving a few metres each is preferred to one vehicle sent across the field; the
// bottleneck (the least longest first lap any assignment allows) bounds which pairs may be used.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <vector>

#include <Eigen/Core>

namespace sage::agents {

/// The assignment of rows (clusters) 0..n-1 to distinct columns (vehicles) 0..m-1, n <= m, of
/// least total cost(c, k): the Hungarian method in the potentials form of Kuhn-Munkres, O(n^2 m).
/// Returns the vehicle of each cluster.
/// A cost that is not a number below kMaxMatchCost (a vehicle reported at an absurd place, or
/// one that cannot move) counts as kMaxMatchCost: with an infinite or NaN cost no column was ever
/// found for a row and the search looped for ever (the server door's fuzzer hung the tour plan).
inline constexpr double kMaxMatchCost = 1e100;

template <typename Cost>
std::vector<int> MinCostMatch(int n, int m, const Cost& raw_cost) {
  const auto cost = [&](int c, int k) {
    const double x = raw_cost(c, k);
    return x >= -kMaxMatchCost && x <= kMaxMatchCost ? x : kMaxMatchCost;  // NaN fails both
  };
  // Rows 1..n, columns 1..m; u, v the potentials, p[j] the row matched to column j, way[] the
  // alternating path.
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  std::vector<double> minv(m + 1);
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), std::numeric_limits<double>::infinity());
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = std::numeric_limits<double>::infinity();
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double cur = cost(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> vehicle_of(n, -1);
  for (int j = 1; j <= m; ++j)
    if (p[j] > 0) vehicle_of[p[j] - 1] = j - 1;
  return vehicle_of;
}

namespace matching_detail {

// Whether rows 0..n-1 can each have a column of its own among 0..m-1 over the pairs (c, k) with
// k in columns[begin[c] .. begin[c + 1]): Hopcroft-Karp's phases (a breadth-first layering of the
// rows from the free ones, then vertex-disjoint augmenting paths along the layers by depth-first
// search). The layering runs to the end rather than stopping at the first layer that reaches a
// free column, so the paths are not all shortest and O(E sqrt(n)) is not guaranteed; each phase
// still augments, and the matching found is maximum. The depth-first search recurses at most n
// deep (n <= 1,200 where it is used).
class RowCover {
 public:
  RowCover(int n, int m, const std::vector<int>& begin, const std::vector<int>& columns)
      : n_(n), begin_(begin), columns_(columns), col_of_(n, -1), row_of_(m, -1), layer_(n), next_(n) {}

  bool CoversEveryRow() {
    int matched = 0;
    while (Layer()) {
      for (int c = 0; c < n_; ++c) next_[c] = begin_[c];
      for (int c = 0; c < n_; ++c) matched += col_of_[c] < 0 && Augment(c);
    }
    return matched == n_;
  }

 private:
  static constexpr int kUnreached = std::numeric_limits<int>::max();
  // Layers rows by alternating distance from the free rows; true if some free column is reached.
  bool Layer() {
    std::vector<int> queue;
    queue.reserve(static_cast<std::size_t>(n_));
    for (int c = 0; c < n_; ++c) {
      layer_[c] = col_of_[c] < 0 ? 0 : kUnreached;
      if (col_of_[c] < 0) queue.push_back(c);
    }
    bool free_column = false;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int c = queue[head];
      for (int e = begin_[c]; e < begin_[c + 1]; ++e) {
        const int r = row_of_[columns_[e]];
        if (r < 0) {
          free_column = true;
        } else if (layer_[r] == kUnreached) {
          layer_[r] = layer_[c] + 1;
          queue.push_back(r);
        }
      }
    }
    return free_column;
  }
  bool Augment(int c) {
    for (; next_[c] < begin_[c + 1]; ++next_[c]) {
      const int k = columns_[next_[c]], r = row_of_[k];
      if (r < 0 || (layer_[r] == layer_[c] + 1 && Augment(r))) {
        col_of_[c] = k;
        row_of_[k] = c;
        return true;
      }
    }
    layer_[c] = kUnreached;  // a dead end this phase
    return false;
  }

  int n_;
  const std::vector<int>& begin_;
  const std::vector<int>& columns_;
  std::vector<int> col_of_, row_of_, layer_, next_;
};

}  // namespace matching_detail

/// The bottleneck of an assignment of rows (tours) 0..n-1 to distinct columns (vehicles) 0..m-1,
/// n <= m: the least t such that every row can have a column of its own with value(c, k) <= t.
/// A value that is not finite (NaN, infinite) marks a pair never to be used; +infinity if the
/// finite pairs hold no such assignment. Bisection over the pairs' distinct values, each bound
/// tried with Hopcroft-Karp: O(n m log(n m) + log(n m) E sqrt(n)).
template <typename Value>
double BottleneckBound(int n, int m, const Value& value) {
  std::vector<double> values(static_cast<std::size_t>(n) * static_cast<std::size_t>(m));
  std::vector<double> distinct;
  double least = -std::numeric_limits<double>::infinity();  // no bound below a row's least value
  for (int c = 0; c < n; ++c) {
    double row_least = std::numeric_limits<double>::infinity();
    for (int k = 0; k < m; ++k) {
      const double x = value(c, k);
      const bool usable = std::isfinite(x);
      values[static_cast<std::size_t>(c) * m + k] = usable ? x : std::numeric_limits<double>::infinity();
      if (usable) distinct.push_back(x), row_least = std::min(row_least, x);
    }
    least = std::max(least, row_least);
  }
  if (n == 0) return 0.0;
  if (!std::isfinite(least)) return std::numeric_limits<double>::infinity();  // a row with no pair
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  std::vector<int> begin(static_cast<std::size_t>(n) + 1), columns;
  const auto covers = [&](double bound) {
    columns.clear();
    for (int c = 0; c < n; ++c) {
      begin[c] = static_cast<int>(columns.size());
      for (int k = 0; k < m; ++k) {
        if (values[static_cast<std::size_t>(c) * m + k] <= bound) columns.push_back(k);
      }
    }
    begin[n] = static_cast<int>(columns.size());
    return matching_detail::RowCover(n, m, begin, columns).CoversEveryRow();
  };
  auto lo = std::lower_bound(distinct.begin(), distinct.end(), least), hi = distinct.end() - 1;
  if (!covers(*hi)) return std::numeric_limits<double>::infinity();
  while (lo < hi) {  // covers(*hi) holds; the answer is in [lo, hi]
    const auto mid = lo + (hi - lo) / 2;
    if (covers(*mid)) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return *hi;
}

/// MinCostMatch for fleets too large for O(n^2 m) (10,000 vehicles: 1e12 steps), by recursive
/// bisection: the clusters are split at the median of the longer side of the bounding box of
/// clusters and vehicles, and the vehicles at the same line (those below it go with the lower
/// clusters), moved across it in order along the axis only as far as each side needs one vehicle
/// per cluster; down to at most `leaf` clusters, each part matched exactly. With as many vehicles
/// as clusters each split is the 1-D optimal transport of squared distance along its axis (the
/// monotone rearrangement), so clusters and vehicles pair by their quantiles, alternately in x and
/// y: where vehicles are spread evenly and valves come in clusters, nobody is left the far side of
/// the field, as shortest-pair-first greedy leaves its last vehicles (900-1,250 m transits
/// measured on a 10,000-vehicle field). With spare vehicles (m > n) the quantiles no longer pair
/// well (1.5-2.2x the optimum measured; greedy 1.3-1.45x). Ties break by index: deterministic. n <= m;
/// cost(c, k) is priced only within a part. O((n + m) log n) for the splits (a linear selection
/// each), then O(leaf^2 m') for each part of m' vehicles.
template <typename Cost>
std::vector<int> BisectedMatch(const std::vector<Eigen::Vector2d>& centroids,
                               const std::vector<Eigen::Vector2d>& positions, const Cost& cost, int leaf) {
  const int n = static_cast<int>(centroids.size()), m = static_cast<int>(positions.size());
  std::vector<int> vehicle_of(n, -1);
  std::vector<int> clusters(n), vehicles(m);
  std::iota(clusters.begin(), clusters.end(), 0);
  std::iota(vehicles.begin(), vehicles.end(), 0);
  // Parts as [begin, end) ranges of `clusters` and `vehicles`, reordered in place.
  struct Part {
    int c0, c1, k0, k1;
  };
  std::vector<Part> stack{{0, n, 0, m}};
  while (!stack.empty()) {
    const Part part = stack.back();
    stack.pop_back();
    const int pn = part.c1 - part.c0, pm = part.k1 - part.k0;
    if (pn == 0) continue;
    if (pn <= std::max(1, leaf)) {
      const std::vector<int> local = MinCostMatch(pn, pm, [&](int c, int k) {
        return cost(clusters[part.c0 + c], vehicles[part.k0 + k]);
      });
      for (int c = 0; c < pn; ++c) vehicle_of[clusters[part.c0 + c]] = vehicles[part.k0 + local[c]];
      continue;
    }
    Eigen::Vector2d lo = centroids[clusters[part.c0]], hi = lo;
    for (int i = part.c0; i < part.c1; ++i) lo = lo.cwiseMin(centroids[clusters[i]]), hi = hi.cwiseMax(centroids[clusters[i]]);
    for (int i = part.k0; i < part.k1; ++i) lo = lo.cwiseMin(positions[vehicles[i]]), hi = hi.cwiseMax(positions[vehicles[i]]);
    const int axis = hi.x() - lo.x() >= hi.y() - lo.y() ? 0 : 1;
    const auto by = [axis](const std::vector<Eigen::Vector2d>& at) {
      return [&at, axis](int a, int b) { return at[a][axis] < at[b][axis] || (at[a][axis] == at[b][axis] && a < b); };
    };
    const int n_low = pn / 2;
    std::nth_element(clusters.begin() + part.c0, clusters.begin() + part.c0 + n_low, clusters.begin() + part.c1,
                     by(centroids));
    const double cut = centroids[clusters[part.c0 + n_low]][axis];
    int below = 0;
    for (int i = part.k0; i < part.k1; ++i) below += positions[vehicles[i]][axis] < cut;
    const int m_low = std::clamp(below, n_low, pm - (pn - n_low));
    std::nth_element(vehicles.begin() + part.k0, vehicles.begin() + part.k0 + m_low, vehicles.begin() + part.k1,
                     by(positions));
    stack.push_back({part.c0 + n_low, part.c1, part.k0 + m_low, part.k1});
    stack.push_back({part.c0, part.c0 + n_low, part.k0, part.k0 + m_low});
  }
  return vehicle_of;
}

}  // namespace sage::agents
