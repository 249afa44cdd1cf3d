#pragma once
// Text from outside (a scenario file, a DDS sample's names) on its way into logs, CSV and JSON
// files: UTF-8 checked byte by byte. nlohmann::json refuses to write invalid UTF-8 (a valve named
// with a 0xFF byte ran its mission and then lost metrics.json, and librsvg refused the plot), and a
// C1 control (U+0080..U+009F, e.g. CSI) can drive a terminal as ESC does.
#include <cstddef>
#include <string>
#include <string_view>

namespace sage::maps {

/// The length (1-4) of the well-formed UTF-8 sequence at text[i] (no overlong forms, no
/// surrogates, at most U+10FFFF), or 0 if the bytes there are not one.
inline std::size_t Utf8SequenceAt(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return 1;
  const std::size_t n = b0 >= 0xC2 && b0 <= 0xDF ? 2 : b0 >= 0xE0 && b0 <= 0xEF ? 3 : b0 >= 0xF0 && b0 <= 0xF4 ? 4 : 0;
  if (n == 0 || i + n > text.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  const unsigned char b1 = byte(i + 1);
  if (b0 == 0xE0 && b1 < 0xA0) return 0;   // overlong
  if (b0 == 0xED && b1 >= 0xA0) return 0;  // surrogates
  if (b0 == 0xF0 && b1 < 0x90) return 0;   // overlong
  if (b0 == 0xF4 && b1 >= 0x90) return 0;  // beyond U+10FFFF
  return n;
}

/// The offset of the first byte that does not start a well-formed UTF-8 sequence, or npos.
inline std::size_t FirstNonUtf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = Utf8SequenceAt(text, i);
    if (n == 0) return i;
    i += n;
  }
  return std::string_view::npos;
}

/// `text` as one printable line of valid UTF-8: every C0 control, DEL, C1 control and byte of an
/// ill-formed sequence becomes `replacement`; at most max_chars characters (code points), then
/// `cut_mark` if there was more.
inline std::string PrintableUtf8(std::string_view text, std::size_t max_chars, char replacement = '?',
                                 std::string_view cut_mark = "...") {
  std::string out;
  std::size_t chars = 0, i = 0;
  for (; i < text.size() && chars < max_chars; ++chars) {
    const std::size_t n = Utf8SequenceAt(text, i);
    const unsigned char b0 = static_cast<unsigned char>(text[i]);
    const bool c0 = n == 1 && (b0 < 0x20 || b0 == 0x7f);
    const bool c1 = n == 2 && b0 == 0xC2 && static_cast<unsigned char>(text[i + 1]) < 0xA0;
    if (n == 0 || c0 || c1) {
      out += replacement;
      i += n == 0 ? 1 : n;
    } else {
      out.append(text.substr(i, n));
      i += n;
    }
  }
  if (i < text.size()) out.append(cut_mark);
  return out;
}

}  // namespace sage::maps
