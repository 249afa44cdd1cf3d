#pragma once
// The mission in Foxglove's schemas, over foxglove.websocket.v1 (foxglove_socket.h), so that
// Foxglove and Lichtblick users see the fleet as ROS users see their robots. JSON encoding, in
// the "seabed" frame (x east, y north, z up, metres; the workspace's corner at the origin);
// message times are mission time, which the server also publishes as the clock ("time").
//
//   /sage/vehicles   foxglove.PosesInFrame  every vehicle alive (heading as a yaw), each frame
//   /sage/scene      foxglove.SceneUpdate   XTs (cubes), valves (spheres coloured by risk, with
//                                           name and time since the last visit), vehicles
//                                           (arrows, grey when stale, lost or gone) and names
//   /sage/risk_grid  foxglove.Grid          the risk density (float32, 1/m^2), when it changes
//   /sage/mission    sage.MissionStatus     clock, vehicles alive / stale / lost / left, metric
//
// Messages for a channel are made only while someone subscribes to it.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "server/live/heat_grid.h"
#include "server/live/live_frame.h"

namespace sage::live {

class FoxgloveSocket;

class FoxgloveBridge {
 public:
  /// Listens on 127.0.0.1:port (0: any free port). Throws maps::ScenarioError if it cannot.
  FoxgloveBridge(const LiveScene& scene, int port, std::string token);
  ~FoxgloveBridge();
  FoxgloveBridge(const FoxgloveBridge&) = delete;
  FoxgloveBridge& operator=(const FoxgloveBridge&) = delete;

  int port() const;
  /// Clients connected now.
  std::size_t clients() const;
  /// ws://127.0.0.1:PORT/?token=...
  std::string Url() const;
  /// A frame of the mission (with trails), and the heat map as it stands (may be null) with its
  /// sequence number (a new number: a new map).
  void Publish(const LiveFrame& frame, const HeatGrid* heat, std::uint64_t heat_seq);

 private:
  const LiveScene& scene_;
  std::string token_;
  std::unique_ptr<FoxgloveSocket> socket_;
  std::uint64_t last_heat_seq_ = 0;
  std::chrono::steady_clock::time_point last_scene_wall_{};
};

/// The JSON messages, for the bridge and its tests.
std::string PosesInFrameJson(const LiveFrame& frame);
std::string SceneUpdateJson(const LiveScene& scene, const LiveFrame& frame);
std::string GridJson(const HeatGrid& grid, double time_s);
std::string MissionStatusJson(const LiveFrame& frame);

}  // namespace sage::live
