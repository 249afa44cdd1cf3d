// The roster finds its members by id through an index of its own (dense ids in a vector, the
// rest in the map): checked against the map itself for ids at both ends, after joins, leaves
// and a restore, and the names it knows are the members' names.
#include "server/roster.h"

#include <gtest/gtest.h>

namespace sage::server {
namespace {

// Every member found at its own entry, and no id that is not a member found.
void ExpectIndexMatchesMembers(const Roster& roster, const std::vector<int>& absent) {
  for (const auto& [id, member] : roster.members()) {
    const Roster::Member* found = roster.Find(id);
    ASSERT_NE(found, nullptr) << id;
    EXPECT_EQ(found, &member) << id;
    EXPECT_TRUE(roster.NameTaken(member.name)) << member.name;
  }
  for (int id : absent) EXPECT_EQ(roster.Find(id), nullptr) << id;
}

TEST(Roster, FindsEveryMemberByIdAfterJoinsLeavesAndARestore) {
  Roster roster(3);
  const std::vector<int> ids = {0, 2, 7, 1 << 19, (1 << 20) - 1, 1 << 20, (1 << 24) - 1};
  for (int id : ids) ASSERT_NE(roster.Join(id, "rov" + std::to_string(id), 0.5), nullptr);
  ExpectIndexMatchesMembers(roster, {-1, 1, 3, 8, (1 << 20) + 1, 1 << 23});
  EXPECT_FALSE(roster.NameTaken("rov1"));
  // Gone members are still members (and their names still taken).
  ASSERT_NE(roster.Leave(7, true, 1.0), nullptr);
  EXPECT_EQ(roster.Find(7)->status, Roster::Status::kLost);
  EXPECT_TRUE(roster.NameTaken("rov7"));
  // A restore replaces every member: the index points at the restored ones, not the old.
  Roster::State state = roster.Checkpoint();
  state.members.erase(2);
  Roster restored(0);
  restored.Restore(state);
  ExpectIndexMatchesMembers(restored, {2, -1});
  EXPECT_FALSE(restored.NameTaken("rov2"));
  roster.Restore(state);
  ExpectIndexMatchesMembers(roster, {2});
  // A rejoin under another name frees the old one.
  ASSERT_NE(roster.Join(7, "seven", 2.0), nullptr);
  EXPECT_TRUE(roster.NameTaken("seven"));
  EXPECT_FALSE(roster.NameTaken("rov7"));
}

}  // namespace
}  // namespace sage::server
