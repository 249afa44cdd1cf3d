#pragma once
// Per-sender rate limits on operators' requests: one sender flooding the mission with risk
// updates (a probe sent 3 million; every operator's `sage risk set` then failed) spends its own
// allowance and nobody else's.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include "server/rejections.h"

namespace sage::server {

/// A token bucket per sender: `burst` requests at once, then `per_second` a second. Time is the
/// caller's (seconds, non-decreasing per sender; a mission's clock or the wall's). At most
/// `max_senders` are tracked: beyond that the longest idle is forgotten (a sender forgotten
/// starts again with a full bucket, so the cap bounds memory, not fairness).
class SenderLimits {
 public:
  /// Where refusals of senders beyond the first max_senders refused are counted.
  static constexpr const char* kOtherSenders = RejectionCounts::kOtherSenders;

  SenderLimits(double per_second, double burst, std::size_t max_senders = 1024);

  /// True (and one request spent) if `sender` may make a request at time_s; false, and counted
  /// against it, if its bucket is empty.
  bool Allow(const std::string& sender, double time_s);

  /// Requests refused so far, of every sender and of one.
  std::uint64_t refused() const { return refusals_.total(); }
  std::uint64_t refused(const std::string& sender) const { return refusals_.of_sender(sender); }
  /// Senders with at least one refusal and how many (at most max_senders + 1 entries).
  const std::map<std::string, std::uint64_t>& refused_by_sender() const { return refusals_.by_sender(); }

  double per_second() const { return per_second_; }
  double burst() const { return burst_; }

 private:
  struct Bucket {
    double tokens = 0.0;
    double time_s = 0.0;  // of the last request
  };
  double per_second_, burst_;
  std::size_t max_senders_;
  std::map<std::string, Bucket> buckets_;
  RejectionCounts refusals_;  // kept after the bucket is forgotten
};

}  // namespace sage::server
