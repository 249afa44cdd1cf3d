// The example seabed field (see seabed_example.h): the layout is fixed, the seed moves the
// boulders, the sand waves' phases and the risk. Every draw comes from one SplitMix64 stream,
// one draw per statement; depths are printed to the millimetre and lengths snapped to the
// centimetre, so a seed gives the same bytes with any compiler (up to libm's last bit, which
// the rounding absorbs).
#include "maps/scenario/seabed_example.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "maps/scenario/scenario_detail.h"
#include "maps/scenario/split_mix.h"

namespace sage::maps {
namespace {

constexpr double kWidth_m = 60.0, kHeight_m = 40.0;
// The map: 0.5 m nodes over the workspace and 2 m around it, its south-west corner at these
// projected coordinates (a UTM zone's eastings and northings).
constexpr double kNode_m = 0.5, kMapMargin_m = 2.0;
constexpr double kMapEasting_m = 431180.0, kMapNorthing_m = 6478280.0;
constexpr double kValveStandoff_m = 1.0;  // a valve's distance from its structure's face
constexpr int kBoulders = 28, kBouldersByRidge = 10;

const Eigen::Vector2d kRidgeFrom(48.5, 16.0), kRidgeTo(58.0, 22.5);
const Eigen::Vector2d kPockmark(38.0, 35.0);

double Rounded(double x, double per_metre) { return std::round(x * per_metre) / per_metre; }

// The seabed's elevation (m, up) at workspace point (x, y): a slope rising to the north-east,
// two trains of sand waves, a rock ridge, a terrace edge (scarp) and a pockmark.
struct Terrain {
  double wave_angle[2], wave_phase[2], ridge_phase;

  double Elevation(double x, double y) const {
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    double z = -121.0 + 0.045 * x + 0.025 * y;
    const double lengths[2] = {7.0, 3.1}, heights[2] = {0.10, 0.05};
    for (int k = 0; k < 2; ++k) {
      const double along = x * std::cos(wave_angle[k]) + y * std::sin(wave_angle[k]);
      z += heights[k] * std::sin(kTwoPi * along / lengths[k] + wave_phase[k]);
    }
    // The ridge: a crest 2.2 m high (+-15 % along it), 1.2 m sigma across, round at its ends.
    const Eigen::Vector2d p(x, y), d = kRidgeTo - kRidgeFrom;
    const double t = std::clamp((p - kRidgeFrom).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const double across = (p - (kRidgeFrom + t * d)).norm();
    z += 2.2 * (1.0 + 0.15 * std::sin(6.0 * t + ridge_phase)) * std::exp(-across * across / (2 * 1.2 * 1.2));
    // The scarp: 3 m higher west of x = 6 + 0.1 (y - 20), from y ~ 19 north.
    const double edge = 6.0 + 0.1 * (y - 20.0);
    z += 3.0 * 0.5 * (1.0 + std::tanh((y - 19.0) / 1.0)) * 0.5 * (1.0 - std::tanh((x - edge) / 0.3));
    z -= 0.8 * std::exp(-(p - kPockmark).squaredNorm() / (2 * 1.4 * 1.4));
    return z;
  }
};

struct StructurePlan {
  const char* name;
  Eigen::Vector2d center, size;
  double height;
  std::vector<std::pair<const char*, int>> valves;  // name and face: 0 south, 1 east, 2 north, 3 west
};

Eigen::Vector2d OffFace(const StructurePlan& s, int face) {
  const Eigen::Vector2d dirs[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
  const Eigen::Vector2d d = dirs[face];
  return s.center + d.cwiseProduct(s.size / 2 + Eigen::Vector2d::Constant(kValveStandoff_m));
}

double DistanceToAxis(const std::vector<Eigen::Vector2d>& line, const Eigen::Vector2d& p) {
  double best = 1e300;
  for (std::size_t k = 0; k + 1 < line.size(); ++k) {
    const Eigen::Vector2d d = line[k + 1] - line[k];
    const double t = std::clamp((p - line[k]).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (line[k] + t * d)).norm());
  }
  return best;
}

std::string Header(const std::string& name, std::uint64_t seed) {
  return "# " + name + ": a subsea production cluster on a sloping seabed, written by\n"
         "#   sage field seabed --seed " + std::to_string(seed) + " --name " + name + " -o " + name + ".yaml\n"
         "# (the same seed gives these bytes again; tests/maps/seabed/seabed_example_test.cpp checks it).\n"
         "#\n"
         "# The seabed is " + name + ".xyz beside this file: depths (m, positive down) at 0.5 m nodes in\n"
         "# projected coordinates (eastings, northings), 2 m beyond the workspace on every side; the\n"
         "# workspace's corner (0, 0) lies at seabed.origin_m. It slopes up about 3 degrees to the\n"
         "# north-east, with sand waves 0.1-0.15 m high, a rock ridge (2.2 m) east of the manifold, a\n"
         "# 3 m scarp in the north-west, a pockmark north of XT-D's jumper and a field of boulders.\n"
         "# The vehicles fly 0.8-2.0 m above the local seabed (the plane fitted within +-3 m of them):\n"
         "# the ridge, the scarp's upper edge, boulders taller than about 0.8 m and the structures block\n"
         "# them; the flowlines (0.15-0.4 m across) lie under the band and do not.\n"
         "#\n"
         "#   y (m)\n"
         "#  40 +-----------------------------------------------------------+\n"
         "#     |scarp    UMB-1                                             |\n"
         "#     | :    XT-C ===FL-C==\\          /==FL-D=== XT-D    pockmark |\n"
         "#     | :                   MANIFOLD                         ridge |\n"
         "#     |      XT-A ===FL-A==/    |     \\==FL-B=== XT-B        //    |\n"
         "#     |                 rov1 rov2 EXP-1             rov3          |\n"
         "#   0 +-----------------------------------------------------------+ 60 x (m)\n"
         "#\n"
         "# Units are in the field names (_m metres, _s seconds, _mps metres per second); see\n"
         "# scenarios/two_xt.yaml for every field explained. Flowlines: name, outer diameter, axis.\n";
}

}  // namespace

SeabedExample GenerateSeabedExample(std::uint64_t seed, const std::string& name) {
  detail::SplitMix64 rng(seed);
  Terrain terrain{};
  terrain.wave_angle[0] = rng.Range(0.2, 0.5);
  terrain.wave_angle[1] = rng.Range(1.0, 1.4);
  terrain.wave_phase[0] = rng.Range(0.0, 2.0 * std::numbers::pi);
  terrain.wave_phase[1] = rng.Range(0.0, 2.0 * std::numbers::pi);
  terrain.ridge_phase = rng.Range(0.0, 2.0 * std::numbers::pi);

  Scenario s;
  s.name = name;
  s.workspace = {kWidth_m, kHeight_m};
  s.duration_s = 600.0;
  s.visit_radius_m = 0.5;
  s.rearm_radius_m = 0.8;
  s.seed = seed;
  s.start_jitter_m = 0.3;
  s.ergodic.basis_order = 32;
  s.ergodic.forgetting_time_s = 120.0;
  s.ergodic.min_turn_radius_m = 0.5;
  s.guard.weight_floor = 0.02;
  s.guard.revisit_bound_s = 240.0;
  s.astar.grid_resolution_m = 0.1;
  s.astar.clearance_m = 0.5;
  s.astar.wait_per_lap_s = 4.0;

  const std::vector<StructurePlan> plans = {
      {"MANIFOLD", {30.0, 20.0}, {6.0, 4.0}, 3.0, {{"MF-N", 2}, {"MF-S", 0}}},
      {"XT-A", {15.0, 9.0}, {3.5, 3.5}, 3.0, {{"A-W", 3}, {"A-S", 0}, {"A-N", 2}}},
      {"XT-B", {45.0, 9.0}, {3.5, 3.5}, 3.0, {{"B-S", 0}, {"B-E", 1}}},
      {"XT-C", {15.0, 31.0}, {3.5, 3.5}, 3.0, {{"C-W", 3}, {"C-N", 2}, {"C-S", 0}}},
      {"XT-D", {45.0, 31.0}, {3.5, 3.5}, 3.0, {{"D-N", 2}, {"D-E", 1}}},
  };
  for (const StructurePlan& plan : plans) {
    ChristmasTree tree;
    tree.name = plan.name;
    tree.center_m = plan.center;
    tree.size_m = plan.size;
    tree.height_m = plan.height;
    for (const auto& [valve_name, face] : plan.valves) {
      Valve valve;
      valve.name = valve_name;
      valve.position_m = OffFace(plan, face);
      valve.covariance_m2 = 0.25 * Eigen::Matrix2d::Identity();  // sigma 0.5 m
      tree.valves.push_back(valve);
    }
    s.structures.push_back(tree);
  }
  // Jumpers from each XT's face towards the manifold (with a dog-leg, as spools are laid), the
  // export line to the south edge, the umbilical from the north edge.
  const auto flowline = [&](const char* flowline_name, double diameter, std::vector<Eigen::Vector2d> points) {
    Flowline f;
    f.name = flowline_name;
    f.diameter_m = diameter;
    f.points_m = std::move(points);
    s.flowlines.push_back(f);
  };
  flowline("FL-A", 0.25, {{16.75, 9.0}, {21.0, 9.0}, {24.0, 15.0}, {24.0, 19.2}, {27.0, 19.2}});
  flowline("FL-B", 0.25, {{43.25, 9.0}, {39.0, 9.0}, {36.0, 15.0}, {36.0, 19.2}, {33.0, 19.2}});
  flowline("FL-C", 0.25, {{16.75, 31.0}, {21.0, 31.0}, {24.0, 25.0}, {24.0, 20.8}, {27.0, 20.8}});
  flowline("FL-D", 0.25, {{43.25, 31.0}, {39.0, 31.0}, {36.0, 25.0}, {36.0, 20.8}, {33.0, 20.8}});
  flowline("EXP-1", 0.4, {{31.5, 18.0}, {31.5, 12.0}, {33.0, 4.0}, {36.0, 0.0}});
  flowline("UMB-1", 0.15, {{28.5, 22.0}, {28.5, 30.0}, {25.0, 38.0}, {24.0, 40.0}});

  const auto vehicle = [&](const char* vehicle_name, Eigen::Vector2d start, double heading, double speed) {
    VehicleSpec v;
    v.name = vehicle_name;
    v.start_m = start;
    v.start_heading_rad = heading;
    v.model = MotionModel::kBlueRov2;
    v.transit_speed_mps = speed;
    s.vehicles.push_back(v);
  };
  vehicle("rov1", {24.0, 2.5}, 1.5708, 0.7);
  vehicle("rov2", {29.0, 2.5}, 1.5708, 0.75);
  vehicle("rov3", {41.0, 3.0}, 1.5708, 0.7);

  // Boulders: a field along the ridge and more scattered over the cluster, each clear of the
  // structures (1.5 m), the valves (2 m), the flowlines (1 m), the starts (3 m) and each other.
  const auto clear = [&](const Eigen::Vector2d& c, double radius) {
    if (c.x() < radius + 0.5 || c.y() < radius + 0.5 || c.x() > kWidth_m - radius - 0.5 ||
        c.y() > kHeight_m - radius - 0.5) {
      return false;
    }
    for (const ChristmasTree& tree : s.structures) {
      if (((c - tree.center_m).cwiseAbs() - tree.size_m / 2).cwiseMax(0.0).norm() < radius + 1.5) return false;
      for (const Valve& valve : tree.valves) {
        if ((c - valve.position_m).norm() < radius + 2.0) return false;
      }
    }
    for (const Flowline& f : s.flowlines) {
      if (DistanceToAxis(f.points_m, c) < radius + f.diameter_m / 2 + 1.0) return false;
    }
    for (const VehicleSpec& v : s.vehicles) {
      if ((c - v.start_m).norm() < radius + 3.0) return false;
    }
    for (const Boulder& b : s.boulders) {
      if ((c - b.center_m).norm() < radius + b.diameter_m / 2 + 0.3) return false;
    }
    return true;
  };
  while (static_cast<int>(s.boulders.size()) < kBoulders) {
    const bool by_ridge = static_cast<int>(s.boulders.size()) < kBouldersByRidge;
    Eigen::Vector2d c;
    if (by_ridge) {
      const double t = rng.Unit();
      const double side = rng.Range(-6.0, 6.0);
      const Eigen::Vector2d d = (kRidgeTo - kRidgeFrom).normalized();
      c = kRidgeFrom + t * (kRidgeTo - kRidgeFrom) + side * Eigen::Vector2d(-d.y(), d.x());
    } else {
      c = rng.InBox(0.0, 0.0, kWidth_m, kHeight_m);
    }
    Boulder b;
    b.center_m = Eigen::Vector2d(Rounded(c.x(), 100), Rounded(c.y(), 100));
    b.diameter_m = Rounded(rng.Range(0.5, 2.2), 100);
    const double aspect = rng.Range(0.45, 0.75);
    b.height_m = Rounded(b.diameter_m * aspect, 100);
    if (DistanceToAxis({kRidgeFrom, kRidgeTo}, b.center_m) < 1.8 + b.diameter_m / 2) {
      continue;  // not on the ridge's crest itself
    }
    if (clear(b.center_m, b.diameter_m / 2)) s.boulders.push_back(b);
  }

  SeabedSettings seabed;
  seabed.map = name + ".xyz";
  seabed.origin_m = Eigen::Vector2d(kMapEasting_m + kMapMargin_m, kMapNorthing_m + kMapMargin_m);
  seabed.values = SeabedValues::kDepth;
  seabed.altitude_min_m = 0.8;
  seabed.altitude_max_m = 2.0;
  seabed.trend_radius_m = 3.0;
  s.seabed = seabed;

  // Risk: graded (log-normal, median 1, capped at 5), equal, and a leak at a drawn valve at 300 s.
  const std::vector<Valve> valves = s.AllValves();
  RiskProfile graded{"graded", {}, {}}, equal{"equal", {}, {}};
  for (const Valve& valve : valves) {
    const double normal = rng.Normal();
    graded.weights[valve.name] = Rounded(std::min(5.0, std::exp(0.6 * normal)), 100);
    equal.weights[valve.name] = 1.0;
  }
  RiskProfile leak = graded;
  leak.name = "leak";
  const int leaking = rng.Below(static_cast<int>(valves.size()));
  leak.events.push_back({300.0, valves[static_cast<std::size_t>(leaking)].name, 12.0});
  s.profiles = {graded, equal, leak};
  s.default_profile = "graded";
  s.Validate();

  // The bathymetry, north row first (as a raster), each row west to east: GDAL's gridded XYZ.
  const int cols = static_cast<int>(std::lround((kWidth_m + 2 * kMapMargin_m) / kNode_m));
  const int rows = static_cast<int>(std::lround((kHeight_m + 2 * kMapMargin_m) / kNode_m));
  std::string xyz = "easting northing depth\n";
  xyz.reserve(static_cast<std::size_t>(cols) * rows * 30);
  char line[96];
  for (int row = rows - 1; row >= 0; --row) {
    const double y = -kMapMargin_m + (row + 0.5) * kNode_m;
    for (int col = 0; col < cols; ++col) {
      const double x = -kMapMargin_m + (col + 0.5) * kNode_m;
      const double depth = -terrain.Elevation(x, y);
      std::snprintf(line, sizeof line, "%.2f %.2f %.3f\n", kMapEasting_m + kMapMargin_m + x,
                    kMapNorthing_m + kMapMargin_m + y, depth);
      xyz += line;
    }
  }
  return {s, Header(name, seed) + EmitScenario(s), xyz};
}

}  // namespace sage::maps
