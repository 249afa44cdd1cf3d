#pragma once
// The live view's threads (frames to JSON, the HTTP server and its connections, the Foxglove
// socket) run below the mission's priority: a viewer gets the CPU the mission leaves, and the
// server's cycle does not wait behind a page's work on a busy machine (measured on 2 cores with
// 1,000 vehicles and headless chromium on the same machine: the cycle's mean grew 40-79 % with a
// viewer while the view's threads ran at the mission's priority). Linux keeps a nice value per
// thread, and threads a lowered thread starts (httplib's connection pool, asio's handlers) inherit it.
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace sage::live {

/// The name of the view's frame thread (the one that writes each frame's JSON), as `top -H` shows it.
inline constexpr const char* kPublisherThreadName = "sage-view";

/// Nice value of the view's threads: about a tenth of the CPU share of a nice-0 thread under load.
inline constexpr int kViewerNice = 10;

/// Lowers the calling thread to kViewerNice. Best effort (a process already niced further keeps
/// its value); returns whether the priority was set.
inline bool RunAtViewerPriority() {
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  const int current = ::getpriority(PRIO_PROCESS, tid);
  if (current >= kViewerNice) return true;
  return ::setpriority(PRIO_PROCESS, tid, kViewerNice) == 0;
}

}  // namespace sage::live
