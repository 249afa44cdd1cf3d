#pragma once
// The `sage` subcommands of fleet missions over DDS (server, agents, launch, vehicle, risk),
// kept apart from the in-process ones in cli.cpp. Internal to the sage command.
#include <memory>

#include "maps/scenario/scenario.h"

namespace CLI {
class App;
}

namespace sage::server {

struct FleetCli;

/// Declares the fleet subcommands on `app`; the returned state receives their options.
std::shared_ptr<FleetCli> AddFleetSubcommands(CLI::App& app);
/// Runs the fleet subcommand that was parsed, if any; returns its exit code, or -1 if none.
int RunFleetSubcommand(FleetCli& cli);

}  // namespace sage::server
