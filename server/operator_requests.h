#pragma once
// What an operator may ask of a running mission, checked before it reaches the server, and the
// one-line answers they read, in one place for every way of asking: the `sage risk set`,
// `sage vehicle add|remove` and `sage stop` commands (server/app/operators.cpp) and the live
// view's buttons (server/node/server_node.cpp). The mission core's own checks (a valve's
// weight, which vehicle may be taken out, how many may join) come after these in both paths.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"

namespace sage::server {

/// A risk update an operator may send: a valve of this mission, a weight in [0, 1e12]. Throws
/// maps::ScenarioError with the rule ("weight = -1: must be a number in [0, 1e12] ...",
/// "valve = P9: not in this mission (valves: P1, P2, ...)").
void CheckRiskRequest(const maps::Scenario& scenario, const std::string& valve, double weight);
/// How many vehicles an operator may add at once: 1..10000. Throws maps::ScenarioError.
void CheckAddCount(int count);
/// A vehicle id an operator may name: >= 0. Throws maps::ScenarioError.
void CheckVehicleId(int id);

/// "P9: risk 20 applied at t = 31.2 s; now 41.7 % of the field's risk"
std::string RiskAppliedLine(const std::string& valve, double weight, double time_s, double new_share);
/// "the mission did not apply it: <reason>"
std::string RiskRefusedLine(const std::string& reason);
/// "the mission refused: <reason>" (a vehicle's removal or new ids refused)
std::string CommandRefusedLine(const std::string& reason);
/// "started agent host pid 4242 with 2 vehicles: rov9..rov10, ids 8..9 (log: DIR/agents-add-8.log)"; one: "with 1
/// vehicle: rov3, id 2 (log: ...)"
std::string HostStartedLine(int pid, int count, int first_id, const std::string& log_path);
/// "rov4 (id 3) left the mission (told to at t = 12.0 s)"; "vehicle 3 left ..." with no name known
std::string VehicleLeftLine(int id, const std::string& name, double told_at_s);
/// "rov4 (id 3) was told to leave at t = 12.0 s but had not left within 5 s"
std::string VehicleNotLeftLine(int id, const std::string& name, double told_at_s, double waited_s);
/// "the mission stops at t = 40.1 s; its server writes runs/x"
std::string StopLine(double time_s, const std::string& run_dir);

/// What `sage status` heard of a running mission in a second or so on DDS: the server's latest
/// MissionStatus and each vehicle's latest state, each checked at the door (HeardStateProblem).
struct HeardStatus {
  bool has_status = false;  ///< the server's status was heard
  double time_s = 0.0, duration_s = 0.0, time_scale = 1.0, cycle_ms = 0.0;
  double ergodic_metric = std::numeric_limits<double>::quiet_NaN();  ///< NaN: none yet
  std::int64_t alive = 0, lost = 0;
  bool finished = false;
  /// Mission seconds per wall second between the first and last status heard (NaN: too close).
  double measured_rate = std::numeric_limits<double>::quiet_NaN();
  struct Vehicle {
    int id = 0;
    std::string name;
    double time_s = 0.0;  ///< mission time of its latest state
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
    double speed_mps = 0.0;
  };
  std::vector<Vehicle> vehicles;  ///< ascending id, the latest state of each
  double listened_s = 0.0;
  std::size_t refused = 0;  ///< samples refused at the door
  std::string last_refusal;
  /// From the run directory's record (fleet_events.csv), where it could be read: vehicles that
  /// left (-1: not read) and the latest tour or region plan's line (its time and what it says,
  /// how many are held in reserve among it; empty: none).
  std::int64_t left = -1;
  double plan_time_s = 0.0;
  std::string plan;
};

/// Why an operator's risk update may not carry this source (empty: it may): the names the mission
/// records its own changes under ("scenario": the profile's timed events, which a resume replays
/// from the scenario and not from the record, so an operator's change under it was lost on a resume;
/// "operator (live view)": the page's), and a first character a spreadsheet reads as a formula
/// (=, +, -, @) in risk_events.csv.
std::string RiskSourceProblem(std::string_view source);

/// Why a vehicle's state heard on the mission's domain is not believed (empty: it is): an id in
/// 0..max_id, a name as a scenario's (1..64 characters of UTF-8, no control character), a finite
/// mission time >= 0, a place the server's door takes (maps::Workspace::Reaches), a finite speed
/// within three times the scenario's fastest transit speed (10 m/s at least).
std::string HeardStateProblem(std::uint64_t id, const std::string& name, double time_s, const Eigen::Vector2d& position_m,
                              const Eigen::Vector2d& velocity_mps, const maps::Scenario& scenario, std::int64_t max_id);
/// Why a MissionStatus heard is not believed (empty: it is): a time in [0, duration + 1 s] of a
/// finite duration > 0, a time scale in [min_time_scale, max_time_scale] (what a mission's clock
/// may run at: the transport's bounds, given by the caller), a cycle time in [0, 1e6] ms, a metric
/// finite >= 0 or NaN (none yet), vehicle counts in 0..max_id + 1.
std::string HeardStatusProblem(const HeardStatus& status, std::int64_t max_id, double min_time_scale,
                               double max_time_scale);

/// `sage status`'s report: the mission's time against its duration and how fast it runs, its run
/// directory, the server's cycle and metric, vehicles flying and lost, then one row a vehicle
/// heard (id, name, position, speed, time of its state), the first max_rows by id with a count of
/// the rest, and the samples refused. Within 100 columns but for the run directory's and the last
/// refusal's own words.
std::string StatusReport(const HeardStatus& heard, const std::string& mission, const std::string& run_dir,
                         std::size_t max_rows = 40);

}  // namespace sage::server
