#pragma once
// `sage field generate`: a synthetic subsea field of any size (maps/scenario/field_generator.h)
// written as a scenario file, for scale runs and for judging results on fields nobody tuned.
#include <cstdint>
#include <string>

#include "maps/scenario/field_generator.h"

namespace sage::server {

/// The counts a user left out, sized to the ones given: without --valves, about as many valves
/// per XT as the default field has (87 for 28 XTs, within 2..5 per XT); without --xts (and
/// --valves given), as many XTs as hold those valves at that rate; without --vehicles (and
/// either given), a BlueROV2 for every 28 / 24 XTs (at least one). `--xts 4` alone is then a
/// 4-XT field with 12 valves and 3 vehicles, not a refusal that blames a --valves nobody typed.
maps::FieldOptions WithCountsSizedToEachOther(maps::FieldOptions options, bool xts_given, bool valves_given,
                                              bool vehicles_given);

/// Writes the generated scenario to `out_path` and says what it holds in one line.
int CmdFieldGenerate(const maps::FieldOptions& options, const std::string& out_path);

/// `sage field seabed`: writes the example seabed field (maps/scenario/seabed_example.h) to
/// `out_path` and its bathymetry beside it as <name>.xyz, and says what they hold in one line.
int CmdFieldSeabed(std::uint64_t seed, const std::string& name, const std::string& out_path);

}  // namespace sage::server
