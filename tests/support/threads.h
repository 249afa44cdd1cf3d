#pragma once
// Test support: how many threads this process runs (DDS tests check that Cyclone's threads are
// gone with the last participant, and that a forked child starts without any).
#include <dirent.h>

namespace sage::testing {

/// Entries of /proc/self/task, i.e. this process's threads.
inline int CountThreads() {
  int entries = 0;
  DIR* dir = opendir("/proc/self/task");
  while (dir != nullptr && readdir(dir) != nullptr) ++entries;
  if (dir != nullptr) closedir(dir);
  return entries - 2;  // "." and ".."
}

}  // namespace sage::testing
