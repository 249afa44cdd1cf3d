#include "server/node/cycle_priority.h"

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

namespace sage::server {

// sched_setscheduler(0, ...) acts on the calling thread (Linux schedules threads).
CyclePriority::CyclePriority(int priority) {
  if (priority <= 0) {
    line_ = "the cycle runs at normal priority (--cycle-priority 0)";
    return;
  }
  old_policy_ = sched_getscheduler(0);
  sched_getparam(0, &old_param_);
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO | SCHED_RESET_ON_FORK, &param) != 0) {
    const int error = errno;
    line_ = fmt::format("the cycle runs at normal priority: real-time priority {} refused ({}; root, CAP_SYS_NICE or "
                        "an rtprio limit allows it; --cycle-priority 0 asks for none)",
                        priority, std::strerror(error));
    return;
  }
  raised_ = true;
  line_ = fmt::format("the cycle runs at real-time priority {} (SCHED_FIFO; the threads it starts, at normal priority)",
                      priority);
}

CyclePriority::~CyclePriority() {
  if (raised_) sched_setscheduler(0, old_policy_ < 0 ? SCHED_OTHER : old_policy_, &old_param_);
}

}  // namespace sage::server
