#pragma once
// A mission's run directory, written while the mission runs so that nothing is lost when a
// process dies: trajectory.csv, fleet_events.csv and risk_events.csv are appended as things
// happen and flushed at least every second (tail -f works); metrics.json is rewritten
// atomically every few seconds with "complete": false, beside checkpoint.bin, the state a
// resumed server starts from. At the end the final set (the charts plot, metric and revisits as
// .svg and .png, seabed.bt, risk.ot, scenario.yaml, metrics.json with "complete": true) is written as temporaries and renamed into
// place with metrics.json last, so a reader sees either the whole final set or the partial one.
#include <chrono>
#include <cstdint>
#include <future>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "maps/scenario/scenario.h"
#include "maps/world.h"
#include "server/mission_core.h"
#include "server/report/plots/plot_record.h"
#include "server/report/report.h"
#include "server/trajectory.h"

namespace sage::maps {
class RiskLayer;
}

namespace sage::server {

/// A checkpoint's cost is held to 1 / kCheckpointCostRatio of one core (RunDirectoryOptions).
inline constexpr double kCheckpointCostRatio = 20.0;

struct RunDirectoryOptions {
  double flush_period_s = 1.0;       ///< wall seconds between flushes of the appended files
  /// ... or sooner, at the end of the cycle that leaves more than this many bytes of rows waiting:
  /// a mission simulated far faster than real time (fleet_field runs at ~3,600x) had held an hour
  /// of trajectory rows (30 MB) between flushes, and all of a short mission's until its end.
  std::size_t flush_bytes = 4u << 20;
  /// Wall seconds between checkpoints and partial metrics, at least; a checkpoint whose making
  /// cost c CPU-seconds (the copies on the mission's thread, encoding and writing off it) is
  /// followed by the next no sooner than kCheckpointCostRatio c later: a 10,000-vehicle
  /// checkpoint costs ~0.5 s, and every 2 s it took a sixth of the mission's CPU.
  double checkpoint_period_s = 2.0;
  std::size_t plot_points = 200000;  ///< trajectory samples kept in memory for the final plot
  std::size_t plot_events = 2000;    ///< events kept to mark on it (the rest are counted)
  std::string transport = "in-process";
  /// checkpoint.bin with the partial metrics: a launch's server, which `sage launch --resume`
  /// restarts from it. A `sage run` has no resume (run it again: the seed flies the same mission)
  /// and writes only the partial metrics.json, sparing the copy of the mission's state.
  bool resumable = true;
  bool resume = false;               ///< append to a crashed mission's record instead of starting one
  int resumes = 0;                   ///< how many times this mission was resumed before
};

class RunDirectory final : public MissionRecorder {
 public:
  /// Creates `dir` with the record's files (a new mission), or opens them for appending, cut
  /// back to their last complete line (resume). Writes the effective scenario.yaml at once.
  /// Throws maps::ScenarioError ("--out = DIR: cannot write there: ...") before anything runs.
  RunDirectory(std::string dir, const maps::Scenario& scenario, RunDirectoryOptions options = {});
  ~RunDirectory() override;
  RunDirectory(const RunDirectory&) = delete;
  /// Bytes of records formatted and not yet written (the trajectory rows of the cycles since the
  /// last flush, and the event files'), not counting a large cycle's rows still being formatted.
  std::size_t buffered_bytes() const;
  RunDirectory& operator=(const RunDirectory&) = delete;

  /// Rows go to trajectory.csv (and the plots' copy) on the cycles the scenario's
  /// trajectory_rate_hz records, every cycle by default, and at the end (Finish) the mission's
  /// last cycle if the rate left it out.
  void OnSample(const TrajectorySample& sample, const std::string& vehicle_name) override;
  /// A large fleet's cycle of trajectory rows is formatted on another thread while the mission
  /// goes on (10,000 rows took 12 ms of a 10,000-vehicle cycle); the rows land in order.
  void OnSamples(const std::vector<TrajectorySample>& samples, const std::vector<const std::string*>& names) override;
  void OnFleetEvent(const FleetEventRecord& event) override;
  void OnRiskEvent(const RiskEventRecord& event) override;
  void OnRegions(double time_s, const std::vector<RegionRecord>& regions) override;

  /// A resumed mission's plots start from its whole record so far, not from the resume: the
  /// tracks, joins, losses and risk changes before the crash (a resumed launch had drawn only
  /// what came after it). Called once, after the mission is restored and before it records
  /// anything new; `index_of_id` maps vehicle ids to their record indices (the roster's), and a
  /// row's name is the vehicle's whose join last took it. The trajectory is streamed, a row at a
  /// time. Throws maps::ScenarioError naming the file and line of anything unreadable.
  void RestorePlot(const std::map<int, int>& index_of_id);

  /// Once a cycle: flushes the appended files when the flush period is due, and writes the
  /// checkpoint and partial metrics when the checkpoint period is.
  void Tick(const MissionCore& core);
  /// Flushes, then writes the checkpoint and partial metrics now (returns once they are written).
  void Checkpoint(const MissionCore& core);
  /// The mission ended at end_s (the planned end, or earlier if stopped): flushes and writes the
  /// final set. Throws std::runtime_error naming the file that could not be written (the partial
  /// set stays as it was). risk.ot is `risk_layer` as OctoMap .ot (a maps::RiskOcTree); without
  /// one, the mission's live layer (MissionCore::risk_layer(): the leaves the risk loop raised; a
  /// mission without sensors has none, a tree with no leaves).
  void Finish(const MissionCore& core, const maps::World& world, double end_s, bool stopped_early,
              const maps::RiskLayer* risk_layer = nullptr);

  const std::string& dir() const { return dir_; }
  /// Mission time of the last sample flushed to trajectory.csv (-1 before any).
  double flushed_until_s() const { return flushed_until_s_; }
  /// Mission time of the last checkpoint written (-1 before any).
  double checkpoint_time_s() const { return checkpoint_time_s_; }

 private:
  struct Appender {
    std::string path;
    int fd = -1;
    std::string buffer;
  };
  // Whether trajectory.csv records the cycle of mission time t (Scenario::TrajectoryEvery).
  bool RecordedAt(double time_s) const;
  // The last cycle the rate leaves out is held, and written at the end (or an explicit
  // checkpoint) if nothing later was recorded: the record ends where the mission did.
  void Hold(const TrajectorySample& sample, const std::string& name);
  void WriteHeldRows();
  void Open(Appender& file, const char* name, const char* header);
  void Flush();
  void CollectRows();
  void FlushOne(Appender& file);
  void StartCheckpoint(const MissionCore& core, bool wait);
  RunInfo Info(const MissionCore& core, bool complete, bool stopped_early) const;

  std::string dir_;
  const maps::Scenario& scenario_;
  RunDirectoryOptions options_;
  std::int64_t trajectory_every_;  // control cycles between a vehicle's rows (Scenario::TrajectoryEvery)
  std::vector<std::pair<TrajectorySample, std::string>> held_;  // the last unrecorded cycle's samples
  double held_time_s_ = -1.0;
  Appender trajectory_, fleet_events_, risk_events_, regions_;
  std::chrono::steady_clock::time_point last_flush_, last_checkpoint_;
  double pending_until_s_ = -1.0, flushed_until_s_ = -1.0, checkpoint_time_s_ = -1.0;
  double checkpoint_cost_s_ = 0.0;        // CPU seconds the last checkpoint took, copies and writing
  std::future<double> checkpoint_write_;  // the checkpoint is encoded and written off the cycle (its CPU seconds)
  std::future<std::string> rows_;       // the last large cycle's trajectory rows, being formatted
  plots::PlotRecord plot_;               // a thinned copy of the trajectory and the events, for the plots
};

/// What a crashed mission's record holds after its checkpoint (time_s): the samples, fleet
/// events and operators' risk events written later, up to the moment the server died.
struct RecordTail {
  std::vector<std::pair<TrajectorySample, std::string>> samples;  ///< with the vehicle's name (index unset)
  std::vector<FleetEventRecord> fleet_events;
  std::vector<RiskEventRecord> risk_events;
};
/// Reads DIR's record after mission time `after_s`. Throws maps::ScenarioError naming the file
/// and line of anything unreadable.
RecordTail ReadRecordTail(const std::string& dir, double after_s);

}  // namespace sage::server
