#include "server/live/live_view.h"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>

#include "server/live/foxglove_bridge.h"
#include "server/live/viewer_priority.h"

namespace sage::live {
namespace {

constexpr std::size_t kLogKept = 200;      // events kept for pages that open late
constexpr std::size_t kLogPerFrame = 50;   // the latest events each frame carries
// The page waits this long for the server's loop to carry out its request (a removal waits
// for the vehicle to leave, up to 5 s, as `sage vehicle remove` does).
constexpr auto kActionWait = std::chrono::seconds(15);
// The heat map is made again when a share moved, at most this often.
constexpr auto kHeatPeriod = std::chrono::milliseconds(500);
// A view nobody has asked anything of for this long (and no Foxglove client) is not watched:
// its frames keep the trails but leave their JSON to the first request and make no heat map.
constexpr std::int64_t kUnwatchedAfterNs = 5'000'000'000;

}  // namespace

void PendingAction::Answer(bool accepted, std::string line) {
  if (answered_) return;
  answered_ = true;
  promise_.set_value({accepted, std::move(line)});
}

LiveView::LiveView(LiveScene scene, LiveViewOptions options)
    : scene_(std::move(scene)), options_(std::move(options)) {
  scene_.mode = "live";
  scene_.actions = true;
  scene_json_ = live::SceneJson(scene_);
  publisher_ = std::thread([this] {
    pthread_setname_np(pthread_self(), kPublisherThreadName);  // as top -H and /proc show it
    RunAtViewerPriority();
    PublisherLoop();
  });
  try {
    if (options_.http_port) {
      ViewServerOptions http;
      http.port = *options_.http_port;
      http.token = options_.token;
      http_ = std::make_unique<ViewServer>(*this, http);
    }
    if (options_.foxglove_port) foxglove_ = std::make_unique<FoxgloveBridge>(scene_, *options_.foxglove_port, options_.token);
  } catch (...) {
    http_.reset();
    stop_ = true;
    publisher_.join();
    throw;
  }
}

LiveView::~LiveView() {
  Close("the mission has ended");
  // The last frame (the mission's end) is published first, and the pages' streams get a moment
  // to send it before the servers stop.
  stop_ = true;
  if (publisher_.joinable()) publisher_.join();
  delete mailbox_.exchange(nullptr);
  {
    std::lock_guard lock(published_mutex_);
    closed_streams_ = true;
  }
  published_cv_.notify_all();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  http_.reset();
  foxglove_.reset();
}

std::string LiveView::PageUrl() const { return http_ ? http_->Url() : std::string(); }
std::string LiveView::FoxgloveUrl() const { return foxglove_ ? foxglove_->Url() : std::string(); }
int LiveView::http_port() const { return http_ ? http_->port() : -1; }
int LiveView::foxglove_port() const { return foxglove_ ? foxglove_->port() : -1; }

namespace {
std::int64_t SteadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
std::int64_t ThreadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace

bool LiveView::FrameDue() const {
  // Within 80 % of the period: the loop asks once a cycle, and cycles a period apart that come a
  // little early would otherwise make every other one wait (five frames a second, not ten).
  return static_cast<double>(SteadyNs() - last_publish_ns_.load(std::memory_order_relaxed)) >=
         0.8e9 * options_.frame_period_s;
}

void LiveView::Publish(LiveFrame frame) {
  auto* fresh = new LiveFrame(std::move(frame));
  // A frame the view's thread has not taken yet is taken back: its events go with this one.
  if (LiveFrame* stale = mailbox_.exchange(nullptr, std::memory_order_acq_rel)) {
    ++skipped_;
    loop_events_.insert(loop_events_.begin(), std::make_move_iterator(stale->new_events.begin()),
                        std::make_move_iterator(stale->new_events.end()));
    delete stale;
  }
  fresh->new_events = std::move(loop_events_);
  loop_events_.clear();
  mailbox_.store(fresh, std::memory_order_release);
  last_publish_ns_.store(SteadyNs(), std::memory_order_relaxed);
}

void LiveView::OnEvent(EventView event) { loop_events_.push_back(std::move(event)); }

std::vector<std::shared_ptr<PendingAction>> LiveView::TakeActions() {
  std::vector<std::shared_ptr<PendingAction>> out;
  std::unique_lock lock(actions_mutex_, std::try_to_lock);
  if (lock.owns_lock()) out.swap(actions_);
  return out;
}

void LiveView::Close(const std::string& why) {
  std::lock_guard lock(actions_mutex_);
  if (!closed_) closed_ = why;
  for (const auto& a : actions_) a->Answer(false, why);
  actions_.clear();
}

ActionAnswer LiveView::Act(const ActionRequest& request) {
  auto action = std::make_shared<PendingAction>(request);
  std::future<ActionAnswer> answer = action->future();
  {
    std::lock_guard lock(actions_mutex_);
    if (closed_) return {false, *closed_};
    actions_.push_back(action);
  }
  if (answer.wait_for(kActionWait) != std::future_status::ready) {
    // Still queued or carried out later: the answer then goes nowhere, as a command's whose
    // operator gave up.
    return {false, "the server did not answer within 15 s"};
  }
  return answer.get();
}

bool LiveView::closed() const {
  std::lock_guard lock(published_mutex_);
  return closed_streams_;
}

std::uint64_t LiveView::frames_published() const {
  std::lock_guard lock(published_mutex_);
  return seq_;
}

double LiveView::publisher_ms_per_frame() const {
  const std::uint64_t frames = digested_.load();
  return frames == 0 ? 0.0 : static_cast<double>(digest_ns_.load()) * 1e-6 / static_cast<double>(frames);
}

double LiveView::publisher_cpu_ms_per_frame() const {
  const std::uint64_t frames = digested_.load();
  return frames == 0 ? 0.0 : static_cast<double>(digest_cpu_ns_.load()) * 1e-6 / static_cast<double>(frames);
}

std::vector<LoggedEvent> LiveView::RecentEventsLocked() const {
  const std::size_t from = log_.size() > kLogPerFrame ? log_.size() - kLogPerFrame : 0;
  return {log_.begin() + static_cast<long>(from), log_.end()};
}

void LiveView::Asked() { last_asked_ns_.store(SteadyNs(), std::memory_order_relaxed); }

bool LiveView::watched() const {
  return SteadyNs() - last_asked_ns_.load(std::memory_order_relaxed) < kUnwatchedAfterNs ||
         (foxglove_ && foxglove_->clients() > 0);
}

std::shared_ptr<const std::string> LiveView::NextFrame(std::uint64_t after_seq, bool with_trails,
                                                       std::chrono::milliseconds wait, std::uint64_t* seq) {
  Asked();
  std::unique_lock lock(published_mutex_);
  // A page's first frame carries the trails, which a frame published while nobody watched has
  // not: the next one has (this request has made the view watched), within a frame's period.
  published_cv_.wait_for(lock, wait, [&] {
    return closed_streams_ || (seq_ > after_seq && (!with_trails || frame_has_trails_));
  });
  if (seq_ <= after_seq || !frame_) return nullptr;
  *seq = seq_;
  if (!with_trails) {
    // A frame published while nobody watched has no JSON yet: the first to ask makes it.
    if (!frame_json_) {
      frame_json_ = std::make_shared<const std::string>(
          live::FrameJson(*frame_, seq_, RecentEventsLocked(), events_total_, heat_seq_, /*with_trails=*/false));
    }
    return frame_json_;
  }
  if (!frame_json_trails_) {
    const std::vector<LoggedEvent> events(log_.begin(), log_.end());
    frame_json_trails_ = std::make_shared<const std::string>(
        live::FrameJson(*frame_, seq_, events, events_total_, heat_seq_, /*with_trails=*/true));
  }
  return frame_json_trails_;
}

std::string LiveView::FrameJson(std::optional<double>) {
  std::uint64_t seq = 0;
  // Waits for a frame with the trails if the newest has none (nobody watched when it came).
  const std::shared_ptr<const std::string> frame = NextFrame(0, true, std::chrono::milliseconds(500), &seq);
  return frame ? *frame : std::string("{\"seq\":0}");
}

std::string LiveView::HeatJson(std::optional<double>) {
  Asked();
  std::lock_guard lock(published_mutex_);
  return heat_json_ ? *heat_json_ : std::string("{\"seq\":0,\"nx\":0,\"ny\":0}");
}

LiveView::Trail& LiveView::TrailOf(std::size_t i, int id) {
  if (i < last_ids_.size() && last_ids_[i] == id) return trails_[last_slots_[i]];
  const auto [at, fresh] = trail_slot_.try_emplace(id, static_cast<std::uint32_t>(trails_.size()));
  if (fresh) trails_.emplace_back().reserve(static_cast<std::size_t>(std::max(1, options_.trail_points)) + 1);
  if (last_ids_.size() <= i) last_ids_.resize(i + 1), last_slots_.resize(i + 1);
  last_ids_[i] = id;
  last_slots_[i] = at->second;
  return trails_[at->second];
}

// Trails: a point each trail_s / trail_points mission seconds, those of the last trail_s kept.
void LiveView::Digest(LiveFrame& frame, std::vector<EventView>& events) {
  const double step = options_.trail_s / std::max(1, options_.trail_points);
  // The trails go on whether anyone watches or not (a page opened later gets them); a frame
  // carries them only when someone watches, for a page's first frame (NextFrame).
  const bool watching = watched();
  if (watching) frame.trails.resize(frame.vehicles.size());
  for (std::size_t i = 0; i < frame.vehicles.size(); ++i) {
    const VehicleView& v = frame.vehicles[i];
    Trail& points = TrailOf(i, v.id);
    const bool flying = v.status != VehicleStatus::kLost && v.status != VehicleStatus::kLeft;
    if (flying && (points.empty() || frame.time_s - points.back().time_s >= step)) {
      points.push_back({frame.time_s, v.x_m, v.y_m});
    }
    if (flying) {
      const auto kept = std::find_if(points.begin(), points.end(),
                                     [&](const TrailPoint& p) { return p.time_s >= frame.time_s - options_.trail_s; });
      points.erase(points.begin(), kept);
    }
    if (!watching) continue;
    std::vector<float>& trail = frame.trails[i];
    trail.clear();
    trail.reserve(2 * points.size());
    for (const TrailPoint& p : points) {
      trail.push_back(p.x_m);
      trail.push_back(p.y_m);
    }
  }
  // Unwatched (at 10,000 vehicles and 35,000 valves the JSON and the heat map took 47 ms of the
  // view's thread a frame, a sixth of the machine at ten frames a second, with nobody looking):
  // the trails and the log go on, the JSON waits for its first reader (NextFrame) and the heat
  // map for a viewer (the next frame after one asks makes it: its shares differ from the last
  // map's).
  std::vector<double> shares(watching ? frame.valves.size() : 0);
  for (std::size_t i = 0; i < shares.size(); ++i) shares[i] = frame.valves[i].share;
  const auto now = std::chrono::steady_clock::now();
  std::shared_ptr<const HeatGrid> heat;
  if (watching && shares != heat_shares_ && now - last_heat_ >= kHeatPeriod) {
    heat_shares_ = shares;
    last_heat_ = now;
    heat = std::make_shared<const HeatGrid>(RiskDensityGrid(scene_, shares));
  }

  // The log and the sequence numbers under the lock; the JSON is written outside it, so readers
  // wait only for pointers to change.
  std::vector<LoggedEvent> recent;
  std::uint64_t seq = 0, events_total = 0, heat_seq = 0;
  {
    std::lock_guard lock(published_mutex_);
    for (EventView& e : events) {
      log_.push_back({++events_total_, std::move(e)});
      if (log_.size() > kLogKept) log_.pop_front();
    }
    if (watching) recent = RecentEventsLocked();
    seq = seq_ + 1;
    events_total = events_total_;
    heat_seq = heat_seq_ + (heat ? 1 : 0);
  }
  auto shared = std::make_shared<const LiveFrame>(std::move(frame));
  std::shared_ptr<const std::string> json;
  if (watching) {
    json = std::make_shared<const std::string>(
        live::FrameJson(*shared, seq, recent, events_total, heat_seq, /*with_trails=*/false));
  }
  std::shared_ptr<const std::string> heat_json;
  if (heat) heat_json = std::make_shared<const std::string>(live::HeatJson(*heat, heat_seq));
  std::lock_guard lock(published_mutex_);
  if (heat) {
    heat_ = std::move(heat);
    heat_json_ = std::move(heat_json);
    heat_seq_ = heat_seq;
  }
  seq_ = seq;
  frame_ = std::move(shared);
  frame_has_trails_ = watching;
  frame_json_ = std::move(json);
  frame_json_trails_.reset();
}

void LiveView::PublisherLoop() {
  // The view yields to the mission: SCHED_BATCH (a frame handed over does not wake this thread
  // in the loop's place: measured, the loop's copy had taken the publisher's whole work, 1.5 ms
  // of a 10 ms cycle at 1,000 vehicles), at the viewer's nice value its starter set
  // (RunAtViewerPriority; a policy change keeps it). Failing either only costs that.
  sched_param batch{};
  pthread_setschedparam(pthread_self(), SCHED_BATCH, &batch);
  // A look at the mailbox every few ms: the loop never wakes this thread itself.
  constexpr auto kLook = std::chrono::milliseconds(5);
  while (true) {
    const bool stopping = stop_.load();
    std::unique_ptr<LiveFrame> taken(mailbox_.exchange(nullptr, std::memory_order_acq_rel));
    if (!taken) {
      if (stopping) return;  // and nothing left
      std::this_thread::sleep_for(kLook);
      continue;
    }
    LiveFrame frame = std::move(*taken);
    std::vector<EventView> events = std::move(frame.new_events);
    frame.new_events.clear();
    const auto digest_start = std::chrono::steady_clock::now();
    const std::int64_t cpu_start = ThreadCpuNs();
    Digest(frame, events);
    published_cv_.notify_all();
    digest_ns_ += static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - digest_start).count());
    digest_cpu_ns_ += static_cast<std::uint64_t>(std::max<std::int64_t>(0, ThreadCpuNs() - cpu_start));
    ++digested_;
    if (foxglove_) {
      std::shared_ptr<const LiveFrame> latest;
      std::shared_ptr<const HeatGrid> heat;
      std::uint64_t heat_seq = 0;
      {
        std::lock_guard lock(published_mutex_);
        latest = frame_;
        heat = heat_;
        heat_seq = heat_seq_;
      }
      foxglove_->Publish(*latest, heat.get(), heat_seq);
    }
  }
}

}  // namespace sage::live
