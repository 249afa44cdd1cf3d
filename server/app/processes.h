#pragma once
// The processes of a launched mission: spawning this same `sage` binary as the server and the
// agent hosts, describing how one ended, and the terminal the launcher owns (the server's lines
// relayed above a live progress line).
#include <sys/types.h>

#include <optional>
#include <string>
#include <string_view>
#include <utility>
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

/// "exited with status 1", "was killed by SIGKILL", from a waitpid status.
std::string DescribeExit(int wait_status);
/// The process's exit code for a waitpid status: its status, or 128 + signal.
int ExitCode(int wait_status);
/// True if `pid` runs a `sage launch` (another launcher holding a run directory).
bool IsRunningLauncher(int pid);
/// The processes (other than this one) whose command line holds `agents` followed by
/// `scenario_path`: a mission's agent hosts, sage launch's and sage vehicle add's alike. Ascending.
std::vector<int> MissionHostPids(const std::string& scenario_path);

/// A run directory may take a new mission (sage launch, run, compare, evaluate -o) unless one
/// still runs there, or one died there that could be resumed (its record would be overwritten:
/// a new user's `sage run -o` into a crashed launch's directory had replaced its checkpoint with
/// only a warning). Throws ScenarioError naming --out and how to go on.
void CheckRunDirectoryFree(const std::string& dir);

/// An exclusive lock on a run directory (flock on DIR/.launch.lock, not inherited by the
/// processes it starts), held by the launch that runs its mission for as long as it lives; the
/// kernel lets it go however the launcher ends. Two `sage launch --resume DIR` at once had both
/// resumed the mission, each on its own domain, into one record.
class RunDirectoryLock {
 public:
  /// The lock, or nullopt if another process holds it (dir must exist). Throws
  /// std::runtime_error if the lock file cannot be made.
  static std::optional<RunDirectoryLock> TryTake(const std::string& dir);
  RunDirectoryLock(RunDirectoryLock&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  RunDirectoryLock& operator=(RunDirectoryLock&& other) noexcept {
    std::swap(fd_, other.fd_);  // the other's destructor lets go of what this held
    return *this;
  }
  RunDirectoryLock(const RunDirectoryLock&) = delete;
  ~RunDirectoryLock();

 private:
  explicit RunDirectoryLock(int fd) : fd_(fd) {}
  int fd_;
};

/// What a command says along the way goes to stderr, its result to stdout (`sage run ... >
/// table.txt`, `sage launch ... > table.txt` keep the table alone): from now on the default
/// logger writes "[level] message" lines to stderr.
void LogToStderr();
/// Whether a line a child printed is one of its log lines ("[info] ...", "[warning] ...": the
/// pattern every sage process logs with) rather than its result.
bool IsLogLine(std::string_view line);

// The launcher owns the terminal: the server's output comes through a pipe and is printed here
// line by line, so on a terminal the redrawn progress line is cleared first and drawn again
// after, and never ends up with a log line glued to it. Its log lines go to stderr, the rest
// (the final table) to stdout.
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
