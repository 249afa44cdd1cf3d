#include "server/app/processes.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "maps/scenario/scenario.h"
#include "server/report/mission_file.h"

namespace sage::server {

namespace fs = std::filesystem;

namespace {

std::string SelfExe() { return fs::read_symlink("/proc/self/exe").string(); }

}  // namespace

std::optional<RunDirectoryLock> RunDirectoryLock::TryTake(const std::string& dir) {
  const std::string path = (fs::path(dir) / ".launch.lock").string();
  const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(fmt::format("cannot open {}: {}", path, std::strerror(errno)));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    return std::nullopt;
  }
  return RunDirectoryLock(fd);
}

RunDirectoryLock::~RunDirectoryLock() {
  if (fd_ >= 0) close(fd_);  // and with it the lock
}

void LogToStderr() {
  static const std::shared_ptr<spdlog::logger> logger = [] {
    auto made = std::make_shared<spdlog::logger>("sage", std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
    made->set_pattern("%^[%l]%$ %v");
    return made;
  }();
  spdlog::set_default_logger(logger);
}

bool IsLogLine(std::string_view line) {
  for (const std::string_view level : {"[trace] ", "[debug] ", "[info] ", "[warning] ", "[error] ", "[critical] "}) {
    if (line.starts_with(level)) return true;
  }
  return false;
}

// fork + exec of this same `sage` binary; stdout/stderr go to `log_path` unless it is empty.
// With `stdout_pipe` the child's stdout goes into a pipe whose non-blocking read end is
// returned there. Everything is prepared before fork(): the launcher runs DDS threads, and a
// forked child of a multi-threaded process may only call async-signal-safe functions until exec
// (a malloc could deadlock on a lock another thread held at the fork; seen as a join host that
// never started).
pid_t Spawn(const std::vector<std::string>& args, const std::string& log_path, bool detach, int* stdout_pipe) {
  const std::string exe = SelfExe();
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const char* log = log_path.empty() ? nullptr : log_path.c_str();
  int pipe_fds[2] = {-1, -1};
  if (stdout_pipe != nullptr && pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    for (int fd : pipe_fds)
      if (fd >= 0) close(fd);
    throw std::runtime_error("fork failed");
  }
  if (pid == 0) {
    if (detach) {
      setsid();
    } else {
      // The mission's processes go when the launcher goes, however it dies (even SIGKILL):
      // SIGTERM is a clean stop. If it died before this line, stop now.
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(1);
    }
    if (log != nullptr) {
      const int fd = open(log, O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        close(fd);
      }
    }
    if (pipe_fds[1] >= 0) dup2(pipe_fds[1], STDOUT_FILENO);  // dup2 clears close-on-exec on the copy
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (stdout_pipe != nullptr) {
    close(pipe_fds[1]);
    fcntl(pipe_fds[0], F_SETFL, fcntl(pipe_fds[0], F_GETFL) | O_NONBLOCK);
    *stdout_pipe = pipe_fds[0];
  }
  return pid;
}

std::vector<std::string> NetworkArgs(const maps::NetworkSettings& network) {
  if (network == maps::NetworkSettings{}) return {};
  std::vector<std::string> args = {"--interface", network.interface_name};
  for (const std::string& peer : network.peers) args.insert(args.end(), {"--peer", peer});
  args.insert(args.end(), {"--multicast", network.multicast ? "on" : "off"});
  return args;
}

std::string DescribeExit(int wait_status) {
  if (WIFSIGNALED(wait_status)) {
    const int sig = WTERMSIG(wait_status);
    return fmt::format("was killed by SIG{} ({})", sigabbrev_np(sig) ? sigabbrev_np(sig) : "?", strsignal(sig));
  }
  return fmt::format("exited with status {}", WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1);
}

int ExitCode(int wait_status) {
  if (WIFSIGNALED(wait_status)) return 128 + WTERMSIG(wait_status);
  return WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : 1;
}

bool IsRunningLauncher(int pid) {
  if (pid <= 0 || pid == getpid()) return false;
  std::ifstream cmdline(fmt::format("/proc/{}/cmdline", pid));
  const std::string command((std::istreambuf_iterator<char>(cmdline)), std::istreambuf_iterator<char>());
  return command.find("launch") != std::string::npos;
}

std::vector<int> MissionHostPids(const std::string& scenario_path) {
  std::vector<int> pids;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    const int pid = std::stoi(name);
    if (pid == getpid()) continue;
    std::ifstream in(entry.path() / "cmdline");
    const std::string command((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::string> argv;
    for (std::size_t start = 0, end; start < command.size(); start = end + 1) {
      end = command.find('\0', start);
      if (end == std::string::npos) end = command.size();
      argv.push_back(command.substr(start, end - start));
    }
    for (std::size_t i = 0; i + 1 < argv.size(); ++i) {
      if (argv[i] == "agents" && fs::path(argv[i + 1]).lexically_normal() == fs::path(scenario_path).lexically_normal()) {
        pids.push_back(pid);
        break;
      }
    }
  }
  std::sort(pids.begin(), pids.end());
  return pids;
}

TerminalRelay::~TerminalRelay() {
  if (fd_ >= 0) close(fd_);
}

void TerminalRelay::Relay(bool to_eof) {
  char buffer[4096];
  bool printed = false;
  while (fd_ >= 0) {
    const ssize_t n = read(fd_, buffer, sizeof buffer);
    if (n > 0) {
      pending_.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
      close(fd_);  // end of file: the child has exited
      fd_ = -1;
    } else if (!to_eof || errno == EAGAIN) {
      if (!to_eof) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::size_t end;
    while ((end = pending_.find('\n')) != std::string::npos) {
      Print(pending_.substr(0, end + 1));
      pending_.erase(0, end + 1);
      printed = true;
    }
  }
  if (fd_ < 0 && !pending_.empty()) {
    Print(pending_ + "\n");
    pending_.clear();
    printed = true;
  }
  if (printed && tty_ && !progress_.empty()) std::fputs(progress_.c_str(), stderr);
}

void TerminalRelay::Progress(const std::string& text) {
  if (tty_) {
    progress_ = "\r" + text + "\033[K";
    std::fputs(progress_.c_str(), stderr);
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
}

void TerminalRelay::Log(const std::string& message, bool warning) {
  if (tty_ && !progress_.empty()) std::fputs("\r\033[K", stderr);
  std::fflush(stderr);
  if (warning) spdlog::warn("{}", message);
  else spdlog::info("{}", message);
  if (tty_ && !progress_.empty()) std::fputs(progress_.c_str(), stderr);
}

void TerminalRelay::EndProgress() {
  if (tty_ && !progress_.empty()) std::fputs("\n", stderr);
  progress_.clear();
}

void TerminalRelay::Print(const std::string& line) {
  if (tty_ && !progress_.empty()) std::fputs("\r\033[K", stderr);
  std::fflush(stderr);
  std::FILE* to = IsLogLine(line) ? stderr : stdout;
  std::fputs(line.c_str(), to);
  std::fflush(to);
}

void CheckRunDirectoryFree(const std::string& dir) {
  if (fs::exists(fs::path(dir) / "mission.json")) {
    try {
      const MissionFile previous = ReadMissionFile(dir);
      if (IsRunningLauncher(previous.launcher_pid)) {
        throw maps::ScenarioError(fmt::format("--out = {}: a mission is running there (launcher pid {}); stop it or "
                                              "choose another --out",
                                              dir, previous.launcher_pid));
      }
    } catch (const maps::ScenarioError& e) {
      if (std::string(e.what()).find("is running there") != std::string::npos) throw;
    }
  }
  const RecordSummary record = ReadRecordSummary(dir);
  if (record.exists && !record.complete) {
    throw maps::ScenarioError(fmt::format(
        "--out = {}: it holds a mission that did not finish (recorded to t = {:.1f} s{}); resume it with sage launch "
        "--resume {}, or choose another --out",
        dir, record.recorded_until_s,
        record.has_checkpoint ? fmt::format(", checkpoint at t = {:.1f} s", record.checkpoint_s) : std::string(), dir));
  }
}

}  // namespace sage::server
