// shown_text (core/shown_text.hpp): what a message shows of a text it echoes. Visible characters
// stay as they are; an invisible one shows by its code and a byte that starts no well-formed UTF-8
// sequence by its value, one byte at a time, so that what follows it is read as it is.
#include <gtest/gtest.h>

#include <string>

#include "nhdyn/core/shown_text.hpp"

namespace nhdyn {
namespace {

TEST(ShownText, VisibleTextStaysAsItIs) {
  EXPECT_EQ(shown_text("x = 1e-3 * sin(phi)"), "x = 1e-3 * sin(phi)");
  EXPECT_EQ(shown_text("\u00e9t\u00e9 \u03a6 \u2212 \U0001F600"), "\u00e9t\u00e9 \u03a6 \u2212 \U0001F600");
  EXPECT_EQ(shown_text("two\nlines", true), "two\nlines");
  EXPECT_EQ(shown_text("two\nlines"), "two<U+000A>lines");
}

TEST(ShownText, InvisibleCharactersShowByTheirCode) {
  EXPECT_EQ(shown_text("a\u200bb"), "a<U+200B>b");        // zero-width space
  EXPECT_EQ(shown_text("a\u202eb"), "a<U+202E>b");        // right-to-left override
  EXPECT_EQ(shown_text("a\u2067b"), "a<U+2067>b");        // right-to-left isolate
  EXPECT_EQ(shown_text("\ufeffa"), "<U+FEFF>a");          // byte order mark
  EXPECT_EQ(shown_text("a\x1b[2Jb"), "a<U+001B>[2Jb");    // an escape sequence
  EXPECT_EQ(shown_text("a\tb\rc"), "a<U+0009>b<U+000D>c");
  EXPECT_EQ(shown_text("soft\u00adhyphen"), "soft<U+00AD>hyphen");
  EXPECT_EQ(shown_text("a\u061cb\u2028c"), "a<U+061C>b<U+2028>c");
  EXPECT_EQ(shown_text("tag\U000E0041"), "tag<U+E0041>");
}

TEST(ShownText, BytesThatAreNotUtf8ShowByTheirValueOneAtATime) {
  EXPECT_EQ(shown_text("a\xff" "b"), "a<0xFF>b");
  EXPECT_EQ(shown_text("x\x80y"), "x<0x80>y");             // a continuation byte alone; x stays x
  EXPECT_EQ(shown_text("\xc3"), "<0xC3>");                 // a sequence cut short at the end
  EXPECT_EQ(shown_text("\xe2\x80" "a"), "<0xE2><0x80>a");  // cut short before an ASCII byte
  EXPECT_EQ(shown_text("\xc0\xaf"), "<0xC0><0xAF>");       // an overlong '/'
  EXPECT_EQ(shown_text("\xed\xa0\x80"), "<0xED><0xA0><0x80>");  // a surrogate, U+D800
  EXPECT_EQ(shown_text("\xf4\x90\x80\x80"), "<0xF4><0x90><0x80><0x80>");  // past U+10FFFF
}

}  // namespace
}  // namespace nhdyn
