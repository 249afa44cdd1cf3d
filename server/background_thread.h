#pragma once
// A kept thread for work the mission's loop hands off within a cycle (a large fleet's
// trajectory rows, the fleet metric's coverage sums), run in the order handed over.
//
// Not a new thread each time: a thread std::async starts is placed beside its creator and, on a
// busy machine, runs in its place (measured over DDS at 1,000 vehicles on 2 cores: the server's
// cycle thread was preempted 1.3 times a cycle, mostly by the two threads it had just started,
// and with a browser on the other core it waited there 0.5 ms a cycle longer). This thread runs
// as SCHED_BATCH, which Linux never lets preempt a thread on waking: the work takes a free core,
// or waits for the loop to block or finish its slice.
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>

namespace sage::server {

class BackgroundThread {
 public:
  BackgroundThread();
  /// Runs what was handed over, then stops.
  ~BackgroundThread();
  BackgroundThread(const BackgroundThread&) = delete;
  BackgroundThread& operator=(const BackgroundThread&) = delete;

  /// Runs `job` after those handed over before it; its result (or exception) comes in the future.
  template <typename Job>
  std::future<std::invoke_result_t<Job>> Run(Job job) {
    auto task = std::make_shared<std::packaged_task<std::invoke_result_t<Job>()>>(std::move(job));
    std::future<std::invoke_result_t<Job>> result = task->get_future();
    Post([task] { (*task)(); });
    return result;
  }

 private:
  void Post(std::function<void()> job);
  void Loop();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::thread thread_;  // last: started once the rest is made
};

}  // namespace sage::server
