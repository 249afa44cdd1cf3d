#include "server/live/view_server.h"

#include <sys/socket.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>
#include <httplib.h>

#include "maps/scenario/scenario.h"
#include "server/live/frame_json.h"
#include "server/live/web_assets.h"
#include "server/live/viewer_priority.h"
#include "server/report/view_token.h"

namespace sage::live {
namespace {

constexpr const char* kJson = "application/json; charset=utf-8";
constexpr const char* kTokenHeader = "X-Sage-Token";

// The page may load only its own script and style and talk only to this server.
void SecurityHeaders(httplib::Response& res) {
  res.set_header("Content-Security-Policy",
                 "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
                 "base-uri 'none'; form-action 'none'; frame-ancestors 'none'");
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Referrer-Policy", "no-referrer");
  res.set_header("Cache-Control", "no-store");
}

// A whole number of the request, or nullopt.
std::optional<long long> WholeNumber(const std::string& text) {
  long long value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) return std::nullopt;
  return value;
}

std::optional<double> RealNumber(const std::string& text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty() || !std::isfinite(value)) return std::nullopt;
  return value;
}

// Text from a request as it may appear in an answer: at most 64 characters, control characters as '?'.
std::string Quoted(const std::string& text) {
  std::string out = text.substr(0, 64);
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return text.size() > 64 ? out + "..." : out;
}

}  // namespace

ViewServer::ViewServer(ViewSource& source, ViewServerOptions options)
    : source_(source), options_(std::move(options)), http_(std::make_unique<httplib::Server>()) {
  if (options_.token.empty()) throw std::invalid_argument("ViewServer: an empty token");
  const int pool = options_.max_streams + 4;
  http_->new_task_queue = [pool] { return new httplib::ThreadPool(static_cast<std::size_t>(pool)); };
  http_->set_payload_max_length(4096);
  http_->set_read_timeout(5, 0);
  http_->set_write_timeout(5, 0);
  http_->set_keep_alive_max_count(1000);
  // SO_REUSEADDR only: cpp-httplib's default also sets SO_REUSEPORT, with which a second server
  // binds the same port and takes half its requests.
  http_->set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  Routes();
  if (options_.port < 0 || options_.port > 65535) {
    throw maps::ScenarioError(fmt::format("--http = {}: must be a port in 0..65535 (0: any free one) or off", options_.port));
  }
  if (options_.port == 0) {
    port_ = http_->bind_to_any_port("127.0.0.1");
  } else {
    port_ = http_->bind_to_port("127.0.0.1", options_.port) ? options_.port : -1;
  }
  if (port_ <= 0) {
    throw maps::ScenarioError(fmt::format("--http = {}: cannot listen on 127.0.0.1:{} (in use? 0 takes any free port)",
                                          options_.port, options_.port));
  }
  thread_ = std::thread([this] {
    RunAtViewerPriority();  // and the connection threads it starts
    http_->listen_after_bind();
  });
}

ViewServer::~ViewServer() {
  stopping_ = true;
  http_->stop();
  if (thread_.joinable()) thread_.join();
}

std::string ViewServer::Url() const { return fmt::format("http://127.0.0.1:{}/#token={}", port_, options_.token); }

bool ViewServer::Authorised(const std::string& token) const { return server::SameToken(token, options_.token); }

void ViewServer::Routes() {
  // Every /api/ request carries the token, whatever its path (an unknown path had answered 404
  // without one: which paths exist was for anyone to probe); a refusal changes nothing and says why
  // in one line.
  const auto refused = [this](const httplib::Request& req, httplib::Response& res) {
    const std::string token =
        req.has_header(kTokenHeader) ? req.get_header_value(kTokenHeader) : req.get_param_value("token");
    if (Authorised(token)) return false;
    ++refused_;
    SecurityHeaders(res);
    res.status = 403;
    res.set_content(AnswerJson(false, token.empty() ? "refused: no token (it is in the address sage launch or "
                                                      "sage view printed, after #token=)"
                                                    : "refused: wrong token"),
                    kJson);
    return true;
  };
  // Only this machine's names for this server: a page elsewhere whose name was rebound to
  // 127.0.0.1 sends its own name.
  http_->set_pre_routing_handler([this, refused](const httplib::Request& req, httplib::Response& res) {
    const std::string host = req.get_header_value("Host");
    const std::string port = std::to_string(port_);
    if (host != "127.0.0.1:" + port && host != "localhost:" + port) {
      res.status = 403;
      res.set_content(AnswerJson(false, "refused: this server answers only requests to 127.0.0.1:" + port), kJson);
      return httplib::Server::HandlerResponse::Handled;
    }
    if (req.path.starts_with("/api/") && refused(req, res)) return httplib::Server::HandlerResponse::Handled;
    return httplib::Server::HandlerResponse::Unhandled;
  });
  for (const WebAsset& asset : WebAssets()) {
    http_->Get(std::string(asset.path), [asset](const httplib::Request&, httplib::Response& res) {
      SecurityHeaders(res);
      res.set_content(asset.body.data(), asset.body.size(), std::string(asset.content_type).c_str());
    });
  }
  // The API's handlers (the token was checked before routing, and is again here).
  const auto guarded = [refused](auto handler) {
    return [refused, handler](const httplib::Request& req, httplib::Response& res) {
      SecurityHeaders(res);
      if (refused(req, res)) return;
      handler(req, res);
    };
  };
  const auto time_param = [](const httplib::Request& req, httplib::Response& res, std::optional<double>& t) {
    if (!req.has_param("t")) return true;
    t = RealNumber(req.get_param_value("t"));
    if (t) return true;
    res.status = 400;
    res.set_content(AnswerJson(false, "t = " + Quoted(req.get_param_value("t")) + ": must be a number (mission seconds)"),
                    kJson);
    return false;
  };
  http_->Get("/api/scene", guarded([this](const httplib::Request&, httplib::Response& res) {
               res.set_content(source_.SceneJson(), kJson);
             }));
  http_->Get("/api/frame", guarded([this, time_param](const httplib::Request& req, httplib::Response& res) {
               std::optional<double> t;
               if (!time_param(req, res, t)) return;
               res.set_content(source_.FrameJson(t), kJson);
             }));
  http_->Get("/api/heat", guarded([this, time_param](const httplib::Request& req, httplib::Response& res) {
               std::optional<double> t;
               if (!time_param(req, res, t)) return;
               res.set_content(source_.HeatJson(t), kJson);
             }));
  http_->Get("/api/stream", guarded([this](const httplib::Request&, httplib::Response& res) {
               if (!source_.live()) {
                 res.status = 404;
                 res.set_content(AnswerJson(false, "a replay has no stream: ask /api/frame?t=S"), kJson);
                 return;
               }
               if (streams_.fetch_add(1) >= options_.max_streams) {
                 --streams_;
                 res.status = 503;
                 res.set_content(AnswerJson(false, fmt::format("refused: {} pages already watch this mission",
                                                               options_.max_streams)),
                                 kJson);
                 return;
               }
               auto last = std::make_shared<std::uint64_t>(0);
               res.set_header("X-Accel-Buffering", "no");
               res.set_chunked_content_provider(
                   "text/event-stream",
                   [this, last](std::size_t, httplib::DataSink& sink) {
                     if (stopping_) {
                       sink.done();
                       return true;
                     }
                     std::uint64_t seq = 0;
                     const std::shared_ptr<const std::string> frame =
                         source_.NextFrame(*last, *last == 0, std::chrono::milliseconds(1000), &seq);
                     if (!frame && source_.closed()) {
                       sink.done();
                       return true;
                     }
                     if (!frame) {
                       // A comment line: keeps the connection and finds a page that went away.
                       static constexpr char kKeepAlive[] = ": waiting for the mission\n\n";
                       return sink.write(kKeepAlive, sizeof kKeepAlive - 1);
                     }
                     *last = seq;
                     std::string event = "data: ";
                     event.reserve(frame->size() + 10);
                     event += *frame;
                     event += "\n\n";
                     return sink.write(event.data(), event.size());
                   },
                   [this](bool) { --streams_; });
             }));
  http_->Post("/api/action", guarded([this](const httplib::Request& req, httplib::Response& res) {
                ActionRequest a;
                a.verb = req.get_param_value("verb");
                std::string problem;
                if (a.verb == "risk") {
                  a.valve = req.get_param_value("valve");
                  const std::optional<double> w = RealNumber(req.get_param_value("weight"));
                  if (a.valve.empty()) problem = "valve: give a valve's name";
                  else if (!w) problem = "weight = " + Quoted(req.get_param_value("weight")) + ": must be a number";
                  else a.weight = *w;
                } else if (a.verb == "add") {
                  const std::optional<long long> n = WholeNumber(req.get_param_value("count"));
                  if (!n || *n < 1 || *n > 10000) problem = "count = " + Quoted(req.get_param_value("count")) + ": must be in 1..10000";
                  else a.count = static_cast<int>(*n);
                } else if (a.verb == "remove") {
                  const std::optional<long long> id = WholeNumber(req.get_param_value("id"));
                  if (!id || *id < 0 || *id > 1'000'000'000) problem = "id = " + Quoted(req.get_param_value("id")) + ": must be a vehicle id >= 0";
                  else a.id = static_cast<int>(*id);
                } else if (a.verb != "stop") {
                  problem = "verb = " + Quoted(a.verb) + ": must be risk, add, remove or stop";
                }
                if (!problem.empty()) {
                  res.status = 400;
                  res.set_content(AnswerJson(false, problem), kJson);
                  return;
                }
                const ActionAnswer answer = source_.Act(a);
                res.set_content(AnswerJson(answer.accepted, answer.line), kJson);
              }));
  http_->set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    SecurityHeaders(res);
    res.set_content(AnswerJson(false, fmt::format("HTTP {}", res.status)), kJson);
  });
}

}  // namespace sage::live
