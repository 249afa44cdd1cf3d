// The seabed model's obstacles for Box2D and the checks on them (see seabed_obstacles.h).
#include "maps/seabed/seabed_obstacles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "maps/seabed_map.h"

namespace sage::maps {

OccupancyGrid TerrainObstacles(const OccupancyGrid& obstacles, const std::vector<ChristmasTree>& structures) {
  OccupancyGrid terrain = obstacles;
  const double r = obstacles.resolution_m();
  for (const ChristmasTree& structure : structures) {
    const Eigen::Vector2d lo = structure.center_m - structure.size_m / 2, hi = structure.center_m + structure.size_m / 2;
    const int i0 = std::max(0, static_cast<int>(std::floor(lo.x() / r - 0.5)) - 1);
    const int i1 = std::min(terrain.cols() - 1, static_cast<int>(std::ceil(hi.x() / r - 0.5)) + 1);
    const int j0 = std::max(0, static_cast<int>(std::floor(lo.y() / r - 0.5)) - 1);
    const int j1 = std::min(terrain.rows() - 1, static_cast<int>(std::ceil(hi.y() / r - 0.5)) + 1);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        const Eigen::Vector2d c = terrain.CenterOf({i, j});
        if ((c.array() >= lo.array()).all() && (c.array() <= hi.array()).all()) terrain.SetOccupied(i, j, false);
      }
    }
  }
  return terrain;
}

std::vector<CellRectangle> MergeIntoRectangles(const OccupancyGrid& grid) {
  const int cols = grid.cols(), rows = grid.rows();
  std::vector<unsigned char> taken(static_cast<std::size_t>(cols) * rows, 0);
  const auto free_to_take = [&](int i, int j) {
    return grid.InBounds(i, j) && grid.Occupied(i, j) && !taken[static_cast<std::size_t>(i) * rows + j];
  };
  const double r = grid.resolution_m();
  std::vector<CellRectangle> rectangles;
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) {
      if (!free_to_take(i, j)) continue;
      int j1 = j;
      while (free_to_take(i, j1 + 1)) ++j1;
      int i1 = i;
      const auto column_free = [&](int column) {
        for (int b = j; b <= j1; ++b) {
          if (!free_to_take(column, b)) return false;
        }
        return true;
      };
      while (column_free(i1 + 1)) ++i1;
      for (int a = i; a <= i1; ++a) {
        for (int b = j; b <= j1; ++b) taken[static_cast<std::size_t>(a) * rows + b] = 1;
      }
      rectangles.push_back({Eigen::Vector2d(i * r, j * r), Eigen::Vector2d((i1 + 1) * r, (j1 + 1) * r)});
    }
  }
  return rectangles;
}

void CheckOnOpenSeabed(const Scenario& scenario, const OccupancyGrid& terrain) {
  const std::string file = scenario.source_path.empty() ? "<scenario>" : scenario.source_path;
  const auto point = [](const Eigen::Vector2d& p) { return fmt::format("[{}, {}]", p.x(), p.y()); };
  const auto blocked = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2i cell = terrain.CellOf(p);
    return terrain.Occupied(cell.x(), cell.y());
  };
  for (std::size_t i = 0; i < scenario.structures.size(); ++i) {
    for (std::size_t j = 0; j < scenario.structures[i].valves.size(); ++j) {
      const Valve& valve = scenario.structures[i].valves[j];
      if (blocked(valve.position_m)) {
        throw ScenarioError(fmt::format("{}: structures[{}].valves[{}].position_m = {}: {} lies on blocked seabed (the "
                                        "terrain, a boulder or a flowline rises into the vehicles' altitude band there)",
                                        file, i, j, point(valve.position_m), valve.name));
      }
    }
  }
  const double reach = scenario.start_jitter_m + kVehicleClearance_m;
  const auto check_start = [&](const std::string& field, const VehicleSpec& vehicle) {
    if (StartIsClear(terrain, vehicle.start_m, scenario.start_jitter_m)) return;
    throw ScenarioError(fmt::format("{}: {}.start_m = {}: {} starts within {} m (start jitter and hull) of blocked seabed",
                                    file, field, point(vehicle.start_m), vehicle.name, std::round(reach * 1000.0) / 1000.0));
  };
  for (std::size_t i = 0; i < scenario.vehicles.size(); ++i) check_start(fmt::format("vehicles[{}]", i), scenario.vehicles[i]);
  for (std::size_t i = 0; i < scenario.fleet_events.size(); ++i) {
    if (scenario.fleet_events[i].kind == FleetEvent::Kind::kJoin) {
      check_start(fmt::format("fleet_events[{}].join", i), scenario.fleet_events[i].vehicle);
    }
  }
}

void CheckValvesReachable(const Scenario& scenario, const OccupancyGrid& blocked) {
  const int cols = blocked.cols(), rows = blocked.rows();
  const double r = blocked.resolution_m();
  const auto index = [&](int i, int j) { return static_cast<std::size_t>(j) * static_cast<std::size_t>(cols) + i; };
  // The free cells whose centre lies within `radius` of p.
  const auto free_near = [&](const Eigen::Vector2d& p, double radius, auto&& visit) {
    const Eigen::Vector2i lo = blocked.CellOf(p - Eigen::Vector2d::Constant(radius));
    const Eigen::Vector2i hi = blocked.CellOf(p + Eigen::Vector2d::Constant(radius));
    for (int j = lo.y(); j <= hi.y(); ++j) {
      for (int i = lo.x(); i <= hi.x(); ++i) {
        if (!blocked.Occupied(i, j) && (blocked.CenterOf({i, j}) - p).norm() <= radius) visit(i, j);
      }
    }
  };
  // Flood from every start over free cells side by side.
  std::vector<char> reached(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), 0);
  std::vector<Eigen::Vector2i> frontier;
  const auto seed = [&](int i, int j) {
    if (reached[index(i, j)]) return;
    reached[index(i, j)] = 1;
    frontier.emplace_back(i, j);
  };
  for (const VehicleSpec& v : scenario.vehicles) free_near(v.start_m, 0.5, seed);
  for (const FleetEvent& e : scenario.fleet_events)
    if (e.kind == FleetEvent::Kind::kJoin) free_near(e.vehicle.start_m, 0.5, seed);
  if (frontier.empty()) return;  // no start in open water: said by the starts' own checks
  while (!frontier.empty()) {
    const Eigen::Vector2i c = frontier.back();
    frontier.pop_back();
    for (const Eigen::Vector2i d : {Eigen::Vector2i(1, 0), Eigen::Vector2i(-1, 0), Eigen::Vector2i(0, 1), Eigen::Vector2i(0, -1)}) {
      const Eigen::Vector2i n = c + d;
      if (blocked.InBounds(n.x(), n.y()) && !blocked.Occupied(n.x(), n.y())) seed(n.x(), n.y());
    }
  }
  const std::string file = scenario.source_path.empty() ? "<scenario>" : scenario.source_path;
  for (std::size_t i = 0; i < scenario.structures.size(); ++i) {
    for (std::size_t j = 0; j < scenario.structures[i].valves.size(); ++j) {
      const Valve& valve = scenario.structures[i].valves[j];
      bool reachable = false;
      free_near(valve.position_m, scenario.visit_radius_m + r, [&](int a, int b) { reachable = reachable || reached[index(a, b)]; });
      if (reachable) continue;
      throw ScenarioError(fmt::format(
          "{}: structures[{}].valves[{}].position_m = [{}, {}]: no vehicle can reach {}: no way from any start to within "
          "its visit radius ({} m) keeps a hull ({} m) off the structures, boulders and blocked seabed",
          file, i, j, valve.position_m.x(), valve.position_m.y(), valve.name, scenario.visit_radius_m, kVehicleClearance_m));
    }
  }
}

bool StartIsClear(const OccupancyGrid& terrain, const Eigen::Vector2d& start, double jitter_m) {
  const double reach = jitter_m + kVehicleClearance_m, r = terrain.resolution_m();
  const Eigen::Vector2i lo = terrain.CellOf(start - Eigen::Vector2d::Constant(reach + r));
  const Eigen::Vector2i hi = terrain.CellOf(start + Eigen::Vector2d::Constant(reach + r));
  for (int i = lo.x(); i <= hi.x(); ++i) {
    for (int j = lo.y(); j <= hi.y(); ++j) {
      if (terrain.Occupied(i, j) && (terrain.CenterOf({i, j}) - start).norm() <= reach) return false;
    }
  }
  return true;
}

int MoveStartsOffBlockedSeabed(Scenario& scenario, std::size_t first) {
  if (!scenario.HasSeabedModel() || first >= scenario.vehicles.size()) return 0;
  const SeabedMap seabed(scenario, scenario.astar.grid_resolution_m);
  const OccupancyGrid terrain = TerrainObstacles(seabed.OperatingSlice(), scenario.structures);
  constexpr double kStep_m = 0.25, kEdge_m = 0.5, kFootprint_m = 0.5, kApart_m = 1.0;
  const Eigen::Vector2d box(scenario.workspace.width_m, scenario.workspace.height_m);
  const auto others_clear = [&](const Eigen::Vector2d& p, std::size_t self) {
    for (std::size_t k = 0; k < scenario.vehicles.size(); ++k) {
      if (k != self && (scenario.vehicles[k].start_m - p).norm() < kApart_m) return false;
    }
    for (const FleetEvent& e : scenario.fleet_events) {
      if (e.kind == FleetEvent::Kind::kJoin && (e.vehicle.start_m - p).norm() < kApart_m) return false;
    }
    return true;
  };
  const auto usable = [&](const Eigen::Vector2d& p, std::size_t self) {
    if ((p.array() < kEdge_m).any() || (p.array() > box.array() - kEdge_m).any()) return false;
    for (const ChristmasTree& t : scenario.structures) {
      if ((((p - t.center_m).cwiseAbs() - t.size_m / 2).array() < kFootprint_m).all()) return false;
    }
    return StartIsClear(terrain, p, scenario.start_jitter_m) && others_clear(p, self);
  };
  int moved = 0;
  for (std::size_t v = first; v < scenario.vehicles.size(); ++v) {
    VehicleSpec& vehicle = scenario.vehicles[v];
    if (StartIsClear(terrain, vehicle.start_m, scenario.start_jitter_m)) continue;
    // Rings of lattice points ever farther out (Chebyshev distance k steps), the nearest usable
    // point of the first ring that has one (ties: the first met).
    const int rings = static_cast<int>(std::ceil(box.maxCoeff() / kStep_m));
    bool found = false;
    for (int k = 1; k <= rings && !found; ++k) {
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector2d best_point = vehicle.start_m;
      for (int a = -k; a <= k; ++a) {
        for (int b = -k; b <= k; ++b) {
          if (std::max(std::abs(a), std::abs(b)) != k) continue;
          const Eigen::Vector2d p = vehicle.start_m + kStep_m * Eigen::Vector2d(a, b);
          const double d = (p - vehicle.start_m).norm();
          if (d < best && usable(p, v)) best = d, best_point = p;
        }
      }
      if (std::isfinite(best)) vehicle.start_m = best_point, found = true;
    }
    if (!found) {
      throw ScenarioError(fmt::format("{}: vehicles[{}].start_m: no clear seabed for {} in the workspace",
                                      scenario.source_path.empty() ? "<scenario>" : scenario.source_path, v,
                                      vehicle.name));
    }
    ++moved;
  }
  return moved;
}

void CheckMissionMaps(const Scenario& scenario) {
  if (!scenario.HasSeabedModel()) {
    // The flat seabed's obstacles are the footprints, each the cells whose centre it holds (as
    // the seabed map voxelises them), without building the OctoMap.
    OccupancyGrid footprints(scenario.workspace.width_m, scenario.workspace.height_m, scenario.astar.grid_resolution_m);
    for (const ChristmasTree& tree : scenario.structures) {
      footprints.FillBox(tree.center_m - tree.size_m / 2, tree.center_m + tree.size_m / 2);
    }
    CheckValvesReachable(scenario, footprints.Inflated(kVehicleClearance_m));
    return;
  }
  const SeabedMap seabed(scenario, scenario.astar.grid_resolution_m);
  const OccupancyGrid slice = seabed.OperatingSlice();
  CheckOnOpenSeabed(scenario, TerrainObstacles(slice, scenario.structures));
  CheckValvesReachable(scenario, slice.Inflated(kVehicleClearance_m));
}

}  // namespace sage::maps
