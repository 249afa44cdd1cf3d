// The live view's JSON, read back by an independent parser: every string from outside escaped
// (quotes, backslashes, control characters, '<' so no text can close a tag), numbers that are
// not finite written as null, and base64 as RFC 4648 gives it.
#include "server/live/frame_json.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "maps/scenario/scenario.h"

namespace sage::live {
namespace {

using Json = nlohmann::json;

TEST(FrameJson, EscapesEveryOutsideString) {
  const std::string nasty = "rov\"1\\</script><b>\n\t\x01";
  const std::string text = JsonString(nasty);
  EXPECT_EQ(text.find('<'), std::string::npos);
  EXPECT_EQ(text.find('\n'), std::string::npos);
  EXPECT_EQ(Json::parse(text).get<std::string>(), nasty);
}

TEST(FrameJson, FrameReadsBackWithNullsForNonFinite) {
  LiveFrame frame;
  frame.time_s = 12.25;
  frame.duration_s = 600;
  frame.ergodic_metric = std::numeric_limits<double>::quiet_NaN();
  frame.vehicles = {{0, "rov1", 1.5f, 2.25f, 0.5f, VehicleStatus::kAlive},
                    {3, "a\"b", 4.0f, 5.0f, -3.0f, VehicleStatus::kLost}};
  frame.trails = {{1.0f, 2.0f, 1.5f, 2.25f}, {}};
  ValveView never;
  never.raw_weight = 2.0;
  never.share = 0.5;
  ValveView seen;
  seen.raw_weight = 2.0;
  seen.share = 0.5;
  seen.last_visit_s = 7.5;
  seen.visits = 3;
  frame.valves = {never, seen};
  const std::vector<LoggedEvent> events = {{4, {3.0, "lost", "rov2 (id 1) lost"}}};
  const Json j = Json::parse(FrameJson(frame, 9, events, 4, 2, /*with_trails=*/true));
  EXPECT_EQ(j["seq"], 9);
  EXPECT_DOUBLE_EQ(j["t"].get<double>(), 12.25);
  EXPECT_TRUE(j["metric"].is_null());
  EXPECT_EQ(j["counts"]["alive"], 1);
  EXPECT_EQ(j["counts"]["lost"], 1);
  ASSERT_EQ(j["v"].size(), 2u);
  EXPECT_EQ(j["v"][1][1], "a\"b");
  EXPECT_EQ(j["v"][1][5], 2);
  EXPECT_TRUE(j["valves"][0][2].is_null());
  EXPECT_DOUBLE_EQ(j["valves"][1][2].get<double>(), 7.5);
  EXPECT_EQ(j["valves"][1][3], 3);
  EXPECT_EQ(j["events"][0][0], 4);
  EXPECT_EQ(j["events"][0][3], "rov2 (id 1) lost");
  EXPECT_EQ(j["trails"][0].size(), 4u);
  EXPECT_FALSE(Json::parse(FrameJson(frame, 9, events, 4, 2, /*with_trails=*/false)).contains("trails"));
}

// The page draws the seabed's pipes and boulders: the scene of fleet_field_leaks carries each
// flowline's name, diameter and every vertex, and a boulder its centre and diameter, to the mm.
TEST(FrameJson, SceneCarriesFlowlinesAndBoulders) {
  maps::Scenario scenario = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field_leaks.yaml");
  scenario.boulders.push_back({Eigen::Vector2d(1.25, 8.5), 0.6, 0.4});
  const Json j = Json::parse(SceneJson(SceneOf(scenario)));
  ASSERT_EQ(j["flowlines"].size(), scenario.flowlines.size());
  for (std::size_t i = 0; i < scenario.flowlines.size(); ++i) {
    const maps::Flowline& f = scenario.flowlines[i];
    const Json& line = j["flowlines"][i];
    EXPECT_EQ(line[0], f.name);
    EXPECT_NEAR(line[1].get<double>(), f.diameter_m, 5e-4);
    ASSERT_EQ(line[2].size(), 2 * f.points_m.size());
    for (std::size_t k = 0; k < f.points_m.size(); ++k) {
      EXPECT_NEAR(line[2][2 * k].get<double>(), f.points_m[k].x(), 5e-4);
      EXPECT_NEAR(line[2][2 * k + 1].get<double>(), f.points_m[k].y(), 5e-4);
    }
  }
  ASSERT_EQ(j["boulders"].size(), 1u);
  EXPECT_NEAR(j["boulders"][0][0].get<double>(), 1.25, 5e-4);
  EXPECT_NEAR(j["boulders"][0][2].get<double>(), 0.6, 5e-4);
  EXPECT_EQ(j["structures"].size(), scenario.structures.size());
  // A field without a seabed model sends empty lists, which the page draws as nothing.
  const Json plain = Json::parse(SceneJson(SceneOf(maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml"))));
  EXPECT_TRUE(plain["flowlines"].empty());
  EXPECT_TRUE(plain["boulders"].empty());
}

TEST(FrameJson, Base64AsRfc4648) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

// The heat map's bytes: each cell scaled to the largest (255), decodable as sent.
TEST(FrameJson, HeatScalesToTheLargestCell) {
  HeatGrid grid;
  grid.nx = 2;
  grid.ny = 2;
  grid.cell_m = 0.5;
  grid.values = {0.0f, 1.0f, 2.0f, 4.0f};
  grid.max = 4.0f;
  const Json j = Json::parse(HeatJson(grid, 3));
  EXPECT_EQ(j["nx"], 2);
  EXPECT_EQ(j["data"], Base64(std::string("\x00\x40\x80\xff", 4)));
}

}  // namespace
}  // namespace sage::live
