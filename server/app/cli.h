#pragma once
// The `sage` command: run a mission, compare ergodic control with the A* tour, evaluate a
// recorded trajectory. main() only calls RunCli.
#include <string>

namespace sage::server {

/// Parses the command line and runs the subcommand. Returns the process exit code: 0 on
/// success, 1 on a failed run, 2 on bad input (with one line on stderr saying what is wrong).
int RunCli(int argc, char** argv);

/// What is wrong with a number option's text for the range [low, high] (whole: a whole number in
/// low..high), in the project's words ("must be a number in [0, 4]"), or empty if it fits. The
/// options' checks say this rather than CLI11's "Value 5 not in range 0.000000 to 4.000000".
std::string RangeProblem(const std::string& text, double low, double high, bool whole);

}  // namespace sage::server
