#pragma once
// Axis ticks and scale bars at numbers a reader takes in at a glance: 1, 2 or 5 times a power
// of ten (Heckbert's "nice numbers", Graphics Gems I, 1990), in metres on a map, in seconds on
// a time axis.
#include <string>
#include <vector>

namespace sage::server::plots {

/// Ticks of a linear axis over [lo, hi]: the multiples of a nice step that lie in it, at most
/// about `max_ticks` of them (at least 2 when lo < hi). `step` is the spacing chosen.
struct Ticks {
  std::vector<double> values;
  double step = 0.0;
};
Ticks LinearTicks(double lo, double hi, int max_ticks);

/// Ticks of a log axis over [lo, hi] (0 < lo < hi): the powers of ten in it, with 2 and 5 times
/// them when fewer than three powers fall inside.
std::vector<double> LogTicks(double lo, double hi);

/// A tick's text: as few decimals as the step needs ("0", "2.5", "10"), thousands grouped
/// ("1,000"), or 1e-05 style when the step is below 1e-3 or above 1e6.
std::string TickLabel(double value, double step);

/// A scale bar's length: the largest nice length (1, 2, 5 x 10^k) not above `max_length`.
double ScaleBarLength(double max_length);

/// "1,000" for 1000: an integer with its thousands grouped.
std::string Grouped(long long n);

}  // namespace sage::server::plots
