// Compiled as C++17: see foxglove_socket.h.
#include "server/live/foxglove_socket.h"
#include "server/live/viewer_priority.h"

#define ASIO_STANDALONE
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <future>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "server/report/view_token.h"

namespace sage::live {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
using Json = nlohmann::json;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
// Bytes waiting for a slow client beyond which its messages are dropped.
constexpr std::size_t kMaxBuffered = 8u << 20;
// What a client may send at once (subscribe / unsubscribe are a few hundred bytes).
constexpr std::size_t kMaxClientMessage = 64u << 10;

std::string TokenOf(const std::string& resource) {
  const std::size_t q = resource.find('?');
  if (q == std::string::npos) return {};
  std::size_t at = q + 1;
  while (at < resource.size()) {
    const std::size_t end = std::min(resource.find('&', at), resource.size());
    const std::string pair = resource.substr(at, end - at);
    if (pair.rfind("token=", 0) == 0) return pair.substr(6);
    at = end + 1;
  }
  return {};
}

void PutLe(std::string& out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((value >> (8 * i)) & 0xff);
}

}  // namespace

struct FoxgloveSocket::Impl {
  WsServer ws;
  std::string token, name;
  std::vector<FoxgloveChannel> channels;
  std::thread thread;
  int port = 0;
  std::atomic<std::uint64_t> refused{0};

  mutable std::mutex mutex;
  // Each client's subscriptions: subscription id -> channel id.
  std::map<Handle, std::map<std::uint32_t, std::uint32_t>, std::owner_less<Handle>> clients;
  std::map<std::uint32_t, std::pair<std::uint64_t, std::string>> latest;  // channel -> (stamp, payload)

  bool Known(std::uint32_t channel) const {
    return std::any_of(channels.begin(), channels.end(), [&](const FoxgloveChannel& c) { return c.id == channel; });
  }

  void SendText(Handle h, const std::string& text) {
    websocketpp::lib::error_code ec;
    ws.send(h, text, websocketpp::frame::opcode::text, ec);
  }

  void Status(Handle h, int level, const std::string& message) {
    SendText(h, Json{{"op", "status"}, {"level", level}, {"message", message}}.dump());
  }

  // Sends a binary frame unless too much already waits for this client. Called with `mutex` held.
  void SendBinary(Handle h, const std::string& frame) {
    websocketpp::lib::error_code ec;
    WsServer::connection_ptr con = ws.get_con_from_hdl(h, ec);
    if (ec || con->get_buffered_amount() > kMaxBuffered) return;
    con->send(frame.data(), frame.size(), websocketpp::frame::opcode::binary);
  }

  static std::string MessageFrame(std::uint32_t subscription, std::uint64_t stamp_ns, const std::string& payload) {
    std::string frame;
    frame.reserve(13 + payload.size());
    frame += static_cast<char>(0x01);
    PutLe(frame, subscription, 4);
    PutLe(frame, stamp_ns, 8);
    frame += payload;
    return frame;
  }

  bool Validate(Handle h) {
    WsServer::connection_ptr con = ws.get_con_from_hdl(h);
    const std::string host = con->get_request_header("Host");
    const std::string p = std::to_string(port);
    if (!server::SameToken(TokenOf(con->get_resource()), token) || (host != "127.0.0.1:" + p && host != "localhost:" + p)) {
      ++refused;
      con->set_status(websocketpp::http::status_code::forbidden);
      return false;
    }
    const std::vector<std::string>& asked = con->get_requested_subprotocols();
    if (std::find(asked.begin(), asked.end(), kSubprotocol) == asked.end()) {
      ++refused;
      con->set_status(websocketpp::http::status_code::bad_request);
      return false;
    }
    con->select_subprotocol(kSubprotocol);
    return true;
  }

  void Open(Handle h) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      clients[h];
    }
    SendText(h, Json{{"op", "serverInfo"},
                     {"name", name},
                     {"capabilities", Json::array({"time"})},
                     {"metadata", Json::object()},
                     {"sessionId", std::to_string(reinterpret_cast<std::uintptr_t>(this))}}
                    .dump());
    Json list = Json::array();
    for (const FoxgloveChannel& c : channels) {
      list.push_back({{"id", c.id},
                      {"topic", c.topic},
                      {"encoding", c.encoding},
                      {"schemaName", c.schema_name},
                      {"schema", c.schema},
                      {"schemaEncoding", c.schema_encoding}});
    }
    SendText(h, Json{{"op", "advertise"}, {"channels", list}}.dump());
  }

  void Close(Handle h) {
    std::lock_guard<std::mutex> lock(mutex);
    clients.erase(h);
  }

  // subscribe / unsubscribe; anything else is answered with a status line, never trusted.
  void Message(Handle h, WsServer::message_ptr message) {
    if (message->get_opcode() != websocketpp::frame::opcode::text) {
      Status(h, 1, "this server takes no client messages (no clientPublish)");
      return;
    }
    const Json request = Json::parse(message->get_payload(), nullptr, /*allow_exceptions=*/false);
    if (!request.is_object() || !request.contains("op") || !request["op"].is_string()) {
      Status(h, 2, "not a foxglove.websocket.v1 request (a JSON object with \"op\")");
      return;
    }
    const std::string op = request["op"].get<std::string>();
    if (op == "subscribe" && request.contains("subscriptions") && request["subscriptions"].is_array()) {
      std::vector<std::pair<std::uint32_t, std::uint32_t>> added;
      std::string problem;
      {
        std::lock_guard<std::mutex> lock(mutex);
        auto client = clients.find(h);
        if (client == clients.end()) return;
        for (const Json& s : request["subscriptions"]) {
          if (!s.is_object() || !s.contains("id") || !s.contains("channelId") || !s["id"].is_number_unsigned() ||
              !s["channelId"].is_number_unsigned() || s["id"].get<std::uint64_t>() > 0xffffffffull ||
              s["channelId"].get<std::uint64_t>() > 0xffffffffull) {
            problem = "a subscription needs an \"id\" and a \"channelId\" (unsigned 32-bit numbers)";
            continue;
          }
          const auto id = s["id"].get<std::uint32_t>();
          const auto channel = s["channelId"].get<std::uint32_t>();
          if (!Known(channel)) {
            problem = "no channel " + std::to_string(channel);
          } else if (client->second.count(id) != 0) {
            problem = "subscription id " + std::to_string(id) + " is in use";
          } else {
            client->second[id] = channel;
            added.emplace_back(id, channel);
          }
        }
        // A new subscriber gets each channel's latest message at once (the scene, the grid).
        for (const auto& [id, channel] : added) {
          const auto last = latest.find(channel);
          if (last != latest.end()) SendBinary(h, MessageFrame(id, last->second.first, last->second.second));
        }
      }
      if (!problem.empty()) Status(h, 1, problem);
    } else if (op == "unsubscribe" && request.contains("subscriptionIds") && request["subscriptionIds"].is_array()) {
      std::lock_guard<std::mutex> lock(mutex);
      auto client = clients.find(h);
      if (client == clients.end()) return;
      for (const Json& id : request["subscriptionIds"]) {
        if (id.is_number_unsigned() && id.get<std::uint64_t>() <= 0xffffffffull) client->second.erase(id.get<std::uint32_t>());
      }
    } else {
      Status(h, 1, "unsupported op: " + op.substr(0, 64));
    }
  }
};

FoxgloveSocket::FoxgloveSocket(int port, std::string token, std::string server_name,
                               std::vector<FoxgloveChannel> channels)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.token = std::move(token);
  m.name = std::move(server_name);
  m.channels = std::move(channels);
  m.ws.clear_access_channels(websocketpp::log::alevel::all);
  m.ws.clear_error_channels(websocketpp::log::elevel::all);
  m.ws.init_asio();
  m.ws.set_reuse_addr(true);
  m.ws.set_max_message_size(kMaxClientMessage);
  m.ws.set_validate_handler([&m](Handle h) { return m.Validate(h); });
  m.ws.set_open_handler([&m](Handle h) { m.Open(h); });
  m.ws.set_close_handler([&m](Handle h) { m.Close(h); });
  m.ws.set_fail_handler([&m](Handle h) { m.Close(h); });
  m.ws.set_message_handler([&m](Handle h, WsServer::message_ptr message) { m.Message(h, message); });
  websocketpp::lib::error_code ec;
  m.ws.listen(asio::ip::tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)), ec);
  if (!ec) m.port = m.ws.get_local_endpoint(ec).port();
  if (!ec) m.ws.start_accept(ec);
  if (ec) throw std::runtime_error("cannot listen on 127.0.0.1:" + std::to_string(port) + ": " + ec.message());
  m.thread = std::thread([&m] {
    RunAtViewerPriority();
    m.ws.run();
  });
}

FoxgloveSocket::~FoxgloveSocket() {
  Impl& m = *impl_;
  // The acceptor is the socket thread's (asio's objects are not thread-safe). Closed from here,
  // it raced that thread: the aborted accept's handler (websocketpp's handle_accept) re-arms the
  // accept while websocketpp still says it is listening, and asio's start_op found the acceptor's
  // descriptor gone under its lock (SIGSEGV at the server's teardown, now and then on a loaded
  // machine). So the thread stops listening and closes the clients itself, then the loop stops.
  std::promise<void> closed;
  asio::post(m.ws.get_io_service(), [&m, &closed] {
    websocketpp::lib::error_code ec;
    m.ws.stop_listening(ec);
    {
      std::lock_guard<std::mutex> lock(m.mutex);
      for (const auto& [h, subscriptions] : m.clients) m.ws.close(h, websocketpp::close::status::going_away, "mission ended", ec);
    }
    closed.set_value();
  });
  // Bounded: if the thread never got to it, the endpoint's destructor closes the acceptor after
  // the join below, with no thread left to race.
  closed.get_future().wait_for(std::chrono::seconds(2));
  m.ws.stop();
  if (m.thread.joinable()) m.thread.join();
}

int FoxgloveSocket::port() const { return impl_->port; }

bool FoxgloveSocket::Subscribed(std::uint32_t channel) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  for (const auto& [h, subscriptions] : impl_->clients)
    for (const auto& [id, c] : subscriptions)
      if (c == channel) return true;
  return false;
}

void FoxgloveSocket::Send(std::uint32_t channel, std::uint64_t timestamp_ns, const std::string& payload) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lock(m.mutex);
  m.latest[channel] = {timestamp_ns, payload};
  for (const auto& [h, subscriptions] : m.clients)
    for (const auto& [id, c] : subscriptions)
      if (c == channel) m.SendBinary(h, Impl::MessageFrame(id, timestamp_ns, payload));
}

void FoxgloveSocket::SendTime(std::uint64_t timestamp_ns) {
  Impl& m = *impl_;
  std::string frame(1, static_cast<char>(0x02));
  PutLe(frame, timestamp_ns, 8);
  std::lock_guard<std::mutex> lock(m.mutex);
  for (const auto& [h, subscriptions] : m.clients) m.SendBinary(h, frame);
}

std::size_t FoxgloveSocket::clients() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->clients.size();
}

std::uint64_t FoxgloveSocket::refused() const { return impl_->refused.load(); }

}  // namespace sage::live
