// leaks.json, leaks.md and leaks.svg of `sage bench leaks`.
#include "server/report/leak_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <map>
#include <random>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/atomic_write.h"
#include "server/report/plots/nice_scale.h"
#include "server/report/plots/svg_writer.h"

namespace sage::server {
// Internals in a named namespace: this file shares a unity batch with the other report writers.
namespace leak_report_internal {

using Json = nlohmann::ordered_json;

Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// The nearest-rank percentile of times where a NaN (never) is later than any time; NaN if the
// rank falls on a never or there is nothing.
double RankWithNever(std::vector<double> times, double q) {
  if (times.empty()) return std::nan("");
  std::sort(times.begin(), times.end(), [](double a, double b) {
    return std::isnan(b) ? !std::isnan(a) : (!std::isnan(a) && a < b);
  });
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(times.size())));
  return times[std::clamp<std::size_t>(rank, 1, times.size()) - 1];
}

double Mean(const std::vector<double>& values) {
  double sum = 0.0;
  int n = 0;
  for (double v : values) {
    if (std::isfinite(v)) {
      sum += v;
      ++n;
    }
  }
  return n > 0 ? sum / n : std::nan("");
}

std::string Seconds(double s) { return std::isfinite(s) ? fmt::format("{:.1f} s", s) : std::string("never"); }
std::string Plain(double v, const char* format = "{:.2f}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string("-");
}

// A colour per configuration, in plot.svg's palette.
const char* Colour(std::size_t k) {
  static const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
  return kPalette[k % (sizeof kPalette / sizeof kPalette[0])];
}

}  // namespace leak_report_internal

namespace lr = leak_report_internal;

LeakPairing PairDetections(const std::vector<LeakRun>& runs, const std::string& config, const std::string& baseline) {
  LeakPairing out;
  // The same leak under both: its run, site and onset (a run may hide several leaks).
  using Key = std::tuple<int, std::string, double>;
  std::map<Key, double> base, mine;
  for (const LeakRun& r : runs) {
    if (r.config == baseline) base[{r.run, r.where, r.start_s}] = r.detected_s - r.start_s;
    else if (r.config == config) mine[{r.run, r.where, r.start_s}] = r.detected_s - r.start_s;
  }
  std::vector<std::pair<double, double>> matched;  // (config, baseline), NaN = never
  for (const auto& [key, t] : mine) {
    const auto other = base.find(key);
    if (other != base.end()) matched.emplace_back(t, other->second);
  }
  std::vector<double> differences;
  double sooner = 0.0, tied = 0.0;
  for (const auto& [a, b] : matched) {
    if (std::isfinite(a) && std::isfinite(b)) {
      differences.push_back(a - b);
      sooner += a < b ? 1.0 : 0.0;
      tied += a == b ? 1.0 : 0.0;
    } else if (std::isfinite(a)) {
      ++out.only_config;
    } else if (std::isfinite(b)) {
      ++out.only_baseline;
    }
  }
  out.pairs = static_cast<int>(differences.size());
  if (differences.empty()) return out;
  const double n = static_cast<double>(differences.size());
  out.mean_difference_s = lr::Mean(differences);
  out.sooner_share = sooner / n;
  out.tied_share = tied / n;
  if (out.pairs >= LeakPairing::kLeastPairs) {
    double squares = 0.0;
    for (double d : differences) squares += (d - out.mean_difference_s) * (d - out.mean_difference_s);
    out.mean_half_width_s = 1.96 * std::sqrt(squares / (n - 1.0)) / std::sqrt(n);
  }
  if (out.pairs >= LeakPairing::kLeastPairs && static_cast<std::size_t>(out.pairs) == matched.size()) {
    const auto p90_difference = [](const std::vector<std::pair<double, double>>& sample) {
      std::vector<double> a, b;
      for (const auto& [x, y] : sample) {
        a.push_back(x);
        b.push_back(y);
      }
      return lr::RankWithNever(a, 0.9) - lr::RankWithNever(b, 0.9);
    };
    out.p90_difference_s = p90_difference(matched);
    std::mt19937_64 rng(0x5A6E);  // a fixed seed: the same runs, the same interval
    std::uniform_int_distribution<std::size_t> pick(0, matched.size() - 1);
    std::vector<double> resampled;
    std::vector<std::pair<double, double>> sample(matched.size());
    for (int k = 0; k < LeakPairing::kResamples; ++k) {
      for (auto& pair : sample) pair = matched[pick(rng)];
      resampled.push_back(p90_difference(sample));
    }
    std::sort(resampled.begin(), resampled.end());
    out.p90_low_s = resampled[static_cast<std::size_t>(0.025 * LeakPairing::kResamples)];
    out.p90_high_s = resampled[static_cast<std::size_t>(0.975 * LeakPairing::kResamples) - 1];
  }
  return out;
}

std::string PairingText(const LeakPairing& p) {
  if (p.pairs == 0) return "no leak detected under both";
  const auto signed_s = [](double v) { return fmt::format("{:+.1f} s", v); };
  std::string out = signed_s(p.mean_difference_s);
  out += std::isfinite(p.mean_half_width_s) ? fmt::format(" ± {:.1f} s (95 %, {} pairs)", p.mean_half_width_s, p.pairs)
                                            : fmt::format(" ({} pairs: too few for an interval)", p.pairs);
  out += fmt::format(", sooner in {:.0f} %", 100.0 * p.sooner_share);
  if (p.tied_share > 0.0) out += fmt::format(", as soon in {:.0f} %", 100.0 * p.tied_share);
  if (std::isfinite(p.p90_difference_s)) {
    out += fmt::format("; p90 {} ({} .. {})", signed_s(p.p90_difference_s), signed_s(p.p90_low_s), signed_s(p.p90_high_s));
  }
  if (p.only_config + p.only_baseline > 0) {
    out += fmt::format("; detected under one only: {} / {}", p.only_config, p.only_baseline);
  }
  return out;
}

std::vector<LeakSummary> SummariseLeakRuns(const std::vector<LeakRun>& runs, const std::vector<std::string>& configs,
                                           const std::vector<std::string>& descriptions) {
  std::vector<LeakSummary> out;
  for (std::size_t c = 0; c < configs.size(); ++c) {
    LeakSummary s;
    s.config = configs[c];
    s.description = c < descriptions.size() ? descriptions[c] : configs[c];
    std::vector<double> detection, confirmation, visits, alarms, false_confirmed;
    std::map<int, bool> run_seen;
    for (const LeakRun& r : runs) {
      if (r.config != s.config) continue;
      ++s.leaks;
      if (!run_seen[r.run]) {
        run_seen[r.run] = true;
        alarms.push_back(r.false_alarms);
        false_confirmed.push_back(r.false_alarms_confirmed);
      }
      const double to_detection = r.detected_s - r.start_s, to_confirmation = r.confirmed_s - r.start_s;
      detection.push_back(to_detection);
      confirmation.push_back(to_confirmation);
      if (std::isfinite(to_detection)) ++s.detected;
      if (std::isfinite(to_confirmation)) ++s.confirmed;
      if (r.at_valve && std::isfinite(r.visits_per_min_after_detection)) visits.push_back(r.visits_per_min_after_detection);
    }
    s.runs = static_cast<int>(run_seen.size());
    s.detection_mean_s = lr::Mean(detection);
    s.detection_median_s = lr::RankWithNever(detection, 0.5);
    s.detection_p90_s = lr::RankWithNever(detection, 0.9);
    s.detection_max_s = lr::RankWithNever(detection, 1.0);
    s.confirmation_mean_s = lr::Mean(confirmation);
    s.confirmation_p90_s = lr::RankWithNever(confirmation, 0.9);
    s.visits_per_min_after_detection = lr::Mean(visits);
    s.false_alarms_per_run = lr::Mean(alarms);
    s.false_confirmations_per_run = lr::Mean(false_confirmed);
    out.push_back(s);
  }
  return out;
}

std::string LeakBenchJson(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                          const std::string& baseline) {
  lr::Json sums = lr::Json::array();
  for (const LeakSummary& s : summaries) {
    sums.push_back({{"config", s.config},
                    {"description", s.description},
                    {"runs", s.runs},
                    {"leaks", s.leaks},
                    {"detected", s.detected},
                    {"confirmed", s.confirmed},
                    {"time_to_detection_s", {{"mean", lr::Number(s.detection_mean_s)},
                                             {"median", lr::Number(s.detection_median_s)},
                                             {"p90", lr::Number(s.detection_p90_s)},
                                             {"max", lr::Number(s.detection_max_s)}}},
                    {"time_to_confirmation_s", {{"mean", lr::Number(s.confirmation_mean_s)}, {"p90", lr::Number(s.confirmation_p90_s)}}},
                    {"visits_per_min_after_detection", lr::Number(s.visits_per_min_after_detection)},
                    {"false_alarms_per_run", lr::Number(s.false_alarms_per_run)},
                    {"false_confirmations_per_run", lr::Number(s.false_confirmations_per_run)}});
    if (baseline.empty() || s.config == baseline) continue;
    const LeakPairing p = PairDetections(runs, s.config, baseline);
    sums.back()["against_baseline"] = {{"baseline", baseline},
                                       {"pairs", p.pairs},
                                       {"detected_only_here", p.only_config},
                                       {"detected_only_by_baseline", p.only_baseline},
                                       {"mean_difference_s", lr::Number(p.mean_difference_s)},
                                       {"mean_half_width_95_s", lr::Number(p.mean_half_width_s)},
                                       {"sooner_share", lr::Number(p.sooner_share)},
                                       {"tied_share", lr::Number(p.tied_share)},
                                       {"p90_difference_s", lr::Number(p.p90_difference_s)},
                                       {"p90_difference_95_s", {lr::Number(p.p90_low_s), lr::Number(p.p90_high_s)}}};
  }
  lr::Json all = lr::Json::array();
  for (const LeakRun& r : runs) {
    all.push_back({{"config", r.config},
                   {"run", r.run},
                   {"seed", r.seed},
                   {"where", r.where},
                   {"at_valve", r.at_valve},
                   {"start_s", lr::Number(r.start_s)},
                   {"detected_s", lr::Number(r.detected_s)},
                   {"confirmed_s", lr::Number(r.confirmed_s)},
                   {"detections", r.detections},
                   {"visits_per_min_after_detection", lr::Number(r.visits_per_min_after_detection)},
                   {"false_alarms", r.false_alarms},
                   {"false_alarms_cleared", r.false_alarms_cleared},
                   {"false_alarms_confirmed", r.false_alarms_confirmed},
                   {"duration_s", lr::Number(r.duration_s)},
                   {"wall_s", lr::Number(r.wall_s)}});
  }
  return lr::Json{{"summaries", sums}, {"runs", all}}.dump(2) + "\n";
}

std::string LeakBenchTable(const std::vector<LeakSummary>& summaries) {
  std::string out =
      "| configuration | leaks | detected | detection mean | median | p90 | max | confirmed | confirmation mean | p90 | "
      "visits/min after detection | false alarms / run | false confirmations / run |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const LeakSummary& s : summaries) {
    out += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", s.description, s.leaks,
                       s.detected, lr::Seconds(s.detection_mean_s), lr::Seconds(s.detection_median_s), lr::Seconds(s.detection_p90_s),
                       lr::Seconds(s.detection_max_s), s.confirmed, lr::Seconds(s.confirmation_mean_s),
                       lr::Seconds(s.confirmation_p90_s), lr::Plain(s.visits_per_min_after_detection),
                       lr::Plain(s.false_alarms_per_run), lr::Plain(s.false_confirmations_per_run));
  }
  return out;
}

std::string LeakBenchTerminalTable(const std::vector<LeakSummary>& summaries) {
  // Times without their unit (the group header says s); a leak never detected where it sets the rank.
  const auto t = [](double s) { return std::isfinite(s) ? fmt::format("{:.1f}", s) : std::string("never"); };
  constexpr const char* kRow = "{:<10} {:>5} {:>5} {:>6} {:>6} {:>6} {:>6} {:>5} {:>6} {:>6} {:>10} {:>9}\n";
  // The groups over their columns: detection from "found" to "max", confirmation to its "p90".
  std::string out = fmt::format("{:<17}{:<34}{}\n", "", "detected (s from onset):", "confirmed (s):");
  out += fmt::format(fmt::runtime(kRow), "config", "leaks", "found", "mean", "median", "p90", "max", "found", "mean",
                     "p90", "visits/min", "false/run");
  for (const LeakSummary& s : summaries) {
    out += fmt::format(fmt::runtime(kRow), s.config.substr(0, 10), s.leaks, s.detected, t(s.detection_mean_s),
                       t(s.detection_median_s), t(s.detection_p90_s), t(s.detection_max_s), s.confirmed,
                       t(s.confirmation_mean_s), t(s.confirmation_p90_s), lr::Plain(s.visits_per_min_after_detection),
                       lr::Plain(s.false_alarms_per_run));
  }
  for (const LeakSummary& s : summaries) out += fmt::format("  {}: {}\n", s.config, s.description);
  return out;
}

std::string LeakBenchMarkdown(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                              const std::string& preamble, const std::string& baseline) {
  std::string out = "# sage bench leaks: time to detect a hidden leak\n\n" + preamble + "\n\n" + LeakBenchTable(summaries);
  const auto base = std::find_if(summaries.begin(), summaries.end(), [&](const LeakSummary& s) { return s.config == baseline; });
  if (base != summaries.end()) {
    out += "\nAgainst " + base->description + ":\n\n| configuration | detection mean | detection p90 | visits/min after detection | "
           "time to detection, leak by leak (minus the baseline's) |\n|---|---:|---:|---:|---|\n";
    for (const LeakSummary& s : summaries) {
      if (s.config == baseline) continue;
      const auto ratio = [](double a, double b) { return std::isfinite(a) && std::isfinite(b) && b > 0.0 ? fmt::format("{:.2f}x", a / b) : std::string("-"); };
      // The means are over the leaks each detected: fewer found can read as sooner, so say so.
      std::string mean_ratio = ratio(s.detection_mean_s, base->detection_mean_s);
      if (s.detected != base->detected || s.leaks != base->leaks) {
        mean_ratio += fmt::format(" (of {} / {} detected against {} / {})", s.detected, s.leaks, base->detected, base->leaks);
      }
      out += fmt::format("| {} | {} | {} | {} | {} |\n", s.description, mean_ratio,
                         ratio(s.detection_p90_s, base->detection_p90_s),
                         ratio(s.visits_per_min_after_detection, base->visits_per_min_after_detection),
                         PairingText(PairDetections(runs, s.config, baseline)));
    }
  }
  out +=
      "\nColumns: *leaks* hidden in all runs (one mission per run and configuration; the runs of every configuration "
      "meet the same leaks at the same onsets, with the same seeds); *detected*: a detection within the association "
      "radius after the onset before the end; times are from the onset; *mean* over the leaks detected; *median*, "
      "*p90*, *max* are nearest-rank over all leaks, a leak never detected counting as later than any (\"never\" when "
      "it sets the rank); *confirmed*: the server's posterior at the leak reached fusion.confirm_probability; "
      "*visits/min after detection*: visits to a leaking valve from its detection to the end, mean over the valve "
      "leaks detected 30 s or more before the end (a shorter stretch gives no rate; a vehicle that stays within the "
      "re-arm radius counts no new visit); *false alarms*: alarms raised (posterior at fusion.alarm_probability) where no leak had started, "
      "and those that reached the confirmation probability; *leak by leak*: each leak's time to detection under the "
      "configuration minus under the baseline, over the leaks both detected (mean, its 95 % interval, the share "
      "detected sooner and, if any, the share detected at the same scan), and the difference of the p90s with a 95 % interval from a paired bootstrap of the leaks "
      "(when both detected every leak): an interval that excludes 0 is a difference the runs show, not noise.\n";
  return out;
}

std::string LeakBenchSvg(const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                         const std::string& title) {
  constexpr double kLeft = 70.0, kTop = 60.0, kW = 560.0, kH = 320.0;
  constexpr double kWidthPx = kLeft + kW + 260.0, kHeightPx = kTop + kH + 70.0;
  double longest = 1.0;
  for (const LeakRun& r : runs) {
    if (std::isfinite(r.detected_s - r.start_s)) longest = std::max(longest, r.detected_s - r.start_s);
  }
  // The time axis on the plots' nice steps (1, 2 or 5 times a power of ten), ending at the first
  // step at or past the longest time (24.8 s: 25 s, where a round end of its own had been 50 s).
  const double x_step = plots::LinearTicks(0.0, longest, 10).step;
  const double x_max = x_step * std::ceil(longest / x_step - 1e-9);
  const auto px = [&](double t) { return kLeft + kW * t / x_max; };
  const auto py = [&](double f) { return kTop + kH * (1.0 - f); };
  fmt::memory_buffer out;
  const auto put = [&]<typename... A>(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(out), format, std::forward<A>(args)...);
  };
  put("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
      "font-family=\"sans-serif\">\n", kWidthPx, kHeightPx, kWidthPx, kHeightPx);
  put("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  put("<text x=\"{}\" y=\"28\" font-size=\"15\">{}</text>\n", kLeft, plots::XmlEscape(title));
  put("<text x=\"{}\" y=\"46\" font-size=\"12\">fraction of leaks detected by a time after their onset</text>\n", kLeft);
  const int x_ticks = static_cast<int>(std::lround(x_max / x_step));
  for (int k = 0; k <= x_ticks; ++k) {
    const double t = x_step * k;
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e5e5e5\"/>\n", px(t), kTop, px(t), kTop + kH);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"middle\">{}</text>\n", px(t), kTop + kH + 16.0,
        plots::TickLabel(t, x_step));
  }
  for (int k = 0; k <= 10; ++k) {
    const double f = k / 10.0;
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e5e5e5\"/>\n", kLeft, py(f), kLeft + kW, py(f));
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" text-anchor=\"end\">{:g}</text>\n", kLeft - 6.0, py(f) + 4.0, f);
  }
  put("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#999\"/>\n", kLeft, kTop, kW, kH);
  put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" text-anchor=\"middle\">time from onset to first detection (s)</text>\n",
      kLeft + 0.5 * kW, kTop + kH + 36.0);
  for (std::size_t c = 0; c < summaries.size(); ++c) {
    const LeakSummary& s = summaries[c];
    std::vector<double> times;
    for (const LeakRun& r : runs) {
      if (r.config == s.config && std::isfinite(r.detected_s - r.start_s)) times.push_back(r.detected_s - r.start_s);
    }
    std::sort(times.begin(), times.end());
    const double n = std::max(1, s.leaks);
    // The empirical CDF as a staircase; it ends below 1 by the share never detected.
    put("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" points=\"{:.1f},{:.1f} ", lr::Colour(c), px(0.0), py(0.0));
    for (std::size_t k = 0; k < times.size(); ++k) {
      put("{:.1f},{:.1f} {:.1f},{:.1f} ", px(times[k]), py(k / n), px(times[k]), py((k + 1) / n));
    }
    put("{:.1f},{:.1f}\"/>\n", px(x_max), py(static_cast<double>(times.size()) / n));
    const double ly = kTop + 16.0 + 20.0 * static_cast<double>(c);
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"3\"/>\n", kLeft + kW + 16.0,
        ly, kLeft + kW + 40.0, ly, lr::Colour(c));
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\">{} ({}/{})</text>\n", kLeft + kW + 46.0, ly + 4.0, plots::XmlEscape(s.description),
        s.detected, s.leaks);
  }
  put("</svg>\n");
  return fmt::to_string(out);
}

void WriteLeakBench(const std::string& dir, const std::vector<LeakSummary>& summaries, const std::vector<LeakRun>& runs,
                    const std::string& preamble, const std::string& baseline, const std::string& title) {
  const std::filesystem::path root(dir);
  detail::WriteAtomically((root / "leaks.json").string(), LeakBenchJson(summaries, runs, baseline));
  detail::WriteAtomically((root / "leaks.md").string(), LeakBenchMarkdown(summaries, runs, preamble, baseline));
  detail::WriteAtomically((root / "leaks.svg").string(), LeakBenchSvg(summaries, runs, title));
}

}  // namespace sage::server
