#pragma once
// The clock every process of a mission shares: CLOCK_REALTIME in nanoseconds. The server
// announces the mission's start on it (MissionStatus.start_ns) with a time scale, and every
// stamp on the wire is on it.
#include <chrono>

namespace sage::proto {

inline long long NowRealtimeNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace sage::proto
