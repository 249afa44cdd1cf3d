// Refused inputs, counted per kind and per sender (see rejections.h).
#include "server/rejections.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace sage::server {

void RejectionCounts::Count(const std::string& kind, const std::string& sender, std::size_t n) {
  total_ += n;
  by_kind_[kind] += n;
  if (sender.empty()) return;
  const auto it = by_sender_.find(sender);
  if (it != by_sender_.end()) {
    it->second += n;
  } else if (by_sender_.size() - by_sender_.count(kOtherSenders) < max_senders_) {
    by_sender_.emplace(sender, n);
  } else {
    by_sender_[kOtherSenders] += n;
  }
}

std::size_t RejectionCounts::of_sender(const std::string& sender) const {
  const auto it = by_sender_.find(sender);
  return it == by_sender_.end() ? 0 : it->second;
}

std::string RejectionCounts::Summary(std::size_t kinds) const {
  if (total_ == 0) return "0";
  std::vector<std::pair<std::size_t, std::string>> largest;
  for (const auto& [kind, n] : by_kind_) largest.emplace_back(n, kind);
  std::stable_sort(largest.begin(), largest.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string out = fmt::format("{} (", total_);
  for (std::size_t k = 0; k < largest.size() && k < kinds; ++k) {
    out += fmt::format("{}{} {}", k > 0 ? ", " : "", largest[k].second, largest[k].first);
  }
  return out + (largest.size() > kinds ? ", ...)" : ")");
}

void RejectionCounts::Restore(std::size_t total, std::map<std::string, std::size_t> by_kind,
                              std::map<std::string, std::size_t> by_sender) {
  const auto sum = [](const std::map<std::string, std::size_t>& m) {
    return std::accumulate(m.begin(), m.end(), std::size_t{0}, [](std::size_t s, const auto& e) { return s + e.second; });
  };
  if (sum(by_kind) != total || sum(by_sender) > total ||
      by_sender.size() - by_sender.count(kOtherSenders) > max_senders_) {
    throw std::invalid_argument(fmt::format("rejected samples: {} in all, {} by kind and {} by sender ({} senders): "
                                            "the kinds must add up to the total, the senders to at most it, and at "
                                            "most {} senders be named",
                                            total, sum(by_kind), sum(by_sender), by_sender.size(), max_senders_));
  }
  total_ = total;
  by_kind_ = std::move(by_kind);
  by_sender_ = std::move(by_sender);
}

}  // namespace sage::server
