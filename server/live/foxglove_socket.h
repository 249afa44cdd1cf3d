#pragma once
// The Foxglove WebSocket protocol (foxglove.websocket.v1) as a server on 127.0.0.1, over
// websocketpp and standalone asio: a client that asks for the subprotocol and gives the
// mission's token (ws://127.0.0.1:PORT/?token=...) gets the server's info and the channels it
// advertises, subscribes to those it wants and receives their messages (binary Message Data
// frames: opcode 1, subscription id, timestamp, payload), and the mission clock (Time frames).
// A client without the token is refused in the handshake (403). A client that reads slower than
// the mission writes loses messages (more than 8 MB waiting for it), never the mission its pace.
//
// This file compiles as C++17 (websocketpp 0.8 does not build as C++20), so its interface holds
// only standard types; what the channels carry is foxglove_bridge.h's business.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace sage::live {

struct FoxgloveChannel {
  std::uint32_t id = 0;
  std::string topic;            ///< e.g. "/sage/vehicles"
  std::string encoding;         ///< "json"
  std::string schema_name;      ///< e.g. "foxglove.PosesInFrame"
  std::string schema;           ///< the schema itself (a JSON Schema for json)
  std::string schema_encoding;  ///< "jsonschema"
};

class FoxgloveSocket {
 public:
  /// Listens on 127.0.0.1:port (0: any free port) and serves from a thread of its own until
  /// destroyed. Throws std::runtime_error if it cannot listen.
  FoxgloveSocket(int port, std::string token, std::string server_name, std::vector<FoxgloveChannel> channels);
  ~FoxgloveSocket();
  FoxgloveSocket(const FoxgloveSocket&) = delete;
  FoxgloveSocket& operator=(const FoxgloveSocket&) = delete;

  int port() const;
  /// Does any client subscribe to `channel`?
  bool Subscribed(std::uint32_t channel) const;
  /// Sends a message to every subscriber of `channel` and keeps it for those who subscribe later.
  void Send(std::uint32_t channel, std::uint64_t timestamp_ns, const std::string& payload);
  /// The mission clock, to every client.
  void SendTime(std::uint64_t timestamp_ns);
  /// Clients connected now, and handshakes refused (no or a wrong token, no subprotocol).
  std::size_t clients() const;
  std::uint64_t refused() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sage::live
