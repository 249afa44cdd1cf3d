#pragma once
// Pixels in and out of the plots: a raster layer encoded as PNG for an SVG <image>, an SVG
// rendered to PNG, and a PNG read back. Cairo and librsvg (Debian's libcairo2, librsvg2) do the
// work; their headers stay in render.cpp.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/report/plots/label_placer.h"

namespace sage::server::plots {

/// An image, row by row from the top, 4 bytes a pixel (red, green, blue, alpha; not premultiplied).
struct RgbaImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
  std::uint8_t* At(int x, int y) { return &rgba[(static_cast<std::size_t>(y) * width + x) * 4]; }
  const std::uint8_t* At(int x, int y) const { return &rgba[(static_cast<std::size_t>(y) * width + x) * 4]; }
};

/// The image as PNG bytes. Throws std::runtime_error if cairo cannot encode it.
std::string EncodePng(const RgbaImage& image);
/// The image as an SVG href: "data:image/png;base64,...".
std::string PngDataUri(const RgbaImage& image);

/// Renders an SVG document at its own width and height in pixels, on white, as PNG bytes.
/// Throws std::runtime_error with librsvg's message for a document it cannot read.
std::string SvgToPng(std::string_view svg);

/// Decodes PNG bytes (what a viewer of plot.png sees). Throws std::runtime_error if they are not
/// a PNG.
RgbaImage DecodePng(std::string_view png);

/// The ink box (px) of the element with this id as librsvg draws it; nullopt if there is none.
/// What the plots' tests hold the label placer's estimate against.
std::optional<Box> RenderedBox(std::string_view svg, const std::string& id);

}  // namespace sage::server::plots
