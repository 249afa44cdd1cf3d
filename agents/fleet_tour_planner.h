#pragma once
// The fleet's inspection-tour baseline: what an operator would fly by hand with N vehicles on M
// valves. The valves are partitioned among the vehicles, balanced on lap time, and each vehicle
// gets one closed Tour through its own share that TourController flies lap after lap.
//
// Objective. Vehicle k flies its tour S_k at speed v_k and waits W = wait_per_lap_s per lap in
// all (TourController renormalises the weights it is given, so W is split over S_k's valves in
// proportion to w_i^alpha / sum_{j in S_k} w_j^alpha and does not depend on the share):
//   T_k = L(S_k) / v_k + W,   minimise max_k T_k   (min-max: the longest revisit interval),
// L(S) the shortest closed tour through S on the A* grid. Ties in max_k T_k are broken by
// sum_k T_k, so the shorter tours stay compact. The wait exponent alpha only splits W.
//
// Distances. d(i, j) is the 8-connected grid distance between the valves' cells: moves r and
// sqrt(2) r, a diagonal only past two free cells, i.e. the graph and costs of PlanGridPath's A*,
// found by the same A* (octile heuristic; costs exact as a + b sqrt 2 steps, agents/grid_steps.h)
// with ties in f broken towards the deeper cell, so open water costs O(L / r) cells, and with no
// search at all when the rectangle of the two cells is free (the octile cost is then the
// distance: no shortest path leaves that rectangle); cached per pair, and kInf at once between valves in
// different connected components. The straight line between cell centres is a lower bound of d
// and prunes every search below before a grid distance is asked for. A* shortcuts its paths, so
// d exceeds the flown leg by at most 8.2 % in open water (octile / Euclidean at 22.5 degrees).
//
// Method (deterministic for a seed):
//  1. k-medoids on d with k = N: k-means++ seeding (the next medoid drawn with probability
//     proportional to the squared straight-line distance to the nearest one so far, from a
//     seeded std::mt19937_64), then alternately "each valve to its nearest medoid by d" (medoids
//     in ascending straight line until that line exceeds the best d found: exact) and "medoid :=
//     argmin_{c} sum_{v in C} d(c, v)" over the current medoid and the 4 members nearest the
//     centroid, until no medoid moves (or medoid_iterations). Assigning by d keeps a wall
//     between two groups of valves from being paired across.
//  2. Clusters to vehicles by least sum of squared straight-line approach times from vehicle to
//     cluster centroid (the approach is not part of a lap, it only decides who flies what):
//     exactly (Hungarian) up to 1,200 clusters, beyond by recursive bisection into exactly
//     matched parts of at most 256 (agents/matching.h), or greedily, shortest pair first, when
//     there are spare vehicles (agents/greedy_match.h).
//  3. Min-max local search. A queue of tours, longest lap first; for each valve v of a popped
//     tour a and each tour b holding one of v's K nearest valves (straight line; every change is
//     priced on d): move v to b, or swap v with that valve u. A change of tours a, b (, c) is
//     taken if, over the laps it touches,
//       max(new) < max(old),  or  max(new) <= max(old) and sum(new) < sum(old)   (1e-9),
//     which makes the descending vector of all laps lexicographically smaller (then the sum), so
//     the search terminates; the pairwise rule lets a long tour shed valves down a chain of
//     neighbours. Tours of up to 8 valves are re-ordered exactly (Held-Karp, O(2^m m^2),
//     memoised by valve set); larger ones are priced by the removal gain d(p, n) - d(p, v) -
//     d(v, n) and the cheapest insertion d(x, u) + d(u, y) - d(x, y), and 2-opt'd once taken.
//     Moves never empty a tour, so they cannot change how many vehicles share a group of valves
//     (e.g. a 5-valve XT flown alone while a 3-valve XT has two vehicles): split-merge does. A
//     small tour t merges into a neighbouring tour u (cheapest merge first, cached per pair of
//     tour versions) and t's vehicle takes part of the longest tour a (the best bipartition of a,
//     or the best of 8 cuts into halves beyond 8 valves), by the same rule on {a, t, u}.
//  4. Iterated local search: perturbation_rounds kicks (two chained random moves from the
//     longest tour, seeded), each followed by step 3 on the touched tours; the best state by
//     (max, sum) is kept.
//  4b. The tours as they came out go to the vehicles again: up to 1,200 tours so that the fleet's
//     longest first lap (approach to a tour's nearest valve, then one lap, at the vehicle's
//     speed) is least, no vehicle given a tour it would fly beyond the search's longest lap (a
//     bottleneck assignment: bisection over the pairs' values, each tried by Hopcroft-Karp,
//     agents/matching.h), then the squared approaches to the centroids as in step 2; beyond,
//     among vehicles of one speed as in step 2.
//  5. Each tour is rotated so that order[0] = 0 and legs[i] = PlanGridPath(valve order[i] ->
//     order[i + 1]) in the direction flown, so the lap time is exactly what TourController flies:
//     sum_i |legs[i]| / v_k + sum_i W w_i. PlanGridPath searches a window of the grid round
//     the leg, grown only as far as a shortest path could reach (tour_planner.cpp, AStar): the
//     full-grid leg at a cost independent of the grid's size.
//
// Complexity, with C grid cells, q = M / N valves per tour and l the length of a leg in cells:
// O(C) to copy and label the grid; straight-line neighbours O(M^2); seeding O(M N); a k-medoids
// round O(M N) (a heap of the medoids per valve) plus O(M q) distances; a local-search pass
// O(M K) candidate changes, each O(2^q q^2) (q <= 8, memoised) or O(q log q); split-merge O(N)
// cached merges per call; matching O(N^3) up to 1,200 vehicles (the bottleneck's
// O(N^2.5 log N)), O(N log N + 256^2 N) beyond; legs O(M l^2 log l). A new distance is an A*
// over O(l) cells in open water, more around structures. Memory O(C + pairs priced). Measured
// (one core of this machine, Release, default options): 20 valves / 4 vehicles (fleet_field)
// 0.05 s, 87 / 24 and 240 / 100 (fleet_large) 0.08 and 0.11 s, 2,400 / 1,000 (fleet_large
// tiled 5 x 2: 1.5 M cells) 1.1 s.
//
// More vehicles than valves (N > M): every valve gets a vehicle of its own (the nearest one,
// greedily), and the N - M others none: they are held in reserve (an empty VehicleTour), for the
// next plan to bring in when a vehicle is lost. They had been given the heaviest valves again,
// and two vehicles sent to one valve keep one another outside its visit radius (the hosts keep
// vehicles apart): on generated fields of 6-12 valves with twice as many vehicles, a valve went
// unwatched for up to 590 s, against at most 15 s with a vehicle a valve.
#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "agents/tour_planner.h"
#include "maps/occupancy_grid.h"

namespace sage::agents {

/// A vehicle as the planner sees it.
struct FleetVehicle {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< current position (m)
  double speed_mps = 0.5;                                ///< transit speed (m/s), > 0
};

/// Knobs of the search; the figures above are with these defaults.
struct FleetTourOptions {
  /// alpha >= 0: a tour's wait W is split over its valves as w_i^alpha / sum_j w_j^alpha (1 = as
  /// TourController given the raw weights; 0 = equal waits).
  double weight_exponent = 1.0;
  std::uint64_t seed = 1;         ///< k-means++ draws and the kicks of step 4
  int neighbours = 8;             ///< K: a valve's nearest valves (straight line) whose tours it may join
  int medoid_iterations = 20;     ///< cap on k-medoids rounds (>= 1)
  int perturbation_rounds = 200;  ///< iterated-local-search kicks (>= 0)
  /// Wall-clock cap (s) on steps 3-4; 0 = none. A plan cut short by it depends on the machine's
  /// speed, so the default keeps results deterministic.
  double time_budget_s = 0.0;
  /// beta >= 0: the search balances lap x (1 + beta n W), W the share of the field's risk a tour
  /// holds (n vehicles), so that a vehicle with the riskier valves gets fewer of them; 0 = the
  /// lap alone (an operator's tours).
  double risk_share = 0.0;
  /// false: no A* legs (every tour's legs empty), each lap priced on the grid distances d the
  /// search used (at most 8.2 % above the flown legs): for a caller that needs the split and its
  /// laps, not a path to fly. The legs were a third of planning a 10,000-vehicle field.
  bool legs = true;
  /// Set (to true) by another thread to give the plan up: it stops at its next grid search and
  /// throws PlanCancelled. For a plan on a thread of its own that nobody will take (the mission
  /// ended first): ten vehicles on a 35,000-valve field plan for hours. nullptr: never.
  const std::atomic<bool>* cancel = nullptr;
};

/// What PlanFleetTours throws when FleetTourOptions::cancel was set while it planned.
struct PlanCancelled : std::runtime_error {
  PlanCancelled() : std::runtime_error("fleet tour plan cancelled") {}
};

/// One vehicle's share and its tour, ready for TourController(tour, grid, speed, wait, weights).
struct VehicleTour {
  /// Global valve indices, ascending; empty only for a vehicle held in reserve (more vehicles
  /// than valves), whose tour is empty and lap 0.
  std::vector<int> valves;
  Eigen::VectorXd weights;  ///< per valves[k]: w^alpha / sum over this tour (sums to 1)
  Tour tour;                ///< order indexes `valves` (order[0] = 0); legs from PlanGridPath (none without options.legs)
  double lap_time_s = 0.0;  ///< sum_i |legs[i]| / speed + sum_k wait_per_lap_s * weights[k] (s)
};

/// The fleet's tours and their lap figures.
struct FleetTourPlan {
  std::vector<VehicleTour> vehicles;  ///< one per input vehicle, same order
  double max_lap_s = 0.0;             ///< max over vehicles of lap_time_s (s)
  double mean_lap_s = 0.0;            ///< mean of lap_time_s over the vehicles not in reserve (s)
  int reserve = 0;                    ///< vehicles held in reserve (more vehicles than valves)
  bool ok = false;                    ///< false if some leg has no grid path (tour.ok false)
};

/// A tour's waits: per valves[k], (w / max w)^exponent over the tour's valves, summing to 1 (equal
/// where every weight is 0). valves: indices into weights, not empty.
Eigen::VectorXd TourWeights(const std::vector<int>& valves, const Eigen::VectorXd& weights, double exponent);

/// Partitions the valves (m) among the vehicles, balanced on lap time, one closed tour each (see
/// the file comment). weights: one per valve, finite, >= 0 (normalised or not: only ratios within
/// a tour matter); a tour whose weights are all 0 waits equally at its valves. grid: the A* grid,
/// already inflated by the clearance. wait_per_lap_s: W (s), >= 0. Throws std::invalid_argument
/// for no valves, no vehicles, mismatched sizes, a speed <= 0 or a negative exponent.
FleetTourPlan PlanFleetTours(const maps::OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& valves_m,
                             const Eigen::VectorXd& weights, const std::vector<FleetVehicle>& vehicles,
                             double wait_per_lap_s, const FleetTourOptions& options = {});

}  // namespace sage::agents
