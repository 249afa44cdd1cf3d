// The roster finds its members by id through an index of its own (dense ids in a vector, the
// rest in the map): checked against the map itself for ids at both ends, after joins, leaves
// and a restore, and the names it knows are the members' names. The live view's glances (one
// compact array kept as states arrive) agree with a walk of the members at every step.
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

// The glances, one a member in ascending id, each as the member stands (compared with a walk).
void ExpectGlancesMatchMembers(const Roster& roster) {
  const std::vector<Roster::Glance>& glances = roster.glances();
  ASSERT_EQ(glances.size(), roster.members().size());
  std::size_t k = 0;
  for (const auto& [id, m] : roster.members()) {
    const Roster::Glance& g = glances[k++];
    EXPECT_EQ(g.id, id);
    EXPECT_EQ(g.name, m.name) << id;
    EXPECT_EQ(g.status, m.status) << id;
    EXPECT_EQ(g.has_state, m.has_state) << id;
    EXPECT_EQ(g.x_m, static_cast<float>(m.last.state.position_m.x())) << id;
    EXPECT_EQ(g.y_m, static_cast<float>(m.last.state.position_m.y())) << id;
    EXPECT_EQ(g.heading_rad, static_cast<float>(m.last.state.heading_rad)) << id;
    EXPECT_EQ(g.heard_s, m.last.time_s) << id;
  }
}

void Hear(Roster& roster, int id, double x, double time_s) {
  Roster::Member& m = *roster.Find(id);
  m.last.time_s = time_s;
  m.last.state.position_m = {x, 2.0 * x};
  m.last.state.heading_rad = 0.1 * x;
  m.has_state = true;
  roster.Heard(m);
}

TEST(Roster, GlancesFollowStatesJoinsLeavesAndARestore) {
  Roster roster(0);
  // Joined in an order other than their ids: the record's indices differ from the glances' order.
  for (int id : {9, 3, 40, 0}) ASSERT_NE(roster.Join(id, "rov" + std::to_string(id), 0.0), nullptr);
  ExpectGlancesMatchMembers(roster);
  for (int id : {9, 3, 40, 0}) Hear(roster, id, 1.5 * id + 0.25, 0.1);
  ExpectGlancesMatchMembers(roster);  // states heard after the glances were made
  Hear(roster, 40, 7.0, 0.2);
  ASSERT_NE(roster.Leave(3, true, 0.3), nullptr);
  ASSERT_NE(roster.Join(5, "rov5", 0.3), nullptr);
  Hear(roster, 9, -3.0, 0.4);  // heard while the glances are stale
  ExpectGlancesMatchMembers(roster);
  Hear(roster, 5, 2.0, 0.5);
  ExpectGlancesMatchMembers(roster);
  Roster restored(0);
  restored.Restore(roster.Checkpoint());
  ExpectGlancesMatchMembers(restored);
  Hear(restored, 0, 11.0, 0.6);
  ExpectGlancesMatchMembers(restored);
  EXPECT_EQ(restored.glances().front().x_m, 11.0f);
}

}  // namespace
}  // namespace sage::server
