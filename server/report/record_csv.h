#pragma once
// Internal to sage_report: reading back the CSV lines the run directory writes (resume, sage view).
#include <string>
#include <string_view>
#include <vector>

namespace sage::server::detail {

/// Fields of one of our own CSV lines: plain fields split at commas, a quoted field ("..." with
/// "" for a quote) taken whole.
std::vector<std::string> SplitCsvLine(std::string_view line);

/// A number field, all of it. Throws maps::ScenarioError "PATH:LINE: 'TEXT' is not a number".
double NumberField(const std::string& text, const std::string& path, long line);

}  // namespace sage::server::detail
