#pragma once
// The main of the Google Benchmark programs: like BENCHMARK_MAIN, but the figures also go to
// `file` (JSON) unless --benchmark_out is given, so every run leaves its figures behind.
#include <cstdio>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace sage::bench {

inline int RunBenchmarksWritingTo(int argc, char** argv, const std::string& file) {
  std::vector<char*> args(argv, argv + argc);
  bool has_out = false;
  for (int i = 1; i < argc; ++i) has_out = has_out || std::string(argv[i]).rfind("--benchmark_out=", 0) == 0;
  std::string out = "--benchmark_out=" + file;
  if (!has_out) args.push_back(out.data());
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!has_out) std::fprintf(stderr, "figures written to %s\n", file.c_str());
  return 0;
}

}  // namespace sage::bench
