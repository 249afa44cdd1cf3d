#pragma once
// The charts a mission leaves in its run directory, each as SVG and as PNG:
// - plot.svg / plot.png: the field — the risk density (or, over 12 vehicles, the fleet's time as
//   a 2-D histogram with the risk as contours and a few highlighted tracks), flowlines, boulders,
//   XTs, valves with their visit radii and weights, the vehicles' tracks, markers where and when
//   risk changed and vehicles joined, were lost or left; axes in metres, a scale bar, a colour
//   bar, labels that do not collide, a legend and a caption saying what the numbers are;
// - metric.svg / metric.png: the ergodic metric over the mission on a log axis, with the same
//   events on the time axis;
// - revisits.svg / revisits.png: each valve's longest unwatched stretch and mean revisit
//   interval, longest first, with its weight.
// Everything is drawn from the mission's figures (MissionMetrics: the run table's numbers) and
// its record (the trajectory, fleet and risk events), never re-derived.
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "maps/scenario/scenario.h"
#include "server/metrics.h"
#include "server/report/plots/label_placer.h"
#include "server/trajectory.h"

namespace sage::server::plots {

/// Something that happened at a place and a time, marked on the plots.
struct EventMarker {
  enum class Kind { kRisk, kJoin, kLoss, kLeave };
  Kind kind = Kind::kRisk;
  double time_s = 0.0;
  /// The valve (a risk change), where the vehicle was first seen (a join) or last seen (a loss
  /// or a leave), in workspace metres.
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  std::string who;  ///< the valve's or the vehicle's name
  double share = std::numeric_limits<double>::quiet_NaN();  ///< a risk change: the valve's new share
};
const char* ToString(EventMarker::Kind kind);

struct MissionPlotInput {
  const maps::Scenario* scenario = nullptr;
  const MissionMetrics* metrics = nullptr;  ///< the run table's figures: weights, gaps, metric over time
  const Trajectory* trajectory = nullptr;   ///< the tracks (a thinned copy is enough)
  std::vector<EventMarker> events;
  std::size_t events_not_kept = 0;          ///< events beyond what the record kept for the plot
  std::string title;
  /// Mission times the mission was resumed at after its server stopped (fleet_events' "resumed"):
  /// marked on the metric chart, whose curve restarts from the checkpoint there.
  std::vector<double> resumed_at_s;
};

struct FieldPlotOptions {
  int max_tracks = 12;         ///< above this many vehicles: the density plot
  int highlighted_tracks = 3;  ///< tracks drawn over the density
};

/// What the field plot drew where, for tests and for whoever places more on it.
struct FieldPlotLayout {
  Box map;                              ///< the workspace's box (px)
  double px_per_m = 0.0;
  bool density = false;                 ///< the fleet's time drawn instead of every track
  int vehicles = 0;
  std::vector<std::string> highlighted; ///< density mode: the tracks drawn
  std::vector<double> x_ticks_m, y_ticks_m;
  double scale_bar_m = 0.0;
  std::vector<Box> structures;          ///< XT footprints (px), in the scenario's order
  std::vector<Box> valve_markers;       ///< each valve's dot (px)
  struct Label {
    std::string id;           ///< the SVG element's id
    std::string text;
    std::string owner;        ///< the XT, valve or vehicle it names
    Box box;                  ///< where the placer put it (px)
    bool inside_owner = false;///< an XT's name written inside its own footprint
  };
  std::vector<Label> labels;
  int labels_left_out = 0;
  std::vector<std::string> caption;     ///< the caption's lines
};

/// plot.svg. Throws std::invalid_argument if an input is missing.
std::string FieldPlotSvg(const MissionPlotInput& input, FieldPlotLayout* layout = nullptr,
                         const FieldPlotOptions& options = {});
/// metric.svg: the ergodic metric over time.
std::string MetricChartSvg(const MissionPlotInput& input);
/// revisits.svg: per valve, sorted by longest gap (at most 40 rows; the rest counted).
std::string RevisitChartSvg(const MissionPlotInput& input);

struct PlotFile {
  std::string name;   ///< e.g. "plot.png"
  std::string bytes;
};
/// The six files: plot, metric and revisits, each .svg and .png (librsvg renders the PNGs).
std::vector<PlotFile> MissionPlotFiles(const MissionPlotInput& input);

}  // namespace sage::server::plots
