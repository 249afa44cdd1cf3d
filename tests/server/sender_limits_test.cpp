// SenderLimits: a token bucket per sender, against a count of what the rule allows, and
// MissionCore's risk updates under it: one sender's flood is refused and counted, another
// sender is still served.
#include "server/sender_limits.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "maps/scenario/scenario.h"
#include "server/mission.h"

namespace sage::server {
namespace {

// Burst b at once, then r a second: over T seconds of requests every dt, floor(b + r T) allowed
// (to one request); a quiet sender refills to b and no further; refusals counted per sender.
TEST(SenderLimits, TokenBucketPerSender) {
  SenderLimits limits(20.0, 100.0);
  int allowed = 0;
  for (int i = 0; i < 10000; ++i) allowed += limits.Allow("flood", 0.001 * i);  // 10 s at 1 kHz
  EXPECT_NEAR(allowed, 100 + 20 * 10, 1);
  EXPECT_EQ(limits.refused("flood"), static_cast<std::uint64_t>(10000 - allowed));
  EXPECT_EQ(limits.refused(), limits.refused("flood"));
  EXPECT_TRUE(limits.Allow("operator", 10.0));  // another sender: its own full bucket
  EXPECT_EQ(limits.refused("operator"), 0u);
  int after_quiet = 0;
  for (int i = 0; i < 300; ++i) after_quiet += limits.Allow("flood", 1000.0);  // 990 s quiet
  EXPECT_EQ(after_quiet, 100);
  int backwards = 0;
  for (int i = 0; i < 10; ++i) backwards += limits.Allow("flood", 500.0);  // a clock gone back refills nothing
  EXPECT_EQ(backwards, 0);
  EXPECT_THROW(SenderLimits(0.0, 10.0), std::invalid_argument);
  EXPECT_THROW(SenderLimits(1.0, 0.5), std::invalid_argument);
}

// Made-up sender names cannot grow the limiter: at most max_senders buckets and counts by name,
// the rest together.
TEST(SenderLimits, ManyNamesStayBounded) {
  SenderLimits limits(1.0, 1.0, 8);
  for (int i = 0; i < 1000; ++i) {
    std::string name = "s";
    name += std::to_string(i);
    EXPECT_TRUE(limits.Allow(name, 0.0));
    EXPECT_FALSE(limits.Allow(name, 0.0));
  }
  EXPECT_EQ(limits.refused(), 1000u);
  EXPECT_LE(limits.refused_by_sender().size(), 9u);
  EXPECT_GT(limits.refused(SenderLimits::kOtherSenders), 0u);
}

// In a mission: 5,000 updates from one sender within a cycle are refused beyond the burst with
// the rule in the answer; an operator's update in the middle of them is applied.
TEST(SenderLimits, MissionServesAnOperatorDuringAFlood) {
  const maps::Scenario s = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  Mission mission(s, MissionOptions{"", ControllerKind::kErgodic, nullptr, false});
  mission.Step();
  const MissionCore& core = mission.core();
  int applied = 0;
  std::string reason;
  for (int i = 0; i < 5000; ++i) {
    const OperatorAnswer a = mission.SetRisk("P1", 1.0 + (i % 7), "flood", "flood (writer 1)");
    applied += a.accepted;
    if (!a.accepted) reason = a.reason;
    if (i == 2500) {
      EXPECT_TRUE(mission.SetRisk("P3", 5.0, "operator", "operator (writer 2)").accepted);
    }
  }
  EXPECT_EQ(applied, static_cast<int>(MissionCore::kRiskUpdateBurst));
  EXPECT_NE(reason.find("rate limit"), std::string::npos) << reason;
  EXPECT_EQ(core.risk_limits().refused("flood (writer 1)"), 5000u - applied);
  EXPECT_EQ(core.risk_limits().refused("operator (writer 2)"), 0u);
  EXPECT_EQ(core.fleet().raw_weights()[s.ValveIndex("P3")], 5.0);
}

}  // namespace
}  // namespace sage::server
