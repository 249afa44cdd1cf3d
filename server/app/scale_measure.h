#pragma once
// The measurement side of `sage bench scale`, free of processes and files so that tests drive
// it: the field a fleet of N flies, the server's end-of-mission summary line and the
// launcher's progress read from its output, when every vehicle got under way, and a measured
// run turned into a row of scale.json (server/report/scale_report.h). bench_scale.cpp runs
// the missions and the launches and hands their figures here.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/field_generator.h"
#include "server/metrics.h"
#include "server/mission_core.h"
#include "server/report/scale_report.h"

namespace sage::server {

/// The field of a weak-scaling run with N vehicles: N XTs, round(3.5 N) valves (inside the
/// generator's 2 to 5 per XT), N vehicles, the given seed; the generator's default name.
maps::FieldOptions ScaleFieldOptions(int vehicles, std::uint64_t seed);

/// What the DDS server's end-of-mission line says (server/node/server_node.cpp):
/// "server: 30 s of mission in 30.0 s wall (1.00x real time); 310149 messages in, 1364 out
/// (10380/s); 31.020 MB in, 1.204 MB out at 1.074 MB/s; server cycle 9.79 ms mean, 21.40 ms p99,
/// 49.30 ms max; peak RSS 80.1 MB; ...". Figures an older server did not print (bytes, p99,
/// peak RSS) are NaN.
struct ServerSummary {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double mission_s = 0.0;
  double wall_s = 0.0;
  double real_time_factor = 0.0;
  std::uint64_t messages_in = 0, messages_out = 0;
  double messages_per_s = 0.0;
  double mb_in = kNaN, mb_out = kNaN, mb_per_s = kNaN;
  double cycle_mean_ms = 0.0, cycle_p99_ms = kNaN, cycle_max_ms = 0.0;
  double peak_rss_mb = kNaN;
};

/// The summary in one line of output (log decorations before "server:" allowed); nullopt if the
/// line is not one.
std::optional<ServerSummary> ParseServerSummary(std::string_view line);
/// The last summary line in a launcher's whole output; nullopt if there is none.
std::optional<ServerSummary> FindServerSummary(std::string_view output);
/// The mission's progress (0..1) from the launcher's last progress line "t = 30 / 60 s ...";
/// nullopt before the first.
std::optional<double> LaunchProgress(std::string_view output);
/// The agent host count from the launcher's line "... 4 agent host(s) for 1000 vehicles ...";
/// -1 if absent.
int LaunchHostCount(std::string_view output);

/// When each vehicle first got more than `distance_m` from its first recorded position: a
/// recorder for an in-process mission, or fed the samples of a recorded trajectory.
class FirstMoveTracker final : public MissionRecorder {
 public:
  explicit FirstMoveTracker(double distance_m = 0.05) : distance_m_(distance_m) {}
  void OnSample(const TrajectorySample& sample, const std::string& vehicle_name) override;
  void OnFleetEvent(const FleetEventRecord&) override {}
  void OnRiskEvent(const RiskEventRecord&) override {}
  void Add(const TrajectorySample& sample) { OnSample(sample, ""); }

  int vehicles() const;
  /// Vehicles seen that never got that far.
  int never_moved() const;
  /// The mission time by which every vehicle seen had moved; NaN if one never did or none was seen.
  double all_moved_s() const;

 private:
  struct Vehicle {
    bool seen = false;
    Eigen::Vector2d start_m = Eigen::Vector2d::Zero();
    double moved_s = std::numeric_limits<double>::quiet_NaN();
  };
  double distance_m_;
  std::vector<Vehicle> by_id_;
};

/// The quality columns of a row from a run's metrics.
void FillQuality(ScaleRow& row, const MissionMetrics& metrics);

/// An in-process run as bench_scale measured it.
struct InprocRun {
  double mission_s = 0.0;     ///< mission seconds stepped
  double loop_wall_s = 0.0;   ///< wall seconds of the stepping loop
  double setup_wall_s = 0.0;  ///< wall seconds to build the Mission
  double cpu_s = 0.0;         ///< user + system CPU seconds of the loop (RUSAGE_SELF after - before)
  /// The loop's second half: the mission seconds, wall and CPU seconds from its middle cycle to
  /// the end (0 mission seconds: not measured).
  double late_mission_s = 0.0, late_wall_s = 0.0, late_cpu_s = 0.0;
  double peak_rss_mb = 0.0;   ///< ru_maxrss of the process
  std::vector<double> server_cycle_s;  ///< each MissionCore::Cycle's wall time
  double all_moved_s = std::numeric_limits<double>::quiet_NaN();
  int never_moved = 0;
  MissionMetrics metrics;
};
/// `base` (vehicles, controller, field columns) with the in-process figures: real-time factor
/// mission_s / loop_wall_s, cycle mean, p99 (nearest rank) and max, CPU per vehicle-second; the
/// real-time factor and CPU per vehicle-second of the second half.
ScaleRow InprocRow(ScaleRow base, const InprocRun& run);

/// A launch as bench_scale measured it.
struct DdsRun {
  ServerSummary server;
  double cpu_s = 0.0;            ///< user + system CPU of the whole launch (wait4 on the launcher)
  double largest_rss_mb = 0.0;   ///< ru_maxrss from wait4: the largest process of the launch
  double agent_host_rss_mb = std::numeric_limits<double>::quiet_NaN();  ///< largest host's VmHWM
  int agent_hosts = -1;
  double all_moved_s = std::numeric_limits<double>::quiet_NaN();
  int never_moved = 0;
  MissionMetrics metrics;
};
/// `base` with the launch's figures: the server's real-time factor, cycle, samples and bytes per
/// second and peak RSS from its summary; CPU per vehicle-second of the whole launch.
ScaleRow DdsRow(ScaleRow base, const DdsRun& run);

}  // namespace sage::server
