#pragma once
// A mission's checkpoint on disk: checkpoint.bin in the run directory, written atomically every
// few seconds while the mission runs, and what `sage server --resume` starts from. CBOR (RFC
// 8949, through nlohmann-json) with the coverage sums as raw little-endian doubles: compact
// (13 MB for 1,000 vehicles at K = 40) and exact (every double read back bit for bit).
#include <cstdint>
#include <string>
#include <vector>

#include "server/mission_core.h"

namespace sage::server {

/// The checkpoint file's name in a run directory.
inline constexpr const char* kCheckpointFile = "checkpoint.bin";

std::vector<std::uint8_t> EncodeCheckpoint(const MissionCheckpoint& checkpoint);
/// Throws maps::ScenarioError naming `source` if the bytes are not a checkpoint of this format.
MissionCheckpoint DecodeCheckpoint(const std::vector<std::uint8_t>& bytes, const std::string& source);

/// Writes DIR/checkpoint.bin atomically. Throws std::runtime_error naming the file.
void WriteCheckpoint(const std::string& dir, const MissionCheckpoint& checkpoint);
/// Reads DIR/checkpoint.bin. Throws maps::ScenarioError with one line if there is none or it is
/// not readable.
MissionCheckpoint ReadCheckpoint(const std::string& dir);

}  // namespace sage::server
