// plot.svg: the trajectory over the risk field with XTs and valves, like the SAGE paper's Fig. 1.
#include "server/report/report.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <Eigen/LU>
#include <fmt/format.h>

#include "server/report/atomic_write.h"

namespace sage::server {
namespace {

using detail::WriteAtomically;

std::string XmlEscape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Sequential light-to-dark red (ColorBrewer "Reds"), v in [0, 1].
std::string RedScale(double v) {
  static constexpr double kStops[5][3] = {
      {255, 245, 240}, {252, 187, 161}, {251, 106, 74}, {203, 24, 29}, {103, 0, 13}};
  const double x = std::clamp(v, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  const auto channel = [&](int c) {
    return static_cast<int>(std::lround(kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c])));
  };
  return fmt::format("#{:02x}{:02x}{:02x}", channel(0), channel(1), channel(2));
}

// The mixture density up to its constant factor (the raster is scaled to its maximum anyway);
// computed here rather than through maps::RiskField, which would need a spectral basis.
double MixtureDensity(const std::vector<maps::Valve>& valves, const Eigen::VectorXd& weights,
                      const Eigen::Vector2d& x) {
  double density = 0.0;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const Eigen::Matrix2d& sigma = valves[i].covariance_m2;
    const double det = sigma.determinant();
    if (!(det > 0.0)) continue;  // not SPD: the scenario validator reports it, the plot skips it
    const Eigen::Vector2d d = x - valves[i].position_m;
    density += weights[i] * std::exp(-0.5 * d.dot(sigma.inverse() * d)) / std::sqrt(det);
  }
  return density;
}

}  // namespace

std::string PlotSvg(const maps::Scenario& scenario, const Eigen::VectorXd& weights,
                  const Trajectory& trajectory, const std::string& title) {
  const std::vector<maps::Valve> valves = scenario.AllValves();
  if (weights.size() != static_cast<Eigen::Index>(valves.size())) {
    throw std::invalid_argument(fmt::format("WritePlotSvg: {} weights for {} valves", weights.size(), valves.size()));
  }
  constexpr double kWidthPx = 800.0, kSide = 30.0, kTop = 44.0, kMaxPointsPerPath = 5000.0;
  static constexpr const char* kPalette[] = {"#1f77b4", "#2ca02c", "#9467bd", "#17becf", "#ff7f0e",
                                             "#8c564b", "#e377c2", "#bcbd22", "#000080", "#7f7f7f"};
  const double width_m = scenario.workspace.width_m, height_m = scenario.workspace.height_m;
  const double scale = (kWidthPx - 2.0 * kSide) / width_m;  // px per metre
  const double plot_h = height_m * scale;
  // World (m, y up) to SVG (px, y down).
  const auto px = [&](double x) { return kSide + x * scale; };
  const auto py = [&](double y) { return kTop + (height_m - y) * scale; };

  std::map<int, std::vector<Eigen::Vector2d>> paths;
  for (const TrajectorySample& s : trajectory.samples) paths[s.vehicle].push_back(s.position_m);
  const auto vehicle_name = [&](int v) {
    const bool named = v >= 0 && v < static_cast<int>(trajectory.vehicle_names.size()) &&
                       !trajectory.vehicle_names[v].empty();
    return named ? trajectory.vehicle_names[v] : fmt::format("vehicle {}", v);
  };
  // Legend entries below the plot, wrapped into rows of kPerRow.
  constexpr int kPerRow = 4;
  const bool seabed_objects = !scenario.flowlines.empty() || !scenario.boulders.empty();
  const int legend_items =
      static_cast<int>(paths.size()) + 2 + (seabed_objects ? 1 : 0) + (scenario.leaks.empty() ? 0 : 1);
  const double legend_y = kTop + plot_h + 26.0;
  const double height_px = legend_y + 20.0 * ((legend_items + kPerRow - 1) / kPerRow) + 6.0;

  fmt::memory_buffer out;
  const auto put = [&]<typename... A>(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(out), format, std::forward<A>(args)...);
  };
  put("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
      "font-family=\"sans-serif\">\n", kWidthPx, height_px, kWidthPx, height_px);
  put("<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
  put("<text x=\"{}\" y=\"28\" font-size=\"16\">{}</text>\n", kSide, XmlEscape(title));

  // Risk density raster, about 80 cells across, normalised to its maximum.
  const int nx = 80, ny = std::clamp(static_cast<int>(std::lround(nx * height_m / width_m)), 1, 200);
  const Eigen::VectorXd w = weights.sum() > 0.0 ? Eigen::VectorXd(weights / weights.sum()) : weights;
  Eigen::MatrixXd density(nx, ny);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      density(i, j) = MixtureDensity(valves, w, {(i + 0.5) * width_m / nx, (j + 0.5) * height_m / ny});
    }
  }
  const double peak = density.maxCoeff() > 0.0 ? density.maxCoeff() : 1.0;
  const double cell_w = width_m * scale / nx, cell_h = plot_h / ny;
  // The lightest colour fills the whole box once; only cells darker than it are drawn, which
  // keeps the file small (most of the box is far from every valve).
  const std::string background = RedScale(0.0);
  put("<g shape-rendering=\"crispEdges\">\n<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n",
      kSide, kTop, width_m * scale, plot_h, background);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const std::string fill = RedScale(density(i, j) / peak);
      if (fill == background) continue;
      // Cells overlap by half a pixel so no seams show between them.
      put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n",
          kSide + i * cell_w, kTop + (ny - 1 - j) * cell_h, cell_w + 0.5, cell_h + 0.5, fill);
    }
  }
  put("</g>\n");

  // What lies on the seabed: flowlines at their diameter (at least 1.5 px), boulders across theirs.
  for (const maps::Flowline& f : scenario.flowlines) {
    put("<polyline fill=\"none\" stroke=\"#b8860b\" stroke-opacity=\"0.8\" stroke-linejoin=\"round\" "
        "stroke-width=\"{:.1f}\" points=\"", std::max(1.5, f.diameter_m * scale));
    for (const Eigen::Vector2d& p : f.points_m) put("{:.1f},{:.1f} ", px(p.x()), py(p.y()));
    put("\"><title>{} ({} m)</title></polyline>\n", XmlEscape(f.name), f.diameter_m);
  }
  for (const maps::Boulder& b : scenario.boulders) {
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"#8a8a8a\" stroke=\"#505050\"/>\n", px(b.center_m.x()),
        py(b.center_m.y()), std::max(1.0, 0.5 * b.diameter_m * scale));
  }
  for (const maps::ChristmasTree& xt : scenario.structures) {
    const Eigen::Vector2d lo = xt.center_m - 0.5 * xt.size_m;
    put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#404040\"/>\n",
        px(lo.x()), py(lo.y() + xt.size_m.y()), xt.size_m.x() * scale, xt.size_m.y() * scale);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" fill=\"white\" text-anchor=\"middle\">{}</text>\n",
        px(xt.center_m.x()), py(xt.center_m.y()) + 4.0, XmlEscape(xt.name));
  }
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const double x = px(valves[i].position_m.x()), y = py(valves[i].position_m.y());
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"none\" stroke=\"#222\" stroke-dasharray=\"4 3\"/>\n",
        x, y, scenario.visit_radius_m * scale);
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"#222\"/>\n", x, y);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\" stroke=\"white\" stroke-width=\"3\" "
        "paint-order=\"stroke\">{} ({:.2f})</text>\n", x + 6.0, y - 6.0, XmlEscape(valves[i].name), w[i]);
  }

  // The hidden leaks (the scenario's; the server never knew them), a red cross each with its onset.
  const auto cross = [&](double x, double y, double r) {
    put("<path d=\"M{:.1f},{:.1f} L{:.1f},{:.1f} M{:.1f},{:.1f} L{:.1f},{:.1f}\" stroke=\"#d00\" stroke-width=\"3\"/>\n", x - r,
        y - r, x + r, y + r, x - r, y + r, x + r, y - r);
  };
  for (const maps::LeakSpec& leak : scenario.leaks) {
    const Eigen::Vector2d at = maps::LeakPosition(scenario, leak);
    cross(px(at.x()), py(at.y()), 6.0);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" fill=\"#d00\" stroke=\"white\" stroke-width=\"3\" "
        "paint-order=\"stroke\">leak from {:.0f} s</text>\n", px(at.x()) + 8.0, py(at.y()) + 14.0, leak.start_s);
  }

  int colour = 0;
  for (const auto& [vehicle, points] : paths) {
    const char* stroke = kPalette[colour++ % std::size(kPalette)];
    // Keep every stride-th point and the last, at most ~5000: the eye cannot tell more apart.
    const std::size_t stride = static_cast<std::size_t>(std::ceil(points.size() / kMaxPointsPerPath));
    put("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" stroke-opacity=\"0.85\" points=\"", stroke);
    for (std::size_t k = 0; k < points.size(); k += stride) {
      put("{:.1f},{:.1f} ", px(points[k].x()), py(points[k].y()));
    }
    put("{:.1f},{:.1f}\"/>\n", px(points.back().x()), py(points.back().y()));
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"5\" fill=\"{}\" stroke=\"white\" stroke-width=\"1.5\"/>\n",
        px(points.front().x()), py(points.front().y()), stroke);
  }
  put("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"black\"/>\n", kSide,
      kTop, width_m * scale, plot_h);

  // Legend: one entry per vehicle, then the valve and XT symbols.
  int item = 0;
  const auto slot = [&] {
    const int k = item++;
    return std::pair<double, double>(kSide + (k % kPerRow) * 160.0, legend_y + (k / kPerRow) * 20.0);
  };
  colour = 0;
  for (const auto& [vehicle, points] : paths) {
    const auto [x, y] = slot();
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"3\"/>\n", x,
        y - 4.0, x + 22.0, y - 4.0, kPalette[colour++ % std::size(kPalette)]);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">{}</text>\n", x + 28.0, y, XmlEscape(vehicle_name(vehicle)));
  }
  auto [vx, vy] = slot();
  put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"7\" fill=\"none\" stroke=\"#222\" stroke-dasharray=\"4 3\"/>\n",
      vx + 11.0, vy - 4.0);
  put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">valve, visit radius</text>\n", vx + 28.0, vy);
  auto [tx, ty] = slot();
  put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"22\" height=\"10\" fill=\"#404040\"/>\n", tx, ty - 9.0);
  put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">XT footprint</text>\n", tx + 28.0, ty);
  if (seabed_objects) {
    auto [sx, sy] = slot();
    put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#b8860b\" stroke-width=\"3\"/>\n", sx,
        sy - 4.0, sx + 12.0, sy - 4.0);
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4.5\" fill=\"#8a8a8a\" stroke=\"#505050\"/>\n", sx + 18.0, sy - 4.0);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">flowline, boulder</text>\n", sx + 28.0, sy);
  }
  if (!scenario.leaks.empty()) {
    auto [lx, ly] = slot();
    cross(lx + 11.0, ly - 4.0, 5.0);
    put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"12\">hidden leak</text>\n", lx + 28.0, ly);
  }
  put("</svg>\n");
  return std::string(out.data(), out.size());
}

void WritePlotSvg(const std::string& path, const maps::Scenario& scenario, const Eigen::VectorXd& weights,
                  const Trajectory& trajectory, const std::string& title) {
  WriteAtomically(path, PlotSvg(scenario, weights, trajectory, title));
}

}  // namespace sage::server
