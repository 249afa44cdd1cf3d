// The mission in Foxglove's schemas: the messages read back as the fields Foxglove's schemas name
// (PosesInFrame, SceneUpdate, Grid), poses as unit yaw quaternions, greyed vehicles kept in the
// scene but not among the poses, the grid's bytes the heat map's float32 cells, little-endian.
#include "server/live/foxglove_bridge.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/live/frame_json.h"

namespace sage::live {
namespace {

using Json = nlohmann::json;

LiveFrame Frame() {
  LiveFrame frame;
  frame.time_s = 12.5;
  frame.vehicles = {{0, "rov1", 1.0f, 2.0f, static_cast<float>(M_PI / 2), VehicleStatus::kAlive},
                    {1, "rov2", 3.0f, 4.0f, 0.0f, VehicleStatus::kStale},
                    {2, "rov3", 5.0f, 6.0f, 0.0f, VehicleStatus::kLost}};
  ValveView a, b;
  a.share = 0.25;
  b.share = 0.75;
  b.last_visit_s = 10.0;
  frame.valves = {a, b};
  return frame;
}

TEST(FoxgloveBridge, PosesOfTheVehiclesStillFlying) {
  const Json j = Json::parse(PosesInFrameJson(Frame()));
  EXPECT_EQ(j["timestamp"]["sec"], 12);
  EXPECT_EQ(j["timestamp"]["nsec"], 500000000);
  EXPECT_EQ(j["frame_id"], "seabed");
  ASSERT_EQ(j["poses"].size(), 2u);  // the lost one is not flying
  const Json& q = j["poses"][0]["orientation"];
  EXPECT_NEAR(q["z"].get<double>(), std::sin(M_PI / 4), 1e-6);  // a quarter turn about +z
  EXPECT_NEAR(q["w"].get<double>(), std::cos(M_PI / 4), 1e-6);
  EXPECT_DOUBLE_EQ(j["poses"][1]["position"]["x"].get<double>(), 3.0);
}

TEST(FoxgloveBridge, SceneHasEveryXtValveAndVehicle) {
  LiveScene scene;
  scene.visit_radius_m = 0.3;
  scene.structures = {{"XT-\"A\"", {2.0, 3.0}, {0.5, 0.6}}};
  scene.valves = {{"P1", "XT-A", {1.0, 1.0}, Eigen::Matrix2d::Identity()}, {"P2", "XT-A", {2.0, 1.0}, Eigen::Matrix2d::Identity()}};
  scene.flowlines = {{"FL-1", 0.3, {{0.5, 4.0}, {3.0, 4.0}, {3.0, 2.0}}}};
  scene.boulders = {{{4.0, 1.0}, 0.8}};
  const Json j = Json::parse(SceneUpdateJson(scene, Frame()));
  ASSERT_EQ(j["entities"].size(), 4u);
  const Json& xts = j["entities"][0];
  EXPECT_EQ(xts["cubes"].size(), 1u);
  EXPECT_EQ(xts["texts"][0]["text"], "XT-\"A\"");
  const Json& valves = j["entities"][1];
  ASSERT_EQ(valves["spheres"].size(), 2u);
  EXPECT_DOUBLE_EQ(valves["spheres"][0]["size"]["x"].get<double>(), 0.6);
  // The riskier valve is redder.
  EXPECT_GT(valves["spheres"][1]["color"]["r"].get<double>(), valves["spheres"][0]["color"]["r"].get<double>());
  EXPECT_EQ(valves["texts"][0]["text"], "P1 25.0% never");
  EXPECT_EQ(valves["texts"][1]["text"], "P2 75.0% 2s");
  const Json& vehicles = j["entities"][2];
  EXPECT_EQ(vehicles["arrows"].size(), 3u);  // greyed ones stay in the scene
  EXPECT_EQ(vehicles["texts"][2]["text"], "rov3 (lost)");
  EXPECT_LT(vehicles["arrows"][1]["color"]["g"].get<double>(), 0.6);
  // The seabed: each flowline a line strip through its vertices at its diameter; each boulder a sphere.
  const Json& seabed = j["entities"][3];
  EXPECT_EQ(seabed["id"], "seabed");
  ASSERT_EQ(seabed["lines"].size(), 1u);
  EXPECT_EQ(seabed["lines"][0]["type"], 0);
  EXPECT_DOUBLE_EQ(seabed["lines"][0]["thickness"].get<double>(), 0.3);
  ASSERT_EQ(seabed["lines"][0]["points"].size(), 3u);
  EXPECT_DOUBLE_EQ(seabed["lines"][0]["points"][2]["y"].get<double>(), 2.0);
  ASSERT_EQ(seabed["spheres"].size(), 1u);
  EXPECT_DOUBLE_EQ(seabed["spheres"][0]["size"]["x"].get<double>(), 0.8);
}

TEST(FoxgloveBridge, GridCarriesTheHeatMapsFloats) {
  HeatGrid grid;
  grid.nx = 3;
  grid.ny = 2;
  grid.cell_m = 0.25;
  grid.values = {0.0f, 1.5f, -2.0f, 3.25f, 1e-7f, 7.0f};
  const Json j = Json::parse(GridJson(grid, 1.0));
  EXPECT_EQ(j["column_count"], 3);
  EXPECT_EQ(j["row_stride"], 12);
  EXPECT_EQ(j["cell_stride"], 4);
  EXPECT_EQ(j["fields"][0]["type"], 7);  // FLOAT32
  std::string bytes(24, '\0');
  for (std::size_t i = 0; i < grid.values.size(); ++i) std::memcpy(&bytes[4 * i], &grid.values[i], 4);  // x86: little-endian
  EXPECT_EQ(j["data"], Base64(bytes));
}

}  // namespace
}  // namespace sage::live
