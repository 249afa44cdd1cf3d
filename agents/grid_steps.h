#pragma once
// Exact costs of 8-connected grid paths: a orthogonal and b diagonal steps cost a + b sqrt(2)
// cells. Two paths' costs compare exactly in integers, so the A* searches can break ties in f
// (every cell on some shortest octile path has the same f) on purpose instead of by rounding.
#include <algorithm>
#include <cstdint>
#include <cstdlib>

namespace sage::agents {

struct GridSteps {
  std::int32_t a = 0, b = 0;  // a + b sqrt(2), in cells
  friend GridSteps operator+(GridSteps x, GridSteps y) { return {x.a + y.a, x.b + y.b}; }
  /// The cost in metres on a grid of resolution r.
  double Metres(double r) const { return r * (a + 1.4142135623730951 * b); }
};

/// Sign of x - y, exactly: of p + q sqrt(2) with p = x.a - y.a, q = x.b - y.b.
inline int Compare(const GridSteps& x, const GridSteps& y) {
  const std::int64_t p = x.a - y.a, q = x.b - y.b;
  if (p >= 0 && q >= 0) return p > 0 || q > 0 ? 1 : 0;
  if (p <= 0 && q <= 0) return -1;
  const std::int64_t pp = p * p, qq = 2 * q * q;  // opposite signs; p^2 = 2 q^2 only at 0
  return p > 0 ? (pp > qq ? 1 : -1) : (qq > pp ? 1 : -1);
}

/// The octile (obstacle-free) cost of a move of dx by dy cells.
inline GridSteps Octile(int dx, int dy) {
  dx = std::abs(dx), dy = std::abs(dy);
  return {std::max(dx, dy) - std::min(dx, dy), std::min(dx, dy)};
}

}  // namespace sage::agents
