#pragma once
// The `sage` command: run a mission, compare ergodic control with the A* tour, evaluate a
// recorded trajectory. main() only calls RunCli.
namespace sage::server {

/// Parses the command line and runs the subcommand. Returns the process exit code: 0 on
/// success, 1 on a failed run, 2 on bad input (with one line on stderr saying what is wrong).
int RunCli(int argc, char** argv);

}  // namespace sage::server
