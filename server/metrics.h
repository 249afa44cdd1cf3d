#pragma once
// Inspection metrics of any run (ours, A*'s, or a recorded log), as in the SAGE paper's Table 1:
// per valve visits, revisit intervals, longest gap, time near; for the mission the Pearson
// correlation of visits with weight, the ergodic metric over time, and the time spent outside
// or pinned to the workspace boundary (the paper's corner excursions).
#include <cstdint>
#include <future>
#include <functional>
#include <limits>
#include <iterator>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "maps/nearby_points.h"
#include "maps/risk_field.h"
#include "maps/scenario/scenario.h"
#include "maps/spectral_basis.h"
#include "server/trajectory.h"

namespace sage::server {

/// Counts visits online: a visit is an entry within visit_radius of a valve; the valve is
/// re-armed for that vehicle only after it leaves rearm_radius, so jitter is not counted twice.
/// A vehicle's state is the few valves it has disarmed; a sample looks only at those and at the
/// valves near it. What it keeps of each valve does not grow with the mission's length: the
/// latest kRecentVisits visits exactly, and of the older ones their count, the first and the
/// longest gap between two of them (a 100,000 s mission had held every visit time of every valve).
class VisitTracker {
 public:
  /// Visits of a valve kept exactly (metrics.json's visit_times_s lists them).
  static constexpr std::size_t kRecentVisits = 64;

  /// One valve's visits. Gaps between consecutive visits are exact as long as no visit comes in
  /// older than the kept ones but the first (a vehicle more than kRecentVisits visits late); then
  /// the longest gap may be overstated, never understated.
  struct ValveVisits {
    std::size_t count = 0;
    double first_s = std::numeric_limits<double>::infinity();
    double folded_last_s = -std::numeric_limits<double>::infinity();  ///< the latest visit not kept (-inf: none)
    double folded_max_gap_s = 0.0;  ///< longest gap between consecutive visits up to folded_last_s
    std::vector<double> recent;     ///< the latest visits, ascending, at most kRecentVisits
    void Add(double time_s);
    /// The latest visit (-infinity before the first).
    double last_s() const { return recent.empty() ? folded_last_s : recent.back(); }
    bool operator==(const ValveVisits&) const = default;
  };

  /// How one valve's visits went around one time (a risk event's): before it, their count and the
  /// last; from it on, their count, the first and the last. Kept as visits come, in any order.
  struct EventWatch {
    int valve = 0;
    double time_s = 0.0;
    std::size_t before = 0, after = 0;
    double last_before_s = -std::numeric_limits<double>::infinity();
    double first_after_s = std::numeric_limits<double>::infinity();
    double last_after_s = -std::numeric_limits<double>::infinity();
    void Count(double visit_s);  ///< one more visit of the valve, at visit_s
    bool operator==(const EventWatch&) const = default;
  };

  VisitTracker(std::vector<Eigen::Vector2d> valves, double visit_radius_m, double rearm_radius_m);
  /// Feeds one vehicle's position at time t; returns the indices of valves visited by this sample
  /// (ascending).
  std::vector<int> Update(int vehicle, const Eigen::Vector2d& position_m, double time_s);
  /// Drops a vehicle's arming state (it left the mission).
  void Forget(int vehicle);
  /// Each valve's visits [valve].
  const std::vector<ValveVisits>& visits() const { return visits_; }
  /// Time of the last visit of valve i, or -infinity before the first.
  double LastVisit(int valve) const;
  /// Asks for LastVisit(valve)'s line to be brought into cache (maps/prefetch.h); changes nothing.
  void PrefetchLastVisit(int valve) const;
  /// Asks for what Update(vehicle, ...) reads of the vehicle's own (the valves it has disarmed)
  /// to be brought into cache; changes nothing.
  void PrefetchArming(int vehicle) const;
  /// Follows the visits of `valve` around `time_s` from now on (a risk event's), the ones already
  /// counted taken as their times say (those no longer kept as before it). watches()[i] is the
  /// i-th call's.
  void WatchAround(int valve, double time_s);
  const std::vector<EventWatch>& watches() const { return watches_; }
  /// The valves each vehicle has disarmed ([vehicle] -> ascending valve indices), for a
  /// checkpoint; and its restoration (throws std::invalid_argument for an index out of range,
  /// lists not ascending, or visits and watches that do not fit the valves).
  const std::vector<std::vector<int>>& disarmed() const { return disarmed_; }
  void Restore(std::vector<std::vector<int>> disarmed, std::vector<ValveVisits> visits, std::vector<EventWatch> watches);
  /// Valves within visit_radius of x (ascending), as Update counts them.
  void ValvesWithinVisitRadius(const Eigen::Vector2d& x, std::vector<int>& out) const {
    nearby_.Within(x, visit_radius_m_, out);
  }

 private:
  void Record(int valve, double time_s);

  std::vector<Eigen::Vector2d> valves_;
  double visit_radius_m_;
  double rearm_radius_m_;
  maps::NearbyPoints nearby_;
  std::vector<std::vector<int>> disarmed_;  // [vehicle] -> valves, ascending
  std::vector<ValveVisits> visits_;         // [valve]
  // [valve] visits_[valve].last_s(), in one block: the regions' age weighting asks it for every
  // valve every cycle (35,000 at 10,000 vehicles; two cache misses each through visits_).
  std::vector<double> last_visit_s_;
  std::vector<EventWatch> watches_;
  std::vector<std::vector<std::size_t>> watches_of_;  // [valve] -> indices into watches_
  std::vector<int> near_scratch_;
};

struct ValveMetrics {
  std::string name;
  double weight = 0.0;               ///< time-averaged normalised weight over the mission
  int visits = 0;
  double mean_interval_s = std::numeric_limits<double>::quiet_NaN();  ///< mean of gaps between visits; NaN if < 2
  double max_gap_s = 0.0;            ///< longest of start->first, between visits, last->end
  double time_near_s = 0.0;          ///< time within the visit radius (any vehicle)
  /// The latest visits (at most VisitTracker::kRecentVisits; all of them in a mission with fewer).
  std::vector<double> visit_times_s;
  /// Longest time (s) with no vehicle within the visit radius (start and end included): a
  /// vehicle holding station at a valve watches it, though it makes one visit.
  double longest_unwatched_s = 0.0;
  /// Sum over the unwatched stretches g of g^2 (s^2): a leak starting at a random moment waits
  /// sum g^2 / (2 T) for a vehicle to be there.
  double unwatched_squares_s2 = 0.0;
  /// With sensors: the expected wait (s) from a leak's start here to its first detection, from the
  /// scans the mission made (server/perception/expected_detection.h); NaN without sensors.
  double expected_detection_by_scans_s = std::numeric_limits<double>::quiet_NaN();
  /// With sensors: some scan after the first possible onset could have seen a leak here. False:
  /// no scan ever could, and the wait above is only the time left to the mission's end.
  bool seen_by_scans = false;
};

struct MetricSample {
  double time_s = 0.0;
  double ergodic_metric = 0.0;
};

/// How a risk event (e.g. a leak found at P1) was answered: time to the valve's next visit
/// and its revisit interval before and after (NaN where undefined).
struct EventResponse {
  double time_s = 0.0;
  std::string valve;
  double new_weight = 0.0;              ///< normalised weight after the event
  double time_to_next_visit_s = 0.0;    ///< NaN if never visited after it
  double interval_before_s = 0.0;       ///< mean revisit interval before the event
  double interval_after_s = 0.0;        ///< mean revisit interval after the event
  /// Angle (rad) between the velocity vehicle 0 commanded in the first control cycle at or
  /// after the event and the one it would have commanded without it.
  double heading_change_rad = 0.0;
};

/// One hidden leak, as the mission met it (issue 9's headline metric): from its onset, when a
/// vehicle's sensor first reported it and when the server's posterior confirmed it.
struct LeakMetrics {
  std::string where;                  ///< its valve ("P3") or "seabed (x, y)"
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int valve = -1;                     ///< its valve's index, or -1 on open seabed
  double start_s = 0.0;
  double strength = 1.0;
  /// Mission time of its first detection after the onset (a detection, from a scan that had the
  /// leak in view, is of the nearest leak started within the association radius); NaN if never.
  double detected_s = std::numeric_limits<double>::quiet_NaN();
  /// Mission time a leaf whose nearest started leak within the association radius it is first
  /// reached fusion.confirm_probability, once the leak was detected; NaN if never.
  double confirmed_s = std::numeric_limits<double>::quiet_NaN();
  int detections = 0;                 ///< detections of it (of the nearest leak, as above)
  /// A valve's leak: visits to the valve per minute from its detection to the end (NaN if undetected).
  double visits_per_min_after_detection = std::numeric_limits<double>::quiet_NaN();
};

/// Alarms the posterior raised where no leak was (a leaf reaching fusion.alarm_probability away
/// from every leak that had started), and how they went.
struct FalseAlarmMetrics {
  int detections = 0;     ///< detections associated with no leak that had started
  int raised = 0;
  int cleared = 0;        ///< fell back below half the alarm probability before the end
  int confirmed = 0;      ///< reached the confirmation probability: a leak reported where there is none
  double mean_time_to_clear_s = std::numeric_limits<double>::quiet_NaN();
  double max_time_to_clear_s = std::numeric_limits<double>::quiet_NaN();
};

struct MissionMetrics {
  std::string controller;            ///< "ergodic", "astar", or "recorded"
  std::string profile;
  double duration_s = 0.0;
  int vehicle_count = 0;
  std::vector<ValveMetrics> valves;
  double visit_weight_correlation = std::numeric_limits<double>::quiet_NaN();  ///< NaN if undefined
  double ergodic_metric = 0.0;       ///< final, of the whole fleet's time average vs the final phi
  /// Every metric_sample_period_s while the mission is short; a long one's thinned evenly, at
  /// most about kMetricSamplesKept samples (the spacing doubles as needed), and the end.
  std::vector<MetricSample> metric_over_time;
  double time_outside_s = 0.0;       ///< vehicle-seconds outside the workspace box
  double time_pinned_s = 0.0;        ///< vehicle-seconds within boundary_margin of its edge (inside)
  double boundary_margin_m = 0.2;
  std::vector<EventResponse> events;  ///< filled by a mission run; empty for a recorded log

  // What a fleet is judged by. With g_ij the stretches of valve i with no vehicle within the
  // visit radius (from the start, between, to the end) and weights w_i:
  /// Expected time a leak goes unnoticed if it starts at a uniformly random moment at valve i
  /// with probability w_i: sum_i w_i sum_j g_ij^2 / (2 T) (s). For regular visits every I this is
  /// about I / 2; irregular ones wait longer (the inspection paradox).
  double expected_detection_delay_s = 0.0;
  /// sum_i w_i T / max(n_i, 1): the risk-weighted mean revisit interval (s), n_i visits.
  double risk_weighted_interval_s = 0.0;
  double dominant_interval_s = 0.0;   ///< T / max(n, 1) of the valve with the highest weight (s)
  int unvisited_valves = 0;
  double longest_gap_median_s = 0.0;  ///< over valves, of each valve's longest unwatched stretch (s)
  double longest_gap_p90_s = 0.0;
  double longest_gap_max_s = 0.0;

  // Leak sensing (server/perception): empty / all zero when the scenario has no sensors.
  bool sensing = false;               ///< the vehicles carried leak sensors
  bool tours_on_scans = false;  ///< A* vehicles whose next valves the look planner chose on the scans (astar.order: looks)
  bool steered_on_posterior = false;  ///< ergodic vehicles steered on the fused belief (fusion.steer: posterior), not the profile alone
  std::vector<LeakMetrics> leaks;
  FalseAlarmMetrics false_alarms;
  std::uint64_t scans = 0;            ///< scans fused
  /// The valves' expected_detection_by_scans_s weighted as --random-leaks draws a leak's valve (by
  /// the profile's risk), for onsets in [0.1, 0.9] of the mission: what `sage bench leaks`
  /// measures over seeds, from this one mission's scans (a resumed mission's without those between
  /// its checkpoint and the crash, as its belief). NaN without sensors.
  double expected_detection_by_scans_s = std::numeric_limits<double>::quiet_NaN();
  double leak_onsets_from_s = 0.0, leak_onsets_to_s = 0.0;  ///< the onsets it is over (to the end, if sooner)
};

struct MetricsOptions {
  std::string controller = "recorded";
  std::string profile;
  double boundary_margin_m = 0.2;
  double metric_sample_period_s = 1.0;  ///< spacing of metric_over_time
};

/// Pearson correlation; NaN if either side has zero variance or fewer than 2 entries.
double PearsonCorrelation(const std::vector<double>& a, const std::vector<double>& b);

/// The nearest-rank percentile: the smallest value v of `values` such that at least a fraction q
/// of them are <= v (the ceil(q n)-th smallest; q in (0, 1], q = 1 the maximum). NaN if empty.
/// The p99 of 600 server cycles is the 594th smallest: six cycles took longer.
double NearestRankPercentile(std::vector<double> values, double q);

/// The metrics of a mission computed online, sample by sample, so a running mission can report
/// them at any time (metrics.json every few seconds) and nothing needs the whole trajectory in
/// memory. Each sample stands for the time to the same vehicle's next sample (its hold time);
/// a vehicle's last sample, whose successor never comes, holds for the median spacing seen. The
/// ergodic metric over time is the fleet's time-averaged coverage c_k(T) = sum F_k(x) dt / sum dt
/// of the samples before each checkpoint T against phi_k(T), with a sample still running at T
/// counted only up to it. Samples of one vehicle must come in increasing time; vehicles may
/// interleave, and a sample out of order for its vehicle is refused (counted).
class MetricsAccumulator {
 public:
  /// basis and risk (for phi_k of any weights) must outlive the accumulator.
  MetricsAccumulator(const maps::Scenario& scenario, const maps::SpectralBasis& basis, const maps::RiskField& risk,
                     const MetricsOptions& options = {});
  MetricsAccumulator(const MetricsAccumulator&) = default;
  MetricsAccumulator& operator=(const MetricsAccumulator&) = delete;  // it refers to its scenario, basis and field
  /// Waits for the helpers, which write into this accumulator.
  ~MetricsAccumulator() {
    holds_.Drain();
    coverage_.Drop();
  }

  /// The normalised weights in force from time_s on (the first call sets t = 0's).
  void OnWeights(double time_s, const Eigen::VectorXd& weights);
  /// One sample; returns the valves it visited. A sample before 0, not finite, or not after
  /// its vehicle's previous one is refused (counted, no effect).
  std::vector<int> Add(const TrajectorySample& sample);
  /// A cycle's samples in (time, vehicle) order, as Add takes each: their visits counted at once
  /// (the fleet's guard and the regions' targets read them this cycle), the rest (hold times,
  /// checkpoints, coverage) on a helper thread while the mission's cycle goes on, when there are
  /// at least kHoldBatch of them; whatever reads or changes those waits for it. Bit for bit what
  /// Add gives. Throws std::logic_error before the first OnWeights.
  void AddCycle(const std::vector<TrajectorySample>& samples);
  /// From this many samples a cycle the helper pays: at 10,000 vehicles in one process the
  /// server's cycle went from 20.3 / 18.6 to 16.5 / 14.5 ms; over DDS at 1,000 a thread a cycle
  /// lengthened it (2.09 / 2.19 -> 2.34 / 2.32 ms).
  static constexpr std::size_t kHoldBatch = 2048;
  /// Vehicle `vehicle` sends no more samples (it left or was lost).
  void Retire(int vehicle);
  /// Every sample before time_s has been added: the metric checkpoints up to time_s are taken.
  void Advance(double time_s);
  /// Adds the coverage of the samples held since the last call on a helper thread, if there are
  /// at least kCoverageBatch of them (a mission calls it after each cycle's samples; without it
  /// they are added at the next read). The figures are bit for bit the same either way.
  void LaunchCoverage();
  static constexpr std::size_t kCoverageBatch = 512;

  /// The metrics of [0, end_s] as they stand (a copy is finished; this one goes on).
  MissionMetrics Result(double end_s) const;
  /// The latest checkpoint's ergodic metric (NaN before the first): what a progress line shows.
  double latest_metric() const {
    holds_.Wait();
    return state_.latest_metric;
  }
  /// Samples of the metric over time kept at most: beyond, every other one is dropped and the
  /// spacing doubles, as the run directory's plot copy is thinned (memory and metrics.json stay
  /// the same size however long the mission).
  static constexpr std::size_t kMetricSamplesKept = 4096;
  /// Follows the visits of `valve` around `time_s` (VisitTracker::WatchAround): a risk event's.
  void WatchVisits(int valve, double time_s) { visits_.WatchAround(valve, time_s); }
  const VisitTracker& visits() const { return visits_; }
  std::size_t refused_samples() const { return state_.refused; }

  /// Everything that changes as samples come in, as plain data (a mission's checkpoint).
  struct LastHeld {
    double time_s = 0.0, end_s = 0.0;
    Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  };
  struct State {
    std::map<int, TrajectorySample> pending;  ///< per vehicle, the sample whose hold time is not known yet
    std::map<int, LastHeld> last_held;      ///< per vehicle, the latest sample with a known hold
    std::map<double, std::size_t> spacings; ///< positive spacings seen, with counts (for the median)
    std::vector<double> time_near_s;        ///< per valve
    std::vector<double> watched_until_s;    ///< per valve, when a vehicle was last within the visit radius
    std::vector<double> longest_unwatched_s;  ///< per valve, of the stretches closed so far
    std::vector<double> unwatched_squares_s2; ///< per valve, sum of g^2 of the stretches closed so far
    double time_outside_s = 0.0, time_pinned_s = 0.0;
    Eigen::VectorXd sum_f;                  ///< sum of F_k(x) dt of held samples
    double sum_dt = 0.0;
    std::vector<MetricSample> metric_over_time;  ///< the checkpoints k with k % metric_stride == 0
    int metric_stride = 1;                  ///< doubles whenever metric_over_time outgrows kMetricSamplesKept
    double latest_metric = std::numeric_limits<double>::quiet_NaN();  ///< of the latest checkpoint
    int next_checkpoint = 1;                ///< checkpoint k is at k * metric_sample_period_s
    std::vector<WeightChange> schedule;
    std::size_t refused = 0;
  };
  const State& state() const {
    holds_.Wait();
    SettleCoverage();
    return state_;
  }
  /// Restores a checkpoint's state (and its visits).
  void Restore(State state, VisitTracker visits);

 private:
  // A sample's screening, on the caller's thread: refused (counted) unless at t >= 0, finite and
  // after its vehicle's last accepted sample (throws std::invalid_argument for a vehicle < 0).
  bool Accept(const TrajectorySample& sample);
  // What Add does with an accepted sample besides its visits: the vehicle's previous sample is
  // held until it (checkpoints before it taken first), and it waits for its own hold time.
  void HoldNext(const TrajectorySample& sample);
  void Hold(const TrajectorySample& sample, double dt_s);
  // LaunchCoverage's work, on whichever thread holds the samples (AddCycle's helper included).
  void LaunchQueuedCoverage();
  // Brings state_.sum_f up to date with every held sample (waits for the helper thread).
  void SettleCoverage() const;
  void TakeCheckpointsBefore(double time_s);
  // Checkpoint k's metric: the latest, and kept if k is on the stride (thinning when too many).
  void TakeCheckpoint(int k);
  double MetricAt(double time_s) const;
  double MedianSpacing() const;

  // Where the last lookup of a per-vehicle map landed: a cycle's samples come in ascending
  // vehicle order, so the next one's entry is usually the next element (a search of the map
  // for each of 10,000 vehicles was 15 % of the server's sample accounting). Never copied (a
  // copy's iterators would be into the original's maps); forgotten when its map loses entries.
  template <typename Map>
  class Cursor {
   public:
    Cursor() = default;
    Cursor(const Cursor&) {}
    Cursor& operator=(const Cursor&) {
      valid_ = false;
      return *this;
    }
    void Forget() { valid_ = false; }
    /// The entry of `key` in `map` (map.end() if none).
    typename Map::iterator Find(Map& map, int key) {
      if (valid_ && at_ != map.end()) {
        if (at_->first == key) return at_;
        const auto next = std::next(at_);
        if (next != map.end() && next->first == key) return at_ = next;
      }
      at_ = map.find(key);
      valid_ = at_ != map.end();
      return at_;
    }

   private:
    typename Map::iterator at_{};
    bool valid_ = false;
  };

  // The fleet's coverage sum F_k(x) dt of the held samples, queued and added a batch at a time,
  // on a helper thread when there are many (at 10,000 vehicles and K = 64 a cycle's 41 million
  // terms were a quarter of the server's cycle). Added in the order held, so the sums are bit for
  // bit those of adding each sample at once; whatever reads state_.sum_f settles first. A copy
  // waits for the source's helper and takes its queue.
  class CoverageBacklog {
   public:
    CoverageBacklog() = default;
    CoverageBacklog(const CoverageBacklog& other) : queued_((other.Wait(), other.queued_)) {}
    CoverageBacklog& operator=(const CoverageBacklog& other) {
      if (this != &other) {
        Wait();
        other.Wait();
        queued_ = other.queued_;
      }
      return *this;
    }
    ~CoverageBacklog() { Wait(); }
    void Queue(const Eigen::Vector2d& x_m, double dt_s) { queued_.emplace_back(x_m, dt_s); }
    std::size_t queued() const { return queued_.size(); }
    /// Adds the queue into `sums` on a helper thread, once the previous batch is in.
    void Launch(const maps::SpectralBasis& basis, Eigen::VectorXd& sums);
    /// Waits for the helper, then adds what is still queued: `sums` are complete.
    void Settle(const maps::SpectralBasis& basis, Eigen::VectorXd& sums) const;
    /// Forgets the queue (the sums are being replaced).
    void Drop() {
      Wait();
      queued_.clear();
    }

   private:
    void Wait() const {
      if (job_.valid()) job_.wait();
    }
    mutable std::vector<std::pair<Eigen::Vector2d, double>> queued_;
    std::shared_future<void> job_;
  };

  const maps::Scenario& scenario_;
  const maps::SpectralBasis& basis_;
  const maps::RiskField& risk_;
  MetricsOptions options_;
  std::vector<Eigen::Vector2d> valves_;
  VisitTracker visits_;
  // [vehicle] the time of its last accepted sample (-inf: none): state_.pending's times, kept
  // apart so that AddCycle screens samples while a helper holds the previous cycle's.
  std::vector<double> accepted_until_s_;

  // AddCycle's helper thread: it writes what follows (not visits_, accepted_until_s_ or
  // state_.refused); declared before them, so that a copy waits for the source's helper before
  // it copies them. Wait rethrows what the helper threw.
  class HoldJob {
   public:
    HoldJob() = default;
    HoldJob(const HoldJob& other) { other.Wait(); }
    HoldJob& operator=(const HoldJob&) = delete;
    ~HoldJob() { Drain(); }
    void Launch(std::function<void()> work) {
      Wait();
      job_ = std::async(std::launch::async, std::move(work));
    }
    void Wait() const {
      if (!job_.valid()) return;
      std::future<void> done = std::move(job_);
      done.get();
    }
    void Drain() noexcept {
      if (job_.valid()) job_.wait();
    }

   private:
    mutable std::future<void> job_;
  };
  HoldJob holds_;
  std::vector<int> near_scratch_;
  // Before state_: a copy waits for the source's helper before it copies the sums.
  CoverageBacklog coverage_;
  State state_;
  Cursor<std::map<int, TrajectorySample>> pending_at_;
  Cursor<std::map<int, LastHeld>> held_at_;
  std::vector<Eigen::VectorXd> phi_;  // phi_k of each schedule entry
  mutable Eigen::VectorXd f_;         // scratch
};

/// Fills each risk event's time to the valve's next visit and its revisit interval before and
/// after: metrics.events[i] from visits.watches()[i] (a mission watches each event's valve from
/// the event on, VisitTracker::WatchAround).
void FillEventResponses(const VisitTracker& visits, MissionMetrics& metrics);

/// Fills the fleet figures of `metrics` (expected detection delay, risk-weighted interval,
/// dominant interval, unvisited valves, longest-gap quantiles) from its valves.
void SummariseGaps(MissionMetrics& metrics);

/// Evaluates a trajectory against the scenario's valves and the weight schedule. The mission
/// runs from 0 to duration_s (samples outside are ignored). The ergodic metric uses the
/// scenario's basis order with no forgetting. Throws maps::ScenarioError for a duration that is
/// not finite and > 0, or a period that would ask for more than 1e6 checkpoints.
MissionMetrics ComputeMetrics(const Trajectory& trajectory, const maps::Scenario& scenario,
                              const std::vector<WeightChange>& weights, double duration_s,
                              const MetricsOptions& options = {});

}  // namespace sage::server
