// UTF-8 at the door: the well-formedness check against glibc's own decoder (iconv) on every
// one- and two-byte string and every three-byte string that starts a three-byte sequence; the
// printable form of hostile names (controls C0 and C1, stray bytes, cut by characters); and a
// scenario file with a stray byte refused with its line and column.
#include "maps/scenario/printable_text.h"

#include <iconv.h>

#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "maps/scenario/scenario.h"

namespace sage::maps {
namespace {

// glibc's decoder: whether `text` converts from UTF-8 as a whole.
class Iconv {
 public:
  Iconv() : cd_(iconv_open("UTF-32LE", "UTF-8")) {}
  ~Iconv() { iconv_close(cd_); }
  bool Valid(std::string text) {
    iconv(cd_, nullptr, nullptr, nullptr, nullptr);
    char out[64];
    char* in = text.data();
    std::size_t in_left = text.size(), out_left = sizeof out;
    char* o = out;
    return iconv(cd_, &in, &in_left, &o, &out_left) != static_cast<std::size_t>(-1) && in_left == 0;
  }

 private:
  iconv_t cd_;
};

TEST(PrintableText, WellFormedAsGlibcDecodesIt) {
  Iconv glibc;
  int checked = 0, valid = 0;
  const auto check = [&](const std::string& s) {
    const bool ours = FirstNonUtf8(s) == std::string::npos;
    ASSERT_EQ(ours, glibc.Valid(s)) << "bytes " << std::hex << static_cast<int>(static_cast<unsigned char>(s[0]));
    ++checked;
    valid += ours ? 1 : 0;
  };
  for (int a = 0; a < 256; ++a) check(std::string(1, static_cast<char>(a)));
  for (int a = 0; a < 256; ++a)
    for (int b = 0; b < 256; ++b) check({static_cast<char>(a), static_cast<char>(b)});
  for (int a = 0xE0; a <= 0xEF; ++a)
    for (int b = 0; b < 256; ++b)
      for (int c = 0; c < 256; ++c) check({static_cast<char>(a), static_cast<char>(b), static_cast<char>(c)});
  EXPECT_EQ(checked, 256 + 65536 + 16 * 65536);
  // 128 ASCII + 128 ASCII^2 + 30 x 64 two-byte, and 16 x 64 x 64 less 32 x 64 overlong and 32 x 64 surrogates.
  EXPECT_EQ(valid, 128 + 128 * 128 + 30 * 64 + (16 * 64 * 64 - 2 * 32 * 64));
  // Four bytes: U+10000 and U+10FFFF are; overlong, beyond U+10FFFF and cut short are not.
  EXPECT_EQ(FirstNonUtf8("\xF0\x90\x80\x80"), std::string::npos);
  EXPECT_EQ(FirstNonUtf8("\xF4\x8F\xBF\xBF"), std::string::npos);
  EXPECT_EQ(FirstNonUtf8("\xF0\x8F\xBF\xBF"), 0u);
  EXPECT_EQ(FirstNonUtf8("\xF4\x90\x80\x80"), 0u);
  EXPECT_EQ(FirstNonUtf8("ok\xF0\x90\x80"), 2u);
}

TEST(PrintableText, HostileNamesBecomeOnePrintableLine) {
  EXPECT_EQ(PrintableUtf8("P1", 64), "P1");
  EXPECT_EQ(PrintableUtf8("a\nb\x1b[31m", 64), "a?b?[31m");
  EXPECT_EQ(PrintableUtf8("\xC2\x9B" "31m", 64), "?31m") << "C1 CSI, as a terminal in UTF-8 reads it";
  EXPECT_EQ(PrintableUtf8("\xFF\xFEok", 64), "??ok");
  EXPECT_EQ(PrintableUtf8("Ventil \xC3\xB6l \xE2\x82\xAC", 64), "Ventil \xC3\xB6l \xE2\x82\xAC") << "letters kept";
  // Cut by characters, never inside one: 3 x "e-acute" = 6 bytes, 2 characters kept.
  EXPECT_EQ(PrintableUtf8("\xC3\xA9\xC3\xA9\xC3\xA9", 2), "\xC3\xA9\xC3\xA9...");
  EXPECT_EQ(PrintableUtf8(std::string(100, 'x'), 64, '_', ""), std::string(64, 'x'));
  const std::string out = PrintableUtf8("\xE2\x82", 64);
  EXPECT_EQ(FirstNonUtf8(out), std::string::npos) << "a cut sequence is replaced, not kept";
}

TEST(PrintableText, AScenarioWithAStrayByteIsRefusedWhereItIs) {
  const std::string yaml = "workspace: {width_m: 6, height_m: 5}\n"
                           "structures:\n"
                           "  - {name: XT, center_m: [3, 2.5], size_m: [0.5, 0.5], valves: [{name: \"P\xFF" "1\", position_m: [3, 3.5]}]}\n";
  try {
    ParseScenario(yaml, "x.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const ScenarioError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("x.yaml: line 3, column 74: byte 0xFF is not UTF-8 text"), std::string::npos) << what;
    EXPECT_EQ(FirstNonUtf8(what), std::string::npos) << "the error itself is UTF-8";
  }
}

}  // namespace
}  // namespace sage::maps
