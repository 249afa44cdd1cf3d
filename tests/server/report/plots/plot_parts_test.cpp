// The plots' parts: nice ticks and scale bars, the label placer, and the PNGs cairo and librsvg
// write and read back. Properties over many drawn inputs, each checked by brute force.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "server/report/plots/label_placer.h"
#include "server/report/plots/nice_scale.h"
#include "server/report/plots/render.h"

namespace sage::server::plots {
namespace {

// 1, 2 or 5 times a power of ten (to 1e-9 relative).
bool IsNice(double step) {
  if (!(step > 0.0)) return false;
  const double power = std::pow(10.0, std::floor(std::log10(step) + 1e-12));
  const double m = step / power;
  return std::abs(m - 1.0) < 1e-9 || std::abs(m - 2.0) < 1e-9 || std::abs(m - 5.0) < 1e-9;
}

double NextNice(double step) {
  const double power = std::pow(10.0, std::floor(std::log10(step) + 1e-12));
  const double m = std::round(step / power);
  return (m == 1.0 ? 2.0 : m == 2.0 ? 5.0 : 10.0) * power;
}

// Ticks over 2,000 ranges drawn over eleven decades, offsets of either sign and 2-12 ticks
// asked: the step is nice, every tick a multiple of it inside [lo, hi], the ticks cover the
// range to within one step at each end, at least two of them, and no more than asked unless
// the next nice step up would leave fewer than two.
TEST(NiceScale, TicksAreNiceAndCoverTheAxis) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double span = std::pow(10.0, -4.0 + 11.0 * unit(rng));
    const double lo = (unit(rng) - 0.5) * 4.0 * span, hi = lo + span;
    const int max_ticks = 2 + static_cast<int>(unit(rng) * 11.0);
    const Ticks t = LinearTicks(lo, hi, max_ticks);
    SCOPED_TRACE(testing::Message() << "[" << lo << ", " << hi << "] max " << max_ticks << " step " << t.step);
    ASSERT_TRUE(IsNice(t.step));
    ASSERT_GE(t.values.size(), 2u);
    const double eps = 1e-9 * span;
    for (std::size_t k = 0; k < t.values.size(); ++k) {
      const double v = t.values[k];
      EXPECT_GE(v, lo - eps);
      EXPECT_LE(v, hi + eps);
      EXPECT_NEAR(v / t.step, std::round(v / t.step), 1e-6);
      if (k > 0) {
        EXPECT_NEAR(v - t.values[k - 1], t.step, 1e-9 * span);
      }
    }
    EXPECT_LT(t.values.front() - lo, t.step + eps);
    EXPECT_LT(hi - t.values.back(), t.step + eps);
    if (static_cast<int>(t.values.size()) > max_ticks) {
      const double up = NextNice(t.step);
      const long long with_up = static_cast<long long>(std::floor(hi / up + 1e-9) - std::ceil(lo / up - 1e-9)) + 1;
      EXPECT_LT(with_up, 2) << t.values.size() << " ticks for at most " << max_ticks;
    }
  }
  // The fleet field's 12 m: 0, 2, ..., 12.
  EXPECT_EQ(LinearTicks(0.0, 12.0, 10).values, (std::vector<double>{0, 2, 4, 6, 8, 10, 12}));
}

// A scale bar is the largest nice length not above what fits: nice, <= max, > max / 2.5.
TEST(NiceScale, ScaleBarIsTheLargestNiceLengthThatFits) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> exponent(-3.0, 5.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const double max = std::pow(10.0, exponent(rng));
    const double bar = ScaleBarLength(max);
    EXPECT_TRUE(IsNice(bar)) << max << " -> " << bar;
    EXPECT_LE(bar, max * (1 + 1e-12));
    EXPECT_GT(bar, max / 2.5 * (1 - 1e-12));
  }
  EXPECT_EQ(ScaleBarLength(0.0), 0.0);
}

TEST(NiceScale, TickLabelsReadAsTheNumbers) {
  EXPECT_EQ(TickLabel(1000.0, 500.0), "1,000");
  EXPECT_EQ(TickLabel(0.0, 2.0), "0");
  EXPECT_EQ(TickLabel(2.5, 0.5), "2.5");
  EXPECT_EQ(TickLabel(0.25, 0.25), "0.25");
  EXPECT_EQ(TickLabel(3e-5, 1e-5), "3e-05");
  EXPECT_EQ(Grouped(-1234567), "-1,234,567");
  const std::vector<double> log = LogTicks(2e-5, 0.3);
  EXPECT_EQ(log.size(), 4u);  // 1e-4 .. 1e-1
  for (const double v : log) EXPECT_TRUE(IsNice(v) && std::abs(std::log10(v) - std::round(std::log10(v))) < 1e-9) << v;
}

// 600 labels of random sizes at random anchors among 60 obstacles: every label placed lies in
// the bounds and overlaps no other label and no obstacle (checked pair by pair), and the ones
// left out are counted.
TEST(LabelPlacer, PlacedLabelsNeverOverlap) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(0.0, 700.0), y(0.0, 500.0), w(10.0, 90.0);
  const Box bounds{0.0, 0.0, 700.0, 500.0};
  LabelPlacer placer(bounds, 1.0);
  std::vector<Box> obstacles;
  for (int k = 0; k < 60; ++k) {
    const double x0 = x(rng), y0 = y(rng);
    obstacles.push_back({x0, y0, x0 + w(rng) * 0.5, y0 + w(rng) * 0.5});
    placer.AddObstacle(obstacles.back());
  }
  int placed = 0, missed = 0;
  for (int k = 0; k < 600; ++k) {
    const Box anchor = Box::Around(x(rng), y(rng), 3.0);
    (placer.Place(anchor, w(rng), 12.8, 3.0) ? placed : missed)++;
  }
  const std::vector<Box>& boxes = placer.placed();
  ASSERT_EQ(static_cast<int>(boxes.size()), placed);
  EXPECT_EQ(placer.left_out(), missed);
  EXPECT_GT(placed, 100);  // the placer does find room in a crowded plot
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_TRUE(bounds.Contains(boxes[i]));
    for (std::size_t j = i + 1; j < boxes.size(); ++j) ASSERT_FALSE(boxes[i].Overlaps(boxes[j])) << i << " " << j;
    for (const Box& o : obstacles) ASSERT_FALSE(boxes[i].Overlaps(o)) << i;
  }
}

// The first candidate is the upper right of the marker; with it taken, the next free one.
TEST(LabelPlacer, PrefersUpperRightThenMovesOn) {
  LabelPlacer placer({0, 0, 400, 400}, 1.0);
  const Box anchor = Box::Around(200, 200, 3);
  const auto first = placer.Place(anchor, 40, 12, 3);
  ASSERT_TRUE(first);
  EXPECT_GE(first->box.x0, anchor.x1);
  EXPECT_LE(first->box.y1, anchor.y1);
  const auto second = placer.Place(anchor, 40, 12, 3);
  ASSERT_TRUE(second);
  EXPECT_FALSE(first->box.Grown(1.0).Overlaps(second->box));
  EXPECT_LE(second->box.x1, anchor.x0);  // upper left
}

// PNG bytes as a viewer reads them: the signature, IHDR's width and height (big-endian).
void ExpectPngHeader(const std::string& png, int width, int height) {
  ASSERT_GE(png.size(), 24u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png.substr(12, 4), "IHDR");
  const auto be32 = [&](std::size_t at) {
    return (static_cast<std::uint32_t>(static_cast<std::uint8_t>(png[at])) << 24) |
           (static_cast<std::uint32_t>(static_cast<std::uint8_t>(png[at + 1])) << 16) |
           (static_cast<std::uint32_t>(static_cast<std::uint8_t>(png[at + 2])) << 8) |
           static_cast<std::uint32_t>(static_cast<std::uint8_t>(png[at + 3]));
  };
  EXPECT_EQ(be32(16), static_cast<std::uint32_t>(width));
  EXPECT_EQ(be32(20), static_cast<std::uint32_t>(height));
}

// An image encoded and decoded comes back pixel for pixel (opaque and half-transparent pixels).
TEST(Render, PngRoundTrips) {
  RgbaImage image;
  image.width = 37;
  image.height = 11;
  image.rgba.resize(37 * 11 * 4);
  for (std::size_t k = 0; k < image.rgba.size(); ++k) image.rgba[k] = static_cast<std::uint8_t>((k * 37) % 256);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) image.At(x, y)[3] = (x + y) % 2 ? 255 : 128;
  const std::string png = EncodePng(image);
  ExpectPngHeader(png, 37, 11);
  const RgbaImage back = DecodePng(png);
  ASSERT_EQ(back.width, 37);
  ASSERT_EQ(back.height, 11);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const int tolerance = image.At(x, y)[3] == 255 ? 0 : 2;  // premultiplied at alpha 128: rounding
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(back.At(x, y)[c], image.At(x, y)[c], tolerance) << x << "," << y;
    }
  }
  EXPECT_THROW(DecodePng("not a png"), std::runtime_error);
}

// librsvg draws a document at its size on white: a rectangle's pixels have its colour, the
// rest stay white; the ink box of an element is where it was drawn; bad XML is an error.
TEST(Render, SvgRendersAtItsSize) {
  const std::string svg =
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"120\" height=\"80\">"
      "<rect id=\"r\" x=\"20\" y=\"10\" width=\"30\" height=\"40\" fill=\"#336699\"/></svg>";
  const std::string png = SvgToPng(svg);
  ExpectPngHeader(png, 120, 80);
  const RgbaImage image = DecodePng(png);
  const std::uint8_t* inside = image.At(35, 30);
  EXPECT_EQ(inside[0], 0x33);
  EXPECT_EQ(inside[1], 0x66);
  EXPECT_EQ(inside[2], 0x99);
  const std::uint8_t* outside = image.At(100, 70);
  EXPECT_EQ(outside[0], 255);
  EXPECT_EQ(outside[1], 255);
  EXPECT_EQ(outside[2], 255);
  const std::optional<Box> box = RenderedBox(svg, "r");
  ASSERT_TRUE(box);
  EXPECT_NEAR(box->x0, 20.0, 0.5);
  EXPECT_NEAR(box->y1, 50.0, 0.5);
  EXPECT_THROW(SvgToPng("<svg"), std::runtime_error);
}

// The placer's estimate of a label's box holds the text librsvg draws in DejaVu Sans (what
// the run's PNG shows), to within a pixel: a label that fits on paper fits in the picture.
TEST(Render, TextWidthEstimateHoldsTheRenderedText) {
  for (const std::string text : {"XT-E", "P15 0.03", "rov5 joined 200 s", "WWW mmm 1,000 vehicles", "iiil.,"}) {
    const double font = 11.0, x = 10.0, baseline = 30.0;
    const std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"60\" "
                            "font-family=\"DejaVu Sans, sans-serif\"><text id=\"t\" x=\"10\" y=\"30\" font-size=\"11\">" +
                            text + "</text></svg>";
    const std::optional<Box> ink = RenderedBox(svg, "t");
    ASSERT_TRUE(ink) << text;
    const Box estimate{x, baseline - kAscentEm * font, x + TextWidth(text, font), baseline + kDescentEm * font};
    EXPECT_TRUE(estimate.Grown(1.0).Contains(*ink))
        << text << ": ink " << ink->x0 << "," << ink->y0 << " - " << ink->x1 << "," << ink->y1 << " estimate "
        << estimate.x0 << "," << estimate.y0 << " - " << estimate.x1 << "," << estimate.y1;
  }
}

}  // namespace
}  // namespace sage::server::plots
