#pragma once
// Work over [0, n) in two halves, the upper one on a helper thread, for set-up loops whose items
// are each computed by themselves (so the result is the same either way) and long enough at fleet
// scale for the machine's second core to matter: a large field's regions, its valves' risk.
#include <cstddef>
#include <future>

namespace sage::maps {

/// body(begin, end) over [0, n): on the calling thread alone below two_threads_from items, else the
/// lower half here and the upper half beside it. An exception from either half reaches the caller
/// once both have stopped.
template <class Body>
void InTwoHalves(std::size_t n, std::size_t two_threads_from, Body&& body) {
  if (n < two_threads_from) {
    body(std::size_t{0}, n);
    return;
  }
  auto upper = std::async(std::launch::async, [&body, n] { body(n / 2, n); });
  body(std::size_t{0}, n / 2);
  upper.get();
}

}  // namespace sage::maps
