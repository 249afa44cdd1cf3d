#pragma once
// The generators' random numbers (maps/scenario only): Sebastiano Vigna's SplitMix64, as in
// tests/maps/make_large_field.py, and none from std::*_distribution, whose output differs
// between standard libraries, so a seed gives the same field with any compiler.
#include <cmath>
#include <cstdint>
#include <numbers>

#include <Eigen/Core>

namespace sage::maps::detail {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Unit() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Range(double lo, double hi) { return lo + (hi - lo) * Unit(); }
  int Below(int n) { return static_cast<int>(Next() % static_cast<std::uint64_t>(n)); }
  Eigen::Vector2d InBox(double x0, double y0, double w, double h) {
    const double x = x0 + w * Unit();
    return {x, y0 + h * Unit()};
  }
  double Normal() {  // Box-Muller; 1 - Unit() is in (0, 1]
    const double radius = std::sqrt(-2.0 * std::log(1.0 - Unit()));
    return radius * std::cos(2.0 * std::numbers::pi * Unit());
  }

 private:
  std::uint64_t state_;
};

}  // namespace sage::maps::detail
