#pragma once
// Debian's liboctomap is built with its debug prints on: writing a tree prints " done." (and
// reading one its size) to stderr, which lands in the middle of a progress line. QuietStderr
// silences fd 2 for its lifetime; for the few calls into OctoMap that print.
#include <fcntl.h>
#include <unistd.h>

namespace sage::maps::detail {

class QuietStderr {
 public:
  QuietStderr() : saved_(dup(STDERR_FILENO)) {
    const int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) dup2(null, STDERR_FILENO);
    if (null >= 0) close(null);
  }
  ~QuietStderr() {
    if (saved_ < 0) return;
    dup2(saved_, STDERR_FILENO);
    close(saved_);
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_;
};

}  // namespace sage::maps::detail
