#include "server/perception/expected_detection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sage::server {

ExpectedDetection::ExpectedDetection(int valves, double from_s, double to_s) : from_s_(from_s), to_s_(to_s) {
  if (valves < 0) throw std::invalid_argument("ExpectedDetection: valves must be >= 0");
  if (!std::isfinite(from_s) || !std::isfinite(to_s) || !(from_s < to_s)) {
    throw std::invalid_argument("ExpectedDetection: the onsets need from_s < to_s, both finite");
  }
  const auto n = static_cast<std::size_t>(valves);
  state_.wait_sums.assign(n, 0.0);
  state_.undetected_s.assign(n, 0.0);
  state_.undetected_onset_s2.assign(n, 0.0);
  state_.last_look_s.assign(n, from_s);
}

void ExpectedDetection::Look(int valve, double time_s, double p) {
  if (valve < 0 || static_cast<std::size_t>(valve) >= state_.wait_sums.size()) {
    throw std::invalid_argument("ExpectedDetection::Look: no such valve");
  }
  if (!(p >= 0.0 && p <= 1.0) || !std::isfinite(time_s)) {
    throw std::invalid_argument("ExpectedDetection::Look: p must be in [0, 1] and the time finite");
  }
  if (p == 0.0) return;
  const auto v = static_cast<std::size_t>(valve);
  double& last = state_.last_look_s[v];
  const double t = std::max(time_s, last);
  // The onsets since the last look, up to this one (within [from_s, to_s]), join the undetected.
  const double a = std::min(last, to_s_), b = std::min(t, to_s_);
  double& length = state_.undetected_s[v];
  double& moment = state_.undetected_onset_s2[v];
  if (b > a) {
    length += b - a;
    moment += (b - a) * 0.5 * (a + b);
  }
  // Each undetected onset t0 waits t - t0 if this scan is the first to see it.
  state_.wait_sums[v] += p * (t * length - moment);
  length *= 1.0 - p;
  moment *= 1.0 - p;
  last = t;
}

bool ExpectedDetection::LookedAt(int valve) const {
  if (valve < 0 || static_cast<std::size_t>(valve) >= state_.last_look_s.size()) {
    throw std::invalid_argument("ExpectedDetection::LookedAt: no such valve");
  }
  return state_.last_look_s[static_cast<std::size_t>(valve)] > from_s_;  // a look with p > 0 moves it past from_s
}

std::vector<double> ExpectedDetection::Waits(double end_s) const {
  std::vector<double> waits(state_.wait_sums.size(), std::numeric_limits<double>::quiet_NaN());
  const double last_onset = std::min(to_s_, end_s);
  if (!(last_onset > from_s_)) return waits;
  for (std::size_t v = 0; v < waits.size(); ++v) {
    const double last = state_.last_look_s[v];
    if (end_s < last) continue;
    // Onsets still undetected wait to the end: those before the last look, and those since.
    double sum = state_.wait_sums[v] + end_s * state_.undetected_s[v] - state_.undetected_onset_s2[v];
    const double a = std::min(last, to_s_);
    if (last_onset > a) sum += (last_onset - a) * (end_s - 0.5 * (a + last_onset));
    waits[v] = sum / (last_onset - from_s_);
  }
  return waits;
}

std::vector<double> ExpectedDetection::Undetected(double time_s) const {
  std::vector<double> u(state_.undetected_s.size());
  for (std::size_t v = 0; v < u.size(); ++v) {
    const double last = state_.last_look_s[v];
    const double a = std::min(last, to_s_), b = std::min(std::max(time_s, last), to_s_);
    u[v] = state_.undetected_s[v] + std::max(0.0, b - a);
  }
  return u;
}

void ExpectedDetection::Restore(State state) {
  const std::size_t n = state_.wait_sums.size();
  if (state.wait_sums.size() != n || state.undetected_s.size() != n || state.undetected_onset_s2.size() != n ||
      state.last_look_s.size() != n) {
    throw std::invalid_argument("ExpectedDetection::Restore: not a state of this many valves");
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!std::isfinite(state.wait_sums[v]) || !(state.undetected_s[v] >= 0.0) || !std::isfinite(state.undetected_s[v]) ||
        !std::isfinite(state.undetected_onset_s2[v]) || !std::isfinite(state.last_look_s[v]) ||
        state.last_look_s[v] < from_s_) {
      throw std::invalid_argument("ExpectedDetection::Restore: a value is not finite or out of range");
    }
  }
  state_ = std::move(state);
}

}  // namespace sage::server
