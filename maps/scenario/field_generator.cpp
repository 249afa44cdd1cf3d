// GenerateField (see field_generator.h): counts -> field size -> XTs and their valves ->
// clusters placed -> risk -> vehicle starts -> settings. Every draw comes from one SplitMix64
// stream, one draw per statement (argument order is unspecified in C++), and none from
// std::*_distribution, whose output differs between standard libraries: a seed gives the same
// YAML with any compiler (up to libm's last bit in cos/exp/log, which rounding lengths to
// centimetres or millimetres almost always absorbs).
#include "maps/scenario/field_generator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "maps/scenario/scenario_detail.h"
#include "maps/scenario/split_mix.h"

namespace sage::maps {
namespace {

using detail::FormatNumber;

constexpr double kAspect = 1.5;             // width : height of the field
constexpr double kGrowth = 1.1;             // a side's growth when the clusters do not fit
constexpr double kEdgeMargin_m = 1.0;       // valves to the workspace edges
constexpr double kManifoldRadius_m = 2.5;   // XTs of a 4+ cluster keep this far from its manifold
constexpr double kFaceInset_m = 0.1;        // a lone valve keeps this far from its face's ends
constexpr double kPairHalfSpacing_m = 0.4;  // two valves on one face: >= 0.8 m apart
constexpr double kStartEdge_m = 1.0;        // starts to the workspace edges (0.5 m after jitter)
constexpr double kMaxRoutineWeight = 5;     // graded weights short of a leak (10-20)
constexpr double kBasisHalfWave_m = 1.25;   // SMC detail aimed at (fleet_large: 49.4 m / 39)
constexpr int kMinBasisOrder = 20, kMaxBasisOrder = 64;
constexpr std::array<double, 4> kGridSteps_m = {0.05, 0.1, 0.2, 0.25};
constexpr double kGridCellBudget = 200000;  // fleet_field (0.05 m) and fleet_large (0.1 m) fit it

constexpr int kPlacementRounds = 4, kClusterTries = 3000, kCellTries = 40, kFieldTries = 20000;
// Cluster sizes: satellite wells, 2-4 slot templates, 6- and 8-slot manifolds (relative odds).
constexpr std::array<int, 6> kClusterSizes = {1, 2, 3, 4, 6, 8};
constexpr std::array<int, 6> kClusterOdds = {2, 1, 2, 4, 3, 2};
constexpr int kClusterOddsTotal = std::accumulate(kClusterOdds.begin(), kClusterOdds.end(), 0);

using Rng = detail::SplitMix64;

// x to the nearest 1/per_metre: k / 100.0 is the double nearest the decimal, so YAML reads clean.
double Snap(double x, double per_metre) { return std::round(x * per_metre) / per_metre; }
Eigen::Vector2d Snap(const Eigen::Vector2d& p, double per_metre) { return (p * per_metre).array().round() / per_metre; }

// Euclidean distance between two footprints (m); 0 where they touch or overlap.
double FootprintGap(const Eigen::Vector2d& ca, const Eigen::Vector2d& sa, const Eigen::Vector2d& cb,
                    const Eigen::Vector2d& sb) {
  return ((ca - cb).cwiseAbs() - (sa + sb) / 2).cwiseMax(0.0).norm();
}

// A valve's place on its XT. Faces 0-3 are south, east, north and west: face f looks along
// axis 1 - f % 2, towards + for east and north.
struct ValveSlot {
  int face;
  double offset_m;  // along the face from its middle, within the face
};
int NormalAxis(int face) { return 1 - face % 2; }

Eigen::Vector2d SlotPosition(const Eigen::Vector2d& center, const Eigen::Vector2d& size, const ValveSlot& slot) {
  const int normal = NormalAxis(slot.face);
  Eigen::Vector2d p = center;
  p[normal] += (slot.face == 1 || slot.face == 2 ? 1 : -1) * (size[normal] / 2 + kFieldValveStandoff_m);
  p[1 - normal] += slot.offset_m;
  return p;
}

// An XT relative to its cluster's point, before the cluster is placed.
struct XtPlan {
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero(), size_m;
  double height_m;
  std::vector<ValveSlot> slots;
};

struct ClusterPlan {
  std::vector<XtPlan> xts;
  double envelope_m = 0;  // radius around the cluster's point holding its footprints and valves
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
};

// One XT with `count` valves on distinct faces; for 5 the fifth shares a face >= 0.8 m long.
// Valves on adjacent faces are >= 0.8 * sqrt(2) m apart, as each lies within its face's span.
XtPlan PlanXt(Rng& rng, int count) {
  XtPlan xt;
  xt.size_m.x() = Snap(0.5 + 0.1 * rng.Below(11), 10);
  xt.size_m.y() = Snap(0.5 + 0.1 * rng.Below(11), 10);
  xt.height_m = Snap(2.0 + 0.1 * rng.Below(11), 10);
  std::array<int, 4> faces = {0, 1, 2, 3};
  for (int i = 3; i > 0; --i) std::swap(faces[i], faces[rng.Below(i + 1)]);
  for (int k = 0; k < std::min(count, 4); ++k) {
    const double reach = xt.size_m[1 - NormalAxis(faces[k])] / 2 - kFaceInset_m;
    xt.slots.push_back({faces[k], Snap(rng.Range(-reach, reach), 20)});
  }
  if (count == 5) {
    double& length = xt.size_m[1 - NormalAxis(faces[0])];
    length = std::max(length, 2 * kPairHalfSpacing_m);
    const double far = std::max(kPairHalfSpacing_m, length / 2 - kFaceInset_m);
    const double d = std::max(kPairHalfSpacing_m, Snap(rng.Range(kPairHalfSpacing_m, far), 20));
    xt.slots[0].offset_m = -d;
    xt.slots.push_back({faces[0], d});
  }
  return xt;
}

// XTs at random bearings around the cluster's point, each as near to it as kFieldXtGap_m of
// water to the XTs before allows (the reach widens after every 20 misses): compact clusters,
// unevenly filled. Four or more ring a manifold; fewer stand as a template or a satellite well.
// The cluster is then centred on what it holds, and its envelope measured.
void ArrangeCluster(Rng& rng, ClusterPlan& cluster) {
  std::vector<XtPlan>& xts = cluster.xts;
  const double inner = xts.size() >= 4 ? kManifoldRadius_m : 0.0;
  double reach = inner + 1;
  for (std::size_t i = 0; i < xts.size(); ++i) {
    for (int miss = 1;; ++miss) {
      const double bearing = rng.Range(0, 2 * std::numbers::pi);
      const double distance = rng.Range(inner, reach);
      // Offsets to the centimetre, as the cluster's point: an XT's centre needs no rounding.
      const Eigen::Vector2d p = Snap(distance * Eigen::Vector2d(std::cos(bearing), std::sin(bearing)), 100);
      bool clear = true;
      for (std::size_t j = 0; j < i && clear; ++j) {
        clear = FootprintGap(p, xts[i].size_m, xts[j].offset_m, xts[j].size_m) >= kFieldXtGap_m;
      }
      if (clear) {
        xts[i].offset_m = p;
        break;
      }
      if (miss % 20 == 0) reach += 0.5;
    }
  }
  Eigen::Vector2d low = Eigen::Vector2d::Constant(1e300), high = -low;
  for (const XtPlan& xt : xts) {
    low = low.cwiseMin(xt.offset_m - xt.size_m / 2);
    high = high.cwiseMax(xt.offset_m + xt.size_m / 2);
  }
  const Eigen::Vector2d middle = Snap((low + high) / 2, 100);  // of the footprints
  for (XtPlan& xt : xts) {
    xt.offset_m = Snap(xt.offset_m - middle, 100);
    double extent = xt.size_m.norm() / 2;
    for (const ValveSlot& slot : xt.slots) extent = std::max(extent, SlotPosition({0, 0}, xt.size_m, slot).norm());
    cluster.envelope_m = std::max(cluster.envelope_m, xt.offset_m.norm() + extent);
  }
}

// The XTs, each with 2 valves and the rest of the count on 3 spare slots per XT drawn at
// random (so any count in [2, 5] x XTs comes out exact), grouped into clusters.
std::vector<ClusterPlan> PlanClusters(Rng& rng, const FieldOptions& o) {
  std::vector<int> counts(static_cast<std::size_t>(o.xts), 2), spare(3 * counts.size());
  for (std::size_t i = 0; i < spare.size(); ++i) spare[i] = static_cast<int>(i / 3);
  for (int k = 0; k < o.valves - 2 * o.xts; ++k) {
    std::swap(spare[k], spare[k + rng.Below(static_cast<int>(spare.size()) - k)]);
    ++counts[spare[k]];
  }
  std::vector<ClusterPlan> clusters;
  for (int made = 0; made < o.xts;) {
    int pick = rng.Below(kClusterOddsTotal), kind = 0;
    while (pick >= kClusterOdds[kind]) pick -= kClusterOdds[kind++];
    // At most a third of the XTs in one cluster: a small field is not one manifold filling it.
    const int n = std::min({kClusterSizes[kind], std::max(1, o.xts / 3), o.xts - made});
    ClusterPlan& cluster = clusters.emplace_back();
    for (int i = 0; i < n; ++i) cluster.xts.push_back(PlanXt(rng, counts[made + i]));
    ArrangeCluster(rng, cluster);
    made += n;
  }
  return clusters;
}

// Cluster points by dart throwing, largest clusters first, a few rounds (in a small field a bad
// first throw can block the rest); false if some cluster found no room.
bool PlaceClusters(Rng& rng, std::vector<ClusterPlan>& clusters, const Workspace& field) {
  std::vector<ClusterPlan*> order;
  for (ClusterPlan& c : clusters) order.push_back(&c);
  std::stable_sort(order.begin(), order.end(), [](auto* a, auto* b) { return a->envelope_m > b->envelope_m; });
  for (int round = 0; round < kPlacementRounds; ++round) {
    detail::Buckets placed(2 * order.front()->envelope_m + kFieldClusterGap_m);
    bool all = true;
    for (std::size_t k = 0; k < order.size() && all; ++k) {
      ClusterPlan& c = *order[k];
      const double margin = c.envelope_m + kEdgeMargin_m;
      const auto too_near = [&](int other) {
        const ClusterPlan& o = *order[other];
        return (c.position_m - o.position_m).norm() < c.envelope_m + o.envelope_m + kFieldClusterGap_m;
      };
      all = 2 * margin <= std::min(field.width_m, field.height_m);
      for (int attempt = 0; all; ++attempt) {
        c.position_m = Snap(rng.InBox(margin, margin, field.width_m - 2 * margin, field.height_m - 2 * margin), 100);
        if (!placed.Any(c.position_m, too_near)) break;
        all = attempt < kClusterTries;
      }
      if (all) placed.Add(c.position_m, static_cast<int>(k));
    }
    if (all) return true;
  }
  return false;
}

// A kAspect : 1 field of area_m2, each side times `scale`, to the decimetre up.
Workspace SizeFor(double area_m2, double scale) {
  const double width = std::ceil(std::sqrt(area_m2 * kAspect) * scale * 10) / 10;
  return {width, std::ceil(area_m2 / width * scale * scale * 10) / 10};
}

// The finest A* grid (and OctoMap voxel) with at most kGridCellBudget cells over the field.
double GridStepFor(const Workspace& field) {
  for (double step : kGridSteps_m) {
    if (field.width_m * field.height_m / (step * step) <= kGridCellBudget) return step;
  }
  return kGridSteps_m.back();
}

void CheckOptions(const FieldOptions& o) {
  const auto fail = [](const std::string& option, const std::string& value, const std::string& rule) {
    throw ScenarioError(option + " = " + value + ": " + rule);
  };
  // Five times the largest fleet sage bench scale measures; a field of 50,000 XTs and 50,000
  // vehicles is ~37 MB of YAML, within what a scenario may be (kMaxScenarioBytes; a million
  // vehicles had been written as 116 MB that no command could load).
  constexpr int kMostCount = 50000;
  const std::string counts = "must be in 1.." + std::to_string(kMostCount);
  if (o.xts < 1 || o.xts > kMostCount) fail("--xts", std::to_string(o.xts), counts);
  if (o.vehicles < 1 || o.vehicles > kMostCount) fail("--vehicles", std::to_string(o.vehicles), counts);
  const std::int64_t least = 2 * std::int64_t{o.xts}, most = 5 * std::int64_t{o.xts};
  if (o.valves < least || o.valves > most) {
    const std::string bound = o.valves < least ? ">= 2 x --xts = " + std::to_string(least)
                                               : "<= 5 x --xts = " + std::to_string(most);
    fail("--valves", std::to_string(o.valves), "must be " + bound + " (2 to 5 valves per XT)");
  }
  if (!(o.area_per_xt_m2 >= 50 && o.area_per_xt_m2 <= 10000)) {
    fail("--area-per-xt", FormatNumber(o.area_per_xt_m2), "must be in [50, 10000] m^2 (XT clusters need room)");
  }
  // The loader's rule: a field written under a name it refuses could not be run.
  if (const std::string problem = o.name.empty() ? std::string() : detail::DirectoryNameProblem(o.name); !problem.empty()) {
    throw ScenarioError("--name = " + problem);
  }
}

// Refuses a field an OctoMap at its A* grid cannot span, naming the option that sized it.
void CheckSpan(const FieldOptions& o, const Workspace& field) {
  const double step = GridStepFor(field), span = kMaxOctoMapVoxels * step;
  if (std::max(field.width_m, field.height_m) <= span) return;
  const bool by_xts = o.xts * o.area_per_xt_m2 >= o.vehicles * kFieldAreaPerVehicle_m2;
  throw ScenarioError((by_xts ? "--xts = " + std::to_string(o.xts) : "--vehicles = " + std::to_string(o.vehicles)) +
                      ": the field would be " + FormatNumber(field.width_m) + " x " + FormatNumber(field.height_m) +
                      " m, wider than an OctoMap spans at a " + FormatNumber(step) + " m grid (" + FormatNumber(span) +
                      " m = 2^15 - 1 voxels)");
}

// prefix + number; "P" + std::to_string(n) inlined here trips a GCC 12 -Wrestrict false positive.
std::string Numbered(std::string prefix, int number) { return prefix.append(std::to_string(number)); }

// Structures named in reading order (20 m bands from south to north, west to east in a band).
void AddStructures(std::vector<ClusterPlan> clusters, int xts, Scenario& s) {
  std::stable_sort(clusters.begin(), clusters.end(), [](const ClusterPlan& a, const ClusterPlan& b) {
    return std::pair(std::floor(a.position_m.y() / 20), a.position_m.x()) <
           std::pair(std::floor(b.position_m.y() / 20), b.position_m.x());
  });
  const std::size_t digits = std::max<std::size_t>(2, std::to_string(xts).size());
  int valve_number = 0;
  for (const ClusterPlan& cluster : clusters) {
    for (const XtPlan& xt : cluster.xts) {
      const std::string number = std::to_string(s.structures.size() + 1);
      ChristmasTree& tree = s.structures.emplace_back();
      tree.name = std::string("XT-").append(digits - number.size(), '0') + number;
      tree.center_m = Snap(cluster.position_m + xt.offset_m, 100);
      tree.size_m = xt.size_m;
      tree.height_m = xt.height_m;
      for (const ValveSlot& slot : xt.slots) {
        const Eigen::Vector2d at = Snap(SlotPosition(tree.center_m, tree.size_m, slot), 1000);
        tree.valves.push_back({Numbered("P", ++valve_number), at,
                               kFieldValveSigma_m * kFieldValveSigma_m * Eigen::Matrix2d::Identity()});
      }
    }
  }
}

// `graded`: log-normal raw weights (median 1, 0.3 to 3.3 within two sigma, capped at 5 so a leak
// stands out among any number of valves) and 1-5 leaks at 10 to 20; `equal`: every valve alike.
void AddProfiles(Rng& rng, Scenario& s) {
  RiskProfile graded{"graded", {}, {}}, equal{"equal", {}, {}};
  const std::vector<Valve> valves = s.AllValves();
  for (const Valve& valve : valves) {
    graded.weights[valve.name] = std::clamp(Snap(std::exp(0.6 * rng.Normal()), 100), 0.05, kMaxRoutineWeight);
    equal.weights[valve.name] = 1.0;
  }
  const int count = static_cast<int>(valves.size());
  std::set<int> leaking;
  while (static_cast<int>(leaking.size()) < std::clamp(count / 20, 1, 5)) {
    const int i = rng.Below(count);
    if (leaking.insert(i).second) graded.weights[valves[i].name] = 10 + rng.Below(11);
  }
  s.profiles = {graded, equal};
  s.default_profile = "graded";
}

// Starts spread over the whole field: one in each of `count` cells, drawn at random, of a grid
// of about `count` cells (a cell under a cluster gives way to a point anywhere), each clear of
// footprints, valves and other starts.
std::vector<VehicleSpec> PlaceVehicles(Rng& rng, const Scenario& s, int count) {
  const double width = s.workspace.width_m, height = s.workspace.height_m;
  detail::Buckets xts(2.5), points(2.5);  // >= a query's reach: 1 m + a 1.5 m footprint's half diagonal
  std::vector<std::pair<Eigen::Vector2d, double>> kept;  // valves and starts, and how far to keep
  const auto keep = [&](const Eigen::Vector2d& p, double distance) {
    points.Add(p, static_cast<int>(kept.size()));
    kept.emplace_back(p, distance);
  };
  for (std::size_t i = 0; i < s.structures.size(); ++i) {
    xts.Add(s.structures[i].center_m, static_cast<int>(i));
    for (const Valve& v : s.structures[i].valves) keep(v.position_m, kFieldStartClearance_m);
  }
  const std::size_t first_start = kept.size();
  const Eigen::Vector2d low(kStartEdge_m, kStartEdge_m), high(width - kStartEdge_m, height - kStartEdge_m);
  const auto try_in = [&](double x0, double y0, double w, double h, int tries) {
    for (int t = 0; t < tries; ++t) {
      const Eigen::Vector2d p = Snap(rng.InBox(x0, y0, w, h), 100);
      const auto near_xt = [&](int i) {
        const ChristmasTree& x = s.structures[i];
        return FootprintGap(p, Eigen::Vector2d::Zero(), x.center_m, x.size_m) < kFieldStartClearance_m;
      };
      const auto near_point = [&](int i) { return (p - kept[i].first).norm() < kept[i].second; };
      if (!detail::InsideBox(p, low, high) || xts.Any(p, near_xt) || points.Any(p, near_point)) continue;
      keep(p, kFieldStartSeparation_m);
      return true;
    }
    return false;
  };
  const int cols = std::max(1, static_cast<int>(std::lround(std::sqrt(count * width / height))));
  const int rows = (count + cols - 1) / cols;
  std::vector<int> cells(static_cast<std::size_t>(cols * rows));
  for (std::size_t i = 0; i < cells.size(); ++i) cells[i] = static_cast<int>(i);
  for (int i = static_cast<int>(cells.size()) - 1; i > 0; --i) std::swap(cells[i], cells[rng.Below(i + 1)]);
  cells.resize(static_cast<std::size_t>(count));
  std::sort(cells.begin(), cells.end());  // rov1.. in reading order, south to north
  const double cw = width / cols, ch = height / rows;
  for (int c : cells) {
    if (!try_in((c % cols) * cw, (c / cols) * ch, cw, ch, kCellTries) && !try_in(0, 0, width, height, kFieldTries)) {
      throw ScenarioError("--vehicles = " + std::to_string(count) + ": no free start left in the " +
                          FormatNumber(width) + " x " + FormatNumber(height) + " m field");
    }
  }
  std::vector<VehicleSpec> vehicles;
  for (std::size_t k = first_start; k < kept.size(); ++k) {
    const double heading = Snap(rng.Range(-std::numbers::pi, std::numbers::pi), 100);
    vehicles.push_back({"rov" + std::to_string(vehicles.size() + 1), kept[k].first, heading, MotionModel::kBlueRov2,
                        Snap(0.7 + 0.05 * rng.Below(3), 100)});
  }
  return vehicles;
}

}  // namespace

FieldSensors ParseFieldSensors(const std::string& text, const std::string& option) {
  if (text == "none") return FieldSensors::kNone;
  if (text == "camera") return FieldSensors::kCamera;
  if (text == "camera+sonar") return FieldSensors::kCameraAndSonar;
  throw ScenarioError(option + " = " + text + ": must be none, camera or camera+sonar");
}

namespace {

// The shipped scenarios' sensors (two_xt_leaks' camera, fleet_field_leaks' camera and sonar), so
// that a generated field's detection times compare with theirs (a test holds them equal).
SensorSpec FieldSensor(SensorKind kind) {
  const bool camera = kind == SensorKind::kCamera;
  SensorSpec c;
  c.name = camera ? "camera" : "sonar";
  c.kind = kind;
  c.range_m = camera ? 1.2 : 4.0;
  c.fov_deg = camera ? 80.0 : 120.0;
  c.p_detect = camera ? 0.9 : 0.6;
  c.half_range_m = camera ? 0.7 : 2.0;
  c.false_alarms_per_s = camera ? 0.02 : 0.1;
  c.position_sigma_m = camera ? 0.08 : 0.2;
  c.rate_hz = camera ? 5.0 : 2.0;
  return c;
}

}  // namespace

int RecordEveryForFleet(int vehicles, double control_rate_hz) {
  const double rows_per_s = std::max(0, vehicles) * control_rate_hz;
  return std::max(1, static_cast<int>(std::ceil(rows_per_s / kFieldRecordRowsPerSecond)));
}

Scenario GenerateField(const FieldOptions& o) {
  CheckOptions(o);
  const double area = std::max(o.xts * o.area_per_xt_m2, o.vehicles * kFieldAreaPerVehicle_m2);
  Workspace field = SizeFor(area, 1.0);
  CheckSpan(o, field);
  Rng rng(o.seed);
  std::vector<ClusterPlan> clusters = PlanClusters(rng, o);
  for (int growths = 1; !PlaceClusters(rng, clusters, field); ++growths) {
    if (growths > kFieldMaxGrowths) {
      throw ScenarioError("--area-per-xt = " + FormatNumber(o.area_per_xt_m2) + ": the XT clusters do not fit in " +
                          FormatNumber(field.width_m) + " x " + FormatNumber(field.height_m) + " m; give more area");
    }
    field = SizeFor(area, std::pow(kGrowth, growths));
    CheckSpan(o, field);
  }

  Scenario s;
  const char* sensed = o.sensors == FieldSensors::kCamera ? "_camera" : o.sensors == FieldSensors::kCameraAndSonar ? "_camera_sonar" : "";
  s.name = !o.name.empty() ? o.name
                           : "field_" + std::to_string(o.xts) + "xt_" + std::to_string(o.valves) + "v_" +
                                 std::to_string(o.vehicles) + "rov_s" + std::to_string(o.seed) + sensed;
  s.workspace = field;
  AddStructures(std::move(clusters), o.xts, s);
  AddProfiles(rng, s);
  s.vehicles = PlaceVehicles(rng, s, o.vehicles);

  s.duration_s = 600;
  s.control_rate_hz = kFieldControlRate_hz;
  s.physics_rate_hz = 50;
  // trajectory.csv at most about 10,000 rows a mission second: every cycle up to 1,000 vehicles,
  // beyond that a vehicle's row every ceil(N / 1,000) cycles (1 Hz at 10,000: a minute's record
  // 88 MB instead of 880). The metrics count every cycle either way.
  const int every = RecordEveryForFleet(o.vehicles, s.control_rate_hz);
  s.trajectory_rate_hz = every > 1 ? s.control_rate_hz / every : 0.0;
  s.visit_radius_m = 0.3;
  s.rearm_radius_m = 0.45;
  s.seed = o.seed;
  const double longest = std::max(field.width_m, field.height_m), valves = o.valves, vehicles = o.vehicles;
  // Coverage forgotten after a minute, so a lost vehicle's valves are taken over soon; a 0.3 m
  // turning radius flies through a hot valve and loops back; the last 1.5 m to a valve the law
  // sends a vehicle by is flown straight (agents/final_approach.h: on seventeen generated fields
  // the regions' risk-weighted revisit interval went from 0.88-1.25x the tours' to 0.72-0.87x;
  // 1 m and 2 m did less, 2 m lengthening some longest gaps; README, fleet results).
  s.ergodic = {std::clamp(1 + static_cast<int>(std::ceil(longest / kBasisHalfWave_m)), kMinBasisOrder, kMaxBasisOrder),
               60.0, 0.3};
  s.ergodic.final_approach_m = 1.5;
  // A quarter of the risk on floors (as two_xt and fleet_field), two significant digits down;
  // fleet_field's 90 s revisit bound for its 5 valves per vehicle, longer for more.
  const double floor = 0.25 / valves, scale = std::pow(10.0, 1 - std::floor(std::log10(floor)));
  s.guard = {true, std::floor(floor * scale) / scale, std::clamp(std::round(18.0 * valves / vehicles), 90.0, 300.0)};
  s.astar = {GridStepFor(field), 0.3, 1.0};
  // About 500 coverage reports a second from the whole fleet: what the README's 1,000-vehicle
  // scale run (2 s each) put on the server. A fleet flies regions: on generated fields of 10 to
  // 100 vehicles their risk-weighted revisit interval is 4-9x shorter than one shared target's,
  // and they scale (README, fleet allocation).
  s.fleet = {o.vehicles > 1 ? FleetAssignment::kRegions : FleetAssignment::kShared,
             std::max(0.5, std::round(vehicles / 500 * 2) / 2), 0.5};
  // Sensors as the shipped leak scenarios carry them, turned to the valves in reach (two_xt_leaks'
  // gaze: the look planner prices its legs so); the fusion's defaults are theirs too.
  if (o.sensors != FieldSensors::kNone) {
    s.sensors.push_back(FieldSensor(SensorKind::kCamera));
    if (o.sensors == FieldSensors::kCameraAndSonar) s.sensors.push_back(FieldSensor(SensorKind::kSonar));
    s.gaze = Gaze::kValves;
  }
  return s;
}

}  // namespace sage::maps
