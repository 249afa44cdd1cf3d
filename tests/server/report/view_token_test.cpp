// The live view's token in the run directory: the owner's alone (0600), 128 random bits, kept by
// a resumed mission and replaced for a new one, refused when others could read it.
#include "server/report/view_token.h"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "maps/scenario/scenario.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

TEST(ViewToken, OwnersAloneKeptOnResumeNewForANewMission) {
  const fs::path dir = fs::temp_directory_path() / ("sage_view_token_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string first = MissionToken(dir.string(), /*reuse=*/true);  // none there yet: a new one
  EXPECT_EQ(first.size(), 32u);
  EXPECT_EQ(first.find_first_not_of("0123456789abcdef"), std::string::npos);
  struct stat st {};
  ASSERT_EQ(stat((dir / "live_token").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(MissionToken(dir.string(), /*reuse=*/true), first);
  const std::string second = MissionToken(dir.string(), /*reuse=*/false);
  EXPECT_NE(second, first);
  EXPECT_EQ(MissionToken(dir.string(), true), second);
  chmod((dir / "live_token").c_str(), 0644);
  try {
    MissionToken(dir.string(), true);
    FAIL() << "a token others can read was taken";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("mode 644"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "live_token", std::ios::trunc) << "not a token\n";
  chmod((dir / "live_token").c_str(), 0600);
  EXPECT_THROW(MissionToken(dir.string(), true), maps::ScenarioError);
  fs::remove_all(dir);
}

TEST(ViewToken, ComparesWholeTokensOnly) {
  const std::string token = NewToken();
  EXPECT_NE(NewToken(), token);
  EXPECT_TRUE(SameToken(token, token));
  EXPECT_FALSE(SameToken(token, token.substr(0, 31)));
  EXPECT_FALSE(SameToken(token + "0", token));
  EXPECT_FALSE(SameToken("", ""));
  std::string flipped = token;
  flipped[31] = flipped[31] == 'a' ? 'b' : 'a';
  EXPECT_FALSE(SameToken(flipped, token));
}

}  // namespace
}  // namespace sage::server
