#pragma once
// The size on the wire of one sample of each message, from its type and its sequence and string
// lengths: the serialised payload Cyclone DDS sends (XCDR1, the representation it uses for
// these final types), its 4-byte encapsulation header included, the RTPS and UDP headers around
// it not. The server counts bytes in and out with it (a DDS reader does not say how many bytes
// a sample took); tests/proto checks every type against Cyclone's own serialised size.
//
// XCDR1 in short: each primitive is aligned to its own size (8 at most) from the start of the
// payload after the header; a string is a uint32 length (characters + 1), the characters and a
// NUL; a sequence is a uint32 length, then its elements aligned to their size; members follow
// in declaration order; the payload is padded to a multiple of 4 bytes.
#include <cstddef>

#include "proto/messages.h"

namespace sage::proto {

std::size_t WireBytes(const VehicleState& m);
std::size_t WireBytes(const VehicleCoverage& m);
std::size_t WireBytes(const ErgodicTarget& m);
std::size_t WireBytes(const ErgodicTargets& m);
std::size_t WireBytes(const FleetCoverage& m);
std::size_t WireBytes(const RiskUpdate& m);
std::size_t WireBytes(const RiskUpdateResult& m);
std::size_t WireBytes(const MissionStatus& m);
std::size_t WireBytes(const FleetCommand& m);
std::size_t WireBytes(const FleetCommandResult& m);
std::size_t WireBytes(const Detection& m);

}  // namespace sage::proto
