// RejectionCounts: refusals per kind and per sender, bounded in senders, summarised for a
// progress line, restored only when its parts add up.
#include "server/rejections.h"

#include <map>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

// Kinds and senders add up to the total; a refusal with no sender counts by kind only.
TEST(RejectionCounts, CountsPerKindAndPerSender) {
  RejectionCounts r;
  EXPECT_EQ(r.Summary(), "0");
  r.Count("state not finite", "vehicle 3");
  r.Count("state not finite", "vehicle 3", 4);
  r.Count("coverage ahead of the clock", "vehicle 9");
  r.Count("sample out of order", "");
  EXPECT_EQ(r.total(), 7u);
  EXPECT_EQ(r.by_kind().at("state not finite"), 5u);
  EXPECT_EQ(r.by_kind().at("coverage ahead of the clock"), 1u);
  EXPECT_EQ(r.by_kind().at("sample out of order"), 1u);
  EXPECT_EQ(r.by_sender().at("vehicle 3"), 5u);
  EXPECT_EQ(r.by_sender().at("vehicle 9"), 1u);
  EXPECT_EQ(r.by_sender().size(), 2u);
  // The largest kinds first, ties in name order, at most `kinds` of them.
  EXPECT_EQ(r.Summary(), "7 (state not finite 5, coverage ahead of the clock 1, sample out of order 1)");
  EXPECT_EQ(r.Summary(1), "7 (state not finite 5, ...)");
}

// A flood of made-up ids names kMaxSenders of them and counts the rest together; the senders
// already named keep their own counts.
TEST(RejectionCounts, MadeUpSendersCannotGrowTheAccount) {
  RejectionCounts r;
  for (std::size_t k = 0; k < 5000; ++k) r.Count("state of no vehicle (id < 0)", "vehicle -" + std::to_string(k + 1));
  r.Count("state not finite", "vehicle -1");
  EXPECT_EQ(r.total(), 5001u);
  EXPECT_EQ(r.by_sender().size(), RejectionCounts::kMaxSenders + 1);
  EXPECT_EQ(r.by_sender().at(RejectionCounts::kOtherSenders), 5000u - RejectionCounts::kMaxSenders);
  EXPECT_EQ(r.by_sender().at("vehicle -1"), 2u);
}

// Restore takes an account whose parts add up, and refuses one whose kinds miss refusals,
// whose senders claim more than the total, or that names too many senders.
TEST(RejectionCounts, RestoresOnlyAConsistentAccount) {
  RejectionCounts r;
  r.Restore(3, {{"state not finite", 3}}, {{"vehicle 1", 2}});
  EXPECT_EQ(r.total(), 3u);
  EXPECT_EQ(r.by_sender().at("vehicle 1"), 2u);
  EXPECT_THROW(r.Restore(3, {{"state not finite", 2}}, {}), std::invalid_argument);
  EXPECT_THROW(r.Restore(1, {{"state not finite", 1}}, {{"vehicle 1", 2}}), std::invalid_argument);
  std::map<std::string, std::size_t> senders;
  for (std::size_t k = 0; k <= RejectionCounts::kMaxSenders; ++k) senders["vehicle " + std::to_string(k)] = 1;
  EXPECT_THROW(r.Restore(senders.size(), {{"state not finite", senders.size()}}, senders), std::invalid_argument);
  EXPECT_EQ(r.total(), 3u);  // unchanged by the refusals
}

}  // namespace
}  // namespace sage::server
