#pragma once
// The server's belief where leaks are, fused from the vehicles' scans by Bayes' rule. Each leaf
// of the risk layer's grid (r = its resolution) holds the log-odds l that a leak lies in it,
// starting from the prior l0 = logit(fusion.prior_probability). A scan of sensor s from pose
// (x, psi) with detections Z updates every leaf c whose centre is in view (maps::SensorModel):
//   l_c += ln[ (1 - p_c) + p_c sum_{z in Z} N(z; c, sigma^2) / kappa ],
// p_c the sensor's detection probability at the leaf's distance and kappa its clutter density
// (false alarms per scan per m^2 of view). That is the likelihood ratio of "a leak in c" against
// "none in c" when each scan sees a leak in view with probability p_c, at its position give or
// take sigma, among Poisson false alarms spread over the view: a detection near c raises l_c at
// once (by ln(1 + p N / kappa)), a scan that sees nothing lowers it by ln(1 - p_c), and a
// detection elsewhere in view lowers it as a miss does. l is held in [l0 + min_evidence,
// max_log_odds] (OctoMap's clamping: the belief can always be moved again), and between scans
// relaxes to the prior, l - l0 decaying as exp(-t / relax_time_s): a leak may begin anywhere at
// any time. The prior is per leaf: the leaves of the flowlines' joints (tie-ins, flanges) start
// at logit(fusion.joint_prior_probability) when it is set, every other leaf at l0; evidence is
// always held as l minus the leaf's own prior. No transport, no files.
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "maps/perception/sensor_model.h"
#include "maps/scenario/scenario.h"
#include "maps/world.h"

namespace sage::server {

class LeakBelief {
 public:
  /// A leaf's indices: it spans [i r, (i + 1) r] x [j r, (j + 1) r].
  struct Cell {
    int i = 0, j = 0;
    bool operator<(const Cell& o) const { return i != o.i ? i < o.i : j < o.j; }
    bool operator==(const Cell& o) const = default;
  };
  /// One leaf that differs from the prior, as a checkpoint keeps it.
  struct Entry {
    Cell cell;
    double evidence = 0.0;  ///< l - l0 as of time_s
    double time_s = 0.0;
  };

  /// world and scenario outlive the belief; resolution_m: the risk layer's leaf edge.
  LeakBelief(const maps::Scenario& scenario, const maps::World& world, double resolution_m);

  const std::vector<maps::SensorModel>& sensors() const { return sensors_; }
  double resolution_m() const { return resolution_m_; }
  /// The open seabed's prior (every leaf but the joints').
  double prior_log_odds() const { return prior_; }
  /// A leaf's own prior log-odds and probability.
  double PriorLogOdds(Cell c) const;
  double PriorProbability(Cell c) const;
  /// The leaves of the flowlines' joints whose prior is above the open seabed's (none unless
  /// fusion.joint_prior_probability is set), ascending; joints inside a structure's footprint,
  /// where no sensor sees, are left out.
  const std::vector<Cell>& joints() const { return joints_; }

  /// Fuses one scan (checked at the door) of sensor `sensor` at time_s (>= every earlier scan's).
  /// Returns how many leaves were updated.
  int Fuse(int sensor, const Eigen::Vector2d& position_m, double heading_rad,
           const std::vector<Eigen::Vector2d>& detections_m, double time_s);

  Cell CellOf(const Eigen::Vector2d& x_m) const;
  bool OnGrid(Cell c) const { return c.i >= 0 && c.j >= 0 && c.i < cells_x_ && c.j < cells_y_; }
  Eigen::Vector2d CentreOf(Cell c) const;
  /// l - l0 of a leaf at time_s (0: the prior).
  double Evidence(Cell c, double time_s) const;
  double LogOdds(Cell c, double time_s) const { return PriorLogOdds(c) + Evidence(c, time_s); }
  double Probability(Cell c, double time_s) const;
  /// The leaves above the prior (evidence > 0), ascending; those relaxed below 1e-4 are dropped.
  const std::set<Cell>& positive() const { return positive_; }
  void DropRelaxed(double time_s);
  /// Per valve (scenario order), the evidence of no leak at its leaf: P / P0 <= 1 (1 where the
  /// belief is at or above the prior).
  Eigen::VectorXd ValveFactors(double time_s) const;

  std::vector<Entry> Checkpoint() const;
  /// Throws std::invalid_argument for a leaf off the grid or evidence not finite.
  void Restore(const std::vector<Entry>& entries);

 private:
  struct Value {
    double evidence = 0.0;
    double time_s = 0.0;
  };
  static std::uint64_t Key(Cell c) { return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.i)) << 32) | static_cast<std::uint32_t>(c.j); }
  double Relaxed(std::uint64_t key, const Value& v, double time_s) const;
  void Prune(double time_s);

  const maps::Scenario& scenario_;
  std::vector<maps::SensorModel> sensors_;
  double resolution_m_;
  int cells_x_ = 0, cells_y_ = 0;
  double prior_ = 0.0, prior_probability_ = 0.0, floor_ = 0.0, ceiling_ = 0.0;
  std::unordered_map<std::uint64_t, Value> cells_;
  std::vector<Cell> joints_;
  double joint_prior_ = 0.0, joint_prior_probability_ = 0.0;
  std::unordered_set<std::uint64_t> joint_keys_;
  bool IsJoint(std::uint64_t key) const { return !joint_keys_.empty() && joint_keys_.count(key) != 0; }
  std::set<Cell> positive_;
  std::vector<Cell> valve_cells_;
  double next_prune_s_ = 0.0;
};

}  // namespace sage::server
