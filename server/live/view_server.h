#pragma once
// The live view's web server (cpp-httplib), bound to 127.0.0.1 only: the page and its script
// and style, compiled into the binary (web/), and the mission's data under /api/, each request
// of which must carry the mission's token (header X-Sage-Token, or ?token= where a browser
// cannot set a header: the event stream). Without it, or with another, a request is answered
// 403 and changes nothing. Requests naming another host than 127.0.0.1 or localhost (a page
// elsewhere rebinding its name to this address) are refused too.
//
//   GET  /api/scene           the scene (frame_json.h SceneJson)
//   GET  /api/stream          Server-Sent Events: every new frame (live)
//   GET  /api/frame[?t=S]     the latest frame (live) or the frame at mission time S (replay)
//   GET  /api/heat[?t=S]      the risk heat map
//   POST /api/action          verb=risk&valve=P1&weight=0.9 | verb=add&count=2 | verb=remove&id=3
//                             | verb=stop: {"accepted": bool, "line": the operator's one-line answer}
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace sage::live {

/// An operator's request from the page, checked for form (numbers are numbers) but not yet
/// against the mission.
struct ActionRequest {
  std::string verb;  ///< risk | add | remove | stop
  std::string valve;
  double weight = 0.0;
  int count = 0;
  int id = -1;
};

struct ActionAnswer {
  bool accepted = false;
  std::string line;  ///< what `sage risk set` etc. would print (without "sage: error: ")
};

/// What the page reads: a running mission (LiveView) or a run directory (Replay).
class ViewSource {
 public:
  virtual ~ViewSource() = default;
  virtual std::string SceneJson() const = 0;
  /// Live: the newest frame's JSON once it is newer than `after_seq`, waiting up to `wait`;
  /// nullptr if none came. `with_trails`: with every vehicle's trail (a page's first frame).
  virtual std::shared_ptr<const std::string> NextFrame(std::uint64_t after_seq, bool with_trails,
                                                       std::chrono::milliseconds wait, std::uint64_t* seq) = 0;
  /// The frame at mission time t (replay), or the latest (live, t empty).
  virtual std::string FrameJson(std::optional<double> t) = 0;
  virtual std::string HeatJson(std::optional<double> t) = 0;
  /// Carries out an operator's request and returns the answer (refused where there is no
  /// mission to act on).
  virtual ActionAnswer Act(const ActionRequest& request) = 0;
  /// Live sources stream frames; a replay answers /api/frame?t= instead.
  virtual bool live() const = 0;
  /// No frame will come any more (the mission has ended): streams end.
  virtual bool closed() const { return false; }
};

struct ViewServerOptions {
  int port = 0;                 ///< 0: any free port
  std::string token;            ///< every /api/ request must carry it (not empty)
  int max_streams = 8;          ///< event streams open at once; more are refused (503)
};

class ViewServer {
 public:
  /// Listens on 127.0.0.1:port and serves from a thread of its own until destroyed. Throws
  /// maps::ScenarioError ("--http = 8080: cannot listen on 127.0.0.1:8080 ...") if it cannot.
  ViewServer(ViewSource& source, ViewServerOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const { return port_; }
  /// The page's address with the token in its fragment (never sent to the server in a request).
  std::string Url() const;
  /// Requests refused for a missing or wrong token so far.
  std::uint64_t refused() const { return refused_.load(); }

 private:
  void Routes();
  bool Authorised(const std::string& token) const;

  ViewSource& source_;
  ViewServerOptions options_;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
  int port_ = 0;
  std::atomic<int> streams_{0};
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> refused_{0};
};

}  // namespace sage::live
