#pragma once
// `sage field generate`: a synthetic subsea field of any size (maps/scenario/field_generator.h)
// written as a scenario file, for scale runs and for judging results on fields nobody tuned.
#include <cstdint>
#include <string>

#include "maps/scenario/field_generator.h"

namespace sage::server {

/// Writes the generated scenario to `out_path` and says what it holds in one line.
int CmdFieldGenerate(const maps::FieldOptions& options, const std::string& out_path);

/// `sage field seabed`: writes the example seabed field (maps/scenario/seabed_example.h) to
/// `out_path` and its bathymetry beside it as <name>.xyz, and says what they hold in one line.
int CmdFieldSeabed(std::uint64_t seed, const std::string& name, const std::string& out_path);

}  // namespace sage::server
