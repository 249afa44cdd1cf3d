#pragma once
// Shortest-pair-first matching of tours (clusters) to vehicles, for fleets too large for the
// Hungarian method (agents/fleet_tour_planner.cpp).
#include <algorithm>
#include <cstddef>
#include <queue>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "maps/nearby_points.h"

namespace sage::agents {

/// The min(keep, m) cheapest of vehicles 0..m-1 priced by cost(k), as (cost, vehicle) ascending.
template <typename Cost>
void RankAll(int m, std::size_t keep, const Cost& cost, std::vector<std::pair<double, int>>& list) {
  list.clear();
  for (int k = 0; k < m; ++k) list.emplace_back(cost(k), k);
  keep = std::min(keep, list.size());
  std::partial_sort(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(keep), list.end());
  list.resize(keep);
}

/// Greedy matching, shortest pair first: the pairs in ascending (cost, cluster, vehicle) order,
/// each taken if both ends are free, over clusters c (0..n-1) and vehicles k (0..m-1), n <= m.
/// Returns the vehicle of each cluster.
/// Without the n x m list (10,000 vehicles: 1e8 pairs, 2.4 GB sorted): each cluster keeps its
/// kShortlist cheapest vehicles in (cost, vehicle) order and a heap holds every unmatched
/// cluster's cheapest free one; a cluster whose shortlist runs out ranks all vehicles. The next
/// pair taken is the heap's least, the pair the sorted list would give next.
/// rank(c, keep, list) fills `list` with cluster c's min(keep, m) cheapest (cost, vehicle) pairs,
/// ascending: exactly the first entries of all m sorted (a spatial search may find them without
/// pricing every vehicle).
template <typename Rank>
std::vector<int> GreedyMatchRanked(int n, int m, const Rank& rank_into) {
  constexpr std::size_t kShortlist = 16;
  using Pair = std::pair<double, int>;  // (cost, vehicle)
  std::vector<std::vector<Pair>> shortlist(n);
  std::vector<std::size_t> next(n, 0);
  std::vector<char> full(n, 0);
  const auto rank = [&](int c, std::size_t keep) {
    rank_into(c, keep, shortlist[c]);
    full[c] = shortlist[c].size() == static_cast<std::size_t>(m);
  };
  using Entry = std::tuple<double, int, int>;  // (cost, cluster, vehicle)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
  for (int c = 0; c < n; ++c) {
    rank(c, kShortlist);
    heap.emplace(shortlist[c][0].first, c, shortlist[c][0].second);
  }
  std::vector<int> vehicle_of(n, -1);
  std::vector<char> taken(m, 0);
  while (!heap.empty()) {
    const auto [d, c, k] = heap.top();
    heap.pop();
    if (!taken[k]) {
      vehicle_of[c] = k, taken[k] = 1;
      continue;
    }
    // Its vehicle went to another cluster: on to this cluster's next free one.
    std::size_t& i = next[c];
    while (i < shortlist[c].size() && taken[shortlist[c][i].second]) ++i;
    if (i == shortlist[c].size() && !full[c]) {
      rank(c, static_cast<std::size_t>(m));
      i = 0;
      while (i < shortlist[c].size() && taken[shortlist[c][i].second]) ++i;
    }
    if (i < shortlist[c].size()) heap.emplace(shortlist[c][i].first, c, shortlist[c][i].second);
  }
  return vehicle_of;
}

/// The list of every pair priced by cost(c, k), O(n m + n log n).
template <typename Cost>
std::vector<int> GreedyMatch(int n, int m, const Cost& cost) {
  return GreedyMatchRanked(n, m, [&](int c, std::size_t keep, std::vector<std::pair<double, int>>& list) {
    RankAll(m, keep, [&](int k) { return cost(c, k); }, list);
  });
}

/// GreedyMatch of clusters at `centroids` to vehicles at `positions`, where cost(c, k) grows with
/// the distance, cost >= |centroid_c - position_k|^2 / fastest^2 (a travel time squared at a
/// speed <= fastest), with the shortlists taken from the vehicles near each cluster: pricing all
/// 10,000 vehicles for each of 10,000 clusters was 30 % of a 10,000-vehicle plan. A vehicle beyond
/// radius r costs more than r^2 / fastest^2, so once the keep-th cheapest within r costs less than
/// that, they are the keep cheapest of all, in the same order; else r doubles. The same matching
/// as GreedyMatch(n, m, cost).
template <typename Cost>
std::vector<int> GreedyMatchNear(const std::vector<Eigen::Vector2d>& centroids,
                                 const std::vector<Eigen::Vector2d>& positions, double fastest, const Cost& cost) {
  const int n = static_cast<int>(centroids.size()), m = static_cast<int>(positions.size());
  Eigen::Vector2d lo = positions.front(), hi = lo;
  for (const Eigen::Vector2d& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Cells of about one vehicle each; a first radius of a few of them.
  const double spacing = std::max(std::sqrt((hi - lo).prod() / m), 1e-3);
  const maps::NearbyPoints index(positions, spacing);
  const double reach = (hi - lo).norm() + spacing;
  std::vector<int> near;
  return GreedyMatchRanked(n, m, [&](int c, std::size_t keep, std::vector<std::pair<double, int>>& list) {
    for (double r = 3.0 * spacing; keep < static_cast<std::size_t>(m) && r < 4.0 * reach; r *= 2.0) {
      index.Within(centroids[c], r, near);
      if (near.size() < keep) continue;
      // near is ascending, so (cost, place in near) sorts as (cost, vehicle) does.
      RankAll(static_cast<int>(near.size()), keep, [&](int i) { return cost(c, near[i]); }, list);
      for (auto& pair : list) pair.second = near[pair.second];
      if (near.size() == static_cast<std::size_t>(m) || list.back().first < (1.0 - 1e-9) * r * r / (fastest * fastest)) {
        return;
      }
    }
    RankAll(m, keep, [&](int k) { return cost(c, k); }, list);
  });
}

}  // namespace sage::agents
