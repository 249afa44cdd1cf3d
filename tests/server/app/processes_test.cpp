// The tunable under which `sage` starts itself again with its heaps on transparent huge pages
// (server/app/processes.h): set once, added to a user's other tunables, never over a user's own
// choice of it, and not at all with SAGE_HUGE_PAGES=0.
#include "server/app/processes.h"

#include <gtest/gtest.h>

namespace sage::server {
namespace {

TEST(HugePageTunables, SetOnceBesideTheUsersOwnAndNeverOverThem) {
  EXPECT_EQ(HugePageTunables(nullptr, nullptr), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables("", nullptr), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables("glibc.malloc.arena_max=2", nullptr), "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables(nullptr, "1"), "glibc.malloc.hugetlb=1");
  // Started again with it (or the user's own value, whichever): nothing more to change, no loop.
  EXPECT_EQ(HugePageTunables("glibc.malloc.hugetlb=1", nullptr), std::nullopt);
  EXPECT_EQ(HugePageTunables("glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1", nullptr), std::nullopt);
  EXPECT_EQ(HugePageTunables("glibc.malloc.hugetlb=0", nullptr), std::nullopt);
  EXPECT_EQ(HugePageTunables(nullptr, "0"), std::nullopt);
  EXPECT_EQ(HugePageTunables("glibc.malloc.arena_max=2", "0"), std::nullopt);
}

}  // namespace
}  // namespace sage::server
