#pragma once
// The fleet's messages between their plain form (agents/fleet_messages.h) and their DDS form
// (proto/sage_msgs.idl), field by field, for both nodes. A message going out borrows the plain
// value's memory (write it while the value lives); one coming in is copied out of the sample.
#include <cstdint>
#include <span>
#include <vector>

#include "agents/fleet_messages.h"
#include "proto/messages.h"

namespace sage::agents::wire {

/// DDS -> plain. A vehicle state's time is its cycle / control_rate_hz.
StateReport FromWire(const proto::VehicleState& m, double control_rate_hz);
CoverageMessage FromWire(const proto::VehicleCoverage& m);
FleetSnapshot FromWire(const proto::FleetCoverage& m);
Assignment FromWire(const proto::ErgodicTarget& m);
/// A scan's time is its cycle / control_rate_hz; an odd count of coordinates leaves a last
/// detection that is not finite, for the server's door to refuse.
ScanReport FromWire(const proto::Detection& m, double control_rate_hz);

/// plain -> DDS (borrowing). stamp_ns: when it is written, on the mission clock.
/// server_instance: the server whose clock the state's cycle is on.
proto::VehicleState ToWire(const StateReport& s, std::uint64_t server_instance, long long stamp_ns);
proto::VehicleCoverage ToWire(const CoverageMessage& c, long long stamp_ns);
/// `ids` and `seqs` are scratch the message borrows (the snapshot's accounted reports).
proto::FleetCoverage ToWire(const FleetSnapshot& s, std::uint64_t server_instance, std::uint32_t basis_order,
                            long long stamp_ns, std::vector<std::uint32_t>& ids, std::vector<std::uint64_t>& seqs);
proto::ErgodicTarget ToWire(const Assignment& a, std::uint64_t server_instance, std::uint32_t basis_order,
                            long long stamp_ns);
/// A cycle's changed assignments in one sample, borrowing `targets` (each made by the ToWire above).
proto::ErgodicTargets ToWire(std::span<const proto::ErgodicTarget> targets, std::uint64_t server_instance,
                             std::uint64_t cycle, long long stamp_ns);
/// `xy` is scratch the message borrows (the detections' coordinates, flattened).
proto::Detection ToWire(const ScanReport& s, std::uint64_t server_instance, long long stamp_ns, std::vector<double>& xy);

}  // namespace sage::agents::wire
