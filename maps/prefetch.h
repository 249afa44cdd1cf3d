#pragma once
// Software prefetch for the loops that walk thousands of vehicles a cycle. Each vehicle's state
// lives in heap blocks of its own (its controller, its coverage sums and target, its Box2D body):
// at 10,000 vehicles none of it is in cache when its turn comes, and the SMC step that takes
// 0.4 us on warm arrays took 1.7 us (`sage bench scale --vehicles 10000`, perf). Asking for the
// next vehicles' blocks while this one is worked on hides those misses; nothing computed changes.
#include <cstddef>
#include <cstdint>

namespace sage::maps {

inline constexpr std::size_t kCacheLine = 64;

/// Asks for every cache line of [p, p + bytes) to be read (a hint: never faults, even on nullptr).
inline void PrefetchBytes(const void* p, std::size_t bytes) {
  if (p == nullptr || bytes == 0) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(p) & ~(kCacheLine - 1);
  const auto end = reinterpret_cast<std::uintptr_t>(p) + bytes;
  for (std::uintptr_t line = begin; line < end; line += kCacheLine) {
    __builtin_prefetch(reinterpret_cast<const void*>(line));
  }
}

/// The lines of one object.
template <typename T>
void PrefetchObject(const T* p) {
  PrefetchBytes(p, sizeof(T));
}

}  // namespace sage::maps
