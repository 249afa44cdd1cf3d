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
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "Remote secure participant %x:%x:%x:%x not allowed\n", 0xab7fdb26u, 1u,
          2u, 0x1c1u);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "Remote secure participant %x:%x:%x:%x not allowed\n", 0x1234u, 5u, 6u,
          0x1c1u);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: a lease of %d ms ran out\n", 250);
  dds_log(DDS_LC_WARNING, __FILE__, __LINE__, "test", "sage dds_log test: a lease of %d ms ran out\n", 500);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(Occurrences(err, "sage: dds: a secured participant on this DDS domain was refused"), 1u) << err;
  EXPECT_EQ(Occurrences(err, "sage: dds: sage dds_log test: a lease of 250 ms ran out"), 1u) << err;
  EXPECT_EQ(Occurrences(err, "a lease of 500 ms"), 0u) << err;
  EXPECT_EQ(Occurrences(err, "Remote secure participant"), 0u) << err;
  EXPECT_EQ(Occurrences(err, "\n"), 2u) << err;
}

}  // namespace
}  // namespace sage::proto
