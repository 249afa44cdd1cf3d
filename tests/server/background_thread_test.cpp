// The kept thread the mission hands its helper work to (a large cycle's trajectory rows, the
// fleet metric's coverage batches): jobs run one at a time in the order handed over (the
// coverage sums depend on it, bit for bit), results and exceptions come through the futures,
// a job runs off the caller's thread, at SCHED_BATCH, and what was handed over before the
// thread is destroyed still runs.
#include "server/background_thread.h"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

TEST(BackgroundThread, RunsJobsOneAtATimeInTheOrderHandedOver) {
  BackgroundThread worker;
  std::vector<int> order;  // written by the worker only; read after the last future
  std::atomic<int> running{0};
  std::atomic<bool> overlapped{false};
  std::vector<std::future<int>> results;
  for (int i = 0; i < 200; ++i) {
    results.push_back(worker.Run([i, &order, &running, &overlapped] {
      if (running.fetch_add(1) != 0) overlapped = true;
      if (i % 50 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));  // a slow one
      order.push_back(i);
      running.fetch_sub(1);
      return i * i;
    }));
  }
  for (int i = 0; i < 200; ++i) EXPECT_EQ(results[i].get(), i * i);
  EXPECT_FALSE(overlapped.load());
  ASSERT_EQ(order.size(), 200u);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(order[i], i);
}

TEST(BackgroundThread, AJobRunsOffTheCallersThreadAsABatchThread) {
  BackgroundThread worker;
  const auto [id, policy] = worker
                                .Run([] {
                                  int p = -1;
                                  sched_param param{};
                                  pthread_getschedparam(pthread_self(), &p, &param);
                                  return std::make_pair(std::this_thread::get_id(), p);
                                })
                                .get();
  EXPECT_NE(id, std::this_thread::get_id());
  EXPECT_EQ(policy, SCHED_BATCH);
}

TEST(BackgroundThread, AJobsExceptionComesThroughItsFutureAndTheThreadGoesOn) {
  BackgroundThread worker;
  std::future<int> failed = worker.Run([]() -> int { throw std::runtime_error("no disk"); });
  std::future<int> next = worker.Run([] { return 7; });
  EXPECT_THROW(failed.get(), std::runtime_error);
  EXPECT_EQ(next.get(), 7);
}

TEST(BackgroundThread, WhatWasHandedOverRunsBeforeTheThreadStops) {
  std::atomic<int> ran{0};
  {
    BackgroundThread worker;
    for (int i = 0; i < 20; ++i) {
      // Futures dropped: nobody waits, the destructor must still run every job.
      (void)worker.Run([&ran] {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        ++ran;
      });
    }
  }
  EXPECT_EQ(ran.load(), 20);
}

}  // namespace
}  // namespace sage::server
