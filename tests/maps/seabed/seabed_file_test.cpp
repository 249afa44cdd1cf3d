// Seabed map files at the door: each bad file is refused with one line naming the scenario, the
// field, the file and the rule; an OctoMap seabed is read as the top of its occupied voxels; the
// scenario's seabed sections load, resolve the map beside the scenario, and round-trip.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include "maps/seabed/seabed_file.h"
#include "maps/seabed_map.h"
#include "tests/maps/seabed/seabed_test_support.h"

namespace sage::maps {
namespace {

using testing::MakeRaster;
using testing::Raster;
using testing::ScratchDir;
using testing::SmallScenario;

double Gentle(double x, double y) { return -80.0 + 0.03 * x + 0.01 * y; }

Scenario OnMap(const std::string& map) {
  Scenario s = SmallScenario(12.0, 8.0, 0.1);
  SeabedSettings seabed;
  seabed.map = map;
  s.seabed = seabed;
  return s;
}

// What a refusal must be: one line, naming the scenario, seabed.map and the file, with the rule.
void ExpectRefused(const Scenario& s, const std::string& rule) {
  try {
    const SeabedMap map(s, s.astar.grid_resolution_m);
    ADD_FAILURE() << s.seabed->map << " was accepted; expected: " << rule;
  } catch (const ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind("seabed_test.yaml: seabed.map = " + s.seabed->map + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(rule), std::string::npos) << what;
  }
}

TEST(SeabedFile, BadRastersAreRefusedInOneLine) {
  ScratchDir dir("sage_seabed_bad");
  const Raster good = MakeRaster(130, 90, 0.1, 0.0, 0.0, Gentle);
  testing::WriteGeoTiff(good, dir.File("good.tif"));
  EXPECT_NO_THROW(SeabedMap(OnMap(dir.File("good.tif")), 0.1));

  std::ofstream(dir.File("garbage.tif")) << "this is not a GeoTIFF\n";
  ExpectRefused(OnMap(dir.File("garbage.tif")), "cannot be read as a GeoTIFF");

  const Raster small = MakeRaster(100, 90, 0.1, 0.0, 0.0, Gentle);  // 10 m wide, the workspace 12 m
  testing::WriteGeoTiff(small, dir.File("small.tif"));
  ExpectRefused(OnMap(dir.File("small.tif")), "covers x in [0, 10], y in [0, 9] (map coordinates); the workspace at "
                                              "origin (0, 0) needs x in [0, 12], y in [0, 8]: the map must cover the workspace");
  Scenario shifted = OnMap(dir.File("good.tif"));
  shifted.seabed->origin_m = Eigen::Vector2d(2.0, 0.0);  // 2 + 12 > 13
  ExpectRefused(shifted, "must cover the workspace");

  Raster hole = good;
  hole.at(40, 30) = -9999.0f;
  const double nodata = -9999.0;
  testing::WriteGeoTiff(hole, dir.File("nodata.tif"), true, &nodata);
  ExpectRefused(OnMap(dir.File("nodata.tif")), "pixel (column 40, row 30) at (4.05, 5.95) is no-data (-9999): the map "
                                               "must cover the workspace without holes");
  Raster nan = good;
  nan.at(3, 80) = std::nanf("");
  testing::WriteGeoTiff(nan, dir.File("nan.tif"));
  ExpectRefused(OnMap(dir.File("nan.tif")), "pixel (column 3, row 80) at (0.35, 0.95) is no-data (not a number)");
  Raster undeclared = good;
  undeclared.at(10, 10) = -32767.0f;
  testing::WriteGeoTiff(undeclared, dir.File("undeclared.tif"));
  ExpectRefused(OnMap(dir.File("undeclared.tif")), "= -32767 m: a seabed lies within 12000 m of the surface");

  testing::WriteGeoTiff(good, dir.File("utm.tif"), true, nullptr, 0.0, 32631);  // UTM 31N, metres: fine
  EXPECT_NO_THROW(SeabedMap(OnMap(dir.File("utm.tif")), 0.1));
  testing::WriteGeoTiff(good, dir.File("degrees.tif"), true, nullptr, 0.0, 4326);
  ExpectRefused(OnMap(dir.File("degrees.tif")), "is in geographic coordinates (degrees)");
  testing::WriteGeoTiff(good, dir.File("feet.tif"), true, nullptr, 0.0, 2263);  // NY Long Island, US feet
  ExpectRefused(OnMap(dir.File("feet.tif")), "a seabed map's coordinates must be in metres");
  testing::WriteGeoTiff(good, dir.File("plain.tif"), /*georeferenced=*/false);
  ExpectRefused(OnMap(dir.File("plain.tif")), "has no georeferencing");
  testing::WriteGeoTiff(good, dir.File("rotated.tif"), true, nullptr, 0.01);
  ExpectRefused(OnMap(dir.File("rotated.tif")), "must be a north-up raster");
  const Raster fine = MakeRaster(130, 90, 0.0005, 0.0, 0.0, Gentle);
  testing::WriteGeoTiff(fine, dir.File("fine.tif"));
  ExpectRefused(OnMap(dir.File("fine.tif")), "pixel size = 0.0005 x 0.0005 m: must be in [0.001, 10000] m");

  // 5 km of relief at 0.1 m needs 50,000 voxels: more than OctoMap's 16-bit keys hold.
  const Raster cliff = MakeRaster(130, 90, 0.1, 0.0, 0.0, [](double x, double) { return x < 6.0 ? -5500.0 : -500.0; });
  testing::WriteGeoTiff(cliff, dir.File("cliff.tif"));
  ExpectRefused(OnMap(dir.File("cliff.tif")), "OctoMap's keys hold at most 32767");

  // A seabed model of more columns than every process of a mission should voxelise.
  Scenario wide = OnMap(dir.File("good.tif"));
  wide.workspace = {250.0, 200.0};
  ExpectRefused(wide, "the workspace has 5000000 cells at astar.grid_resolution_m = 0.1 m; a seabed model at most 4 million");

  // A gridded XYZ file with one node missing is refused (GDAL reads the gap as no-data, or not at all).
  testing::WriteXyz(good, dir.File("gap.xyz"), /*skip_one=*/true);
  ExpectRefused(OnMap(dir.File("gap.xyz")), "");
  testing::WriteXyz(good, dir.File("whole.xyz"));
  EXPECT_NO_THROW(SeabedMap(OnMap(dir.File("whole.xyz")), 0.1));
  std::ofstream(dir.File("words.csv")) << "x,y,z\nsome,words,here\n";
  ExpectRefused(OnMap(dir.File("words.csv")), "line 2: 'some' is not a number");
  // A height that is not a number, which GDAL's driver reads as 0 (a new user's "abc" among
  // depths of -100 m had loaded), is refused with its line; so is a line short of x y z. The
  // header line of names stays allowed (whole.xyz has one; it reads without it too).
  std::ifstream whole_in(dir.File("whole.xyz"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(whole_in, line);) lines.push_back(line);
  ASSERT_GT(lines.size(), 10u);
  const auto write_with = [&](const std::string& name, std::size_t at, const std::string& replaced) {
    std::ofstream out(dir.File(name));
    for (std::size_t k = 0; k < lines.size(); ++k) out << (k == at ? replaced : lines[k]) << "\n";
  };
  const std::string fifth = lines[4].substr(0, lines[4].find_last_of(" ,\t") + 1);
  write_with("word.xyz", 4, fifth + "abc");
  ExpectRefused(OnMap(dir.File("word.xyz")), "line 5: 'abc' is not a number");
  // A binary file's bytes are shown as printable text (they had come out raw: escapes and bytes
  // that are not UTF-8, which a script reading the error as text choked on).
  write_with("bytes.xyz", 4, fifth + "\x1b[31m\xcd\xc3x");
  ExpectRefused(OnMap(dir.File("bytes.xyz")), "line 5: '?[31m??x' is not a number");
  write_with("short.xyz", 6, fifth);
  ExpectRefused(OnMap(dir.File("short.xyz")), "line 7: 2 fields; a gridded XYZ file holds x y z on every line");
  ASSERT_EQ(lines[0], "x y z");
  {
    std::ofstream out(dir.File("bare.xyz"));
    for (std::size_t k = 1; k < lines.size(); ++k) out << lines[k] << "\n";
  }
  EXPECT_NO_THROW(SeabedMap(OnMap(dir.File("bare.xyz")), 0.1));
}

// A band's scale and offset are applied (heights stored as value * scale + offset), before the
// check against 12,000 m: raw values of 1,000-1,200 are depths of -50 to -150 m here.
TEST(SeabedFile, ScaleAndOffsetAreApplied) {
  ScratchDir dir("sage_seabed_scaled");
  const Raster raw = MakeRaster(96, 64, 0.125, 0.0, 0.0, [](double x, double y) { return 1000.0 + 2.0 * x + y; });
  testing::WriteGeoTiff(raw, dir.File("scaled.tif"));
  GDALDatasetH ds = GDALOpen(dir.File("scaled.tif").c_str(), GA_Update);
  ASSERT_NE(ds, nullptr);
  GDALSetRasterScale(GDALGetRasterBand(ds, 1), -0.5);
  GDALSetRasterOffset(GDALGetRasterBand(ds, 1), 450.0);
  GDALClose(ds);
  Scenario s = SmallScenario(12.0, 8.0, 0.125);
  SeabedSettings seabed;
  seabed.map = dir.File("scaled.tif");
  s.seabed = seabed;
  const HeightGrid heights = ReadSeabedHeights(s, 0.125);
  for (int i = 0; i < heights.cols(); ++i) {
    for (int j = 0; j < heights.rows(); ++j) {
      ASSERT_DOUBLE_EQ(heights.at(i, j), -0.5 * raw.at(i, raw.rows - 1 - j) + 450.0) << i << ", " << j;
    }
  }
}

// An OctoMap seabed: its occupied voxels' top in each column is the seabed; a column with no
// voxel is a hole and refused; a file that is no tree is refused.
TEST(SeabedFile, OctoMapSeabedIsTheTopOfItsVoxels) {
  ScratchDir dir("sage_seabed_octomap");
  const double res = 0.2;
  // A terrace: z top -40.0 west of x = 6, -38.0 east of it, three voxels thick, 13 x 9 m.
  const auto terrace = [&](auto& tree) {
    for (int i = 0; i < 65; ++i) {
      for (int j = 0; j < 45; ++j) {
        const int top = (i + 0.5) * res < 6.0 ? -201 : -191;  // voxel k spans [k r, (k + 1) r)
        for (int k = top - 2; k <= top; ++k) tree.updateNode(octomap::OcTreeKey(i + 32768, j + 32768, k + 32768), true);
      }
    }
  };
  octomap::OcTree tree(res);
  terrace(tree);
  ASSERT_TRUE(tree.writeBinary(dir.File("terrace.bt")));
  Scenario s = OnMap(dir.File("terrace.bt"));
  const HeightGrid heights = ReadSeabedHeights(s, 0.1);
  for (int i = 0; i < heights.cols(); ++i) {
    for (int j = 0; j < heights.rows(); ++j) {
      ASSERT_NEAR(heights.at(i, j), (i + 0.5) * 0.1 < 6.0 ? -40.0 : -38.0, 1e-4) << i << ", " << j;
    }
  }
  const SeabedMap map(s, 0.1);
  EXPECT_GT(map.OperatingSlice().OccupiedCount(), 100 + 10 * 10) << "the terrace's upper edge blocks, and the XT";
  // The same seabed as an .ot file (OctoMap's full format, read by its type name), and as a
  // ColorOcTree (a coloured seabed survey): the same heights.
  ASSERT_TRUE(tree.write(dir.File("terrace.ot")));
  octomap::ColorOcTree coloured(res);
  terrace(coloured);
  ASSERT_TRUE(coloured.write(dir.File("coloured.ot")));
  for (const char* name : {"terrace.ot", "coloured.ot"}) {
    const HeightGrid again = ReadSeabedHeights(OnMap(dir.File(name)), 0.1);
    ASSERT_EQ(again.values(), heights.values()) << name;
  }

  for (int k = -193; k <= -191; ++k) tree.deleteNode(octomap::OcTreeKey(30 + 32768, 20 + 32768, k + 32768));
  ASSERT_TRUE(tree.writeBinary(dir.File("hole.bt")));
  ExpectRefused(OnMap(dir.File("hole.bt")), "no occupied voxel under workspace point (6.05, 4.05) (map (6.05, 4.05))");
  std::ofstream(dir.File("junk.bt")) << "# Octomap OcTree binary file\nnot really\n";
  ExpectRefused(OnMap(dir.File("junk.bt")), "is not an OctoMap binary tree (.bt)");
}

// The seabed sections in YAML: the map resolved beside the scenario file and hashed, flowlines
// and boulders read, emitted and read back the same; the map file checked at the door.
TEST(SeabedFile, ScenarioSectionsLoadAndRoundTrip) {
  ScratchDir dir("sage_seabed_yaml");
  testing::WriteXyz(MakeRaster(130, 90, 0.1, 431000.0, 6478000.0, Gentle), dir.File("bathy.xyz"));
  const std::string yaml = R"(name: on_map
workspace: {width_m: 12.0, height_m: 8.0}
structures:
  - {name: XT-A, center_m: [3.0, 4.0], size_m: [1.0, 1.0], valves: [{name: P1, position_m: [3.0, 5.3]}]}
vehicles: [{name: rov1, start_m: [1.0, 1.0]}]
profiles: {equal: {weights: {P1: 1}}}
seabed: {map: bathy.xyz, origin_m: [431000.5, 6478000.5], values: elevation, altitude_band_m: [0.8, 2.0], trend_radius_m: 3}
flowlines:
  - {name: FL-A, diameter_m: 0.25, points_m: [[1, 1], [5, 1], [5, 6]]}
boulders:
  - {center_m: [9, 6], diameter_m: 1.5, height_m: 0.9}
)";
  std::ofstream(dir.File("on_map.yaml")) << yaml;
  const Scenario s = LoadScenario(dir.File("on_map.yaml"));
  ASSERT_TRUE(s.seabed);
  EXPECT_EQ(s.seabed->map, dir.File("bathy.xyz"));
  EXPECT_NE(s.seabed->map_fnv1a, 0u);
  EXPECT_EQ(s.seabed->altitude_min_m, 0.8);
  EXPECT_EQ(s.seabed->altitude_max_m, 2.0);
  ASSERT_EQ(s.flowlines.size(), 1u);
  EXPECT_DOUBLE_EQ(s.flowlines[0].Length_m(), 9.0);
  EXPECT_EQ(s.FlowlinePoint("FL-A", 6.5), Eigen::Vector2d(5.0, 3.5));
  EXPECT_THROW(s.FlowlinePoint("FL-A", 9.5), ScenarioError);
  EXPECT_THROW(s.FlowlinePoint("FL-B", 1.0), ScenarioError);
  ASSERT_EQ(s.boulders.size(), 1u);
  // Emitted (absolute map path) and read back: the same scenario, the same hashes.
  const Scenario again = ParseScenario(EmitScenario(s), dir.File("elsewhere/copy.yaml"));
  EXPECT_EQ(EmitScenario(again), EmitScenario(s));
  EXPECT_EQ(ScenarioHash(again), ScenarioHash(s));
  EXPECT_EQ(VehicleFingerprint(again), VehicleFingerprint(s));
  // The same map bytes at another path fly the same world; other bytes do not.
  std::filesystem::copy_file(dir.File("bathy.xyz"), dir.File("copy.xyz"));
  Scenario moved = s;
  moved.seabed->map = "copy.xyz";
  EXPECT_EQ(VehicleFingerprint(ParseScenario(EmitScenario(moved), dir.File("x.yaml"))), VehicleFingerprint(s));
  const Scenario before = ParseScenario(EmitScenario(moved), dir.File("x.yaml"));
  std::ofstream(dir.File("copy.xyz"), std::ios::app) << "\n";
  const Scenario after = ParseScenario(EmitScenario(moved), dir.File("x.yaml"));
  EXPECT_NE(VehicleFingerprint(after), VehicleFingerprint(s));
  EXPECT_NE(ScenarioHash(after), ScenarioHash(before)) << "a checkpoint is not resumed over a changed map";

  const auto refused = [&](const std::string& from, const std::string& to, const std::string& message) {
    std::string text = yaml;
    text.replace(text.find(from), from.size(), to);
    try {
      ParseScenario(text, dir.File("bad.yaml"));
      ADD_FAILURE() << "accepted: " << to;
    } catch (const ScenarioError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused("map: bathy.xyz", "map: nothere.xyz", "bad.yaml: seabed.map = " + dir.File("nothere.xyz") + ": cannot open: no such file");
  refused("map: bathy.xyz", "map: bathy.png", "seabed.map = bathy.png: must end in .tif or .tiff (GeoTIFF)");
  refused("altitude_band_m: [0.8, 2.0]", "altitude_band_m: [0.8, 0.85]", "seabed.altitude_band_m = [0.8, 0.85]: the ceiling must exceed");
  refused("values: elevation", "values: height", "seabed.values = height: must be elevation (heights, up) or depth");
  refused("[[1, 1], [5, 1], [5, 6]]", "[[1, 1], [1, 1]]", "flowlines[0].points_m[1] = [1, 1]: repeats the point before it");
  refused("[[1, 1], [5, 1], [5, 6]]", "[[1, 1], [15, 1]]", "flowlines[0].points_m[1] = [15, 1]: must be inside the workspace");
  refused("diameter_m: 0.25", "diameter_m: 7", "flowlines[0].diameter_m = 7: must be <= 5 m");
  refused("height_m: 0.9", "height_m: -1", "boulders[0].height_m = -1: must be > 0");
  refused("trend_radius_m: 3", "trend_radius_m: 3, depth: 4", "seabed.depth: unknown key");
  // A file over the size a map may have is refused without reading it (a sparse file here).
  std::filesystem::resize_file(dir.File("copy.xyz"), kMaxSeabedMapBytes + 1);
  refused("map: bathy.xyz", "map: copy.xyz", "over 256 MB: too large for a seabed map");
}

}  // namespace
}  // namespace sage::maps
