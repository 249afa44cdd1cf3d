// plot.svg: the field as a reader should see it after a mission (see mission_plots.h).
#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <map>
#include <set>
#include <stdexcept>

#include <Eigen/LU>
#include <fmt/format.h>

#include "maps/scenario/perception.h"
#include "server/report/plots/mission_plots.h"
#include "server/report/plots/nice_scale.h"
#include "server/report/plots/render.h"
#include "server/report/plots/weight_text.h"
#include "server/report/plots/svg_writer.h"

namespace sage::server::plots {
namespace {

// Figure geometry (px). The map keeps the workspace's aspect and fits kMapMaxWidth x
// kMapMaxHeight, so any field, 5 m or 500 m, wide or tall, gives a figure of at most about
// 950 x 1,000 px.
constexpr double kLeft = 78.0, kTop = 40.0, kMapMaxWidth = 720.0, kMapMaxHeight = 620.0;
constexpr double kColourBarGap = 22.0, kColourBarWidth = 14.0, kRightZone = 140.0, kMinFigureWidth = 660.0;
constexpr double kLabelFont = 11.0, kLegendFont = 12.0, kCaptionFont = 11.0;
// Event labels tried at most (the rest keep their markers and are counted in the caption).
constexpr int kMaxEventLabels = 40;
// Above this many valves the field is crowded: only the heaviest valves' labels are tried, first.
constexpr std::size_t kCrowdedValves = 60, kMaxCrowdedValveLabels = 40;

// Tracks: colours that are none of the markers' (red, green, orange) nor the risk's reds.
constexpr const char* kTrackColours[] = {"#1f77b4", "#9467bd", "#17becf", "#8c564b", "#e377c2", "#7f7f7f",
                                         "#bcbd22", "#000080", "#008080", "#6a3d9a", "#222222", "#b15928"};
// Over the fleet's density (blues), the few tracks drawn take none of the blues (a new user's
// highlighted rov9 in #1f77b4 was lost in it), each on a white halo.
constexpr const char* kTracksOverDensity[] = {"#e377c2", "#8c564b", "#bcbd22", "#222222", "#9467bd", "#b15928"};
constexpr const char* kStructureFill = "#404040";
constexpr const char* kRiskMarker = "#e6550d";
constexpr const char* kJoinMarker = "#2ca02c";
constexpr const char* kLossMarker = "#111111";  // black: red crosses are the hidden leaks
constexpr const char* kLeakMarker = "#dd0000";
constexpr const char* kLeaveMarker = "#555555";

std::string Seconds(double t) { return t >= 100.0 ? fmt::format("{:.0f} s", t) : fmt::format("{:.1f} s", t); }

// The risk density phi(x) = sum_i w_i N(x; mu_i, Sigma_i) (share of the field's risk per m^2),
// averaged over each raster cell of side h metres: cells much smaller than a valve's spread take
// the density at their centre (exact covariance); larger ones the Gaussian's mass in the cell
// from its marginals (erf; exact for axis-aligned covariances), so a 0.35 m valve on a 300 m
// field still shows in its cell instead of falling between samples. Each valve touches only
// the cells within 4 sigma of it.
Eigen::MatrixXd RiskRaster(const std::vector<maps::Valve>& valves, const std::vector<double>& weights, int nx, int ny,
                           double h) {
  Eigen::MatrixXd raster = Eigen::MatrixXd::Zero(nx, ny);  // (column, row from the bottom)
  for (std::size_t v = 0; v < valves.size(); ++v) {
    const double w = weights[v];
    const Eigen::Matrix2d& sigma = valves[v].covariance_m2;
    const double det = sigma.determinant();
    if (!(w > 0.0) || !(det > 0.0)) continue;
    const double sx = std::sqrt(sigma(0, 0)), sy = std::sqrt(sigma(1, 1));
    const Eigen::Vector2d mu = valves[v].position_m;
    const int i0 = std::max(0, static_cast<int>(std::floor((mu.x() - 4 * sx) / h)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((mu.x() + 4 * sx) / h)));
    const int j0 = std::max(0, static_cast<int>(std::floor((mu.y() - 4 * sy) / h)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((mu.y() + 4 * sy) / h)));
    if (h <= 0.5 * std::min(sx, sy)) {
      const Eigen::Matrix2d inverse = sigma.inverse();
      const double norm = w / (2.0 * M_PI * std::sqrt(det));
      for (int i = i0; i <= i1; ++i) {
        for (int j = j0; j <= j1; ++j) {
          const Eigen::Vector2d d = Eigen::Vector2d((i + 0.5) * h, (j + 0.5) * h) - mu;
          raster(i, j) += norm * std::exp(-0.5 * d.dot(inverse * d));
        }
      }
    } else {
      const auto mass = [](double a, double b, double m, double s) {
        return 0.5 * (std::erf((b - m) / (s * M_SQRT2)) - std::erf((a - m) / (s * M_SQRT2)));
      };
      for (int i = i0; i <= i1; ++i) {
        const double mx = mass(i * h, (i + 1) * h, mu.x(), sx);
        for (int j = j0; j <= j1; ++j) raster(i, j) += w * mx * mass(j * h, (j + 1) * h, mu.y(), sy) / (h * h);
      }
    }
  }
  return raster;
}

// Marching squares: the segments (px) where the raster (values at cell centres) crosses `level`.
std::string ContourPath(const Eigen::MatrixXd& raster, double level, const std::function<double(double)>& px,
                        const std::function<double(double)>& py, double h) {
  std::string path;
  const auto point = [&](double i, double j) { return fmt::format("{:.1f},{:.1f}", px((i + 0.5) * h), py((j + 0.5) * h)); };
  for (int i = 0; i + 1 < raster.rows(); ++i) {
    for (int j = 0; j + 1 < raster.cols(); ++j) {
      // Corners counter-clockwise from the lower left, and where each edge crosses the level.
      const double v[4] = {raster(i, j), raster(i + 1, j), raster(i + 1, j + 1), raster(i, j + 1)};
      const int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
      std::vector<std::string> crossings;
      for (int e = 0; e < 4; ++e) {
        const double a = v[e], b = v[(e + 1) % 4];
        if ((a >= level) == (b >= level)) continue;
        const double f = (level - a) / (b - a);
        const auto* p = corner[e];
        const auto* q = corner[(e + 1) % 4];
        crossings.push_back(point(p[0] + f * (q[0] - p[0]), p[1] + f * (q[1] - p[1])));
      }
      // Two crossings: one segment; four (a saddle): pair them in order round the cell.
      for (std::size_t k = 0; k + 1 < crossings.size(); k += 2) path += "M" + crossings[k] + "L" + crossings[k + 1];
    }
  }
  return path;
}

struct LegendItem {
  std::string symbol;  // SVG drawn with its origin at the item's left, baseline - 4
  std::string text;
};

std::string MarkerSvg(EventMarker::Kind kind, double x, double y, double size) {
  const double r = 0.5 * size;
  switch (kind) {
    case EventMarker::Kind::kRisk:
      return fmt::format("<path d=\"M{0:.1f},{1:.1f}l{2:.1f},{2:.1f}l-{2:.1f},{2:.1f}l-{2:.1f},-{2:.1f}z\" fill=\"none\" "
                         "stroke=\"{3}\" stroke-width=\"2.2\"/>",
                         x, y - r - 2.0, r + 2.0, kRiskMarker);
    case EventMarker::Kind::kJoin:
      return fmt::format("<path d=\"M{0:.1f},{1:.1f}l{2:.1f},{3:.1f}h-{4:.1f}z\" fill=\"{5}\" stroke=\"white\" "
                         "stroke-width=\"1\"/>",
                         x, y - r - 1.0, r + 1.0, 2.0 * r + 1.5, 2.0 * r + 2.0, kJoinMarker);
    case EventMarker::Kind::kLoss:
      return fmt::format("<path d=\"M{0:.1f},{1:.1f}l{2:.1f},{2:.1f}M{0:.1f},{3:.1f}l{2:.1f},-{2:.1f}\" stroke=\"white\" "
                         "stroke-width=\"4.5\"/><path d=\"M{0:.1f},{1:.1f}l{2:.1f},{2:.1f}M{0:.1f},{3:.1f}l{2:.1f},-{2:.1f}\" "
                         "stroke=\"{4}\" stroke-width=\"2.4\"/>",
                         x - r, y - r, 2.0 * r, y + r, kLossMarker);
    case EventMarker::Kind::kLeave:
      return fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\" stroke=\"white\"/>",
                         x - r, y - r, size, size, kLeaveMarker);
  }
  return "";
}

// The tracks to draw over the density: vehicles with an event first (in the order of their
// events), then spread evenly through the fleet's indices.
std::vector<int> HighlightedTracks(const std::map<int, std::vector<Eigen::Vector2d>>& paths,
                                   const std::vector<std::string>& names, const std::vector<EventMarker>& events,
                                   int count) {
  std::vector<int> chosen;
  std::map<std::string, int> by_name;
  for (const auto& [v, points] : paths) {
    if (v >= 0 && v < static_cast<int>(names.size())) by_name[names[v]] = v;
  }
  for (const EventMarker& e : events) {
    if (static_cast<int>(chosen.size()) >= count) break;
    if (e.kind == EventMarker::Kind::kRisk) continue;
    const auto it = by_name.find(e.who);
    if (it != by_name.end() && std::find(chosen.begin(), chosen.end(), it->second) == chosen.end()) chosen.push_back(it->second);
  }
  std::vector<int> all;
  for (const auto& [v, points] : paths) all.push_back(v);
  for (int k = 0; static_cast<int>(chosen.size()) < count && k < count; ++k) {
    const int v = all[std::min(all.size() - 1, static_cast<std::size_t>(std::llround((k + 0.5) * all.size() / count)))];
    if (std::find(chosen.begin(), chosen.end(), v) == chosen.end()) chosen.push_back(v);
  }
  return chosen;
}

}  // namespace

const char* ToString(EventMarker::Kind kind) {
  switch (kind) {
    case EventMarker::Kind::kRisk: return "risk change";
    case EventMarker::Kind::kJoin: return "joined";
    case EventMarker::Kind::kLoss: return "lost";
    case EventMarker::Kind::kLeave: return "left";
  }
  return "";
}

std::string FieldPlotSvg(const MissionPlotInput& input, FieldPlotLayout* layout_out, const FieldPlotOptions& options) {
  if (input.scenario == nullptr || input.metrics == nullptr || input.trajectory == nullptr) {
    throw std::invalid_argument("FieldPlotSvg: scenario, metrics and trajectory are required");
  }
  const maps::Scenario& scenario = *input.scenario;
  const Trajectory& trajectory = *input.trajectory;
  const std::vector<maps::Valve> valves = scenario.AllValves();
  FieldPlotLayout layout;

  // The run table's weights (mission averages), by name.
  std::map<std::string, double> table_weight;
  for (const ValveMetrics& v : input.metrics->valves) table_weight[v.name] = v.weight;
  std::vector<double> weights(valves.size(), 0.0);
  double weight_sum = 0.0;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const auto it = table_weight.find(valves[i].name);
    weights[i] = it != table_weight.end() && std::isfinite(it->second) ? it->second : 0.0;
    weight_sum += weights[i];
  }
  std::vector<double> shares = weights;
  if (weight_sum > 0.0) for (double& s : shares) s /= weight_sum;

  // Geometry.
  const double width_m = scenario.workspace.width_m, height_m = scenario.workspace.height_m;
  const double scale = std::min(kMapMaxWidth / width_m, kMapMaxHeight / height_m);
  const double map_w = width_m * scale, map_h = height_m * scale;
  layout.px_per_m = scale;
  layout.map = {kLeft, kTop, kLeft + map_w, kTop + map_h};
  const auto px = [&](double x) { return kLeft + x * scale; };
  const auto py = [&](double y) { return kTop + (height_m - y) * scale; };
  const double figure_w = std::max(kLeft + map_w + kRightZone, kMinFigureWidth);
  const double colour_bar_h = std::clamp(map_h, 150.0, 300.0);
  const double content_bottom = std::max(kTop + map_h, kTop + colour_bar_h);

  // The tracks, per vehicle.
  std::map<int, std::vector<Eigen::Vector2d>> paths;
  std::map<int, std::vector<double>> times;
  for (const TrajectorySample& s : trajectory.samples) {
    paths[s.vehicle].push_back(s.position_m);
    times[s.vehicle].push_back(s.time_s);
  }
  const auto vehicle_name = [&](int v) {
    const bool named = v >= 0 && v < static_cast<int>(trajectory.vehicle_names.size()) && !trajectory.vehicle_names[v].empty();
    return named ? trajectory.vehicle_names[v] : fmt::format("vehicle {}", v);
  };
  layout.vehicles = static_cast<int>(paths.size());
  layout.density = layout.vehicles > options.max_tracks;
  std::vector<int> drawn;
  if (layout.density) {
    drawn = HighlightedTracks(paths, trajectory.vehicle_names, input.events, options.highlighted_tracks);
  } else {
    for (const auto& [v, points] : paths) drawn.push_back(v);
  }
  for (const int v : drawn) layout.highlighted.push_back(vehicle_name(v));

  // Everything below the map is laid out before the document starts (its height depends on it).
  std::vector<LegendItem> legend;
  std::map<int, std::string> colour_of;
  for (std::size_t k = 0; k < drawn.size(); ++k) {
    colour_of[drawn[k]] = layout.density ? kTracksOverDensity[k % std::size(kTracksOverDensity)]
                                         : kTrackColours[k % std::size(kTrackColours)];
    legend.push_back({fmt::format("<line x1=\"0\" y1=\"0\" x2=\"22\" y2=\"0\" stroke=\"{}\" stroke-width=\"3\"/>",
                                  colour_of[drawn[k]]),
                      vehicle_name(drawn[k])});
  }
  if (!drawn.empty()) {
    legend.push_back({"<circle cx=\"5\" cy=\"0\" r=\"4\" fill=\"#666\" stroke=\"white\" stroke-width=\"1.5\"/>"
                      "<rect x=\"14\" y=\"-4\" width=\"8\" height=\"8\" fill=\"#666\" stroke=\"white\"/>",
                      "start, end"});
  }
  legend.push_back({"<circle cx=\"11\" cy=\"0\" r=\"7\" fill=\"none\" stroke=\"#222\" stroke-dasharray=\"3 2\"/>"
                    "<circle cx=\"11\" cy=\"0\" r=\"2.5\" fill=\"#222\"/>",
                    "valve, visit radius"});
  legend.push_back({fmt::format("<rect x=\"0\" y=\"-5\" width=\"22\" height=\"10\" fill=\"{}\"/>", kStructureFill),
                    "XT footprint"});
  if (!scenario.flowlines.empty() || !scenario.boulders.empty()) {
    legend.push_back({"<line x1=\"0\" y1=\"0\" x2=\"12\" y2=\"0\" stroke=\"#b8860b\" stroke-width=\"3\"/>"
                      "<circle cx=\"18\" cy=\"0\" r=\"4.5\" fill=\"#8a8a8a\" stroke=\"#505050\"/>",
                      "flowline, boulder"});
  }
  if (!scenario.leaks.empty()) {
    legend.push_back({fmt::format("<path d=\"M6,-5L16,5M6,5L16,-5\" stroke=\"{}\" stroke-width=\"3\"/>", kLeakMarker),
                      "hidden leak (onset)"});
  }
  std::map<EventMarker::Kind, int> event_count;
  for (const EventMarker& e : input.events) ++event_count[e.kind];
  for (const auto& [kind, count] : event_count) {
    const char* text = kind == EventMarker::Kind::kRisk   ? "risk change"
                       : kind == EventMarker::Kind::kJoin ? "vehicle joined"
                       : kind == EventMarker::Kind::kLoss ? "vehicle lost"
                                                          : "vehicle left";
    legend.push_back({MarkerSvg(kind, 11.0, 0.0, 9.0), fmt::format("{} ({})", text, count)});
  }
  if (layout.density) {
    legend.push_back({"<path d=\"M0,3 C6,-6 14,6 22,-3\" fill=\"none\" stroke=\"#cb181d\" stroke-width=\"1.5\"/>",
                      "risk density contours"});
  }
  // Legend rows: items flow left to right, wrapped at the figure's width.
  struct Placed {
    double x, y;
    const LegendItem* item;
  };
  std::vector<Placed> legend_at;
  const double legend_top = content_bottom + 52.0;
  {
    double x = kLeft, y = legend_top;
    for (const LegendItem& item : legend) {
      const double w = 30.0 + TextWidth(item.text, kLegendFont) + 18.0;
      if (x > kLeft && x + w > figure_w - 10.0) {
        x = kLeft;
        y += 20.0;
      }
      legend_at.push_back({x, y, &item});
      x += w;
    }
  }
  const double legend_bottom = legend_at.empty() ? legend_top : legend_at.back().y + 8.0;

  // The raster: the risk density, or the fleet's time.
  const int res = 2;  // px per raster cell; the raster is drawn pixel for pixel over the map
  const int nx = std::max(1, static_cast<int>(std::ceil(map_w / res))), ny = std::max(1, static_cast<int>(std::ceil(map_h / res)));
  const double cell_m = res / scale;
  Eigen::MatrixXd risk = RiskRaster(valves, shares, nx, ny, cell_m);
  const double risk_peak = risk.maxCoeff() > 0.0 ? risk.maxCoeff() : 1.0;
  RgbaImage image;
  image.width = static_cast<int>(std::ceil(map_w));
  image.height = static_cast<int>(std::ceil(map_h));
  image.rgba.assign(static_cast<std::size_t>(image.width) * image.height * 4, 0);
  std::vector<double> bar_ticks;
  double bar_lo = 0.0, bar_hi = risk_peak, bin_m = 0.0, sample_s = 0.0;
  std::string bar_title, shading_text;
  const auto paint = [&](int i, int j, int cells_px, const Rgb& c) {  // raster cell (i, j from the bottom)
    for (int dy = 0; dy < cells_px; ++dy) {
      const int y = image.height - 1 - (j * cells_px + dy);
      if (y < 0) continue;
      for (int dx = 0; dx < cells_px; ++dx) {
        const int x = i * cells_px + dx;
        if (x >= image.width) continue;
        std::uint8_t* p = image.At(x, y);
        p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
      }
    }
  };
  if (!layout.density) {
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < ny; ++j) paint(i, j, res, Reds(risk(i, j) / risk_peak));
    const Ticks t = LinearTicks(0.0, risk_peak, 6);
    bar_ticks = t.values;
    bar_title = "risk density (share per m\u00b2)";
    shading_text = "Shading: the risk density, the valves' Gaussians with those weights (share of the field's risk per m\u00b2).";
  } else {
    // The fleet's time per bin of a nice size, about 100 bins across (at least 4 px each).
    bin_m = ScaleBarLength(std::max(width_m / 100.0, 4.0 / scale) * 1.999);
    const int bins_x = std::max(1, static_cast<int>(std::ceil(width_m / bin_m)));
    const int bins_y = std::max(1, static_cast<int>(std::ceil(height_m / bin_m)));
    // Each kept sample stands for its vehicle's median spacing of kept samples.
    std::vector<double> spacings;
    for (const auto& [v, ts] : times) {
      for (std::size_t k = 1; k < ts.size() && spacings.size() < 100000; ++k) spacings.push_back(ts[k] - ts[k - 1]);
    }
    if (!spacings.empty()) {
      std::nth_element(spacings.begin(), spacings.begin() + spacings.size() / 2, spacings.end());
      sample_s = spacings[spacings.size() / 2];
    }
    if (!(sample_s > 0.0)) sample_s = 1.0 / scenario.control_rate_hz;
    Eigen::MatrixXd seconds = Eigen::MatrixXd::Zero(bins_x, bins_y);
    for (const TrajectorySample& s : trajectory.samples) {
      const int i = static_cast<int>(std::floor(s.position_m.x() / bin_m)), j = static_cast<int>(std::floor(s.position_m.y() / bin_m));
      if (i >= 0 && i < bins_x && j >= 0 && j < bins_y) seconds(i, j) += sample_s;
    }
    const Eigen::MatrixXd density = seconds / (bin_m * bin_m);  // vehicle-s per m^2
    bar_hi = density.maxCoeff() > 0.0 ? density.maxCoeff() : 1.0;
    double lowest = bar_hi;
    for (Eigen::Index k = 0; k < density.size(); ++k)
      if (density.data()[k] > 0.0) lowest = std::min(lowest, density.data()[k]);
    bar_lo = std::max(lowest, bar_hi / 1000.0);
    if (!(bar_hi > bar_lo)) bar_lo = bar_hi / 10.0;
    const double span = std::log(bar_hi / bar_lo);
    for (int i = 0; i < bins_x; ++i) {
      for (int j = 0; j < bins_y; ++j) {
        const double d = density(i, j);
        if (!(d > 0.0)) continue;
        const double v = 0.12 + 0.88 * std::clamp(std::log(d / bar_lo) / span, 0.0, 1.0);
        // Bins are whole metres and not whole pixels: paint each bin's pixel rectangle.
        const int x0 = static_cast<int>(std::floor(i * bin_m * scale)), x1 = static_cast<int>(std::floor((i + 1) * bin_m * scale));
        const int y0 = static_cast<int>(std::floor(j * bin_m * scale)), y1 = static_cast<int>(std::floor((j + 1) * bin_m * scale));
        const Rgb c = Blues(v);
        for (int y = y0; y < std::min(y1, image.height); ++y) {
          for (int x = x0; x < std::min(x1, image.width); ++x) {
            std::uint8_t* p = image.At(x, image.height - 1 - y);
            p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
          }
        }
      }
    }
    bar_ticks = LogTicks(bar_lo, bar_hi);
    bar_title = "fleet time (vehicle-s per m\u00b2)";
    shading_text = fmt::format(
        "Shading: the fleet's time, vehicle-seconds per m\u00b2 in {} m bins (log scale; each plotted sample counts {} s); red "
        "lines: the risk density at 10 % and 50 % of its peak.",
        TickLabel(bin_m, bin_m), TickLabel(sample_s, sample_s < 1.0 ? 0.1 : 1.0));
  }

  // The caption, wrapped at the figure's width (its lines are known once the labels are placed:
  // it is written last, and its height reserved for the longest it can be).
  const double caption_width = figure_w - kLeft - 10.0;

  fmt::memory_buffer body;  // the drawing; the document's header needs the final height
  const auto put = [&]<typename... A>(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(body), format, std::forward<A>(args)...);
  };

  put("<text x=\"{}\" y=\"26\" font-size=\"15\">{}</text>\n", kLeft, XmlEscape(input.title));
  put("<image x=\"{:.1f}\" y=\"{:.1f}\" width=\"{}\" height=\"{}\" preserveAspectRatio=\"none\" href=\"{}\"/>\n", kLeft, kTop,
      image.width, image.height, PngDataUri(image));
  if (layout.density) {
    put("<path fill=\"none\" stroke=\"#cb181d\" stroke-width=\"0.8\" d=\"{}\"/>\n",
        ContourPath(risk, 0.1 * risk_peak, px, py, cell_m));
    put("<path fill=\"none\" stroke=\"#cb181d\" stroke-width=\"1.6\" d=\"{}\"/>\n",
        ContourPath(risk, 0.5 * risk_peak, px, py, cell_m));
  }
  // Clip what is drawn in metres to the map.
  put("<defs><clipPath id=\"map\"><rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\"/></clipPath></defs>\n",
      kLeft, kTop, map_w, map_h);
  put("<g clip-path=\"url(#map)\">\n");
  for (const maps::Flowline& f : scenario.flowlines) {
    put("<polyline fill=\"none\" stroke=\"#b8860b\" stroke-opacity=\"0.8\" stroke-linejoin=\"round\" stroke-width=\"{:.1f}\" "
        "points=\"", std::max(1.5, f.diameter_m * scale));
    for (const Eigen::Vector2d& p : f.points_m) put("{:.1f},{:.1f} ", px(p.x()), py(p.y()));
    put("\"><title>{} ({} m)</title></polyline>\n", XmlEscape(f.name), f.diameter_m);
  }
  for (const maps::Boulder& b : scenario.boulders) {
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"#8a8a8a\" stroke=\"#505050\"/>\n", px(b.center_m.x()),
        py(b.center_m.y()), std::max(1.0, 0.5 * b.diameter_m * scale));
  }
  // Tracks: at most ~4,000 points each (the eye cannot tell more apart at this size).
  constexpr double kMaxPointsPerTrack = 4000.0;
  std::vector<std::string> lines;  // each track's points, drawn halos first (a later halo had cut earlier tracks)
  for (const int v : drawn) {
    const std::vector<Eigen::Vector2d>& points = paths.at(v);
    const std::size_t stride = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(points.size() / kMaxPointsPerTrack)));
    std::string& line = lines.emplace_back();
    for (std::size_t k = 0; k < points.size(); k += stride) fmt::format_to(std::back_inserter(line), "{:.1f},{:.1f} ", px(points[k].x()), py(points[k].y()));
    fmt::format_to(std::back_inserter(line), "{:.1f},{:.1f}", px(points.back().x()), py(points.back().y()));
    if (layout.density) {
      put("<polyline fill=\"none\" stroke=\"white\" stroke-width=\"3.6\" stroke-opacity=\"0.9\" stroke-linejoin=\"round\" "
          "points=\"{}\"/>\n",
          line);
    }
  }
  for (std::size_t k = 0; k < drawn.size(); ++k) {
    put("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-opacity=\"0.8\" stroke-linejoin=\"round\" "
        "points=\"{}\"><title>{}</title></polyline>\n",
        colour_of[drawn[k]], layout.density ? 1.6 : 1.2, lines[k], XmlEscape(vehicle_name(drawn[k])));
  }
  put("</g>\n");

  // What labels must keep clear of: the scale bar, structures, valve dots, markers, track ends.
  LabelPlacer placer(layout.map, 1.5);
  const double bar_m = ScaleBarLength(0.25 * width_m), bar_px = bar_m * scale;
  layout.scale_bar_m = bar_m;
  const Box scale_box{kLeft + 6.0, kTop + map_h - 30.0, kLeft + 18.0 + bar_px + 10.0, kTop + map_h - 4.0};
  const bool draw_scale_bar = map_h >= 40.0 && bar_px >= 20.0;
  if (draw_scale_bar) placer.AddObstacle(scale_box);
  // On a crowded field (hundreds of valves) the riskiest valves matter more to a reader than the
  // XTs' names: the kMaxCrowdedValveLabels heaviest are labelled first, and an XT is named only
  // inside its footprint (hundreds of names beside XTs, with leader lines, read as noise).
  const bool crowded = valves.size() > kCrowdedValves;
  std::vector<std::size_t> by_weight(valves.size());
  for (std::size_t i = 0; i < valves.size(); ++i) by_weight[i] = i;
  std::stable_sort(by_weight.begin(), by_weight.end(), [&](std::size_t a, std::size_t b) { return weights[a] > weights[b]; });
  const std::size_t valve_labels_tried = crowded ? std::min(valves.size(), kMaxCrowdedValveLabels) : valves.size();
  // XT footprints under 3 px on a crowded field (10,000 XTs a few px apart) are specks like the
  // faded valve dots: a label may cover them, as the caption says.
  int specks_not_kept_clear = 0;
  for (const maps::ChristmasTree& xt : scenario.structures) {
    const Eigen::Vector2d lo = xt.center_m - 0.5 * xt.size_m;
    const Box box{px(lo.x()), py(lo.y() + xt.size_m.y()), px(lo.x() + xt.size_m.x()), py(lo.y())};
    layout.structures.push_back(box);
    if (crowded && std::max(box.width(), box.height()) < 3.0) {
      ++specks_not_kept_clear;
    } else {
      placer.AddObstacle(box);
    }
  }
  // Valve dots shrink with the room each valve has (35,000 valves on 720 x 480 px: 0.8 px) so
  // that they do not blacken the map, and fade below 1.5 px.
  const double valve_dot_r =
      std::clamp(0.25 * std::sqrt(map_w * map_h / std::max<std::size_t>(valves.size(), 1)), 0.8, 2.5);
  const bool faded_dots = valve_dot_r < 1.5;
  const char* valve_dot_fill = faded_dots ? "fill=\"#222\" fill-opacity=\"0.55\"" : "fill=\"#222\"";
  // Faded dots (thousands of valves, a few px apart) leave no label room anywhere: there only the
  // dots of the valves to be labelled are kept clear, and a label's white outline may hide others.
  std::vector<char> keep_clear(valves.size(), faded_dots && crowded ? 0 : 1);
  for (std::size_t k = 0; k < valve_labels_tried; ++k) keep_clear[by_weight[k]] = 1;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const Box dot = Box::Around(px(valves[i].position_m.x()), py(valves[i].position_m.y()), valve_dot_r + 1.0);
    layout.valve_markers.push_back(dot);
    if (keep_clear[i]) placer.AddObstacle(dot);
  }
  for (const EventMarker& e : input.events) placer.AddObstacle(Box::Around(px(e.position_m.x()), py(e.position_m.y()), 7.0));
  // The hidden leaks (the scenario's; the server never knew them): a red cross each.
  std::vector<Eigen::Vector2d> leaks_px;
  for (const maps::LeakSpec& leak : scenario.leaks) {
    const Eigen::Vector2d at = maps::LeakPosition(scenario, leak);
    leaks_px.emplace_back(px(at.x()), py(at.y()));
    placer.AddObstacle(Box::Around(leaks_px.back().x(), leaks_px.back().y(), 7.5));
  }
  for (const int v : drawn) {
    placer.AddObstacle(Box::Around(px(paths.at(v).front().x()), py(paths.at(v).front().y()), 5.0));
    placer.AddObstacle(Box::Around(px(paths.at(v).back().x()), py(paths.at(v).back().y()), 5.0));
  }

  // Structures and valves.
  for (std::size_t k = 0; k < scenario.structures.size(); ++k) {
    const Box& b = layout.structures[k];
    put("<rect id=\"xt-{}\" x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n", k, b.x0, b.y0,
        std::max(1.0, b.width()), std::max(1.0, b.height()), kStructureFill);
  }
  const double visit_r = scenario.visit_radius_m * scale;
  for (std::size_t i = 0; i < valves.size(); ++i) {
    const double x = px(valves[i].position_m.x()), y = py(valves[i].position_m.y());
    if (visit_r >= 4.0) {
      put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"none\" stroke=\"#222\" stroke-width=\"0.8\" "
          "stroke-dasharray=\"3 2\"/>\n", x, y, visit_r);
    }
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" {}/>\n", x, y, valve_dot_r, valve_dot_fill);
  }
  // Track starts and ends.
  for (const int v : drawn) {
    const Eigen::Vector2d a = paths.at(v).front(), b = paths.at(v).back();
    put("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4\" fill=\"{}\" stroke=\"white\" stroke-width=\"1.5\"/>\n", px(a.x()), py(a.y()),
        colour_of[v]);
    put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"8\" height=\"8\" fill=\"{}\" stroke=\"white\"/>\n", px(b.x()) - 4.0,
        py(b.y()) - 4.0, colour_of[v]);
  }
  // Event markers.
  for (const EventMarker& e : input.events) put("{}\n", MarkerSvg(e.kind, px(e.position_m.x()), py(e.position_m.y()), 9.0));
  for (const Eigen::Vector2d& p : leaks_px) {
    put("<path d=\"M{0:.1f},{1:.1f}l12,12M{0:.1f},{2:.1f}l12,-12\" stroke=\"white\" stroke-width=\"5\"/>"
        "<path d=\"M{0:.1f},{1:.1f}l12,12M{0:.1f},{2:.1f}l12,-12\" stroke=\"{3}\" stroke-width=\"3\"/>\n",
        p.x() - 6.0, p.y() - 6.0, p.y() + 6.0, kLeakMarker);
  }

  // Labels, most important first: XT names, valves by weight, then events in time order.
  const double label_h = (kAscentEm + kDescentEm) * kLabelFont;
  int label_id = 0;
  const auto write_label = [&](const Box& box, const std::string& text, const std::string& owner, bool inside,
                               const char* fill) {
    const std::string id = fmt::format("label-{}", label_id++);
    put("<text id=\"{}\" x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"{}\" fill=\"{}\"{}>{}</text>\n", id, box.x0,
        box.y0 + kAscentEm * kLabelFont, kLabelFont, fill,
        inside ? "" : " stroke=\"white\" stroke-width=\"3\" stroke-linejoin=\"round\" paint-order=\"stroke\"", XmlEscape(text));
    layout.labels.push_back({id, text, owner, box, inside});
  };
  const auto place = [&](const Box& anchor, const std::string& text, const std::string& owner, const char* fill) {
    const std::optional<LabelPlacer::Placed> at = placer.Place(anchor, TextWidth(text, kLabelFont), label_h, 3.0);
    if (!at) return false;
    if (at->far) {
      put("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#555\" stroke-width=\"0.7\"/>\n", at->from_x,
          at->from_y, at->to_x, at->to_y);
    }
    write_label(at->box, text, owner, false, fill);
    return true;
  };
  int xt_labels_out = 0, valve_labels_out = 0, event_labels_out = 0;
  int xt_labels_not_tried = 0;
  const auto label_xts = [&](bool beside) {
    for (std::size_t k = 0; k < scenario.structures.size(); ++k) {
      const maps::ChristmasTree& xt = scenario.structures[k];
      const Box& b = layout.structures[k];
      const double w = TextWidth(xt.name, kLabelFont);
      // Inside its own footprint when it fits (white on the footprint), else beside it.
      const Box inside{0.5 * (b.x0 + b.x1) - 0.5 * w, 0.5 * (b.y0 + b.y1) - 0.5 * label_h, 0.5 * (b.x0 + b.x1) + 0.5 * w,
                       0.5 * (b.y0 + b.y1) + 0.5 * label_h};
      if (b.Grown(-2.0).Contains(inside)) {
        write_label(inside, xt.name, xt.name, true, "white");
      } else if (!beside) {
        ++xt_labels_not_tried;
      } else if (!place(b, xt.name, xt.name, "#222")) {
        ++xt_labels_out;
      }
    }
  };
  const auto label_valves = [&] {
    for (std::size_t k = 0; k < valve_labels_tried; ++k) {
      const std::size_t i = by_weight[k];
      // The weight as the run table prints it.
      const std::string text = valves[i].name + " " + WeightText(weights[i]);
      if (!place(layout.valve_markers[i], text, valves[i].name, "#111")) ++valve_labels_out;
    }
  };
  // The hidden leaks' onsets first: what the mission was out to find (at most kMaxEventLabels).
  int leak_labels_out = 0;
  for (std::size_t k = 0; k < scenario.leaks.size(); ++k) {
    const maps::LeakSpec& leak = scenario.leaks[k];
    const std::string text = fmt::format("leak from {}", Seconds(leak.start_s));
    if (static_cast<int>(k) >= kMaxEventLabels ||
        !place(Box::Around(leaks_px[k].x(), leaks_px[k].y(), 7.5), text, "leak " + maps::LeakWhere(leak), kLeakMarker)) {
      ++leak_labels_out;
    }
  }
  if (crowded) {
    label_valves();
    label_xts(false);
  } else {
    label_xts(true);
    label_valves();
  }
  // Risk changes at one valve share a label: "150 s: 0.45, 300 s: 0.10".
  std::map<std::string, std::string> risk_text;
  std::map<std::string, Eigen::Vector2d> risk_at;
  std::vector<std::string> risk_order;
  int event_labels_tried = 0;
  for (const EventMarker& e : input.events) {
    if (e.kind != EventMarker::Kind::kRisk) continue;
    if (!risk_text.count(e.who)) risk_order.push_back(e.who);
    std::string& t = risk_text[e.who];
    t += fmt::format("{}{}: {:.2f}", t.empty() ? "" : ", ", Seconds(e.time_s), e.share);
    risk_at[e.who] = e.position_m;
  }
  for (const std::string& valve : risk_order) {
    if (++event_labels_tried > kMaxEventLabels) {
      ++event_labels_out;
      continue;
    }
    const Eigen::Vector2d p = risk_at[valve];
    if (!place(Box::Around(px(p.x()), py(p.y()), 7.0), risk_text[valve], valve, kRiskMarker)) ++event_labels_out;
  }
  for (const EventMarker& e : input.events) {
    if (e.kind == EventMarker::Kind::kRisk) continue;
    if (++event_labels_tried > kMaxEventLabels) {
      ++event_labels_out;
      continue;
    }
    const char* colour = e.kind == EventMarker::Kind::kJoin ? "#1a7a1a" : e.kind == EventMarker::Kind::kLoss ? kLossMarker : "#333";
    const std::string text = fmt::format("{} {} {}", e.who, ToString(e.kind), Seconds(e.time_s));
    if (!place(Box::Around(px(e.position_m.x()), py(e.position_m.y()), 7.0), text, e.who, colour)) ++event_labels_out;
  }
  layout.labels_left_out = xt_labels_out + valve_labels_out + event_labels_out + leak_labels_out;

  // The map's frame, axes and scale bar.
  put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#222\"/>\n", kLeft, kTop, map_w,
      map_h);
  const Ticks x_ticks = LinearTicks(0.0, width_m, std::max(2, static_cast<int>(map_w / 70.0)));
  const Ticks y_ticks = LinearTicks(0.0, height_m, std::max(2, static_cast<int>(map_h / 45.0)));
  layout.x_ticks_m = x_ticks.values;
  layout.y_ticks_m = y_ticks.values;
  // The document: header, body, then what is drawn in document terms.
  std::vector<std::string> caption;
  caption.push_back(
      "Valve labels: name and weight; the weight is averaged over the mission, as in the run table's Weight column.");
  caption.push_back(shading_text);
  if (layout.density) {
    std::string names;
    for (std::size_t k = 0; k < layout.highlighted.size(); ++k) names += (k ? ", " : "") + layout.highlighted[k];
    caption.insert(caption.begin(), fmt::format("{} vehicles; {} tracks shown ({}: vehicles with an event first, then spread "
                                                "through the fleet).",
                                                Grouped(layout.vehicles), layout.highlighted.size(), names));
  }
  if (!scenario.leaks.empty()) {
    caption.push_back(fmt::format("Red crosses: the scenario's {} hidden leak{} with {} onset{}; the server never knew them.",
                                  scenario.leaks.size(), scenario.leaks.size() == 1 ? "" : "s",
                                  scenario.leaks.size() == 1 ? "its" : "their", scenario.leaks.size() == 1 ? "" : "s"));
  }
  if (!input.events.empty() || input.events_not_kept > 0) {
    std::string events = "Markers: where and when risk changed (at the valve), and where a vehicle joined (first seen), "
                         "was lost or left (last seen)";
    if (input.events_not_kept > 0) events += fmt::format("; {} later events not drawn", Grouped(static_cast<long long>(input.events_not_kept)));
    caption.push_back(events + ".");
  }
  if (layout.labels_left_out > 0) {
    caption.push_back(fmt::format("{} of {} labels left out where they would cover another label, a structure or a marker "
                                  "({}, then events).",
                                  Grouped(layout.labels_left_out),
                                  Grouped(static_cast<long long>(layout.labels.size()) + layout.labels_left_out),
                                  crowded ? "the heaviest valves, then XTs" : "XTs, then valves by weight"));
  }
  if (xt_labels_not_tried > 0) {
    caption.push_back(xt_labels_not_tried == 1
                          ? std::string("1 XT is too small at this scale to hold its name and is not named.")
                          : fmt::format("{} XTs are too small at this scale to hold their names and are not named.",
                                        Grouped(xt_labels_not_tried)));
  }
  if (valve_labels_tried < valves.size()) {
    caption.push_back(fmt::format("Of {} valves, the {} of highest weight are labelled (where there is room){}.",
                                  Grouped(static_cast<long long>(valves.size())), valve_labels_tried,
                                  faded_dots && specks_not_kept_clear > 0
                                      ? "; a label's outline may hide the faded dots of other valves and XT footprints under 3 px"
                                  : faded_dots            ? "; a label's outline may hide the faded dots of other valves"
                                  : specks_not_kept_clear ? "; a label's outline may hide XT footprints under 3 px"
                                                          : ""));
  }
  std::vector<std::string> caption_lines;
  for (const std::string& c : caption)
    for (std::string& line : WrapText(c, caption_width, kCaptionFont)) caption_lines.push_back(std::move(line));
  layout.caption = caption_lines;
  const double caption_top = legend_bottom + 22.0;
  const double figure_h = caption_top + 15.0 * caption_lines.size() + 6.0;

  SvgDocument svg(figure_w, figure_h);
  svg.Put("{}", std::string_view(body.data(), body.size()));
  DrawAxis(svg, {AxisSpec::Side::kBottom, kLeft, kTop, kLeft + map_w, kTop + map_h, x_ticks.values, px,
                 [&](double v) { return TickLabel(v, x_ticks.step); }, "x (m)"});
  DrawAxis(svg, {AxisSpec::Side::kLeft, kLeft, kTop, kLeft + map_w, kTop + map_h, y_ticks.values, py,
                 [&](double v) { return TickLabel(v, y_ticks.step); }, "y (m)"});
  if (draw_scale_bar) {
    const double x = scale_box.x0 + 6.0, y = scale_box.y1 - 8.0;
    svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"white\" fill-opacity=\"0.8\" rx=\"2\"/>\n",
            scale_box.x0, scale_box.y0, scale_box.width(), scale_box.height());
    svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"4\" fill=\"#222\"/>\n", x, y, 0.5 * bar_px);
    svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"4\" fill=\"white\" stroke=\"#222\" stroke-width=\"0.8\"/>\n",
            x + 0.5 * bar_px, y, 0.5 * bar_px);
    svg.Text(x + 0.5 * bar_px, y - 4.0, fmt::format("{} m", TickLabel(bar_m, bar_m)), 11.0, "middle");
  }
  // The colour bar, right of the map.
  {
    const double x = kLeft + map_w + kColourBarGap, y0 = kTop, y1 = kTop + colour_bar_h;
    const bool log_scale = layout.density;
    const auto to_unit = [&](double v) {
      return log_scale ? std::log(v / bar_lo) / std::log(bar_hi / bar_lo) : (v - bar_lo) / (bar_hi - bar_lo);
    };
    const auto bar_y = [&](double v) { return y1 - to_unit(v) * (y1 - y0); };
    constexpr int kSteps = 64;
    for (int k = 0; k < kSteps; ++k) {
      const double u = (k + 0.5) / kSteps;
      const Rgb c = log_scale ? Blues(0.12 + 0.88 * u) : Reds(u);
      svg.Put("<rect x=\"{:.1f}\" y=\"{:.2f}\" width=\"{}\" height=\"{:.2f}\" fill=\"{}\"/>\n", x, y1 - (k + 1) * (y1 - y0) / kSteps,
              kColourBarWidth, (y1 - y0) / kSteps + 0.3, Hex(c));
    }
    svg.Put("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{}\" height=\"{:.1f}\" fill=\"none\" stroke=\"#222\"/>\n", x, y0,
            kColourBarWidth, y1 - y0);
    const double step = bar_ticks.size() > 1 ? bar_ticks[1] - bar_ticks[0] : bar_hi;
    double widest = 0.0;
    for (const double t : bar_ticks) {
      const double y = bar_y(t);
      svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"#222\"/>\n", x + kColourBarWidth, y,
              x + kColourBarWidth + 4.0);
      const std::string text = log_scale ? TickLabel(t, t) : TickLabel(t, step);
      widest = std::max(widest, TextWidth(text, 11.0));
      svg.Text(x + kColourBarWidth + 7.0, y + 4.0, text, 11.0, "start", "fill=\"#333\"");
    }
    svg.Put("<text transform=\"translate({:.1f} {:.1f}) rotate(90)\" font-size=\"12\" text-anchor=\"middle\">{}</text>\n",
            x + kColourBarWidth + 14.0 + widest, 0.5 * (y0 + y1), XmlEscape(bar_title));
  }
  // Legend and caption.
  for (const Placed& p : legend_at) {
    svg.Put("<g transform=\"translate({:.1f} {:.1f})\">{}</g>\n", p.x, p.y - 4.0, p.item->symbol);
    svg.Text(p.x + 30.0, p.y, p.item->text, kLegendFont);
  }
  for (std::size_t k = 0; k < caption_lines.size(); ++k) {
    svg.Text(kLeft, caption_top + 15.0 * k, caption_lines[k], kCaptionFont, "start", "fill=\"#444\"");
  }
  if (layout_out != nullptr) *layout_out = std::move(layout);
  return svg.Finish();
}

}  // namespace sage::server::plots
