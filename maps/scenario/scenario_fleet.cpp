// WithVehicleCount: a scenario resized to a chosen fleet, new vehicles placed at free starts.
#include "maps/scenario/scenario.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>

#include "maps/scenario/scenario_detail.h"

namespace sage::maps {
namespace {

using detail::FormatNumber;
using detail::InsideBox;

// Starts added by WithVehicleCount keep clear of footprints and of each other: a BlueROV2 hull is
// 0.46 x 0.58 m (0.74 m across), so 1 m between starts leaves two hulls apart whatever headings.
constexpr double kStartEdgeMargin_m = 0.5;       // from the workspace edges
constexpr double kStartFootprintMargin_m = 0.5;  // added to each side of every footprint
constexpr double kStartSeparation_m = 1.0;       // from every other start, joiners' included
constexpr double kDenseStartSeparation_m = 0.8;  // large fleets, when 1.0 m does not fit
// single_integrator vehicles are the paper's points (kinematic bodies that pass through each
// other): they need no hull's room, only to start apart.
constexpr double kPointStartSeparation_m = 0.3;
constexpr double kDensePointStartSeparation_m = 0.2;
constexpr std::size_t kLineStartsMax = 50;       // more added vehicles than this fill a lattice
constexpr double kStartSearchStep_m = 0.05;      // grid step of the search for a free start

std::uint64_t Fnv1a(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

// What an added start keeps from each side of every footprint: kStartFootprintMargin_m, and at
// least what a scenario's own starts keep (StartFootprintReach: the start jitter and the hull), a
// millimetre more so that no rounding in Validate's distance finds it a hair short.
double StartFootprintMargin(const Scenario& s) {
  const bool hull = s.vehicles.empty() || s.vehicles.front().model == MotionModel::kBlueRov2;
  return std::max(kStartFootprintMargin_m, StartFootprintReach(s.start_jitter_m, hull) + 1e-3);
}

bool IsFreeStart(const Scenario& s, const std::vector<Eigen::Vector2d>& taken, const Eigen::Vector2d& p,
                 double separation_m) {
  const double margin = StartFootprintMargin(s);
  for (const ChristmasTree& tree : s.structures) {
    const Eigen::Vector2d half = tree.size_m / 2 + Eigen::Vector2d::Constant(margin);
    if (((p - tree.center_m).array().abs() < half.array()).all()) return false;
  }
  for (const Eigen::Vector2d& other : taken) {
    if ((p - other).norm() < separation_m) return false;
  }
  return true;
}

// Of the points wanted + kStartSearchStep_m * (i, j), to the mm, inside the workspace less its edge
// margin, the free one nearest to `wanted` (ties: the first found). Rings of growing Chebyshev
// radius are searched until no point of a further ring can be nearer than the best so far.
std::optional<Eigen::Vector2d> NearestFreeStart(const Scenario& s, const std::vector<Eigen::Vector2d>& taken,
                                                const Eigen::Vector2d& wanted, double separation_m) {
  const Eigen::Vector2d size(s.workspace.width_m, s.workspace.height_m);
  const Eigen::Vector2d margin = (size / 2).cwiseMin(Eigen::Vector2d::Constant(kStartEdgeMargin_m));
  // A hair of tolerance so that the wanted point on the margin line itself counts as inside.
  const Eigen::Vector2d low = margin.array() - 1e-9, high = (size - margin).array() + 1e-9;
  const int last_ring = static_cast<int>(std::ceil(size.maxCoeff() / kStartSearchStep_m)) + 1;
  std::optional<Eigen::Vector2d> best;
  double best_distance = std::numeric_limits<double>::infinity();
  const auto consider = [&](int i, int j) {
    // Whole millimetres, so a written scenario reads cleanly; the rules are checked on this value.
    const Eigen::Vector2d p =
        ((wanted + kStartSearchStep_m * Eigen::Vector2d(i, j)) * 1000.0).array().round().matrix() / 1000.0;
    const double distance = (p - wanted).norm();
    if (distance >= best_distance || !InsideBox(p, low, high)) return;
    if (!IsFreeStart(s, taken, p, separation_m)) return;
    best = p;
    best_distance = distance;
  };
  for (int ring = 0; ring <= last_ring && ring * kStartSearchStep_m <= best_distance; ++ring) {
    if (ring == 0) {
      consider(0, 0);
      continue;
    }
    for (int i = -ring; i <= ring; ++i) {
      consider(i, -ring);
      consider(i, ring);
    }
    for (int j = -ring + 1; j < ring; ++j) {
      consider(-ring, j);
      consider(ring, j);
    }
  }
  return best;
}

}  // namespace

Scenario WithVehicleCount(const Scenario& scenario, int count) {
  const std::string option = "--vehicles = " + std::to_string(count);
  if (count < 1) throw ScenarioError(option + ": must be >= 1");
  Scenario s = scenario;
  const std::size_t wanted = static_cast<std::size_t>(count);
  if (wanted <= s.vehicles.size()) {
    std::set<std::string> dropped;
    for (std::size_t i = wanted; i < s.vehicles.size(); ++i) dropped.insert(s.vehicles[i].name);
    s.vehicles.resize(wanted);
    std::erase_if(s.fleet_events, [&](const FleetEvent& event) {
      return event.kind != FleetEvent::Kind::kJoin && dropped.count(event.vehicle.name) != 0;
    });
  } else {
    const VehicleSpec first = s.vehicles.empty() ? VehicleSpec() : s.vehicles.front();
    const bool points = first.model == MotionModel::kSingleIntegrator;
    const double separation = points ? kPointStartSeparation_m : kStartSeparation_m;
    const double dense_separation = points ? kDensePointStartSeparation_m : kDenseStartSeparation_m;
    std::set<std::string> used;
    std::vector<Eigen::Vector2d> taken;
    for (const VehicleSpec& vehicle : s.vehicles) {
      used.insert(vehicle.name);
      taken.push_back(vehicle.start_m);
    }
    for (const FleetEvent& event : s.fleet_events) {
      if (event.kind != FleetEvent::Kind::kJoin) continue;
      used.insert(event.vehicle.name);
      taken.push_back(event.vehicle.start_m);
    }
    const std::size_t added = wanted - s.vehicles.size();
    const double width = s.workspace.width_m;
    const double y = std::min(kStartEdgeMargin_m, s.workspace.height_m / 2);
    std::size_t number = s.vehicles.size() + 1;
    auto make_vehicle = [&](const Eigen::Vector2d& start) {
      VehicleSpec vehicle;
      while (used.count("rov" + std::to_string(number)) != 0) ++number;
      vehicle.name = "rov" + std::to_string(number);
      used.insert(vehicle.name);
      vehicle.model = first.model;
      vehicle.transit_speed_mps = first.transit_speed_mps;
      vehicle.start_heading_rad = 0.0;
      vehicle.start_m = start;
      taken.push_back(start);
      s.vehicles.push_back(vehicle);
    };
    // `count` vehicles along the bottom edge, evenly from x = 0.5 to width - 0.5, each moved to the
    // nearest free point 1 m from the others; nothing where one finds none.
    const auto on_a_line = [&](std::size_t count) -> std::optional<std::vector<Eigen::Vector2d>> {
      std::vector<Eigen::Vector2d> starts, near = taken;
      for (std::size_t k = 0; k < count; ++k) {
        const double x = (count == 1 || width <= 2 * kStartEdgeMargin_m)
                             ? width / 2
                             : kStartEdgeMargin_m + (width - 2 * kStartEdgeMargin_m) * static_cast<double>(k) /
                                                        static_cast<double>(count - 1);
        const std::optional<Eigen::Vector2d> start = NearestFreeStart(s, near, Eigen::Vector2d(x, y), separation);
        if (!start) return std::nullopt;
        starts.push_back(*start);
        near.push_back(*start);
      }
      return starts;
    };
    std::optional<std::vector<Eigen::Vector2d>> line;
    if (added <= kLineStartsMax) line = on_a_line(added);
    if (line) {
      for (const Eigen::Vector2d& start : *line) make_vehicle(start);
    }
    // Many vehicles (scale runs), or a few the line has no room for: the lattice, which also says
    // how many the workspace holds (the line had refused 15 vehicles on two_xt, flown 16, and the
    // lattice's limit said 15).
    if (!line) {
      // Fill a lattice row by row from the bottom edge, 1.0 m apart, or 0.8 m (still clear of a
      // 0.73 m hull diagonal) if that is the only way to fit them.
      const std::size_t existing = taken.size();
      std::size_t dense_room = 0;  // free lattice points at the dense spacing (all of them when too few)
      // Each lattice point is checked against the structures and the starts near it, not all of
      // them: the 10,000-XT field's 1.25 million points against 10,000 of each had taken 187 s to
      // refuse 99,999 vehicles. The same points are free as with every one checked.
      const double footprint_margin = StartFootprintMargin(s);
      double reach_m = separation;
      for (const ChristmasTree& tree : s.structures) {
        reach_m = std::max(reach_m, (tree.size_m / 2 + Eigen::Vector2d::Constant(footprint_margin)).norm());
      }
      detail::Buckets near_structures(reach_m), near_starts(separation);  // separation >= either spacing
      for (std::size_t i = 0; i < s.structures.size(); ++i) near_structures.Add(s.structures[i].center_m, static_cast<int>(i));
      for (std::size_t i = 0; i < existing; ++i) near_starts.Add(taken[i], static_cast<int>(i));
      for (double spacing : {separation, dense_separation}) {
        std::vector<Eigen::Vector2d> lattice;
        for (double y = kStartEdgeMargin_m; y <= s.workspace.height_m - kStartEdgeMargin_m && lattice.size() < added;
             y += spacing) {
          for (double x = kStartEdgeMargin_m; x <= width - kStartEdgeMargin_m && lattice.size() < added; x += spacing) {
            const Eigen::Vector2d p(x, y);
            const bool on_structure = near_structures.Any(p, [&](int i) {
              const ChristmasTree& tree = s.structures[static_cast<std::size_t>(i)];
              const Eigen::Vector2d half = tree.size_m / 2 + Eigen::Vector2d::Constant(footprint_margin);
              return ((p - tree.center_m).cwiseAbs() - half).maxCoeff() < 0.0;
            });
            const bool free = !on_structure && !near_starts.Any(p, [&](int i) {
              return (p - taken[static_cast<std::size_t>(i)]).norm() < spacing;
            });
            if (free) lattice.push_back(p);
          }
        }
        if (spacing == dense_separation) dense_room = lattice.size();
        if (lattice.size() < added) continue;
        for (const Eigen::Vector2d& p : lattice) make_vehicle(p);
        break;
      }
      if (s.vehicles.size() < wanted) {
        // At most what the lattice holds, and what the workspace's area holds (Validate's rule:
        // an area per vehicle), joins included.
        const auto area_of = [](const VehicleSpec& v) {
          return v.model == MotionModel::kBlueRov2 ? kMinAreaPerBlueRov2_m2 : kMinAreaPerPointVehicle_m2;
        };
        double used_m2 = 0.0;
        std::size_t joins = 0;
        for (const VehicleSpec& v : s.vehicles) used_m2 += area_of(v);
        for (const FleetEvent& e : s.fleet_events) {
          if (e.kind != FleetEvent::Kind::kJoin) continue;
          used_m2 += area_of(e.vehicle);
          ++joins;
        }
        const double free_m2 = s.workspace.width_m * s.workspace.height_m * (1.0 + 1e-12) - used_m2;
        const std::size_t by_area = free_m2 > 0.0 ? static_cast<std::size_t>(std::floor(free_m2 / area_of(first))) : 0;
        // The joins are named: a running mission's limit (sage vehicle add) counts them in its fleet.
        const std::string besides = joins == 0 ? std::string()
                                               : " at the start, besides the " + std::to_string(joins) +
                                                     (joins == 1 ? " that joins later" : " that join later");
        // As many as a line of fewer holds, if that is more (a small workspace: a trial per count).
        std::size_t room = std::min(dense_room, by_area);
        double room_spacing = dense_separation;
        if (room < kLineStartsMax) {
          for (std::size_t fewer = std::min(added - 1, kLineStartsMax); fewer > room; --fewer) {
            if (on_a_line(fewer)) {
              room = std::min(fewer, by_area);
              room_spacing = separation;
              break;
            }
          }
        }
        throw ScenarioError(option + ": the workspace has room for at most " +
                            std::to_string(s.vehicles.size() + room) + " vehicles" + besides +
                            " (starts " +
                            FormatNumber(room_spacing) + " m apart and " +
                            FormatNumber(std::round(StartFootprintMargin(s) * 100.0) / 100.0) + " m from structures, " +
                            FormatNumber(area_of(first)) + " m^2 of workspace each)");
      }
    }
  }
  // Dropping vehicles can make a kept vehicle's loss leave the fleet empty; say which option did it.
  try {
    s.Validate();
  } catch (const ScenarioError& e) {
    throw ScenarioError(std::string(e.what()) + " (with " + option + ")");
  }
  return s;
}

std::uint64_t VehicleFingerprint(const Scenario& scenario) {
  Scenario vehicles_only = scenario;
  vehicles_only.name.clear();
  vehicles_only.source_path.clear();
  vehicles_only.duration_s = 1.0;
  vehicles_only.profiles = {RiskProfile{"any", {}, {}}};
  vehicles_only.default_profile = "any";
  vehicles_only.guard = StarvationGuard{};
  vehicles_only.astar = AstarSettings{};
  vehicles_only.fleet.assignment = FleetAssignment::kShared;
  vehicles_only.fleet_events.clear();
  // The seabed map by its content, not its path: two processes reading the same map from
  // different folders fly the same world, and the same path holding another map does not.
  if (vehicles_only.seabed && !vehicles_only.seabed->map.empty()) {
    vehicles_only.seabed->map = "fnv1a-" + std::to_string(vehicles_only.seabed->map_fnv1a) + ".bt";
  }
  vehicles_only.network = {};  // each machine has its own
  vehicles_only.fusion = FusionSettings{};  // the server's alone (the sensors and the leaks are the vehicles' world)
  vehicles_only.trajectory_rate_hz = 0.0;   // what the server records, not how anything flies
  return Fnv1a(EmitScenario(vehicles_only));
}

std::uint64_t ScenarioHash(const Scenario& scenario) {
  // The network is each machine's own; the seabed map counts by its content (hashed at the door),
  // not by where it lies: a run directory keeps its own copy, and may be moved before a resume.
  Scenario same = scenario;
  same.network = {};
  if (same.seabed && !same.seabed->map.empty()) {
    same.seabed->map = "fnv1a-" + std::to_string(same.seabed->map_fnv1a) + ".bt";
  }
  return Fnv1a(EmitScenario(same));
}

}  // namespace sage::maps
