#pragma once
// What `sage bench leaks` leaves in its output directory: leaks.json (every run of every
// configuration, and the summaries), leaks.md (the summaries as a Markdown table, with what each
// column means) and leaks.svg (the distribution of the time from a leak's onset to its first
// detection: one empirical CDF per configuration). The runs are flown by server/app/bench_leaks;
// here they are only summarised and turned into text and files.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace sage::server {

/// One hidden leak of one Monte Carlo run under one configuration. NaN = never (or not a valve).
struct LeakRun {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string config;     ///< e.g. "bayes", "astar", "fixed equal"
  int run = 0;            ///< 0.. of the Monte Carlo
  std::uint64_t seed = 0; ///< the mission's (and the leak's) seed
  std::string where;      ///< the leak's valve or seabed point
  bool at_valve = false;
  double start_s = kNaN;
  double detected_s = kNaN, confirmed_s = kNaN;
  double visits_per_min_after_detection = kNaN;
  int detections = 0;
  int false_alarms = 0, false_alarms_confirmed = 0, false_alarms_cleared = 0;
  double duration_s = kNaN;
  double wall_s = kNaN;
};

/// A configuration's runs summarised. Times from onset (s); percentiles count a leak never
/// detected as later than any (so a p90 is "never" when more than a tenth went undetected).
struct LeakSummary {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string config;
  std::string description;
  int leaks = 0, detected = 0, confirmed = 0;
  double detection_mean_s = kNaN;    ///< over the leaks detected
  double detection_median_s = kNaN, detection_p90_s = kNaN, detection_max_s = kNaN;
  double confirmation_mean_s = kNaN, confirmation_p90_s = kNaN;
  double visits_per_min_after_detection = kNaN;  ///< mean over valve leaks detected
  double false_alarms_per_run = kNaN, false_confirmations_per_run = kNaN;
  int runs = 0;
};

/// A configuration's times to detection against a baseline's, leak by leak: every configuration
/// meets the same leaks (the same run, site and onset), so the difference of each leak's two
/// times is what the configuration changed, and its interval says whether the runs show a
/// difference or noise (on two_xt, 200 runs: the ergodic loop's mean +0.6 s +- 0.9 s against the
/// tour, not shown; its p90 +2.8 s, 1.1 .. 4.9 s, shown).
struct LeakPairing {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  int pairs = 0;                          ///< leaks detected under both
  int only_config = 0, only_baseline = 0; ///< leaks detected under one of the two only
  double mean_difference_s = kNaN;        ///< config - baseline, over the pairs
  /// Half the 95 % interval of that mean: 1.96 sd / sqrt(pairs); NaN below kLeastPairs pairs.
  double mean_half_width_s = kNaN;
  double sooner_share = kNaN;             ///< share of the pairs detected sooner under config
  double tied_share = kNaN;               ///< share of the pairs detected at the same time (the same scan)
  /// p90 of config minus p90 of baseline over all the leaks, and its 95 % interval from a paired
  /// bootstrap (kResamples resamples of the leaks, a fixed seed); NaN unless both detected every leak
  /// and there are kLeastPairs of them.
  double p90_difference_s = kNaN, p90_low_s = kNaN, p90_high_s = kNaN;
  static constexpr int kLeastPairs = 30;
  static constexpr int kResamples = 2000;
};
/// Pairs config's leaks with baseline's by (run, site, onset); leaks of either without a partner are left out.
LeakPairing PairDetections(const std::vector<LeakRun>& runs, const std::string& config, const std::string& baseline);
/// One line for the terminal and leaks.md, e.g. "+0.6 s ± 0.3 s (95 %, 200 pairs), sooner in 41 %; p90 +2.8 s (+1.1 .. +4.0)".
std::string PairingText(const LeakPairing& pairing);

/// Summaries of `runs` per configuration, in the order `configs` names them (descriptions alike).
std::vector<LeakSummary> SummariseLeakRuns(const std::vector<LeakRun>& runs, const std::vector<std::string>& configs,
                                           const std::vector<std::string>& descriptions);
/// leaks.json: {"summaries": [...], "runs": [...]}; each summary but the baseline's (a config name;
/// empty: none) with "against_baseline", its PairDetections.
std::string LeakBenchJson(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                          const std::string& baseline = "");
/// leaks.md: a heading, `preamble`, the summary table, ratios and the leak-by-leak differences
/// (PairDetections) against `baseline` (a config name; empty: none) and what each column means.
std::string LeakBenchMarkdown(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                              const std::string& preamble, const std::string& baseline);
/// The summary table alone, in Markdown (leaks.md's; 150-190 columns).
std::string LeakBenchTable(const std::vector<LeakSummary>& summaries);
/// The summary for a terminal: aligned columns within 100, by configuration name (its description
/// on a line of its own below), times in seconds from each leak's onset.
std::string LeakBenchTerminalTable(const std::vector<LeakSummary>& summaries);
/// leaks.svg: the empirical CDF of time to first detection, one line per configuration.
std::string LeakBenchSvg(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                         const std::string& title);
/// Writes DIR/leaks.json, leaks.md and leaks.svg, each atomically. Throws std::runtime_error naming the file.
void WriteLeakBench(const std::string& dir, const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                    const std::string& preamble, const std::string& baseline, const std::string& title);

}  // namespace sage::server
