#include "server/sender_limits.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sage::server {

SenderLimits::SenderLimits(double per_second, double burst, std::size_t max_senders)
    : per_second_(per_second), burst_(burst), max_senders_(max_senders), refusals_(max_senders) {
  if (!(per_second > 0.0) || !std::isfinite(per_second) || !(burst >= 1.0) || !std::isfinite(burst) || max_senders < 1) {
    throw std::invalid_argument("SenderLimits: need a rate > 0, a burst >= 1 and room for one sender");
  }
}

bool SenderLimits::Allow(const std::string& sender, double time_s) {
  auto it = buckets_.find(sender);
  if (it == buckets_.end()) {
    if (buckets_.size() >= max_senders_) {
      const auto idle = std::min_element(buckets_.begin(), buckets_.end(),
                                         [](const auto& a, const auto& b) { return a.second.time_s < b.second.time_s; });
      buckets_.erase(idle);
    }
    it = buckets_.emplace(sender, Bucket{burst_, time_s}).first;
  }
  Bucket& b = it->second;
  // A clock that went back (a resumed mission's, or a sender's skew) refills nothing.
  b.tokens = std::min(burst_, b.tokens + per_second_ * std::max(0.0, time_s - b.time_s));
  b.time_s = std::max(b.time_s, time_s);
  if (b.tokens >= 1.0) {
    b.tokens -= 1.0;
    return true;
  }
  // Counted by name for as many senders as are tracked; beyond, together (a flood of made-up
  // names must not grow this either).
  refusals_.Count("over the rate limit", sender);
  return false;
}

}  // namespace sage::server
