#pragma once
// What a mission's length may be, said once for the scenario's duration_s and for every command's
// --duration: within a week, and at least one control cycle flown (a mission flies
// round(duration_s x control_rate_hz) cycles; 0.01 s had flown a 0.1 s cycle and said "0 s").
#include <string>

namespace sage::maps {

/// "" or "must be > 0 and <= 604800 s (a week)".
std::string DurationRangeProblem(double duration_s);

/// "" or "must fly at least one control cycle (>= 0.05 s at control_rate_hz = 10: a mission flies
/// round(duration_s x control_rate_hz) cycles)". control_rate_hz > 0.
std::string DurationCycleProblem(double duration_s, double control_rate_hz);

}  // namespace sage::maps
