// The seabed OctoMap (see seabed_map.h). octomap is included only here and in the risk layer's
// and the seabed file's sources, so the rest of the code sees the maps through SeabedMap,
// OccupancyGrid and RiskLayer.
#include "maps/seabed_map.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <octomap/OcTree.h>

#include "maps/quiet_stderr.h"
#include "maps/seabed/seabed_columns.h"
#include "maps/seabed/seabed_file.h"

namespace sage::maps {
namespace {

// Indices k of the voxels (or cells) of size r whose centres (k + 1/2) r lie in [lo, hi]; the
// tolerance keeps a centre lying exactly on an edge inside despite rounding.
std::pair<int, int> CenterRange(double lo, double hi, double r) {
  return {static_cast<int>(std::ceil(lo / r - 0.5 - 1e-9)), static_cast<int>(std::floor(hi / r - 0.5 + 1e-9))};
}

// Marks every voxel whose centre lies in the axis-aligned box [min, max] (m) as occupied with the
// clamping maximum, i.e. as certain as OctoMap can be. Inner nodes are updated by the caller.
void FillBox(octomap::OcTree& tree, const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const double r = tree.getResolution();
  const auto [i0, i1] = CenterRange(min.x(), max.x(), r);
  const auto [j0, j1] = CenterRange(min.y(), max.y(), r);
  const auto [k0, k1] = CenterRange(min.z(), max.z(), r);
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      for (int k = k0; k <= k1; ++k) {
        tree.setNodeValue((i + 0.5) * r, (j + 0.5) * r, (k + 0.5) * r, tree.getClampingThresMaxLog(),
                          /*lazy_eval=*/true);
      }
    }
  }
}

// OctoMap's key of voxel index k (its centre at (k + 1/2) r): floor(coordinate / r) + 2^15.
octomap::key_type KeyOf(int k) { return static_cast<octomap::key_type>(k + 32768); }

}  // namespace

SeabedMap::SeabedMap(const Scenario& scenario, double resolution_m) : workspace_(scenario.workspace) {
  if (!(resolution_m > 0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("SeabedMap: resolution " + std::to_string(resolution_m) + " m must be > 0");
  }
  tree_ = std::make_unique<octomap::OcTree>(resolution_m);
  if (scenario.HasSeabedModel()) {
    BuildModel(scenario);
  } else {
    BuildFlat(scenario);
  }
  tree_->updateInnerOccupancy();
  tree_->prune();
}

void SeabedMap::BuildFlat(const Scenario& scenario) {
  const double r = tree_->getResolution();
  // One voxel layer just below z = 0 over the workspace: the seabed the XTs stand on. It lies
  // below any operating band (z >= 0), so it never shows in the 2-D projection.
  FillBox(*tree_, Eigen::Vector3d(0, 0, -r), Eigen::Vector3d(workspace_.width_m, workspace_.height_m, 0));
  for (const ChristmasTree& structure : scenario.structures) {
    const Eigen::Vector2d min = structure.center_m - structure.size_m / 2;
    const Eigen::Vector2d max = structure.center_m + structure.size_m / 2;
    FillBox(*tree_, Eigen::Vector3d(min.x(), min.y(), 0), Eigen::Vector3d(max.x(), max.y(), structure.height_m));
  }
}

void SeabedMap::BuildModel(const Scenario& scenario) {
  const double r = tree_->getResolution();
  const SeabedSettings settings = scenario.SeabedOrDefault();
  altitude_min_m_ = settings.altitude_min_m;
  altitude_max_m_ = settings.altitude_max_m;
  const std::string where = (scenario.source_path.empty() ? std::string("<scenario>") : scenario.source_path) + ": " +
                            (settings.map.empty() ? std::string("seabed") : "seabed.map = " + settings.map) + ": ";
  const double cells = std::ceil(workspace_.width_m / r - 1e-9) * std::ceil(workspace_.height_m / r - 1e-9);
  if (cells > kMaxSeabedColumns) {
    throw ScenarioError(where + fmt::format("the workspace has {:.0f} cells at astar.grid_resolution_m = {} m; a seabed "
                                            "model at most {:.0f} million (use a coarser grid)",
                                            cells, r, kMaxSeabedColumns / 1e6));
  }
  columns_ = std::make_unique<SeabedColumns>(StandOnSeabed(scenario, ReadSeabedHeights(scenario, r)));
  const HeightGrid& ground = columns_->ground;
  const HeightGrid& trend = columns_->trend;
  const HeightGrid& top = columns_->top;
  const int cols = ground.cols(), rows = ground.rows();
  // Each column is solid from a voxel below the lowest of its neighbours' ground and its own
  // local seabed up to its top: the surface shows without holes on a slope, and every voxel a
  // band can hold below the top is there, without filling the whole depth of the seabed.
  HeightGrid floor(cols, rows, r);
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) {
      double lowest = trend.at(i, j);
      for (int a = std::max(0, i - 1); a <= std::min(cols - 1, i + 1); ++a) {
        for (int b = std::max(0, j - 1); b <= std::min(rows - 1, j + 1); ++b) lowest = std::min(lowest, ground.at(a, b));
      }
      floor.at(i, j) = lowest - r;
    }
  }
  datum_m_ = r * std::floor(floor.Min() / r);
  const double highest = std::max(top.Max(), trend.Max() + altitude_max_m_) - datum_m_;
  if (highest / r > kMaxOctoMapVoxels - 2) {
    throw ScenarioError(where + fmt::format("the seabed and what stands on it span {:.1f} m in height ({:.0f} voxels at "
                                            "astar.grid_resolution_m = {} m): OctoMap's keys hold at most 32767 (use a "
                                            "coarser grid or a smaller field)",
                                            highest, std::ceil(highest / r), r));
  }
  const float occupied = tree_->getClampingThresMaxLog();
  for (int i = 0; i < cols; ++i) {
    for (int j = 0; j < rows; ++j) {
      const auto [k0, k1] = CenterRange(floor.at(i, j) - datum_m_, top.at(i, j) - datum_m_, r);
      for (int k = k0; k <= k1; ++k) {
        tree_->setNodeValue(octomap::OcTreeKey(KeyOf(i), KeyOf(j), KeyOf(k)), occupied, /*lazy_eval=*/true);
      }
    }
  }
}

SeabedMap::~SeabedMap() = default;
SeabedMap::SeabedMap(SeabedMap&&) noexcept = default;
SeabedMap& SeabedMap::operator=(SeabedMap&&) noexcept = default;

double SeabedMap::resolution_m() const { return tree_->getResolution(); }

OccupancyGrid SeabedMap::Project(double z_min_m, double z_max_m, double grid_resolution_m) const {
  if (!(z_max_m >= z_min_m)) {
    throw std::invalid_argument("SeabedMap::Project: z band [" + std::to_string(z_min_m) + ", " +
                                std::to_string(z_max_m) + "] m is empty");
  }
  OccupancyGrid grid(workspace_.width_m, workspace_.height_m, grid_resolution_m);
  const double g = grid_resolution_m;
  const octomap::point3d bbx_min(0.0f, 0.0f, static_cast<float>(z_min_m));
  const octomap::point3d bbx_max(static_cast<float>(workspace_.width_m), static_cast<float>(workspace_.height_m),
                                 static_cast<float>(z_max_m));
  for (auto it = tree_->begin_leafs_bbx(bbx_min, bbx_max), end = tree_->end_leafs_bbx(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    // A pruned leaf spans size x size; mark every cell its footprint overlaps with positive area
    // (conservative for a coarser grid). The shrink keeps float noise on shared edges out.
    const double half = it.getSize() / 2;
    const double shrink = 1e-3 * std::min(g, it.getSize());
    const auto span = [&](double center, int count) {
      const int first = static_cast<int>(std::floor((center - half + shrink) / g));
      const int last = static_cast<int>(std::floor((center + half - shrink) / g));
      return std::pair<int, int>(std::max(first, 0), std::min(last, count - 1));
    };
    const auto [i0, i1] = span(it.getX(), grid.cols());
    const auto [j0, j1] = span(it.getY(), grid.rows());
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) grid.SetOccupied(i, j);
    }
  }
  return grid;
}

OccupancyGrid SeabedMap::OperatingSlice() const {
  const double r = tree_->getResolution();
  if (!columns_) return Project(kOperatingDepthMin_m, kOperatingDepthMax_m, r);
  OccupancyGrid grid(workspace_.width_m, workspace_.height_m, r);
  const HeightGrid& trend = columns_->trend;
  // The band of each column in the tree's frame; the leaves are read once, over the z range
  // every band together spans.
  const double low = trend.Min() - datum_m_ + altitude_min_m_, high = trend.Max() - datum_m_ + altitude_max_m_;
  const octomap::point3d bbx_min(0.0f, 0.0f, static_cast<float>(low));
  const octomap::point3d bbx_max(static_cast<float>(workspace_.width_m), static_cast<float>(workspace_.height_m),
                                 static_cast<float>(high));
  for (auto it = tree_->begin_leafs_bbx(bbx_min, bbx_max), end = tree_->end_leafs_bbx(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    // The leaf's voxels: indices [first, first + n) on each axis (its corner is a whole number of
    // voxels, so rounding recovers it exactly from OctoMap's float centre).
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / r));
    const int i0 = static_cast<int>(std::lround((it.getX() - size / 2) / r));
    const int j0 = static_cast<int>(std::lround((it.getY() - size / 2) / r));
    const int k0 = static_cast<int>(std::lround((it.getZ() - size / 2) / r));
    for (int i = std::max(0, i0); i < std::min(grid.cols(), i0 + n); ++i) {
      for (int j = std::max(0, j0); j < std::min(grid.rows(), j0 + n); ++j) {
        if (grid.Occupied(i, j)) continue;
        const double base = trend.at(i, j) - datum_m_;
        const auto [ka, kb] = CenterRange(base + altitude_min_m_, base + altitude_max_m_, r);
        if (std::max(ka, k0) <= std::min(kb, k0 + n - 1)) grid.SetOccupied(i, j);
      }
    }
  }
  return grid;
}

OccupancyGrid SeabedMap::OperatingSlice(const Scenario& scenario) {
  return SeabedMap(scenario, scenario.astar.grid_resolution_m).OperatingSlice();
}

Eigen::Vector3d SeabedMap::SeabedPoint(const Eigen::Vector2d& x_m) const {
  const double z = columns_ ? columns_->ground.Sample(x_m) - datum_m_ : 0.0;
  return {x_m.x(), x_m.y(), z};
}

std::string SeabedMap::BinaryBytes() const {
  std::ostringstream out;
  bool written = false;
  {
    detail::QuietStderr quiet;
    written = tree_->writeBinaryConst(out);
  }
  if (!written) throw std::runtime_error("SeabedMap: OctoMap could not serialise the seabed tree");
  return std::move(out).str();
}

}  // namespace sage::maps
