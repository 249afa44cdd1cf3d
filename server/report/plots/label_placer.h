#pragma once
// Where a plot's labels go: each is tried at candidate positions around what it names (the
// cartographers' order: upper right first, then upper left, lower right, lower left, the sides,
// above, below; then the same ring farther out, with a leader line) and takes the first that
// overlaps no label placed before it, no obstacle (structures, valve markers, event markers)
// and stays inside the plot. Labels are placed in the order given, so the caller gives the
// important ones first; one that finds no room is left out and counted, never drawn on top of
// another. Sizes are in SVG pixels, y down.
#include <optional>
#include <string_view>
#include <vector>

namespace sage::server::plots {

struct Box {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  ///< left, top, right, bottom (px)
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  bool Overlaps(const Box& other) const {
    return x0 < other.x1 && other.x0 < x1 && y0 < other.y1 && other.y0 < y1;
  }
  bool Contains(const Box& inner) const {
    return inner.x0 >= x0 && inner.x1 <= x1 && inner.y0 >= y0 && inner.y1 <= y1;
  }
  Box Grown(double by) const { return {x0 - by, y0 - by, x1 + by, y1 + by}; }
  static Box Around(double x, double y, double radius) { return {x - radius, y - radius, x + radius, y + radius}; }
};

/// The text's box in DejaVu Sans (the font the plots name first, and the one librsvg finds on
/// Debian) at `font_px`: its advance widths summed, 1.164 em tall (ascent 0.928 + descent 0.236).
/// Characters outside ASCII count as the widest ASCII one, so the box errs large, never small.
double TextWidth(std::string_view text, double font_px);
constexpr double kAscentEm = 0.928, kDescentEm = 0.236;

class LabelPlacer {
 public:
  /// Labels must lie within `bounds`; `halo` is the clearance kept around each placed label.
  explicit LabelPlacer(Box bounds, double halo = 1.0);

  /// Something no label may cover.
  void AddObstacle(const Box& box);

  struct Placed {
    Box box;  ///< the label's box (px)
    bool far = false;  ///< placed on an outer ring: draw a leader line, from the anchor's edge...
    double from_x = 0, from_y = 0, to_x = 0, to_y = 0;  ///< ... to the label's nearest point
  };
  /// Places a label of `width` x `height` px next to `anchor` (the marker's box), at `gap` px
  /// from it; nullopt if no candidate is free (the label is then counted as left out).
  std::optional<Placed> Place(const Box& anchor, double width, double height, double gap);
  /// Places a label exactly at `box` if it is free (e.g. inside its own structure); the box
  /// becomes taken.
  bool PlaceAt(const Box& box);

  const std::vector<Box>& placed() const { return placed_; }
  int left_out() const { return left_out_; }

 private:
  bool Free(const Box& box) const;
  void Take(const Box& box, bool label);
  std::pair<int, int> Cell(double x, double y) const;

  Box bounds_;
  double halo_;
  double cell_px_ = 48.0;
  int columns_ = 1, rows_ = 1;
  std::vector<Box> placed_, obstacles_;
  // A uniform grid over the plot: each cell lists the boxes (index into boxes_) touching it, so
  // a candidate is tested against its neighbours only (3,500 valve labels on a 1,000-XT field).
  std::vector<Box> boxes_;
  std::vector<std::vector<int>> grid_;
  int left_out_ = 0;
};

}  // namespace sage::server::plots
