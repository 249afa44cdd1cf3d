#include "server/report/plots/render.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <cairo.h>
#include <glib.h>
#include <librsvg/rsvg.h>

namespace sage::server::plots {
namespace {

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
struct HandleDeleter {
  void operator()(RsvgHandle* h) const { g_object_unref(h); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;
using Handle = std::unique_ptr<RsvgHandle, HandleDeleter>;

// The largest side cairo's image surfaces take.
constexpr int kMaxSide = 32767;

cairo_status_t AppendBytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

std::string WritePng(cairo_surface_t* surface) {
  std::string bytes;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, AppendBytes, &bytes);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cannot encode PNG: ") + cairo_status_to_string(status));
  }
  return bytes;
}

Handle ReadSvg(std::string_view svg) {
  GError* error = nullptr;
  Handle handle(rsvg_handle_new_from_data(reinterpret_cast<const guint8*>(svg.data()), svg.size(), &error));
  if (!handle) {
    const std::string message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) g_error_free(error);
    throw std::runtime_error("librsvg cannot read the SVG: " + message);
  }
  return handle;
}

}  // namespace

std::string EncodePng(const RgbaImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.width > kMaxSide || image.height > kMaxSide ||
      image.rgba.size() != static_cast<std::size_t>(image.width) * image.height * 4) {
    throw std::runtime_error("cannot encode PNG: image size");
  }
  Surface surface(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, image.width, image.height));
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  // Cairo holds native-endian 32-bit ARGB, premultiplied by alpha.
  for (int y = 0; y < image.height; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.At(x, y);
      const std::uint32_t a = p[3];
      const auto pre = [a](std::uint32_t c) { return (c * a + 127) / 255; };
      row[x] = (a << 24) | (pre(p[0]) << 16) | (pre(p[1]) << 8) | pre(p[2]);
    }
  }
  cairo_surface_mark_dirty(surface.get());
  return WritePng(surface.get());
}

std::string PngDataUri(const RgbaImage& image) {
  const std::string png = EncodePng(image);
  gchar* base64 = g_base64_encode(reinterpret_cast<const guchar*>(png.data()), png.size());
  std::string uri = std::string("data:image/png;base64,") + base64;
  g_free(base64);
  return uri;
}

std::string SvgToPng(std::string_view svg) {
  Handle handle = ReadSvg(svg);
  gdouble width = 0.0, height = 0.0;
  if (!rsvg_handle_get_intrinsic_size_in_pixels(handle.get(), &width, &height) || !(width >= 1.0) ||
      !(height >= 1.0) || width > kMaxSide || height > kMaxSide) {
    throw std::runtime_error("librsvg cannot render the SVG: it has no size in pixels within 1..32767");
  }
  const int w = static_cast<int>(std::ceil(width)), h = static_cast<int>(std::ceil(height));
  Surface surface(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h));
  Context cr(cairo_create(surface.get()));
  cairo_set_source_rgb(cr.get(), 1.0, 1.0, 1.0);
  cairo_paint(cr.get());
  const RsvgRectangle viewport{0.0, 0.0, width, height};
  GError* error = nullptr;
  if (!rsvg_handle_render_document(handle.get(), cr.get(), &viewport, &error)) {
    const std::string message = error != nullptr ? error->message : "unknown error";
    if (error != nullptr) g_error_free(error);
    throw std::runtime_error("librsvg cannot render the SVG: " + message);
  }
  cairo_surface_flush(surface.get());
  return WritePng(surface.get());
}

RgbaImage DecodePng(std::string_view png) {
  struct Reader {
    std::string_view bytes;
    std::size_t at = 0;
  } reader{png};
  const auto read = [](void* closure, unsigned char* data, unsigned int length) -> cairo_status_t {
    auto* r = static_cast<Reader*>(closure);
    if (r->bytes.size() - r->at < length) return CAIRO_STATUS_READ_ERROR;
    std::memcpy(data, r->bytes.data() + r->at, length);
    r->at += length;
    return CAIRO_STATUS_SUCCESS;
  };
  Surface surface(cairo_image_surface_create_from_png_stream(read, &reader));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("not a PNG: ") + cairo_status_to_string(cairo_surface_status(surface.get())));
  }
  // Whatever format the PNG had, draw it onto ARGB32 and undo the premultiplication.
  RgbaImage image;
  image.width = cairo_image_surface_get_width(surface.get());
  image.height = cairo_image_surface_get_height(surface.get());
  Surface argb(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, image.width, image.height));
  Context cr(cairo_create(argb.get()));
  cairo_set_source_surface(cr.get(), surface.get(), 0, 0);
  cairo_set_operator(cr.get(), CAIRO_OPERATOR_SOURCE);
  cairo_paint(cr.get());
  cairo_surface_flush(argb.get());
  const unsigned char* data = cairo_image_surface_get_data(argb.get());
  const int stride = cairo_image_surface_get_stride(argb.get());
  image.rgba.resize(static_cast<std::size_t>(image.width) * image.height * 4);
  for (int y = 0; y < image.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
    for (int x = 0; x < image.width; ++x) {
      const std::uint32_t v = row[x], a = v >> 24;
      const auto un = [a](std::uint32_t c) { return a == 0 ? 0u : std::min(255u, (c * 255 + a / 2) / a); };
      std::uint8_t* p = image.At(x, y);
      p[0] = static_cast<std::uint8_t>(un((v >> 16) & 0xff));
      p[1] = static_cast<std::uint8_t>(un((v >> 8) & 0xff));
      p[2] = static_cast<std::uint8_t>(un(v & 0xff));
      p[3] = static_cast<std::uint8_t>(a);
    }
  }
  return image;
}

std::optional<Box> RenderedBox(std::string_view svg, const std::string& id) {
  Handle handle = ReadSvg(svg);
  gdouble width = 0.0, height = 0.0;
  if (!rsvg_handle_get_intrinsic_size_in_pixels(handle.get(), &width, &height)) return std::nullopt;
  const RsvgRectangle viewport{0.0, 0.0, width, height};
  RsvgRectangle ink{}, logical{};
  GError* error = nullptr;
  const std::string selector = "#" + id;
  if (!rsvg_handle_get_geometry_for_layer(handle.get(), selector.c_str(), &viewport, &ink, &logical, &error)) {
    if (error != nullptr) g_error_free(error);
    return std::nullopt;
  }
  return Box{ink.x, ink.y, ink.x + ink.width, ink.y + ink.height};
}

}  // namespace sage::server::plots
