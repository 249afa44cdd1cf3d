#include "server/report/plots/label_placer.h"

#include <algorithm>
#include <cmath>

namespace sage::server::plots {
namespace {

// DejaVu Sans advance widths of ASCII 32..126, per 1,000 em (read from the font with cairo,
// hinting off).
constexpr short kAdvance[95] = {
    318, 401, 460, 838, 636, 950, 780, 275, 390, 390, 500, 838, 318, 361, 318, 337,   // ' '..'/'
    636, 636, 636, 636, 636, 636, 636, 636, 636, 636, 337, 337, 838, 838, 838, 531,   // '0'..'?'
    1000, 684, 686, 698, 770, 632, 575, 775, 752, 295, 295, 656, 557, 863, 748, 787,  // '@'..'O'
    603, 787, 695, 635, 611, 732, 684, 989, 685, 611, 685, 390, 337, 390, 838, 500,   // 'P'..'_'
    500, 613, 635, 550, 635, 615, 352, 635, 634, 278, 278, 579, 278, 974, 634, 612,   // '`'..'o'
    635, 635, 411, 521, 392, 634, 592, 818, 592, 592, 525, 636, 337, 636, 838};       // 'p'..'~'
constexpr double kWidestEm = 1.0;

}  // namespace

double TextWidth(std::string_view text, double font_px) {
  double em = 0.0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 32 && c < 127) {
      em += kAdvance[c - 32] / 1000.0;
    } else if ((c & 0xC0) != 0x80) {  // the first byte of a UTF-8 sequence: one character
      em += kWidestEm;
    }
  }
  return em * font_px;
}

LabelPlacer::LabelPlacer(Box bounds, double halo) : bounds_(bounds), halo_(halo) {
  columns_ = std::max(1, static_cast<int>(std::ceil(bounds_.width() / cell_px_)));
  rows_ = std::max(1, static_cast<int>(std::ceil(bounds_.height() / cell_px_)));
  grid_.resize(static_cast<std::size_t>(columns_) * rows_);
}

std::pair<int, int> LabelPlacer::Cell(double x, double y) const {
  return {std::clamp(static_cast<int>(std::floor((x - bounds_.x0) / cell_px_)), 0, columns_ - 1),
          std::clamp(static_cast<int>(std::floor((y - bounds_.y0) / cell_px_)), 0, rows_ - 1)};
}

void LabelPlacer::Take(const Box& box, bool label) {
  (label ? placed_ : obstacles_).push_back(box);
  const int index = static_cast<int>(boxes_.size());
  boxes_.push_back(label ? box.Grown(halo_) : box);
  const auto [c0, r0] = Cell(box.x0 - halo_, box.y0 - halo_);
  const auto [c1, r1] = Cell(box.x1 + halo_, box.y1 + halo_);
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) grid_[static_cast<std::size_t>(r) * columns_ + c].push_back(index);
}

void LabelPlacer::AddObstacle(const Box& box) { Take(box, false); }

bool LabelPlacer::Free(const Box& box) const {
  if (!bounds_.Contains(box)) return false;
  const auto [c0, r0] = Cell(box.x0, box.y0);
  const auto [c1, r1] = Cell(box.x1, box.y1);
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      for (const int i : grid_[static_cast<std::size_t>(r) * columns_ + c]) {
        if (boxes_[i].Overlaps(box)) return false;
      }
    }
  }
  return true;
}

bool LabelPlacer::PlaceAt(const Box& box) {
  if (!Free(box)) return false;
  Take(box, true);
  return true;
}

std::optional<LabelPlacer::Placed> LabelPlacer::Place(const Box& anchor, double width, double height, double gap) {
  // Candidates as (horizontal, vertical) sides: -1 left/above, 0 centred, +1 right/below.
  static constexpr int kOrder[8][2] = {{1, -1}, {-1, -1}, {1, 1}, {-1, 1}, {1, 0}, {-1, 0}, {0, -1}, {0, 1}};
  for (const double reach : {gap, gap + 0.9 * height + 4.0, gap + 2.2 * height + 8.0}) {
    for (const auto& [h, v] : kOrder) {
      const double cx = 0.5 * (anchor.x0 + anchor.x1), cy = 0.5 * (anchor.y0 + anchor.y1);
      const double x0 = h > 0 ? anchor.x1 + reach : h < 0 ? anchor.x0 - reach - width : cx - 0.5 * width;
      // A label beside its marker (v = 0) is centred on it; diagonal ones sit just off its corner.
      const double y0 = v > 0 ? anchor.y1 + (h == 0 ? reach : reach * 0.3)
                        : v < 0 ? anchor.y0 - (h == 0 ? reach : reach * 0.3) - height
                                : cy - 0.5 * height;
      const Box box{x0, y0, x0 + width, y0 + height};
      if (!Free(box)) continue;
      Take(box, true);
      Placed placed{box, reach > gap};
      placed.to_x = std::clamp(cx, box.x0, box.x1);
      placed.to_y = std::clamp(cy, box.y0, box.y1);
      placed.from_x = std::clamp(placed.to_x, anchor.x0, anchor.x1);
      placed.from_y = std::clamp(placed.to_y, anchor.y0, anchor.y1);
      return placed;
    }
  }
  ++left_out_;
  return std::nullopt;
}

}  // namespace sage::server::plots
