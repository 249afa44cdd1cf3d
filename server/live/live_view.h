#pragma once
// The live view of a running mission: the server's loop hands it a frame now and then (it asks
// FrameDue(), at most ten a second) and the record's events as they happen, and takes the
// operators' requests from the page once a cycle; it never waits on a viewer. A publisher thread
// of its own keeps each vehicle's short trail and the event log, writes each frame's JSON once
// for every page, and the heat map when the risk changes; the web server's threads (and the
// Foxglove server's) only read what it last published.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "server/live/frame_json.h"
#include "server/live/heat_grid.h"
#include "server/live/live_frame.h"
#include "server/live/view_server.h"

namespace sage::live {

class FoxgloveBridge;

struct LiveViewOptions {
  std::optional<int> http_port = 0;      ///< the page's port (0: any free one); none: no page
  std::optional<int> foxglove_port = 0;  ///< foxglove.websocket.v1 (0: any free one); none: off
  std::string token;                     ///< the mission's token (both servers ask for it)
  double frame_period_s = 0.1;           ///< wall seconds between frames (10 a second)
  double trail_s = 4.0;                  ///< mission seconds of each vehicle's trail (the page's too)
  int trail_points = 8;                  ///< points of a trail
};

/// An operator's request from the page, waiting for the server's loop to carry it out.
class PendingAction {
 public:
  explicit PendingAction(ActionRequest request) : request_(std::move(request)) {}
  const ActionRequest& request() const { return request_; }
  /// The answer (once; later calls do nothing).
  void Answer(bool accepted, std::string line);
  std::future<ActionAnswer> future() { return promise_.get_future(); }

 private:
  ActionRequest request_;
  std::promise<ActionAnswer> promise_;
  bool answered_ = false;
};

class LiveView final : public ViewSource {
 public:
  /// Starts the servers. Throws maps::ScenarioError if a port cannot be had.
  LiveView(LiveScene scene, LiveViewOptions options);
  ~LiveView() override;
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// "http://127.0.0.1:PORT/#token=..." (empty without a page).
  std::string PageUrl() const;
  /// "ws://127.0.0.1:PORT/?token=..." (empty without Foxglove).
  std::string FoxgloveUrl() const;
  int http_port() const;
  int foxglove_port() const;

  // ---- from the mission's loop (one thread); none of these waits for a lock ----
  /// Is a frame due (frame_period_s of wall time since the last)?
  bool FrameDue() const;
  /// Hands over a frame with the events since the last; returns at once. The view's thread takes
  /// the newest; a frame it had not taken yet is dropped (its events go with this one).
  void Publish(LiveFrame frame);
  /// An event of the record, for the log (handed over with the next frame).
  void OnEvent(EventView event);
  /// The operators' requests from the page since the last call, to be answered (none this time
  /// if a page is handing one in at this very moment: they come next cycle).
  std::vector<std::shared_ptr<PendingAction>> TakeActions();
  /// The mission has ended: requests still waiting, and any that come, are refused with that.
  void Close(const std::string& why);

  // ---- ViewSource (the web server's threads) ----
  std::string SceneJson() const override { return scene_json_; }
  std::shared_ptr<const std::string> NextFrame(std::uint64_t after_seq, bool with_trails,
                                               std::chrono::milliseconds wait, std::uint64_t* seq) override;
  std::string FrameJson(std::optional<double> t) override;
  std::string HeatJson(std::optional<double> t) override;
  ActionAnswer Act(const ActionRequest& request) override;
  bool live() const override { return true; }
  bool closed() const override;

  /// Whether someone watches: a page asked for a frame or the heat map in the last 5 s, or a
  /// Foxglove client is connected. An unwatched view's thread keeps the trails and the log only.
  bool watched() const;
  /// Frames published so far.
  std::uint64_t frames_published() const;
  /// The publisher thread's time a frame (trails, log, JSON, heat map; the Foxglove messages
  /// while someone subscribes), in ms of the clock: what the view takes from the machine besides
  /// the loop's copy, with the time the thread (at nice 5) waited for a core.
  double publisher_ms_per_frame() const;
  /// The same on the thread's CPU clock: its own work alone.
  double publisher_cpu_ms_per_frame() const;

 private:
  void PublisherLoop();
  void Digest(LiveFrame& frame, std::vector<EventView>& events);
  void Asked();  // a reader asked: the view is watched
  std::vector<LoggedEvent> RecentEventsLocked() const;  // what a frame carries of the log; published_mutex_ held

  LiveScene scene_;
  LiveViewOptions options_;
  std::string scene_json_;
  // The hand-over: the loop swaps a frame in, the view's thread swaps it out (it looks every
  // few ms). No lock: a lock the view's low-priority thread held when preempted had kept the
  // loop waiting.
  std::atomic<LiveFrame*> mailbox_{nullptr};
  std::vector<EventView> loop_events_;  // the loop's own, until its next frame
  std::atomic<std::int64_t> last_publish_ns_{0};
  std::atomic<bool> stop_{false};

  std::mutex actions_mutex_;
  std::vector<std::shared_ptr<PendingAction>> actions_;
  std::optional<std::string> closed_;

  // The publisher's own (only its thread touches them).
  struct TrailPoint {
    double time_s;
    float x_m, y_m;
  };
  using Trail = std::vector<TrailPoint>;  // oldest first; at most trail_points + 1
  // Each vehicle's trail in a slot of its own, found through the last frame's order (a frame
  // lists the vehicles in ascending id, every one ever heard of, so the order changes only when
  // one joins): a map of 10,000 deques walked every frame had been most of the view's thread at
  // 10,000 vehicles with nobody watching.
  std::vector<Trail> trails_;
  std::unordered_map<int, std::uint32_t> trail_slot_;
  std::vector<int> last_ids_;
  std::vector<std::uint32_t> last_slots_;
  Trail& TrailOf(std::size_t i, int id);
  std::vector<double> heat_shares_;
  std::chrono::steady_clock::time_point last_heat_{};

  // What the readers read.
  mutable std::mutex published_mutex_;
  std::condition_variable published_cv_;
  std::uint64_t seq_ = 0;
  std::shared_ptr<const LiveFrame> frame_;        // with trails if someone watched when it came
  bool frame_has_trails_ = false;
  std::shared_ptr<const std::string> frame_json_; // without trails
  std::shared_ptr<const std::string> frame_json_trails_;  // made when first asked
  std::deque<LoggedEvent> log_;                   // the latest kLogKept
  std::uint64_t events_total_ = 0;
  std::uint64_t heat_seq_ = 0;
  std::shared_ptr<const std::string> heat_json_;
  std::shared_ptr<const HeatGrid> heat_;
  std::uint64_t skipped_ = 0;  // frames replaced before the view's thread took them (the loop's)
  bool closed_streams_ = false;  // the last frame is out: streams end
  std::atomic<std::uint64_t> digest_ns_{0}, digest_cpu_ns_{0}, digested_{0};
  std::atomic<std::int64_t> last_asked_ns_{INT64_MIN / 2};

  std::thread publisher_;
  std::unique_ptr<ViewServer> http_;
  std::unique_ptr<FoxgloveBridge> foxglove_;
};

}  // namespace sage::live
