#pragma once
// Inputs refused at the door of a mission — a vehicle state or coverage report that is not
// finite, names an impossible vehicle, or is stamped before the mission or ahead of its clock —
// counted per kind and per sender, so that an operator reading the progress line or
// metrics.json can tell one faulty vehicle from a flood of forgeries. Nothing refused is
// propagated; this only keeps the account.
#include <cstddef>
#include <map>
#include <string>

namespace sage::server {

class RejectionCounts {
 public:
  /// Senders named one by one (max_senders of them); refusals of any further sender are counted
  /// under kOtherSenders, so that made-up ids cannot grow the account (or metrics.json) without
  /// bound. The operators' rate limit (SenderLimits) keeps its refusals in one of these too.
  static constexpr std::size_t kMaxSenders = 1024;
  static constexpr const char* kOtherSenders = "(other senders)";

  explicit RejectionCounts(std::size_t max_senders = kMaxSenders) : max_senders_(max_senders) {}

  /// n more refusals of `kind` (a short phrase, e.g. "state ahead of the clock") from `sender`
  /// (e.g. "vehicle 12"; empty: none known, counted by kind only).
  void Count(const std::string& kind, const std::string& sender, std::size_t n = 1);

  std::size_t total() const { return total_; }
  const std::map<std::string, std::size_t>& by_kind() const { return by_kind_; }
  const std::map<std::string, std::size_t>& by_sender() const { return by_sender_; }

  /// For a progress line: "0", or the total and the largest kinds, e.g.
  /// "3 (state ahead of the clock 2, coverage not finite 1)"; at most `kinds` kinds, then "...".
  std::string Summary(std::size_t kinds = 3) const;

  /// The count of one sender (0 if none).
  std::size_t of_sender(const std::string& sender) const;

  /// The account as it was (a checkpoint's); throws std::invalid_argument if the parts do not
  /// add up to the total or more senders are named than max_senders (and the others).
  void Restore(std::size_t total, std::map<std::string, std::size_t> by_kind,
               std::map<std::string, std::size_t> by_sender);

 private:
  std::size_t max_senders_;
  std::size_t total_ = 0;
  std::map<std::string, std::size_t> by_kind_;
  std::map<std::string, std::size_t> by_sender_;
};

}  // namespace sage::server
