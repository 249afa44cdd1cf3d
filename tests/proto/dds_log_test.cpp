// Cyclone DDS's own log lines told in the mission's words, each kind once a process.
#include "proto/dds_log.h"

#include <string>

#include <dds/dds.h>
#include <gtest/gtest.h>

#include "tests/support/text.h"

namespace sage::proto {
namespace {

using sage::testing::Occurrences;

// The refusal a launch's terminal had shown raw becomes one line that says what it means; its
// kind is the same whichever participant it names. Another message keeps its words; numbers
// (ports, addresses, times) do not make it another kind; nothing to say, nothing told.
TEST(DdsLog, TellsCyclonesLinesInTheMissionsWords) {
  std::string kind_a, kind_b, kind_c, kind_d;
  const std::string refused = DdsLogLine("Remote secure participant ab7fdb26:e742c:51ba:1c1 not allowed\n", &kind_a);
  EXPECT_EQ(refused.rfind("sage: dds: a secured participant on this DDS domain was refused", 0), 0u) << refused;
  DdsLogLine("  Remote secure participant 1f00:2:3:1c1 not allowed", &kind_b);
  EXPECT_EQ(kind_a, kind_b);
  EXPECT_EQ(DdsLogLine("udp_conn_write to udp/127.0.0.1:7412 failed with retcode -1\n", &kind_c),
            "sage: dds: udp_conn_write to udp/127.0.0.1:7412 failed with retcode -1");
  DdsLogLine("udp_conn_write to udp/127.0.0.1:7650 failed with retcode -1", &kind_d);
  EXPECT_EQ(kind_c, kind_d);
  EXPECT_NE(kind_a, kind_c);
  EXPECT_EQ(DdsLogLine(" \n", &kind_c), "");
  EXPECT_EQ(DdsLogLine("", nullptr), "");
}

// Through Cyclone's own log: once routed, its warnings reach stderr as the lines above, each kind
// once however often Cyclone says it, and nothing of Cyclone's raw header.
TEST(DdsLog, CyclonesLogGoesThroughItOnceAKind) {
  RouteDdsLog();
  RouteDdsLog();  // idempotent
  ::testing::internal::CaptureStderr();
  // (The refusal's own kind goes through it in the test below: each kind is told once a process,
  // and the tests of a binary run in one process when it is run whole.)
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: udp_conn_write to udp/127.0.0.1:%d failed\n", 7412);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: udp_conn_write to udp/127.0.0.1:%d failed\n", 7650);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: a lease of %d ms ran out\n", 250);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: a lease of %d ms ran out\n", 500);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(Occurrences(err, "sage: dds: sage dds_log test: udp_conn_write to udp/127.0.0.1:7412 failed"), 1u) << err;
  EXPECT_EQ(Occurrences(err, "7650"), 0u) << err;
  EXPECT_EQ(Occurrences(err, "sage: dds: sage dds_log test: a lease of 250 ms ran out"), 1u) << err;
  EXPECT_EQ(Occurrences(err, "a lease of 500 ms"), 0u) << err;
  EXPECT_EQ(Occurrences(err, "\n"), 2u) << err;
}

// A refusal while this process is making a participant (the startup race: a launch's server heard
// its own agent host before its participant was set up, then accepted it) is not told, nor
// counted as told: the same kind after the participant is made is told, once.
TEST(DdsLog, ARefusalWhileAParticipantIsMadeIsNotTold) {
  RouteDdsLog();
  ::testing::internal::CaptureStderr();
  {
    const ParticipantStartup starting;
    dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "Remote secure participant %x:%x:%x:%x not allowed\n", 0xab7fdb26u,
            7u, 8u, 0x1c1u);
    dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: startup's other line %d\n", 1);
  }
  const std::string during = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(Occurrences(during, "refused"), 0u) << during;
  EXPECT_EQ(Occurrences(during, "sage: dds: sage dds_log test: startup's other line 1"), 1u) << during;  // only refusals wait
  ::testing::internal::CaptureStderr();
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "Remote secure participant %x:%x:%x:%x not allowed\n", 0xab7fdb26u, 9u,
          10u, 0x1c1u);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "Remote secure participant %x:%x:%x:%x not allowed\n", 0x1234u, 5u, 6u,
          0x1c1u);
  const std::string after = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(Occurrences(after, "sage: dds: a secured participant on this DDS domain was refused"), 1u) << after;
  EXPECT_EQ(Occurrences(after, "Remote secure participant"), 0u) << after;  // nothing of Cyclone's raw words
}

}  // namespace
}  // namespace sage::proto
