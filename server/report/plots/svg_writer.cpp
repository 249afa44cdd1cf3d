#include "server/report/plots/svg_writer.h"

#include <algorithm>
#include <cmath>

#include "server/report/plots/label_placer.h"

namespace sage::server::plots {
namespace {

Rgb Interpolate(const Rgb (&stops)[5], double v) {
  const double x = std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  Rgb out;
  for (int c = 0; c < 3; ++c) out[c] = static_cast<std::uint8_t>(std::lround(stops[i][c] + f * (stops[i + 1][c] - stops[i][c])));
  return out;
}

}  // namespace

std::string XmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
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

std::vector<std::string> WrapText(std::string_view text, double width_px, double font_px) {
  std::vector<std::string> lines;
  std::string line;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t space = std::min(text.find(' ', at), text.size());
    const std::string_view word = text.substr(at, space - at);
    at = space + 1;
    if (word.empty()) continue;
    const std::string candidate = line.empty() ? std::string(word) : line + " " + std::string(word);
    if (!line.empty() && TextWidth(candidate, font_px) > width_px) {
      lines.push_back(line);
      line = std::string(word);
    } else {
      line = candidate;
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

std::string Hex(const Rgb& c) { return fmt::format("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]); }

Rgb Reds(double v) {
  static constexpr Rgb kStops[5] = {{255, 245, 240}, {252, 187, 161}, {251, 106, 74}, {203, 24, 29}, {103, 0, 13}};
  return Interpolate(kStops, v);
}

Rgb Blues(double v) {
  static constexpr Rgb kStops[5] = {{247, 251, 255}, {198, 219, 239}, {107, 174, 214}, {33, 113, 181}, {8, 48, 107}};
  return Interpolate(kStops, v);
}

SvgDocument::SvgDocument(double width_px, double height_px) : width_(width_px), height_(height_px) {
  Put("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\" "
      "font-family=\"{2}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      width_px, height_px, kFontFamily);
}

void SvgDocument::Text(double x, double y, std::string_view text, double font_px, std::string_view anchor,
                       std::string_view attributes, bool halo) {
  Put("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"{}\"{}{}{}>{}</text>\n", x, y, font_px,
      anchor == "start" ? std::string() : fmt::format(" text-anchor=\"{}\"", anchor),
      halo ? " stroke=\"white\" stroke-width=\"3\" stroke-linejoin=\"round\" paint-order=\"stroke\"" : "",
      attributes.empty() ? std::string() : " " + std::string(attributes), XmlEscape(text));
}

std::string SvgDocument::Finish() {
  Put("</svg>\n");
  return std::string(out_.data(), out_.size());
}

void DrawAxis(SvgDocument& svg, const AxisSpec& a) {
  constexpr double kTick = 5.0, kFont = 11.0;
  const bool bottom = a.side == AxisSpec::Side::kBottom;
  svg.Put("<g stroke=\"#333\" stroke-width=\"1\">\n");
  for (const double t : a.ticks) {
    const double p = a.to_px(t);
    if (bottom) {
      svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\"/>\n", p, a.box_y1, a.box_y1 + kTick);
      if (a.grid) svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/>\n", p, a.box_y0, a.box_y1);
    } else {
      svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\"/>\n", a.box_x0 - kTick, p, a.box_x0);
      if (a.grid) svg.Put("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"#ddd\"/>\n", a.box_x0, p, a.box_x1);
    }
  }
  svg.Put("</g>\n");
  double widest = 0.0;
  for (const double t : a.ticks) {
    const double p = a.to_px(t);
    const std::string text = a.label(t);
    widest = std::max(widest, TextWidth(text, kFont));
    if (bottom) svg.Text(p, a.box_y1 + kTick + kFont + 2.0, text, kFont, "middle", "fill=\"#333\"");
    else svg.Text(a.box_x0 - kTick - 3.0, p + 0.35 * kFont, text, kFont, "end", "fill=\"#333\"");
  }
  if (a.title.empty()) return;
  if (bottom) {
    svg.Text(0.5 * (a.box_x0 + a.box_x1), a.box_y1 + kTick + 2.0 * kFont + 8.0, a.title, 12.0, "middle");
  } else {
    const double x = a.box_x0 - kTick - 3.0 - widest - 8.0, y = 0.5 * (a.box_y0 + a.box_y1);
    svg.Put("<text transform=\"translate({:.1f} {:.1f}) rotate(-90)\" font-size=\"12\" text-anchor=\"middle\">{}</text>\n",
            x, y, XmlEscape(a.title));
  }
}

}  // namespace sage::server::plots
