#pragma once
// The few SVG pieces every chart of a run directory draws: the document, escaped text, wrapped
// captions, axes with nice ticks, and the colour scales. Sizes in SVG pixels, y down.
#include <array>
#include <cstdint>
#include <functional>
#include <iterator>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace sage::server::plots {

/// The plots' font: DejaVu Sans, whose widths the label placer knows, then any sans-serif.
inline constexpr const char* kFontFamily = "DejaVu Sans, sans-serif";

std::string XmlEscape(std::string_view text);

/// Splits `text` at spaces into lines no wider than `width_px` at `font_px` (a word wider than
/// that gets a line of its own).
std::vector<std::string> WrapText(std::string_view text, double width_px, double font_px);

using Rgb = std::array<std::uint8_t, 3>;
std::string Hex(const Rgb& colour);
/// ColorBrewer's sequential "Reds" (risk) and "Blues" (the fleet's time), v in [0, 1], light to dark.
Rgb Reds(double v);
Rgb Blues(double v);

class SvgDocument {
 public:
  SvgDocument(double width_px, double height_px);
  template <typename... A>
  void Put(fmt::format_string<A...> format, A&&... args) {
    fmt::format_to(std::back_inserter(out_), format, std::forward<A>(args)...);
  }
  /// A line of text; `attributes` is added to the element as is (fill, id, ...). With `halo`,
  /// the text has a white outline so it reads over lines and shading.
  void Text(double x, double y, std::string_view text, double font_px, std::string_view anchor = "start",
            std::string_view attributes = "", bool halo = false);
  double width() const { return width_; }
  double height() const { return height_; }
  /// The document, closed.
  std::string Finish();

 private:
  double width_, height_;
  fmt::memory_buffer out_;
};

/// An axis along one side of a plot box: tick marks outward, their labels, and its title.
struct AxisSpec {
  enum class Side { kBottom, kLeft };
  Side side = Side::kBottom;
  double box_x0 = 0, box_y0 = 0, box_x1 = 0, box_y1 = 0;   ///< the plot box (px)
  std::vector<double> ticks;                               ///< in data units
  std::function<double(double)> to_px;                     ///< data -> px along the axis
  std::function<std::string(double)> label;                ///< a tick's text
  std::string title;
  bool grid = false;                                       ///< faint lines across the box at the ticks
};
void DrawAxis(SvgDocument& svg, const AxisSpec& axis);

}  // namespace sage::server::plots
