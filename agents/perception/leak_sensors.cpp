#include "agents/perception/leak_sensors.h"

#include <algorithm>
#include <cmath>

namespace sage::agents {
namespace {

std::uint64_t KeyedSplitMix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Stream tags: what a draw is for.
constexpr std::uint64_t kLeakStream = 1, kClutterStream = 2;
// Tries to place a false alarm in view (an occluded or off-workspace point is drawn again).
constexpr int kClutterTries = 8;

}  // namespace

KeyedRandom::KeyedRandom(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d, std::uint64_t e) {
  std::uint64_t s = 0x5AFE5EA5u;
  for (const std::uint64_t k : {a, b, c, d, e}) {
    s ^= k;
    s = KeyedSplitMix(s);
  }
  state_ = s;
}

std::uint64_t KeyedRandom::Next() { return KeyedSplitMix(state_); }
double KeyedRandom::Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
double KeyedRandom::Gaussian() {
  const double u1 = 1.0 - Uniform();  // (0, 1]
  const double u2 = Uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}
int KeyedRandom::Poisson(double mean) {
  if (!(mean > 0.0)) return 0;
  const double u = Uniform();
  double p = std::exp(-mean), cumulative = p;
  int k = 0;
  while (u >= cumulative && k < 64) {
    ++k;
    p *= mean / k;
    cumulative += p;
  }
  return k;
}

LeakSensors::LeakSensors(const maps::World& world, const maps::Scenario& scenario) : scenario_(scenario) {
  for (const maps::SensorSpec& spec : scenario.sensors) models_.emplace_back(spec, world.obstacles(), scenario.control_rate_hz);
  for (const maps::LeakSpec& leak : scenario.leaks) {
    leaks_.push_back({maps::LeakPosition(scenario, leak), leak.start_s, leak.strength});
  }
}

void LeakSensors::Scan(VehicleId id, std::int64_t cycle, const VehicleState& state, std::vector<ScanReport>& out) const {
  const double t = static_cast<double>(cycle) / scenario_.control_rate_hz;
  const Eigen::Vector2d workspace(scenario_.workspace.width_m, scenario_.workspace.height_m);
  const auto clamp = [&](Eigen::Vector2d p) { return p.cwiseMax(Eigen::Vector2d::Zero()).cwiseMin(workspace); };
  const auto key = [&](std::size_t sensor, std::uint64_t stream, std::uint64_t item) {
    return KeyedRandom(scenario_.seed, static_cast<std::uint64_t>(id), sensor, static_cast<std::uint64_t>(cycle),
                       (stream << 32) | item);
  };
  for (std::size_t s = 0; s < models_.size(); ++s) {
    const maps::SensorModel& model = models_[s];
    if (!model.ScansAt(cycle)) continue;
    ScanReport scan;
    scan.id = id;
    scan.cycle = cycle;
    scan.time_s = t;
    scan.sensor = static_cast<int>(s);
    scan.position_m = state.position_m;
    scan.heading_rad = state.heading_rad;
    for (std::size_t k = 0; k < leaks_.size(); ++k) {
      const Leak& leak = leaks_[k];
      if (t + 1e-9 < leak.start_s || !model.InView(state.position_m, state.heading_rad, leak.position_m)) continue;
      KeyedRandom draw = key(s, kLeakStream, k);
      const double p = model.DetectionProbability((leak.position_m - state.position_m).norm(), leak.strength);
      if (draw.Uniform() >= p) continue;
      const double sigma = model.spec().position_sigma_m;
      const Eigen::Vector2d noise(draw.Gaussian(), draw.Gaussian());
      scan.detections_m.push_back(clamp(leak.position_m + sigma * noise));
    }
    KeyedRandom clutter = key(s, kClutterStream, 0);
    const int alarms = clutter.Poisson(model.false_alarms_per_scan());
    const double half_fov = 0.5 * std::min(model.spec().fov_deg, 360.0) * M_PI / 180.0;
    for (int n = 0; n < alarms; ++n) {
      for (int attempt = 0; attempt < kClutterTries; ++attempt) {
        const double r = model.spec().range_m * std::sqrt(clutter.Uniform());
        const double bearing = state.heading_rad + (2.0 * clutter.Uniform() - 1.0) * half_fov;
        const Eigen::Vector2d y = state.position_m + r * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
        if ((y.array() < 0.0).any() || (y.array() > workspace.array()).any() || !model.LineOfSight(state.position_m, y)) {
          continue;
        }
        scan.detections_m.push_back(y);
        break;
      }
    }
    out.push_back(std::move(scan));
  }
}

}  // namespace sage::agents
