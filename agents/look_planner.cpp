// The look planner: legs scanned once, then a depth-first search with a bound over sequences of
// next valves, each priced by the integral of S(t) = sum_k w_k U_k(t) over the horizon.
#include "agents/look_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "agents/tour_planner.h"

namespace sage::agents {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Between looks S grows at W = sum_k w_k: its integral over dt is S dt + W dt^2 / 2. U_k(t) =
// a_k + t between looks at k (it grows 1 a second): a holds U_k - t.
struct Clock {
  double t = 0.0, s = 0.0, cost = 0.0;
  void Advance(double to, double w_sum) {
    const double dt = to - t;
    if (dt <= 0.0) return;
    cost += s * dt + 0.5 * w_sum * dt * dt;
    s += w_sum * dt;
    t = to;
  }
  // Flies a leg from now: each look before the horizon scales its valve's U by (1 - p); then on
  // to the leg's end or the horizon, whichever comes first.
  void Fly(const LookPlanner::Leg& leg, Eigen::VectorXd& a, const Eigen::VectorXd& w, double w_sum, double horizon) {
    const double start = t;
    for (const LookPlanner::Look& look : leg.looks) {
      if (start + look.time_s > horizon) break;
      Advance(start + look.time_s, w_sum);
      const auto k = static_cast<Eigen::Index>(look.valve);
      const double u = a[k] + t;
      s -= w[k] * u * look.p;
      a[k] = u * (1.0 - look.p) - t;
    }
    Advance(std::min(horizon, start + leg.duration_s), w_sum);
  }
  // The price: the integral to the horizon, and what is left unseen there for terminal_s more.
  double Price(double horizon, double w_sum, double terminal_s) const {
    Clock end = *this;
    end.Advance(horizon, w_sum);
    return end.cost + end.s * terminal_s;
  }
};

void CheckInputs(int n, int from, const Eigen::VectorXd& u, const Eigen::VectorXd& w) {
  if (from < 0 || from >= n || u.size() != n || w.size() != n) {
    throw std::invalid_argument("LookPlanner: " + std::to_string(n) + " valves, from " + std::to_string(from) + ", " +
                                std::to_string(u.size()) + " U and " + std::to_string(w.size()) + " weights");
  }
  if (!u.allFinite() || !w.allFinite() || (u.array() < 0.0).any() || (w.array() < 0.0).any()) {
    throw std::invalid_argument("LookPlanner: U and the weights must be finite and >= 0");
  }
}

}  // namespace

LookPlanner::LookPlanner(const maps::OccupancyGrid& grid, std::vector<Eigen::Vector2d> valves,
                         const maps::SensorModel& sensor, double speed_mps, Options options)
    : valves_(std::move(valves)), options_(options) {
  if (valves_.empty()) throw std::invalid_argument("LookPlanner: no valves");
  if (!(speed_mps > 0.0) || !std::isfinite(speed_mps)) throw std::invalid_argument("LookPlanner: speed must be > 0");
  if (!(options_.horizon_s > 0.0) || !(options_.legs_per_horizon >= 0.0) || options_.max_sequences < 1 || !(options_.turn_s >= 0.0) ||
      !(options_.terminal_s >= 0.0)) {
    throw std::invalid_argument("LookPlanner: horizon > 0, max_sequences >= 1; legs_per_horizon, turn_s and terminal_s >= 0");
  }
  const int n = size();
  const double period = sensor.scan_period_s();
  // The camera turns to the nearest valve in sight (ValveGaze with every valve weighing 1).
  const auto look_from = [&](const Eigen::Vector2d& x, double time_s, std::vector<Look>& looks) {
    int best = -1;
    double best_d = kInf;
    for (int k = 0; k < n; ++k) {
      const double d = (valves_[static_cast<std::size_t>(k)] - x).norm();
      if (d >= best_d || d > sensor.spec().range_m || !sensor.LineOfSight(x, valves_[static_cast<std::size_t>(k)])) continue;
      best = k;
      best_d = d;
    }
    if (best < 0) return;
    const double p = sensor.DetectionProbability(best_d);
    if (p > 0.0) looks.push_back({time_s, best, p});
  };
  legs_.resize(static_cast<std::size_t>(n * n));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      Leg& leg = legs_[static_cast<std::size_t>(i * n + j)];
      if (i == j) continue;
      const std::vector<Eigen::Vector2d> path = PlanGridPath(grid, valves_[static_cast<std::size_t>(i)], valves_[static_cast<std::size_t>(j)]);
      if (path.empty()) {
        leg.duration_s = kInf;
        continue;
      }
      const double flight_s = PathLength(path) / speed_mps;
      leg.duration_s = flight_s + options_.turn_s;
      // Walk the path scan by scan (the first scan one period out: the last leg's end saw the start).
      std::size_t segment = 0;
      double along_m = 0.0;  // where segment starts, along the path
      for (double t = period; t <= leg.duration_s + 1e-9; t += period) {
        const double at_m = std::min(t, flight_s) * speed_mps;
        while (segment + 1 < path.size() &&
               along_m + (path[segment + 1] - path[segment]).norm() < at_m) {
          along_m += (path[segment + 1] - path[segment]).norm();
          ++segment;
        }
        Eigen::Vector2d x = path.back();
        if (segment + 1 < path.size()) {
          const Eigen::Vector2d step = path[segment + 1] - path[segment];
          const double length = step.norm();
          x = length > 0.0 ? Eigen::Vector2d(path[segment] + step * ((at_m - along_m) / length)) : path[segment];
        }
        look_from(x, t, leg.looks);
      }
    }
  }
  // The deepest search that keeps the sequences within max_sequences.
  depth_ = 1;
  if (n > 1) {
    double sequences = n - 1;
    while (sequences * (n - 1) <= options_.max_sequences && depth_ < 64) {
      sequences *= n - 1;
      ++depth_;
    }
  }
  // The horizon: legs_per_horizon of the longest leg (a far valve is worth its flight), but no
  // longer than the search's legs last on average (past its last leg a sequence sees nothing, so
  // a longer horizon would charge a sequence of short legs for hovering and send it far).
  double longest_s = 0.0, sum_s = 0.0;
  int finite = 0;
  for (const Leg& leg : legs_) {
    if (!std::isfinite(leg.duration_s) || leg.duration_s <= 0.0) continue;
    longest_s = std::max(longest_s, leg.duration_s);
    sum_s += leg.duration_s;
    ++finite;
  }
  const double mean_s = finite > 0 ? sum_s / finite : 0.0;
  horizon_s_ = std::max(options_.horizon_s, std::min(options_.legs_per_horizon * longest_s, depth_ * mean_s));
}

double LookPlanner::Cost(int from, const std::vector<int>& sequence, const Eigen::VectorXd& undetected_s,
                         const Eigen::VectorXd& weights) const {
  CheckInputs(size(), from, undetected_s, weights);
  Eigen::VectorXd a = undetected_s;  // U_k - t (Clock)
  const double w_sum = weights.sum();
  Clock clock;
  clock.s = weights.dot(a);
  int at = from;
  for (int next : sequence) {
    if (next < 0 || next >= size() || next == at) throw std::invalid_argument("LookPlanner::Cost: not a sequence of legs");
    clock.Fly(leg(at, next), a, weights, w_sum, horizon_s_);
    if (clock.t >= horizon_s_) break;
    at = next;
  }
  return clock.Price(horizon_s_, w_sum, options_.terminal_s);
}

std::vector<int> LookPlanner::Plan(int from, const Eigen::VectorXd& undetected_s, const Eigen::VectorXd& weights,
                                   int avoid_first) const {
  CheckInputs(size(), from, undetected_s, weights);
  const int n = size();
  if (n == 1) return {from};
  if (n == 2 || avoid_first == from) avoid_first = -1;  // nowhere else to go, or nothing to avoid
  const double w_sum = weights.sum();
  const double horizon = horizon_s_;
  // One U a depth (the search copies it down a level, leg by leg), as U_k - t (see Cost).
  std::vector<Eigen::VectorXd> u(static_cast<std::size_t>(depth_ + 1), undetected_s);
  std::vector<int> sequence(static_cast<std::size_t>(depth_), -1), best(static_cast<std::size_t>(depth_), -1);
  double best_cost = kInf;
  // The cost so far only grows along a sequence (S >= 0), so a branch already dearer than the
  // best is cut.
  const auto search = [&](auto&& self, int at, int depth, Clock clock) -> void {
    if (clock.cost >= best_cost) return;
    if (depth == depth_ || clock.t >= horizon) {
      const double cost = clock.Price(horizon, w_sum, options_.terminal_s);
      if (cost < best_cost) {
        best_cost = cost;
        best = sequence;
      }
      return;
    }
    for (int next = 0; next < n; ++next) {
      if (next == at || (depth == 0 && next == avoid_first)) continue;
      const Leg& l = leg(at, next);
      if (!std::isfinite(l.duration_s)) continue;
      Eigen::VectorXd& v = u[static_cast<std::size_t>(depth + 1)];
      v = u[static_cast<std::size_t>(depth)];
      Clock c = clock;
      c.Fly(l, v, weights, w_sum, horizon);
      sequence[static_cast<std::size_t>(depth)] = next;
      self(self, next, depth + 1, c);
      sequence[static_cast<std::size_t>(depth)] = -1;
    }
  };
  Clock clock;
  clock.s = weights.dot(undetected_s);
  search(search, from, 0, clock);
  // A sequence cut by the horizon ends where it was cut.
  std::vector<int> plan;
  for (int k : best) {
    if (k < 0) break;
    plan.push_back(k);
  }
  if (plan.empty()) {  // no leg with a path: stay
    plan.push_back(from);
  }
  return plan;
}

}  // namespace sage::agents
