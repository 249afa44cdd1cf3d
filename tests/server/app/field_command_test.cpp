// `sage field seabed` writes a scenario and its map beside it: the map is named after the scenario
// file unless --name says otherwise, and another scenario's map is never written over (a user's
// second example in the same folder had replaced the first one's seabed, which then flew on it).
#include "server/app/field_command.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>

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
    // One folder per test and process: ctest runs this fixture's tests side by side, and a folder
    // named by gtest's random seed alone (the same in both) was removed by one while the other wrote.
    dir_ = fs::temp_directory_path() / ("sage_field_seabed_" +
                                        std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                                        "_" + std::to_string(::getpid()));
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

// `sage field generate -o FILE` replaces a field sage wrote there, and refuses any other file (a
// new user's -o scenarios/fleet_field.yaml would have replaced a shipped scenario) and a folder,
// leaving them as they were.
TEST_F(FieldSeabedCommand, GenerateReplacesOnlyAFieldItWrote) {
  maps::FieldOptions options;
  options.xts = 3;
  options.valves = 8;
  options.vehicles = 2;
  const fs::path field = dir_ / "field.yaml";
  ASSERT_EQ(CmdFieldGenerate(options, field.string()), 0);
  const std::string first = Text(field);
  options.seed = 9;
  ASSERT_EQ(CmdFieldGenerate(options, field.string()), 0);
  EXPECT_NE(Text(field), first);  // replaced: another seed, another field
  const fs::path hand = dir_ / "hand.yaml";
  {
    std::ofstream out(hand);
    out << "# my field\nname: mine\n";
  }
  try {
    CmdFieldGenerate(options, hand.string());
    ADD_FAILURE() << "a hand-written file was replaced";
  } catch (const maps::ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--out = " + hand.string() + ": exists and is a file that sage did not write", 0), 0u)
        << e.what();
  }
  EXPECT_EQ(Text(hand), "# my field\nname: mine\n");
  EXPECT_THROW(CmdFieldGenerate(options, dir_.string()), maps::ScenarioError);
  EXPECT_TRUE(fs::is_directory(dir_));
  // Not opened to be read: /dev/stdout piped to a reader had blocked on itself.
  try {
    CmdFieldGenerate(options, "/dev/null");
    ADD_FAILURE() << "/dev/null taken as a field's file";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("is not a regular file"), std::string::npos) << e.what();
  }
}

// `sage field generate --xts 4` alone was refused for the default --valves = 87 the user never
// typed; a count left out is now sized to the one given, at the default field's rate.
TEST(FieldGenerateCounts, ACountLeftOutIsSizedToTheOneGiven) {
  const maps::FieldOptions defaults;
  const double per_xt = static_cast<double>(defaults.valves) / defaults.xts;
  for (int xts = 1; xts <= 2000; ++xts) {
    maps::FieldOptions o;
    o.xts = xts;
    const maps::FieldOptions sized = WithCountsSizedToEachOther(o, true, false, false);
    ASSERT_EQ(sized.xts, xts);
    ASSERT_GE(sized.valves, 2 * xts) << xts;
    ASSERT_LE(sized.valves, 5 * xts) << xts;
    ASSERT_LE(std::abs(sized.valves - per_xt * xts), 0.5 + 1e-9) << xts;  // the default's rate, rounded
    ASSERT_GE(sized.vehicles, 1) << xts;
    ASSERT_LE(std::abs(sized.vehicles - xts * static_cast<double>(defaults.vehicles) / defaults.xts), 0.5 + 1e-9) << xts;
  }
  for (int valves = 2; valves <= 5000; ++valves) {
    maps::FieldOptions o;
    o.valves = valves;
    const maps::FieldOptions sized = WithCountsSizedToEachOther(o, false, true, false);
    ASSERT_EQ(sized.valves, valves);
    ASSERT_GE(5 * sized.xts, valves) << valves;  // 2 to 5 valves per XT
    ASSERT_LE(2 * sized.xts, valves) << valves;
  }
  // Too few valves given alone are refused in their own terms, not as "2 x --xts = 56" of a
  // default --xts the user never gave.
  for (const int valves : {-3, 0, 1}) {
    maps::FieldOptions few;
    few.valves = valves;
    try {
      WithCountsSizedToEachOther(few, false, true, false);
      ADD_FAILURE() << "--valves " << valves << " taken";
    } catch (const maps::ScenarioError& e) {
      EXPECT_EQ(std::string(e.what()), "--valves = " + std::to_string(valves) + ": must be >= 2 (an XT carries 2 to 5 valves)");
    }
  }
  // The default field is the default's own size either way.
  maps::FieldOptions o;
  EXPECT_EQ(WithCountsSizedToEachOther(o, true, false, false).valves, defaults.valves);
  o.valves = defaults.valves;
  EXPECT_EQ(WithCountsSizedToEachOther(o, false, true, false).xts, defaults.xts);
  // Both typed, or neither: as given (a typed pair out of range is still refused by the generator).
  o.xts = 4;
  o.valves = 87;
  EXPECT_EQ(WithCountsSizedToEachOther(o, true, true, true).valves, 87);
  EXPECT_EQ(WithCountsSizedToEachOther(o, false, false, false).xts, 4);
  // A typed fleet stays as typed.
  o.vehicles = 500;
  EXPECT_EQ(WithCountsSizedToEachOther(o, true, false, true).vehicles, 500);
  // A field of four XTs alone is made, with valves on every one.
  maps::FieldOptions four;
  four.xts = 4;
  const maps::Scenario field = maps::GenerateField(WithCountsSizedToEachOther(four, true, false, false));
  EXPECT_EQ(field.structures.size(), 4u);
  EXPECT_EQ(field.ValveCount(), 12);      // 87 / 28 x 4 = 12.4
  EXPECT_EQ(field.vehicles.size(), 3u);   // 24 / 28 x 4 = 3.4
}

}  // namespace
}  // namespace sage::server
