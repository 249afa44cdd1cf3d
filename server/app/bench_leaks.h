#pragma once
// `sage bench leaks SCENARIO`: how long a leak the server is not told of goes unnoticed. A Monte
// Carlo over seeds: run r hides random leaks drawn from seed first_seed + r (maps::WithRandomLeaks)
// and flies the same mission, in-process, under each configuration:
//   bayes  the ergodic fleet steering on the Bayesian risk loop (fusion.steer = posterior), on the
//          chosen profile (default: the scenario's);
//   astar  the fleet of A* tours on that profile (the tour baseline; its tours do not move for a
//          detection: an operator would re-plan by hand);
//   fixed  the ergodic fleet on each of the scenario's profiles with the loop scoring the scans but
//          not steering (the paper's fixed profiles).
// Every run of every configuration meets the same leaks at the same onsets. Writes DIR/leaks.json,
// leaks.md and leaks.svg (rewritten every tenth of the way, so an interrupted bench keeps what it measured)
// and prints the summary table; progress on stderr.
#include "server/app/options.h"

namespace sage::server {

/// Runs the benchmark; returns 0. Throws maps::ScenarioError for bad input (a scenario without
/// sensors, an unknown configuration) before anything runs.
int CmdBenchLeaks(const BenchLeaksCommand& command);

}  // namespace sage::server
