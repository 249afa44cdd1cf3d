#pragma once
// The clock every process of a mission shares: CLOCK_REALTIME in nanoseconds. The server
// announces the mission's start on it (MissionStatus.start_ns) with a time scale, and every
// stamp on the wire is on it.
#include <chrono>
#include <cmath>

namespace sage::proto {

/// Time scales a mission may run at (mission seconds per wall second): from a thousandth of real
/// time to a thousand times it. What a host takes from a server's status, and what --time-scale
/// accepts: a clock outside them cannot be waited on (a wall time beyond any clock's range).
inline constexpr double kMinTimeScale = 1e-3, kMaxTimeScale = 1e3;

/// True for a clock a mission can run on: time_scale within kMinTimeScale..kMaxTimeScale and a
/// start within 2^62 ns (146 years) of the epoch, so that wall times computed from it stay in range.
inline bool PlausibleClock(long long start_ns, double time_scale) {
  constexpr long long kMaxStart_ns = 1LL << 62;
  return time_scale >= kMinTimeScale && time_scale <= kMaxTimeScale && start_ns < kMaxStart_ns &&
         start_ns > -kMaxStart_ns;
}

inline long long NowRealtimeNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace sage::proto
