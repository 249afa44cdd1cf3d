#pragma once
// The `sage` command run in the test's own process (RunCli) as a user would type it: its exit
// status and what it said on stdout and stderr. For the app tests, which link sage_app.
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "server/app/cli.h"

namespace sage::server::cli_test {

struct SageRun {
  int status = 0;
  std::string err;  ///< what the command wrote to stderr
  std::string out;  ///< and to stdout
};

/// `sage ARGS...` (args without the leading "sage").
inline SageRun RunSage(std::vector<std::string> args) {
  args.insert(args.begin(), "sage");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const int status = RunCli(static_cast<int>(argv.size()), argv.data());
  std::cout.flush();
  std::string out = ::testing::internal::GetCapturedStdout();
  return {status, ::testing::internal::GetCapturedStderr(), std::move(out)};
}

}  // namespace sage::server::cli_test
