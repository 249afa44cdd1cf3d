// ExpectedDetection: the online expected wait for a leak's first detection against a brute-force
// average over onsets (each onset's wait summed scan by scan), a closed form, and a checkpoint.
#include "server/perception/expected_detection.h"

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
// and what is left undetected waits to the end.
double BruteWait(const std::vector<Scan>& scans, int valve, double t0, double end_s) {
  double undetected = 1.0, wait = 0.0;
  for (const Scan& s : scans) {
    if (s.valve != valve || s.time_s < t0) continue;
    wait += undetected * s.p * (s.time_s - t0);
    undetected *= 1.0 - s.p;
  }
  return wait + undetected * (end_s - t0);
}

// Averaged over onsets by the midpoint rule on 0.5 ms steps; the wait is piecewise linear in t0
// with kinks only at the scans, so the rule's error is below 1e-5 s here.
double BruteMean(const std::vector<Scan>& scans, int valve, double from_s, double to_s, double end_s) {
  const double last = std::min(to_s, end_s);
  const int n = static_cast<int>(std::round((last - from_s) / 0.0005));
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += BruteWait(scans, valve, from_s + (i + 0.5) * (last - from_s) / n, end_s);
  return sum / n;
}

std::vector<Scan> RandomScans(std::uint32_t seed, int valves, double end_s) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Scan> scans;
  // 5 Hz; a valve is in view in bursts (a pass), with p from 0.1 to 0.9, and now and then twice a
  // scan (two sensors).
  for (double t = 0.0; t <= end_s + 1e-9; t += 0.2) {
    for (int v = 0; v < valves; ++v) {
      if (unit(rng) < 0.15) scans.push_back({t, v, 0.1 + 0.8 * unit(rng)});
      if (unit(rng) < 0.02) scans.push_back({t, v, 0.3});
    }
  }
  return scans;
}

// The online waits equal the brute-force average over onsets, valve by valve, for missions that
// end after the onsets' window and inside it (only the onsets before the end count).
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
      EXPECT_NEAR(waits[static_cast<std::size_t>(v)], brute, 1e-5) << "valve " << v << ", end " << end_s;
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
}

// A checkpoint taken mid-mission and restored into a new one goes on to the same waits, bit for
// bit; a state of another size or with a probability out of range is refused; so are a scan
// earlier than the valve's last and a p outside [0, 1].
TEST(ExpectedDetection, CheckpointAndRefusals) {
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
  bad.blocks[0].push_back({1.0, 2.0, 1.5});
  EXPECT_THROW(second.Restore(bad), std::invalid_argument);
  EXPECT_THROW(whole.Look(0, 10.0, 0.5), std::invalid_argument);  // its last look was at 50 s
  EXPECT_THROW(whole.Look(0, 60.0, 1.5), std::invalid_argument);
  EXPECT_THROW(whole.Look(5, 60.0, 0.5), std::invalid_argument);
  EXPECT_THROW(ExpectedDetection(1, 10.0, 10.0), std::invalid_argument);
}

}  // namespace
}  // namespace sage::server
