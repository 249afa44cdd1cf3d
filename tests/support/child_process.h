#pragma once
// Test support: a child process of the `sage` binary for the integration tests (a server, agent
// hosts, a launch, an operator's command), stopped with everything it started when the test
// ends, also when it fails.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

extern char** environ;

namespace sage::testing {

namespace fs = std::filesystem;

/// A child process of the `sage` binary, in a process group of its own (so that `sage launch` is
/// stopped with the server and agent hosts it started), stdout and stderr to one log file.
/// `prefix`, if given, is a command the binary runs under (e.g. ip netns exec NS).
class ChildProcess {
 public:
  ChildProcess(std::string label, const std::vector<std::string>& args, const fs::path& log, const fs::path& cwd,
               const std::vector<std::string>& prefix = {})
      : label_(std::move(label)), log_(log) {
    // posix_spawn rather than fork: this process may hold Cyclone participants (threads).
    std::vector<std::string> all = prefix;
    all.push_back(SAGE_BINARY);
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    command_line_ = fmt::format("{}", fmt::join(all, " "));

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t none, defaults;
    sigemptyset(&none);
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGTERM);
    sigaddset(&defaults, SIGINT);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    const int rc = posix_spawnp(&pid_, all[0].c_str(), &actions, &attr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    if (rc != 0) throw std::runtime_error("posix_spawn " + command_line_ + ": " + std::strerror(rc));
    running_ = true;
    started_ = std::chrono::steady_clock::now();
  }
  ~ChildProcess() { Stop(); }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& label() const { return label_; }
  const fs::path& log() const { return log_; }
  const std::string& command_line() const { return command_line_; }
  std::string LogText() const {
    std::ifstream in(log_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  /// True while the process has not exited (reaps it when it has).
  bool Running() {
    if (!running_) return false;
    int status = 0;
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) Reaped(status);
    return running_;
  }

  /// Waits up to `timeout` for the process to exit; its exit code (128 + signal when killed by
  /// one), or nullopt if it is still running.
  std::optional<int> WaitExit(std::chrono::steady_clock::duration timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (Running()) {
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return exit_code_;
  }

  /// Sends `sig` to this process only.
  void Signal(int sig) {
    if (Running()) ::kill(pid_, sig);
  }

  /// SIGTERM to the process group (a clean stop), SIGKILL after `grace`, then reaped.
  void Stop(std::chrono::steady_clock::duration grace = std::chrono::seconds(3)) {
    if (!Running()) return;
    ::kill(-pid_, SIGTERM);
    if (WaitExit(grace)) return;
    KillGroup();
  }
  /// SIGKILL to the whole process group and reap the leader.
  void KillGroup() {
    if (!running_) return;
    ::kill(-pid_, SIGKILL);
    int status = 0;
    if (waitpid(pid_, &status, 0) == pid_) Reaped(status);
  }
  double WallSeconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count(); }

 private:
  void Reaped(int status) {
    running_ = false;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  }

  std::string label_;
  fs::path log_;
  std::string command_line_;
  pid_t pid_ = -1;
  bool running_ = false;
  int exit_code_ = -1;
  std::chrono::steady_clock::time_point started_;
};

}  // namespace sage::testing
