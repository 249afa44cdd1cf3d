#pragma once
// The processes of a launched mission: spawning this same `sage` binary as the server and the
// agent hosts, describing how one ended, and the terminal the launcher owns (the server's lines
// relayed above a live progress line).
#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

#include "maps/scenario/scenario.h"

namespace sage::server {

/// fork + exec of this same `sage` binary with `args`; stdout/stderr go to `log_path` unless it
/// is empty. detach: a session of its own, outliving the caller (sage vehicle add); otherwise
/// the child gets SIGTERM when the caller dies, however it dies. With `stdout_pipe` the child's
/// stdout goes into a pipe whose non-blocking read end is returned there. Throws
/// std::runtime_error if it cannot fork.
pid_t Spawn(const std::vector<std::string>& args, const std::string& log_path, bool detach = false,
            int* stdout_pipe = nullptr);

/// The options that give a child process `network` (--interface, --peer..., --multicast); none
/// for this machine alone (the default).
std::vector<std::string> NetworkArgs(const maps::NetworkSettings& network);

/// The GLIBC_TUNABLES value under which glibc's malloc backs its heaps with transparent huge
/// pages (glibc.malloc.hugetlb=1: madvise, which is all this kernel's THP setting honours), given
/// the current value (null: unset) and SAGE_HUGE_PAGES (null: unset); nullopt when nothing is to
/// change: the tunable already set (by the user, either way, or by this sage's first start) or
/// SAGE_HUGE_PAGES=0. Any other tunables are kept.
std::optional<std::string> HugePageTunables(const char* tunables, const char* sage_huge_pages);

/// At the start of `sage`: glibc reads its tunables once, at a process's start, so when
/// HugePageTunables asks for a change this process sets it and starts itself again (execv of
/// /proc/self/exe with the same arguments); it returns only if it cannot. A 10,000-vehicle mission
/// waits on memory (every vehicle's data is out of the caches by its turn, 3.5 GB in 4 kB pages).
void StartWithHugePages(char** argv);

/// "exited with status 1", "was killed by SIGKILL", from a waitpid status.
std::string DescribeExit(int wait_status);
/// The process's exit code for a waitpid status: its status, or 128 + signal.
int ExitCode(int wait_status);
/// True if `pid` runs a `sage launch` (another launcher holding a run directory).
bool IsRunningLauncher(int pid);

// The launcher owns the terminal: the server's output comes through a pipe and is printed here
// line by line, so on a terminal the redrawn progress line is cleared first and drawn again
// after, and never ends up with a log line glued to it.
class TerminalRelay {
 public:
  TerminalRelay(int fd, bool tty) : fd_(fd), tty_(tty) {}
  ~TerminalRelay();
  TerminalRelay(const TerminalRelay&) = delete;
  TerminalRelay& operator=(const TerminalRelay&) = delete;

  /// Prints the child's complete lines read so far (all of it, to the end, with `to_eof`).
  void Relay(bool to_eof = false);
  /// Shows the launcher's progress: a redrawn line on a terminal, a line of its own otherwise.
  void Progress(const std::string& text);
  /// The launcher's own log line, printed like the child's.
  void Log(const std::string& message, bool warning = false);
  /// Ends the progress line on a terminal (before the final output).
  void EndProgress();
  bool tty() const { return tty_; }

 private:
  void Print(const std::string& line);

  int fd_;
  bool tty_;
  std::string pending_;
  std::string progress_;
};

}  // namespace sage::server
