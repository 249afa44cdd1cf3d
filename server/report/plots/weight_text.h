#pragma once
// A valve's normalised weight as the run table and the field plot print it (the plot's labels
// and the table are one figure read twice: tests/server/report/plots/field_plot_test.cpp).
#include <string>

#include <fmt/format.h>

namespace sage::server {

/// Two decimals (the paper's 0.55) from 0.1 up, two significant digits below (a 1,000-valve
/// field's 0.00093 had printed as 0.00 on every row, and 0.0139 as 0.01 beside 0.0061).
inline std::string WeightText(double w) { return w >= 0.1 || w <= 0.0 ? fmt::format("{:.2f}", w) : fmt::format("{:.2g}", w); }

}  // namespace sage::server
