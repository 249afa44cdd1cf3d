#include "server/report/plots/nice_scale.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace sage::server::plots {

namespace {

// Multiples of step within [lo, hi] (a hair of slack for rounding).
long long TickCount(double lo, double hi, double step) {
  return static_cast<long long>(std::floor(hi / step + 1e-9) - std::ceil(lo / step - 1e-9)) + 1;
}

}  // namespace

Ticks LinearTicks(double lo, double hi, int max_ticks) {
  Ticks ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) {
    ticks.values = {lo};
    return ticks;
  }
  max_ticks = std::max(max_ticks, 2);
  // The nice steps from well below the range to above it, smallest first: the first that keeps
  // the count within max_ticks; if that leaves fewer than two ticks, the last step that gave two.
  const int top = static_cast<int>(std::floor(std::log10(hi - lo))) + 1;
  double chosen = 0.0, last_with_two = 0.0;
  for (int e = top - 3 - static_cast<int>(std::ceil(std::log10(max_ticks))); e <= top && chosen == 0.0; ++e) {
    for (const double m : {1.0, 2.0, 5.0}) {
      const double step = m * std::pow(10.0, e);
      const long long count = TickCount(lo, hi, step);
      if (count <= max_ticks) {
        chosen = count >= 2 || last_with_two == 0.0 ? step : last_with_two;
        break;
      }
      last_with_two = step;
    }
  }
  if (chosen == 0.0) chosen = std::pow(10.0, top);
  ticks.step = chosen;
  for (double k = std::ceil(lo / chosen - 1e-9); k <= std::floor(hi / chosen + 1e-9); k += 1.0) {
    const double v = k * chosen;
    ticks.values.push_back(std::abs(v) < chosen * 1e-9 ? 0.0 : v);
  }
  return ticks;
}

std::vector<double> LogTicks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0.0) || !(hi > lo)) return ticks;
  const int first = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
  const int last = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
  const bool with_steps = last - first + 1 < 3;
  for (int e = first - 1; e <= last; ++e) {
    for (double m : with_steps ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
      const double v = m * std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
    }
  }
  return ticks;
}

std::string Grouped(long long n) {
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

std::string TickLabel(double value, double step) {
  if (step > 0.0 && (step < 1e-3 || step > 1e6)) return fmt::format("{:.0e}", value);
  if (step >= 1.0 && std::abs(value) < 9e15) return Grouped(std::llround(value));
  // Decimals enough to tell ticks apart: 0.5 -> 1, 0.25 -> 2, 0.002 -> 3.
  int decimals = 0;
  while (decimals < 6 && std::abs(step * std::pow(10.0, decimals) - std::round(step * std::pow(10.0, decimals))) > 1e-6) {
    ++decimals;
  }
  return fmt::format("{:.{}f}", value, decimals);
}

double ScaleBarLength(double max_length) {
  if (!(max_length > 0.0) || !std::isfinite(max_length)) return 0.0;
  const double power = std::pow(10.0, std::floor(std::log10(max_length) + 1e-12));
  const double fraction = max_length / power;
  return (fraction >= 5.0 - 1e-9 ? 5.0 : fraction >= 2.0 - 1e-9 ? 2.0 : 1.0) * power;
}

}  // namespace sage::server::plots
