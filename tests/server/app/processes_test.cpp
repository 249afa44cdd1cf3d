// The launcher's terminal: the server's lines come through a pipe, its log lines ("[info] ...")
// go on to stderr and everything else (the final table) to stdout, so `sage launch ... >
// table.txt` keeps the table alone, as `sage run` does. And the lock a launch holds on its run
// directory.
#include "server/app/processes.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/server/app/run_sage.h"

namespace sage::server {
namespace {

TEST(LogLines, AreTheLevelsOfTheSagePattern) {
  EXPECT_TRUE(IsLogLine("[info] server: rov1 (id 0) joined at t = 0.0 s\n"));
  EXPECT_TRUE(IsLogLine("[warning] --duration = 5: left out\n"));
  EXPECT_TRUE(IsLogLine("[error] x"));
  EXPECT_FALSE(IsLogLine("P1             0.034 |      0       ---        4.6 s\n"));
  EXPECT_FALSE(IsLogLine("[P1] a valve's name in brackets\n"));
  EXPECT_FALSE(IsLogLine("info] no opening bracket\n"));
  EXPECT_FALSE(IsLogLine(""));
}

TEST(TerminalRelay, LogLinesGoToStderrAndTheTableToStdout) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const std::string child =
      "[info] server: rov1 (id 0) joined at t = 0.0 s\n"
      "valve     weight | visits\n"
      "[warning] server: no vehicle is alive at t = 9.0 s\n"
      "P1         0.034 |      3\n"
      "the last line, unterminated";
  ASSERT_EQ(write(fds[1], child.data(), child.size()), static_cast<ssize_t>(child.size()));
  close(fds[1]);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  {
    TerminalRelay relay(fds[0], /*tty=*/false);  // owns the read end
    relay.Relay(/*to_eof=*/true);
  }
  const std::string out = testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out, "valve     weight | visits\nP1         0.034 |      3\nthe last line, unterminated\n");
  EXPECT_EQ(err,
            "[info] server: rov1 (id 0) joined at t = 0.0 s\n"
            "[warning] server: no vehicle is alive at t = 9.0 s\n");
}

// A run directory is held by one launch at a time: a second lock is refused while the first
// lives and given once it is gone; `sage launch --resume DIR` refuses a directory another launch
// holds, before anything starts (two resumes at once had both flown into one record).
// A mission's agent hosts are found by their command line (`agents <scenario.yaml>`, however
// the path is written), and nothing else is: a resumed launch stops the silent ones of its own
// mission only.
TEST(MissionHostPids, FindsTheHostsOfOneMissionByTheirCommandLine) {
  const std::string mine = "/tmp/sage_hosts_test/run/scenario.yaml", other = "/tmp/sage_hosts_test/other/scenario.yaml";
  const auto spawn = [](const std::vector<std::string>& tail) {
    const pid_t pid = fork();
    if (pid == 0) {
      // A group of its own (killed whole below, its sleep too), and no hold on the test's output
      // (an orphaned sleep had kept ctest waiting for it).
      setpgid(0, 0);
      const int null = open("/dev/null", O_RDWR);
      dup2(null, STDOUT_FILENO);
      dup2(null, STDERR_FILENO);
      // bash -c "...; true" stays bash (no exec of its one command), its argv ending in `tail`.
      std::vector<const char*> argv = {"bash", "-c", "sleep 30; true"};
      for (const std::string& a : tail) argv.push_back(a.c_str());
      argv.push_back(nullptr);
      execvp("bash", const_cast<char* const*>(argv.data()));
      _exit(127);
    }
    return pid;
  };
  const pid_t a = spawn({"agents", mine, "--offset", "0"});
  const pid_t b = spawn({"agents", "/tmp/sage_hosts_test/run/./scenario.yaml", "--add", "1"});
  const pid_t c = spawn({"agents", other});
  const pid_t d = spawn({"server", mine});
  ASSERT_GT(a, 0);
  ASSERT_GT(d, 0);
  std::vector<int> found;
  const std::vector<int> expected = {std::min(a, b), std::max(a, b)};
  // Until the children have exec'd and nothing else matches: bash forks a copy of itself (its
  // argv, so "agents" and the path) for each `sleep` before that execs, and under load such a copy
  // had been seen among the hosts; up to 10 s, as a loaded CI machine needs.
  for (int tries = 0; tries < 500; ++tries) {
    found = MissionHostPids(mine);
    if (found == expected && MissionHostPids(other) == std::vector<int>{c}) break;
    usleep(20'000);
  }
  EXPECT_EQ(found, expected);
  EXPECT_EQ(MissionHostPids(other), std::vector<int>{c});
  EXPECT_TRUE(MissionHostPids("/tmp/sage_hosts_test/none/scenario.yaml").empty());
  for (const pid_t pid : {a, b, c, d}) {
    kill(-pid, SIGKILL);  // the group: bash and its sleep
    waitpid(pid, nullptr, 0);
  }
  EXPECT_TRUE(MissionHostPids(mine).empty());
}

TEST(RunDirectoryLock, OneLaunchAtATime) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_run_lock_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::optional<RunDirectoryLock> held = RunDirectoryLock::TryTake(dir.string());
    ASSERT_TRUE(held.has_value());
    EXPECT_FALSE(RunDirectoryLock::TryTake(dir.string()).has_value());
    const cli_test::SageRun run = cli_test::RunSage({"launch", "--resume", dir.string()});
    EXPECT_EQ(run.status, 2);
    EXPECT_NE(run.err.find("--resume = " + dir.string() + ": another sage launch is starting or running a mission there"),
              std::string::npos)
        << run.err;
  }
  EXPECT_TRUE(RunDirectoryLock::TryTake(dir.string()).has_value());  // the first is gone
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sage::server
