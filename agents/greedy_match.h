#pragma once
// Shortest-pair-first matching of tours (clusters) to vehicles, for fleets too large for the
// Hungarian method (agents/fleet_tour_planner.cpp).
#include <algorithm>
#include <cstddef>
#include <queue>
#include <tuple>
#include <utility>
#include <vector>

namespace sage::agents {

/// Greedy matching, shortest pair first: the pairs in ascending (cost, cluster, vehicle) order,
/// each taken if both ends are free. cost(c, k): cluster c (0..n-1) served by vehicle k (0..m-1),
/// n <= m. Returns the vehicle of each cluster.
/// Without the n x m list (10,000 vehicles: 1e8 pairs, 2.4 GB sorted): each cluster keeps its
/// kShortlist cheapest vehicles in (cost, vehicle) order and a heap holds every unmatched
/// cluster's cheapest free one; a cluster whose shortlist runs out ranks all vehicles. The next
/// pair taken is the heap's least, the pair the sorted list would give next. O(n m + n log n).
template <typename Cost>
std::vector<int> GreedyMatch(int n, int m, const Cost& cost) {
  constexpr int kShortlist = 16;
  using Pair = std::pair<double, int>;  // (cost, vehicle)
  std::vector<std::vector<Pair>> shortlist(n);
  std::vector<std::size_t> next(n, 0);
  std::vector<char> full(n, 0);
  const auto rank = [&](int c, std::size_t keep) {
    std::vector<Pair>& list = shortlist[c];
    list.clear();
    for (int k = 0; k < m; ++k) list.emplace_back(cost(c, k), k);
    keep = std::min(keep, list.size());
    std::partial_sort(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(keep), list.end());
    list.resize(keep);
    full[c] = keep == static_cast<std::size_t>(m);
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

}  // namespace sage::agents
