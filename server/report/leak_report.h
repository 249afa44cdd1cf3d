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

/// Summaries of `runs` per configuration, in the order `configs` names them (descriptions alike).
std::vector<LeakSummary> SummariseLeakRuns(const std::vector<LeakRun>& runs, const std::vector<std::string>& configs,
                                           const std::vector<std::string>& descriptions);
/// leaks.json: {"summaries": [...], "runs": [...]}.
std::string LeakBenchJson(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs);
/// leaks.md: a heading, `preamble`, the summary table, ratios against `baseline` (a config name;
/// empty: none) and what each column means.
std::string LeakBenchMarkdown(const std::vector<LeakSummary>& summaries, const std::string& preamble,
                              const std::string& baseline);
/// The summary table alone (for the terminal).
std::string LeakBenchTable(const std::vector<LeakSummary>& summaries);
/// leaks.svg: the empirical CDF of time to first detection, one line per configuration.
std::string LeakBenchSvg(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                         const std::string& title);
/// Writes DIR/leaks.json, leaks.md and leaks.svg, each atomically. Throws std::runtime_error naming the file.
void WriteLeakBench(const std::string& dir, const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                    const std::string& preamble, const std::string& baseline, const std::string& title);

}  // namespace sage::server
