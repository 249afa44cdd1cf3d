// `sage field seabed` writes a scenario and its map beside it: the map is named after the scenario
// file unless --name says otherwise, and another scenario's map is never written over (a user's
// second example in the same folder had replaced the first one's seabed, which then flew on it).
#include "server/app/field_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "maps/scenario/scenario.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

std::string Text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class FieldSeabedCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("sage_field_seabed_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(FieldSeabedCommand, NamesTheMapAfterTheScenarioAndKeepsAnotherScenariosMap) {
  ASSERT_EQ(CmdFieldSeabed(7, "", (dir_ / "manifold_slope.yaml").string()), 0);
  ASSERT_TRUE(fs::exists(dir_ / "manifold_slope.xyz"));
  const std::string seven = Text(dir_ / "manifold_slope.xyz");
  // The shipped example is this command's output: the default name keeps it byte for byte.
  EXPECT_EQ(Text(dir_ / "manifold_slope.xyz"), Text(fs::path(SAGE_SOURCE_DIR) / "scenarios/manifold_slope.xyz"));
  EXPECT_EQ(Text(dir_ / "manifold_slope.yaml"), Text(fs::path(SAGE_SOURCE_DIR) / "scenarios/manifold_slope.yaml"));

  // A second example beside it gets a map of its own, and its scenario names that map.
  ASSERT_EQ(CmdFieldSeabed(11, "", (dir_ / "slope11.yaml").string()), 0);
  ASSERT_TRUE(fs::exists(dir_ / "slope11.xyz"));
  EXPECT_NE(Text(dir_ / "slope11.xyz"), seven);
  EXPECT_EQ(Text(dir_ / "manifold_slope.xyz"), seven);
  const maps::Scenario eleven = maps::LoadScenario((dir_ / "slope11.yaml").string());
  ASSERT_TRUE(eleven.seabed.has_value());
  EXPECT_EQ(fs::path(eleven.seabed->map).filename(), "slope11.xyz");

  // Named after the first one's map, a new scenario is refused, and nothing is written.
  try {
    CmdFieldSeabed(12, "manifold_slope", (dir_ / "other.yaml").string());
    ADD_FAILURE() << "another scenario's map was written over";
  } catch (const maps::ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("--name = manifold_slope: ", 0), 0u) << what;
    EXPECT_NE(what.find("another seabed"), std::string::npos) << what;
  }
  EXPECT_EQ(Text(dir_ / "manifold_slope.xyz"), seven);
  EXPECT_FALSE(fs::exists(dir_ / "other.yaml"));

  // Writing the same pair again with another seed replaces both (the scenario file exists).
  ASSERT_EQ(CmdFieldSeabed(8, "", (dir_ / "manifold_slope.yaml").string()), 0);
  EXPECT_NE(Text(dir_ / "manifold_slope.xyz"), seven);

  // A scenario file whose name cannot name a map asks for --name.
  EXPECT_THROW(CmdFieldSeabed(7, "", (dir_ / "my slope.yaml").string()), maps::ScenarioError);
  EXPECT_EQ(CmdFieldSeabed(7, "my_slope", (dir_ / "my slope.yaml").string()), 0);
  EXPECT_TRUE(fs::exists(dir_ / "my_slope.xyz"));
}

}  // namespace
}  // namespace sage::server
