#include "agents/node/wire.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "maps/scenario/scenario.h"

namespace sage::agents::wire {
namespace {

// Every name a scenario allows fits a state's bounded name (proto/sage_msgs.idl).
static_assert(sizeof(proto::VehicleState::name) == maps::kMaxNameLength + 1);

Eigen::VectorXd Copy(std::span<const double> values) {
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}
std::span<const double> View(const Eigen::VectorXd& v) { return {v.data(), static_cast<std::size_t>(v.size())}; }

}  // namespace

StateReport FromWire(const proto::VehicleState& m, double control_rate_hz) {
  StateReport s;
  s.id = static_cast<VehicleId>(m.vehicle_id);
  s.name = std::string(proto::AsBoundedView(m.name));
  s.cycle = m.cycle;
  s.time_s = static_cast<double>(m.cycle) / control_rate_hz;
  s.state.position_m = {m.x_m, m.y_m};
  s.state.velocity_mps = {m.vx_mps, m.vy_mps};
  s.state.heading_rad = m.heading_rad;
  s.command_mps = {m.cmd_x_mps, m.cmd_y_mps};
  s.target_cycle = m.target_cycle;
  return s;
}

CoverageMessage FromWire(const proto::VehicleCoverage& m) {
  return {static_cast<VehicleId>(m.vehicle_id), {m.seq, m.mission_time_s, m.time_s, Copy(proto::AsSpan(m.sums))}};
}

FleetSnapshot FromWire(const proto::FleetCoverage& m) {
  FleetSnapshot s;
  s.cycle = m.cycle;
  s.phi = Copy(proto::AsSpan(m.phi));
  s.coverage.time_s = m.mission_time_s;
  s.coverage.sums = Copy(proto::AsSpan(m.sums));
  s.coverage.kernel_time_s = m.kernel_time_s;
  const auto ids = proto::AsSpan(m.vehicle_ids);
  const auto seqs = proto::AsSpan(m.accounted_seq);
  for (std::size_t i = 0; i < ids.size() && i < seqs.size(); ++i) s.coverage.accounted_seq[static_cast<int>(ids[i])] = seqs[i];
  s.valve_weights = Copy(proto::AsSpan(m.valve_weights));
  return s;
}

Assignment FromWire(const proto::ErgodicTarget& m) {
  Assignment a;
  a.id = static_cast<VehicleId>(m.vehicle_id);
  a.cycle = m.cycle;
  a.shared = m.shared;
  a.phi = Copy(proto::AsSpan(m.phi));
  const auto tour = proto::AsSpan(m.tour);
  a.tour.assign(tour.begin(), tour.end());
  a.tour_weights = Copy(proto::AsSpan(m.tour_weights));
  a.region_origin_m = {m.region_x_m, m.region_y_m};
  a.region_size_m = {m.region_width_m, m.region_height_m};
  a.region_order = static_cast<int>(m.region_order);
  a.region_forgetting_s = m.region_forgetting_s;
  const auto region_valves = proto::AsSpan(m.region_valves);
  a.region_valves.assign(region_valves.begin(), region_valves.end());
  a.region_weights = Copy(proto::AsSpan(m.region_weights));
  return a;
}

ScanReport FromWire(const proto::Detection& m, double control_rate_hz) {
  ScanReport s;
  s.id = static_cast<VehicleId>(m.vehicle_id);
  s.cycle = m.cycle;
  s.time_s = static_cast<double>(m.cycle) / control_rate_hz;
  s.sensor = static_cast<int>(std::min<std::uint32_t>(m.sensor, 1u << 30));
  s.position_m = {m.x_m, m.y_m};
  s.heading_rad = m.heading_rad;
  const auto xy = proto::AsSpan(m.detections_xy_m);
  for (std::size_t k = 0; k < xy.size(); k += 2) {
    s.detections_m.emplace_back(xy[k], k + 1 < xy.size() ? xy[k + 1] : std::numeric_limits<double>::quiet_NaN());
  }
  return s;
}

proto::Detection ToWire(const ScanReport& s, std::uint64_t server_instance, long long stamp_ns, std::vector<double>& xy) {
  xy.clear();
  for (const Eigen::Vector2d& z : s.detections_m) xy.insert(xy.end(), {z.x(), z.y()});
  proto::Detection m{};
  m.vehicle_id = static_cast<std::uint32_t>(s.id);
  m.stamp_ns = stamp_ns;
  m.server_instance = server_instance;
  m.cycle = s.cycle;
  m.sensor = static_cast<std::uint32_t>(s.sensor);
  m.x_m = s.position_m.x();
  m.y_m = s.position_m.y();
  m.heading_rad = s.heading_rad;
  m.detections_xy_m = proto::BorrowSequence(std::span<const double>(xy.data(), xy.size()));
  return m;
}

proto::VehicleState ToWire(const StateReport& s, std::uint64_t server_instance, long long stamp_ns) {
  proto::VehicleState m{};
  m.vehicle_id = static_cast<std::uint32_t>(s.id);
  m.stamp_ns = stamp_ns;
  m.server_instance = server_instance;
  m.cycle = s.cycle;
  if (!proto::CopyBounded(m.name, s.name)) {
    throw std::invalid_argument(fmt::format("vehicle {}: name '{}' is longer than a state carries ({} characters)", s.id,
                                            s.name.substr(0, 20), proto::BoundOf(m.name)));
  }
  m.x_m = s.state.position_m.x();
  m.y_m = s.state.position_m.y();
  m.heading_rad = s.state.heading_rad;
  m.vx_mps = s.state.velocity_mps.x();
  m.vy_mps = s.state.velocity_mps.y();
  m.cmd_x_mps = s.command_mps.x();
  m.cmd_y_mps = s.command_mps.y();
  m.target_cycle = s.target_cycle;
  return m;
}

proto::VehicleCoverage ToWire(const CoverageMessage& c, long long stamp_ns) {
  proto::VehicleCoverage m{};
  m.vehicle_id = static_cast<std::uint32_t>(c.id);
  m.stamp_ns = stamp_ns;
  m.mission_time_s = c.report.stamp_s;
  m.seq = c.report.seq;
  m.time_s = c.report.kernel_time_s;
  m.sums = proto::BorrowSequence(View(c.report.sums));
  return m;
}

proto::FleetCoverage ToWire(const FleetSnapshot& s, std::uint64_t server_instance, std::uint32_t basis_order,
                            long long stamp_ns, std::vector<std::uint32_t>& ids, std::vector<std::uint64_t>& seqs) {
  ids.clear();
  seqs.clear();
  for (const auto& [id, seq] : s.coverage.accounted_seq) {
    ids.push_back(static_cast<std::uint32_t>(id));
    seqs.push_back(seq);
  }
  proto::FleetCoverage m{};
  m.stamp_ns = stamp_ns;
  m.server_instance = server_instance;
  m.cycle = s.cycle;
  m.mission_time_s = s.coverage.time_s;
  m.basis_order = basis_order;
  m.phi = proto::BorrowSequence(View(s.phi));
  m.sums = proto::BorrowSequence(View(s.coverage.sums));
  m.kernel_time_s = s.coverage.kernel_time_s;
  m.vehicle_ids = proto::BorrowSequence(std::span<const std::uint32_t>(ids));
  m.accounted_seq = proto::BorrowSequence(std::span<const std::uint64_t>(seqs));
  m.valve_weights = proto::BorrowSequence(View(s.valve_weights));
  return m;
}

proto::ErgodicTarget ToWire(const Assignment& a, std::uint64_t server_instance, std::uint32_t basis_order,
                            long long stamp_ns) {
  proto::ErgodicTarget m{};
  m.vehicle_id = static_cast<std::uint32_t>(a.id);
  m.stamp_ns = stamp_ns;
  m.server_instance = server_instance;
  m.cycle = a.cycle;
  m.basis_order = basis_order;
  m.shared = a.shared;
  // A region's phi that is its valves' mixture goes as the valves and weights (the host makes it).
  const bool by_valves = !a.region_valves.empty();
  m.phi = proto::BorrowSequence(by_valves ? std::span<const double>() : View(a.phi));
  m.tour = proto::BorrowSequence(std::span<const std::int32_t>(a.tour.data(), a.tour.size()));
  m.tour_weights = proto::BorrowSequence(View(a.tour_weights));
  m.region_x_m = a.region_origin_m.x();
  m.region_y_m = a.region_origin_m.y();
  m.region_width_m = a.region_size_m.x();
  m.region_height_m = a.region_size_m.y();
  m.region_order = static_cast<std::uint32_t>(a.region_order);
  m.region_forgetting_s = a.region_forgetting_s;
  m.region_valves = proto::BorrowSequence(std::span<const std::int32_t>(a.region_valves.data(), a.region_valves.size()));
  m.region_weights = proto::BorrowSequence(View(a.region_weights));
  return m;
}

proto::ErgodicTargets ToWire(std::span<const proto::ErgodicTarget> targets, std::uint64_t server_instance,
                             std::uint64_t cycle, long long stamp_ns) {
  proto::ErgodicTargets m{};
  m.stamp_ns = stamp_ns;
  m.server_instance = server_instance;
  m.cycle = cycle;
  m.targets = proto::BorrowSequence(targets);
  return m;
}

}  // namespace sage::agents::wire
