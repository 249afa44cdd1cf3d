// ExpectedDetection: the online expected wait for a leak's first detection against a brute-force
// average over onsets (each onset's wait summed scan by scan), a closed form, and a checkpoint.
#include "server/perception/expected_detection.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace sage::server {
namespace {

struct Scan {
  double time_s;
  int valve;
  double p;
};

// The wait of an onset t0 at one valve, scan by scan: sum_j (t_j - t0) p_j prod_{l<j} (1 - p_l),
// and what is left undetected waits to the end. A scan older than the valve's latest so far
// counts as made at that latest (as ExpectedDetection::Look says).
double BruteWait(const std::vector<Scan>& scans, int valve, double t0, double end_s) {
  double undetected = 1.0, wait = 0.0, latest = -1e300;
  for (const Scan& s : scans) {
    if (s.valve != valve) continue;
    latest = std::max(latest, s.time_s);
    if (latest < t0) continue;
    wait += undetected * s.p * (latest - t0);
    undetected *= 1.0 - s.p;
  }
  return wait + undetected * (end_s - t0);
}

// Averaged over onsets exactly: between two consecutive (effective) scan times the wait is
// linear in t0, so each piece's integral is its length times the wait at its midpoint.
double BruteMean(const std::vector<Scan>& scans, int valve, double from_s, double to_s, double end_s) {
  const double last = std::min(to_s, end_s);
  std::vector<double> cuts = {from_s, last};
  double latest = -1e300;
  for (const Scan& s : scans) {
    if (s.valve != valve) continue;
    latest = std::max(latest, s.time_s);
    if (latest > from_s && latest < last) cuts.push_back(latest);
  }
  std::sort(cuts.begin(), cuts.end());
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    if (cuts[i + 1] > cuts[i]) sum += (cuts[i + 1] - cuts[i]) * BruteWait(scans, valve, 0.5 * (cuts[i] + cuts[i + 1]), end_s);
  }
  return sum / (last - from_s);
}

std::vector<Scan> RandomScans(std::uint32_t seed, int valves, double end_s) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Scan> scans;
  // 5 Hz; a valve is in view in bursts (a pass), with p from 0.1 to 0.9, and now and then twice a
  // scan (two sensors), or a scan of another vehicle fused up to 0.6 s late.
  for (int i = 0; i <= static_cast<int>(std::lround(5.0 * end_s)); ++i) {
    const double t = i / 5.0;
    for (int v = 0; v < valves; ++v) {
      if (unit(rng) < 0.15) scans.push_back({t, v, 0.1 + 0.8 * unit(rng)});
      if (unit(rng) < 0.02) scans.push_back({t, v, 0.3});
      if (unit(rng) < 0.02) scans.push_back({std::max(0.0, t - 0.6 * unit(rng)), v, 0.5});
    }
  }
  return scans;
}

// The online waits equal the brute-force average over onsets, valve by valve, for missions that
// end after the onsets' window and inside it (only the onsets before the end count), late scans
// included.
TEST(ExpectedDetection, EqualsTheAverageOverOnsetsScanByScan) {
  constexpr int kValves = 3;
  for (const double end_s : {60.0, 40.0}) {
    const std::vector<Scan> scans = RandomScans(3, kValves, end_s);
    ExpectedDetection online(kValves, 6.0, 54.0);
    for (const Scan& s : scans) online.Look(s.valve, s.time_s, s.p);
    const std::vector<double> waits = online.Waits(end_s);
    ASSERT_EQ(waits.size(), static_cast<std::size_t>(kValves));
    for (int v = 0; v < kValves; ++v) {
      const double brute = BruteMean(scans, v, 6.0, 54.0, end_s);
      EXPECT_NEAR(waits[static_cast<std::size_t>(v)], brute, 1e-9 * brute) << "valve " << v << ", end " << end_s;
      EXPECT_GT(brute, 0.1);  // a real wait, not a trivial one
    }
  }
}

// Closed forms: a valve seen for certain every T waits T / 2 on average; one never seen waits to
// the end, (end - from) - (to - from) / 2 for onsets uniform in [from, to]; a valve seen with
// p = 1/2 every T waits T / 2 + T (the geometric number of extra scans, mean 1, at T each).
TEST(ExpectedDetection, ClosedForms) {
  ExpectedDetection d(3, 10.0, 90.0);
  for (double t = 0.0; t <= 200.0 + 1e-9; t += 4.0) {
    d.Look(0, t, 1.0);
    d.Look(2, t, 0.5);
  }
  const std::vector<double> w = d.Waits(200.0);
  EXPECT_NEAR(w[0], 2.0, 1e-9);
  EXPECT_NEAR(w[1], 200.0 - 50.0, 1e-9);
  EXPECT_NEAR(w[2], 2.0 + 4.0, 1e-6);  // a leak of 90 s still undetected at 200 s: 2^-27
  EXPECT_TRUE(std::isnan(ExpectedDetection(1, 10.0, 90.0).Waits(5.0)[0]));  // no onset yet
  // Valve 1 was never looked at: its wait is only the time left to the end, and it says so.
  EXPECT_TRUE(d.LookedAt(0));
  EXPECT_FALSE(d.LookedAt(1));
  EXPECT_TRUE(d.LookedAt(2));
  ExpectedDetection early(2, 10.0, 90.0);
  early.Look(0, 5.0, 1.0);   // before any onset
  early.Look(1, 50.0, 0.0);  // could not have seen it
  EXPECT_FALSE(early.LookedAt(0));
  EXPECT_FALSE(early.LookedAt(1));
  early.Look(1, 50.0, 0.01);
  EXPECT_TRUE(early.LookedAt(1));
  EXPECT_THROW(early.LookedAt(2), std::invalid_argument);
}

// A checkpoint taken mid-mission and restored into a new one goes on to the same waits, bit for
// bit; a state of another size or with a negative undetected length is refused; so are a p
// outside [0, 1] and a valve out of range. A late scan (another vehicle's, fused cycles later)
// counts as made at the valve's last look, never refused (a server had died of it); and an end
// before a valve's last look says nothing (NaN).
TEST(ExpectedDetection, CheckpointLateScansAndRefusals) {
  const std::vector<Scan> scans = RandomScans(8, 2, 50.0);
  ExpectedDetection whole(2, 5.0, 45.0), first(2, 5.0, 45.0), second(2, 5.0, 45.0);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    whole.Look(scans[i].valve, scans[i].time_s, scans[i].p);
    if (i < scans.size() / 2) first.Look(scans[i].valve, scans[i].time_s, scans[i].p);
  }
  second.Restore(first.Checkpoint());
  EXPECT_EQ(second.Checkpoint(), first.Checkpoint());
  for (std::size_t i = scans.size() / 2; i < scans.size(); ++i) second.Look(scans[i].valve, scans[i].time_s, scans[i].p);
  EXPECT_EQ(second.Waits(50.0), whole.Waits(50.0));
  ExpectedDetection::State wrong = first.Checkpoint();
  wrong.wait_sums.pop_back();
  EXPECT_THROW(second.Restore(wrong), std::invalid_argument);
  ExpectedDetection::State bad = first.Checkpoint();
  bad.undetected_s[0] = -1.0;
  EXPECT_THROW(second.Restore(bad), std::invalid_argument);

  ExpectedDetection late(1, 0.0, 10.0), on_time(1, 0.0, 10.0);
  for (ExpectedDetection* d : {&late, &on_time}) d->Look(0, 6.0, 0.5);
  late.Look(0, 4.0, 0.5);  // fused after the 6 s scan
  on_time.Look(0, 6.0, 0.5);
  EXPECT_EQ(late.Checkpoint(), on_time.Checkpoint());
  EXPECT_TRUE(std::isnan(late.Waits(5.0)[0]));
  EXPECT_FALSE(std::isnan(late.Waits(6.0)[0]));

  EXPECT_THROW(whole.Look(0, 60.0, 1.5), std::invalid_argument);
  EXPECT_THROW(whole.Look(5, 60.0, 0.5), std::invalid_argument);
  EXPECT_THROW(ExpectedDetection(1, 10.0, 10.0), std::invalid_argument);
}

}  // namespace
}  // namespace sage::server
