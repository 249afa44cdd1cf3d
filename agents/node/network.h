#pragma once
// A mission's network (the scenario's `network`, maps::NetworkSettings) as the DDS configuration
// takes it (proto::NetworkConfig): shared by the agent node, the server node and the sage
// command, each of which makes its participant from it.
#include "maps/scenario/scenario.h"
#include "proto/dds_config.h"

namespace sage::agents {

inline proto::NetworkConfig NetworkOf(const maps::NetworkSettings& network) {
  proto::NetworkConfig config;
  config.interface_name = network.interface_name;
  config.peers = network.peers;
  config.multicast = network.multicast;
  return config;
}

}  // namespace sage::agents
