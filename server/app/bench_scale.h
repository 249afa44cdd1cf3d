#pragma once
// `sage bench scale`: how the system scales with the fleet. For each fleet size N a field grows
// with it (N XTs, 3.5 N valves, N vehicles: weak scaling) and is written to DIR/fields/; the
// ergodic fleet and the A* tour baseline fly it for the same mission time in-process (Mission in
// a forked process of its own, so each run's CPU and peak memory are its own) and over DDS
// (`sage launch` as a child process, its run directory under DIR/runs/). Each run becomes a row
// of DIR/scale.json, DIR/scale.md and DIR/scale.svg (rewritten after every run, so an
// interrupted benchmark keeps what it measured); the table is printed at the end. Progress
// lines on stderr. Runs one at a time: the figures are of one mission on the machine.
#include <string>
#include <vector>

#include "server/app/options.h"

namespace sage::server {

/// The fleet sizes of --vehicles: comma-separated whole numbers, each in 1..kMaxBenchVehicles,
/// none twice, at least one; returned in increasing order. Throws maps::ScenarioError with one
/// line naming the value and the rule ("--vehicles = 0: ...").
std::vector<int> ParseVehicleCounts(const std::string& text);
inline constexpr int kMaxBenchVehicles = 10000;

/// Runs the benchmark; returns 0 if every run produced its row, 1 if any failed (its row says why).
int CmdBenchScale(const BenchScaleCommand& command);

}  // namespace sage::server
