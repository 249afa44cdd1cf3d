#include "server/perception/expected_detection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sage::server {

namespace {
// A block this unlikely to be still undetected adds nothing that shows in a wait (1e-12 of its
// remaining time).
constexpr double kDone = 1e-12;
}  // namespace

ExpectedDetection::ExpectedDetection(int valves, double from_s, double to_s) : from_s_(from_s), to_s_(to_s) {
  if (valves < 0) throw std::invalid_argument("ExpectedDetection: valves must be >= 0");
  if (!std::isfinite(from_s) || !std::isfinite(to_s) || !(from_s < to_s)) {
    throw std::invalid_argument("ExpectedDetection: the onsets need from_s < to_s, both finite");
  }
  state_.wait_sums.assign(static_cast<std::size_t>(valves), 0.0);
  state_.open_from_s.assign(static_cast<std::size_t>(valves), from_s);
  state_.blocks.assign(static_cast<std::size_t>(valves), {});
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
  double& open_from = state_.open_from_s[v];
  std::vector<Block>& blocks = state_.blocks[v];
  // open_from is the valve's last look within the onsets (from_s_ before any): nothing earlier may come.
  if (time_s < open_from && open_from > from_s_) {
    throw std::invalid_argument("ExpectedDetection::Look: a scan earlier than the valve's last");
  }
  // The onsets since the last look, up to now, become a block of their own.
  const double to = std::min(time_s, to_s_);
  if (to > open_from) {
    blocks.push_back({open_from, to, 1.0});
    open_from = to;
  }
  // Each block's onsets t0 in [a, b] wait time_s - t0 if this scan is the first to see them:
  // integral over the block of (time_s - t0) dt0 = (b - a) (time_s - (a + b) / 2).
  double& sum = state_.wait_sums[v];
  for (Block& b : blocks) {
    sum += b.undetected * p * (b.to_s - b.from_s) * (time_s - 0.5 * (b.from_s + b.to_s));
    b.undetected *= 1.0 - p;
  }
  std::erase_if(blocks, [](const Block& b) { return b.undetected < kDone; });
}

std::vector<double> ExpectedDetection::Waits(double end_s) const {
  std::vector<double> waits(state_.wait_sums.size(), std::numeric_limits<double>::quiet_NaN());
  const double last_onset = std::min(to_s_, end_s);
  if (!(last_onset > from_s_)) return waits;
  for (std::size_t v = 0; v < waits.size(); ++v) {
    double sum = state_.wait_sums[v];
    // Onsets still undetected wait to the end: the blocks' (those that began before end_s) and
    // the onsets since the valve's last look.
    for (const Block& b : state_.blocks[v]) {
      const double a = b.from_s, z = std::min(b.to_s, last_onset);
      if (z > a) sum += b.undetected * (z - a) * (end_s - 0.5 * (a + z));
    }
    const double a = state_.open_from_s[v];
    if (last_onset > a) sum += (last_onset - a) * (end_s - 0.5 * (a + last_onset));
    waits[v] = sum / (last_onset - from_s_);
  }
  return waits;
}

void ExpectedDetection::Restore(State state) {
  const std::size_t n = state_.wait_sums.size();
  if (state.wait_sums.size() != n || state.open_from_s.size() != n || state.blocks.size() != n) {
    throw std::invalid_argument("ExpectedDetection::Restore: not a state of this many valves");
  }
  for (std::size_t v = 0; v < n; ++v) {
    bool ok = std::isfinite(state.wait_sums[v]) && std::isfinite(state.open_from_s[v]);
    for (const Block& b : state.blocks[v]) {
      ok = ok && std::isfinite(b.from_s) && std::isfinite(b.to_s) && b.from_s <= b.to_s && b.undetected >= 0.0 &&
           b.undetected <= 1.0;
    }
    if (!ok) throw std::invalid_argument("ExpectedDetection::Restore: a value is not finite or out of range");
  }
  state_ = std::move(state);
}

}  // namespace sage::server
