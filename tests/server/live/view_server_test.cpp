// The live view's web server at its door: without the mission's token, or with another, no
// request reaches the mission (the loop's queue stays empty) and no data leaves; a request that
// names another host is refused; malformed requests are refused with the rule; with the token a
// request reaches the loop and its answer comes back; frames stream as Server-Sent Events; a
// view nobody watches leaves its frames' JSON to the first reader; once the mission has ended
// every request is answered so.
#include "server/live/live_view.h"
#include "server/live/viewer_priority.h"

#include <sched.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

namespace sage::live {
namespace {

using Json = nlohmann::json;
using namespace std::chrono_literals;
constexpr const char* kToken = "0123456789abcdef0123456789abcdef";
constexpr const char* kForm = "application/x-www-form-urlencoded";

LiveScene Scene() {
  LiveScene scene;
  scene.mission = "test";
  scene.width_m = 10.0;
  scene.height_m = 8.0;
  ValveSite v;
  v.name = "P1";
  v.xt = "XT-A";
  v.position_m = {2.0, 3.0};
  v.covariance_m2 = 0.1 * Eigen::Matrix2d::Identity();
  scene.valves = {v};
  return scene;
}

LiveViewOptions Options() {
  LiveViewOptions options;
  options.http_port = 0;
  options.foxglove_port = std::nullopt;
  options.token = kToken;
  return options;
}

LiveFrame Frame(double t) {
  LiveFrame frame;
  frame.time_s = t;
  frame.duration_s = 60.0;
  frame.vehicles = {{0, "rov1", 1.0f, 1.0f, 0.0f, VehicleStatus::kAlive}};
  ValveView valve;
  valve.raw_weight = 1.0;
  valve.share = 1.0;
  frame.valves = {valve};
  return frame;
}

// The loop's side for a while: every request it takes is answered, and counted.
class FakeLoop {
 public:
  explicit FakeLoop(LiveView& live) : thread_([this, &live] {
    while (!stop_) {
      for (const auto& action : live.TakeActions()) {
        ++taken_;
        const ActionRequest& r = action->request();
        action->Answer(true, r.verb + " " + r.valve + " " + std::to_string(r.weight));
      }
      std::this_thread::sleep_for(2ms);
    }
  }) {}
  ~FakeLoop() {
    stop_ = true;
    thread_.join();
  }
  int taken() const { return taken_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<int> taken_{0};
  std::thread thread_;
};

TEST(ViewServer, WithoutTheTokenNothingReachesTheMission) {
  LiveView live(Scene(), Options());
  FakeLoop loop(live);
  httplib::Client client("127.0.0.1", live.http_port());
  const std::string body = "verb=risk&valve=P1&weight=9";
  auto none = client.Post("/api/action", body, kForm);
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 403);
  EXPECT_NE(none->body.find("no token"), std::string::npos) << none->body;
  auto wrong = client.Post("/api/action", {{"X-Sage-Token", std::string(32, '0')}}, body, kForm);
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 403);
  EXPECT_NE(wrong->body.find("wrong token"), std::string::npos) << wrong->body;
  auto prefix = client.Post("/api/action", {{"X-Sage-Token", std::string(kToken).substr(0, 31)}}, body, kForm);
  ASSERT_TRUE(prefix);
  EXPECT_EQ(prefix->status, 403);
  auto in_query = client.Post("/api/action?token=" + std::string(32, 'f'), body, kForm);
  ASSERT_TRUE(in_query);
  EXPECT_EQ(in_query->status, 403);
  for (const char* path : {"/api/scene", "/api/frame", "/api/heat", "/api/stream"}) {
    auto data = client.Get(path);
    ASSERT_TRUE(data) << path;
    EXPECT_EQ(data->status, 403) << path;
    EXPECT_EQ(data->body.find("\"mission\""), std::string::npos) << path;
  }
  // Nor does a path the API does not have tell itself from one it has (they had answered 404 and
  // 400 without a token, a map of the API for anyone to probe).
  for (const char* path : {"/api/state", "/api/risk", "/api/nonexistent"}) {
    auto get = client.Get(path);
    ASSERT_TRUE(get) << path;
    EXPECT_EQ(get->status, 403) << path;
    auto post = client.Post(path, body, kForm);
    ASSERT_TRUE(post) << path;
    EXPECT_EQ(post->status, 403) << path;
  }
  auto known = client.Get("/api/nonexistent", {{"X-Sage-Token", std::string(kToken)}});
  ASSERT_TRUE(known);
  EXPECT_EQ(known->status, 404) << "with the token, an unknown path is not found";
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(loop.taken(), 0);
  // The page itself (no mission data in it) needs no token.
  auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("script-src 'self'"), std::string::npos);
}

TEST(ViewServer, WithTheTokenARequestIsAnsweredByTheLoop) {
  LiveView live(Scene(), Options());
  FakeLoop loop(live);
  httplib::Client client("127.0.0.1", live.http_port());
  const httplib::Headers token = {{"X-Sage-Token", kToken}};
  auto answer = client.Post("/api/action", token, "verb=risk&valve=P1&weight=0.5", kForm);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, 200);
  const Json j = Json::parse(answer->body);
  EXPECT_TRUE(j["accepted"].get<bool>());
  EXPECT_EQ(j["line"], "risk P1 0.500000");
  EXPECT_EQ(loop.taken(), 1);
  auto scene = client.Get("/api/scene?token=" + std::string(kToken));
  ASSERT_TRUE(scene);
  EXPECT_EQ(Json::parse(scene->body)["mission"], "test");
}

TEST(ViewServer, MalformedRequestsAndForeignHostsAreRefused) {
  LiveView live(Scene(), Options());
  FakeLoop loop(live);
  httplib::Client client("127.0.0.1", live.http_port());
  const httplib::Headers token = {{"X-Sage-Token", kToken}};
  for (const auto& [body, rule] : std::vector<std::pair<std::string, std::string>>{
           {"verb=risk&valve=P1&weight=abc", "weight = abc: must be a number"},
           {"verb=risk&valve=P1&weight=nan", "must be a number"},
           {"verb=risk&weight=1", "valve: give a valve's name"},
           {"verb=add&count=0", "count = 0: must be in 1..10000"},
           {"verb=remove&id=-3", "id = -3: must be a vehicle id"},
           {"verb=launch", "verb = launch: must be risk, add, remove or stop"}}) {
    auto r = client.Post("/api/action", token, body, kForm);
    ASSERT_TRUE(r) << body;
    EXPECT_EQ(r->status, 400) << body;
    EXPECT_NE(r->body.find(rule), std::string::npos) << body << ": " << r->body;
  }
  httplib::Headers foreign = token;
  foreign.emplace("Host", "sage.example:80");
  auto rebound = client.Get("/api/scene", foreign);
  ASSERT_TRUE(rebound);
  EXPECT_EQ(rebound->status, 403);
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(loop.taken(), 0);
}

TEST(ViewServer, FramesStreamAsServerSentEvents) {
  LiveView live(Scene(), Options());
  std::atomic<bool> stop{false};
  std::thread publisher([&] {
    for (int k = 0; !stop; ++k) {
      if (live.FrameDue()) live.Publish(Frame(0.1 * k));
      std::this_thread::sleep_for(20ms);
    }
  });
  httplib::Client client("127.0.0.1", live.http_port());
  std::string received;
  int events = 0;
  auto r = client.Get("/api/stream?token=" + std::string(kToken), [&](const char* data, std::size_t size) {
    received.append(data, size);
    std::size_t at;
    while ((at = received.find("\n\n")) != std::string::npos) {
      const std::string event = received.substr(0, at);
      received.erase(0, at + 2);
      if (event.rfind("data: ", 0) != 0) continue;
      const Json frame = Json::parse(event.substr(6));
      EXPECT_EQ(frame["v"].size(), 1u);
      // The first frame a page gets carries the trails; later ones only positions.
      EXPECT_EQ(frame.contains("trails"), events == 0);
      ++events;
    }
    return events < 3;
  });
  stop = true;
  publisher.join();
  EXPECT_EQ(events, 3);
}

// A view nobody watches keeps its frames but makes their JSON only when first asked, and no heat
// map: the first reader gets the newest frame's JSON, made then; the next frame, watched now,
// comes with its heat map.
TEST(ViewServer, AnUnwatchedViewMakesItsFramesJsonWhenFirstAsked) {
  LiveView live(Scene(), Options());
  EXPECT_FALSE(live.watched());
  const auto publish = [&](double t) {
    const std::uint64_t before = live.frames_published();
    live.Publish(Frame(t));
    for (int i = 0; i < 500 && live.frames_published() == before; ++i) std::this_thread::sleep_for(2ms);
    ASSERT_EQ(live.frames_published(), before + 1);
  };
  for (int k = 1; k <= 3; ++k) publish(0.1 * k);
  EXPECT_FALSE(live.watched());
  std::uint64_t seq = 0;
  const std::shared_ptr<const std::string> first = live.NextFrame(0, /*with_trails=*/false, 0ms, &seq);
  ASSERT_NE(first, nullptr);
  EXPECT_TRUE(live.watched());
  const Json j = Json::parse(*first);
  EXPECT_EQ(seq, 3u);
  EXPECT_EQ(j["seq"], 3);
  EXPECT_NEAR(j["t"].get<double>(), 0.3, 1e-9);
  EXPECT_EQ(j["v"].size(), 1u);
  EXPECT_EQ(j["heat_seq"], 0) << "no heat map while nobody watched";
  EXPECT_EQ(Json::parse(live.HeatJson(std::nullopt))["nx"], 0);
  // Asked again, the same JSON (made once).
  EXPECT_EQ(live.NextFrame(0, false, 0ms, &seq), first);
  publish(0.4);
  const Json next = Json::parse(*live.NextFrame(3, false, 0ms, &seq));
  EXPECT_EQ(next["seq"], 4);
  EXPECT_EQ(next["heat_seq"], 1);
  EXPECT_GT(Json::parse(live.HeatJson(std::nullopt))["nx"].get<int>(), 0);
}

// Trails go on while nobody watches, though frames carry them only for a watcher: a page that
// opens late gets each vehicle's points of the last trail_s in its first frame (the next one
// published after it asked), and a vehicle that joins in front of another in the frame's order
// does not take over the other's trail.
TEST(ViewServer, APageOpenedLateGetsTheTrailsKeptWhileNobodyWatched) {
  LiveView live(Scene(), Options());
  const auto publish = [&](double t, float x, bool joined) {
    const std::uint64_t before = live.frames_published();
    LiveFrame frame = Frame(t);
    frame.vehicles[0].id = 5;
    frame.vehicles[0].x_m = x;
    if (joined) frame.vehicles.insert(frame.vehicles.begin(), {2, "rov3", 9.0f, 7.0f, 0.0f, VehicleStatus::kAlive});
    live.Publish(std::move(frame));
    for (int i = 0; i < 500 && live.frames_published() == before; ++i) std::this_thread::sleep_for(2ms);
    EXPECT_EQ(live.frames_published(), before + 1);
  };
  // A point each 0.5 s (4 s of trail, 8 points): one a frame at 0.6 s apart.
  for (int k = 0; k < 3; ++k) publish(0.6 * k, 1.0f + static_cast<float>(k), false);
  EXPECT_FALSE(live.watched());
  std::thread later([&] {
    std::this_thread::sleep_for(100ms);
    publish(1.8, 4.0f, true);
  });
  std::uint64_t seq = 0;
  const std::shared_ptr<const std::string> first = live.NextFrame(0, /*with_trails=*/true, 5000ms, &seq);
  later.join();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(seq, 4u) << "the frame published after the page asked: the first with trails";
  const Json j = Json::parse(*first);
  ASSERT_EQ(j["trails"].size(), 2u);
  EXPECT_EQ(j["trails"][0].get<std::vector<float>>(), (std::vector<float>{9.0f, 7.0f})) << "the newcomer's own";
  EXPECT_EQ(j["trails"][1].get<std::vector<float>>(), (std::vector<float>{1.0f, 1.0f, 2.0f, 1.0f, 3.0f, 1.0f, 4.0f, 1.0f}));
}

TEST(ViewServer, AfterTheMissionEveryRequestIsAnsweredSo) {
  LiveView live(Scene(), Options());
  live.Close("the mission has ended");
  httplib::Client client("127.0.0.1", live.http_port());
  auto r = client.Post("/api/action", {{"X-Sage-Token", kToken}}, "verb=stop", kForm);
  ASSERT_TRUE(r);
  const Json j = Json::parse(r->body);
  EXPECT_FALSE(j["accepted"].get<bool>());
  EXPECT_EQ(j["line"], "the mission has ended");
}

// A port in use is one line naming the option, not a crash.
// The thread that writes the frames runs below the mission: SCHED_BATCH at the viewer's nice
// value (it had been raised back to nice 5 after its starter set 10). Read from /proc, as top
// shows it; fields after the command's closing parenthesis: the 17th is nice, the 39th the policy.
TEST(ViewServer, TheFrameThreadRunsAtTheViewersPriority) {
  LiveView live(Scene(), Options());
  std::optional<std::pair<long, long>> nice_policy;
  for (int attempt = 0; attempt < 100 && !nice_policy; ++attempt) {
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
      std::ifstream comm(task.path() / "comm");
      std::string name;
      std::getline(comm, name);
      if (name != kPublisherThreadName) continue;
      std::ifstream stat_file(task.path() / "stat");
      std::string stat((std::istreambuf_iterator<char>(stat_file)), std::istreambuf_iterator<char>());
      std::istringstream rest(stat.substr(stat.rfind(')') + 2));
      std::vector<std::string> fields{std::istream_iterator<std::string>(rest), std::istream_iterator<std::string>()};
      ASSERT_GE(fields.size(), 39u) << stat;
      const long nice = std::stol(fields[16]), policy = std::stol(fields[38]);
      if (nice == kViewerNice || attempt == 99) nice_policy = std::make_pair(nice, policy);
    }
    if (!nice_policy) std::this_thread::sleep_for(10ms);  // the thread lowers itself as it starts
  }
  ASSERT_TRUE(nice_policy.has_value()) << "no thread named " << kPublisherThreadName;
  EXPECT_EQ(nice_policy->first, kViewerNice);
  EXPECT_EQ(nice_policy->second, SCHED_BATCH);
}

TEST(ViewServer, APortInUseIsABadInput) {
  LiveView first(Scene(), Options());
  LiveViewOptions same = Options();
  same.http_port = first.http_port();
  try {
    LiveView second(Scene(), same);
    FAIL() << "listened twice on " << first.http_port();
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("--http = " + std::to_string(first.http_port()) + ": cannot listen"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sage::live
