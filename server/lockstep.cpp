#include "server/lockstep.h"

#include <algorithm>
#include <cstddef>

namespace sage::server {
namespace {

bool Dense(int id, int dense_ids) { return id >= 0 && id < dense_ids; }

}  // namespace

LockstepWait::LockstepWait(const std::map<int, std::int64_t>& ends, std::vector<std::pair<std::int64_t, int>> joins,
                           std::int64_t join_wait_cycles)
    : joins_(std::move(joins)), join_wait_cycles_(join_wait_cycles) {
  for (const auto& [id, cycle] : ends) {
    if (!Dense(id, kDenseIds)) {
      end_far_[id] = cycle;
      continue;
    }
    const auto at = static_cast<std::size_t>(id);
    if (at >= end_.size()) end_.resize(at + 1, kNoEnd);
    end_[at] = cycle;
  }
}

void LockstepWait::Heard(int id, std::int64_t cycle) {
  if (!Dense(id, kDenseIds)) {
    heard_far_[id] = cycle;
    return;
  }
  const auto at = static_cast<std::size_t>(id);
  if (at >= heard_.size()) heard_.resize(std::max(at + 1, heard_.size() * 2), kNever);
  heard_[at] = cycle;
}

std::int64_t LockstepWait::heard(int id) const {
  if (!Dense(id, kDenseIds)) {
    const auto it = heard_far_.find(id);
    return it == heard_far_.end() ? kNever : it->second;
  }
  const auto at = static_cast<std::size_t>(id);
  return at < heard_.size() ? heard_[at] : kNever;
}

bool LockstepWait::Waited(int id, std::int64_t cycle) const {
  std::int64_t end = kNoEnd;
  if (Dense(id, kDenseIds)) {
    const auto at = static_cast<std::size_t>(id);
    if (at < end_.size()) end = end_[at];
  } else if (const auto it = end_far_.find(id); it != end_far_.end()) {
    end = it->second;
  }
  return cycle < end && heard(id) < cycle;
}

bool LockstepWait::AllIn(const std::vector<int>& alive, std::int64_t cycle) {
  // Start at the vehicle last found missing in this cycle and go round once: the states come
  // in roughly by id, so the next missing one is usually just past it, and only the ask that
  // finds all in walks the whole fleet. Going round (not skipping what lay before it) keeps
  // the answer exact when vehicles join or leave during the wait.
  const std::size_t n = alive.size();
  std::size_t from = 0;
  if (missing_cycle_ == cycle) {
    from = static_cast<std::size_t>(std::lower_bound(alive.begin(), alive.end(), missing_) - alive.begin());
  }
  for (std::size_t k = 0; k < n; ++k) {
    const int id = alive[(from + k) % n];
    if (Waited(id, cycle)) {
      missing_ = id;
      missing_cycle_ = cycle;
      return false;
    }
  }
  for (const auto& [join_cycle, id] : joins_) {
    if (cycle < join_cycle || cycle > join_cycle + join_wait_cycles_) continue;
    if (heard(id) < cycle) return false;
  }
  return true;
}

}  // namespace sage::server
