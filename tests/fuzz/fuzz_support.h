#pragma once
// What every fuzz harness checks beyond crashes and sanitizer reports: a broken property stops
// the fuzzer (libFuzzer keeps the input), and a message for the user is one printable line.
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sage::fuzz {

/// Stops the fuzzer with a message: a property does not hold (libFuzzer saves the input).
[[noreturn]] inline void Broken(const std::string& what) {
  std::fprintf(stderr, "property broken: %s\n", what.c_str());
  std::abort();
}

/// True for a message that is one non-empty line without control characters (no newline, tab,
/// escape: it reaches a terminal and a log as it is).
inline bool PrintableLine(const std::string& message) {
  for (const char c : message) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  }
  return !message.empty();
}

}  // namespace sage::fuzz
