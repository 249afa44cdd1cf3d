#pragma once
// Test support: how often a piece of text occurs in a program's output.
#include <cstddef>
#include <string>

namespace sage::testing {

/// Occurrences of `what` (not empty) in `text`, overlapping ones included.
inline std::size_t Occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace sage::testing
