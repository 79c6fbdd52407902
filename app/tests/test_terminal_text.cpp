// SPDX-License-Identifier: BSD-3-Clause
// terminal_text (app/terminal_text.hpp): what a terminal acts on is escaped, the rest unchanged.
#include <gtest/gtest.h>

#include <string>

#include "terminal_text.hpp"

namespace ukdyn::cli {
namespace {

TEST(TerminalText, ControlCharactersAreEscaped) {
  // C0 (ESC, BEL, CR), DEL
  EXPECT_EQ(terminal_text("\x1b]0;owned\x07\x1b[31mRED\r\x7f"),
            "\\x1b]0;owned\\x07\\x1b[31mRED\\x0d\\x7f");
  // C1 (U+009B, CSI) and the bidirectional controls U+202A..U+202E, U+2066..U+2069
  EXPECT_EQ(terminal_text("a\xc2\x9b"
                          "2J"),
            "a\\u009b2J");
  EXPECT_EQ(terminal_text("\xe2\x80\xaa\xe2\x80\xae\xe2\x81\xa6\xe2\x81\xa9"),
            "\\u202a\\u202e\\u2066\\u2069");
  // bytes that are not UTF-8: a lone 0x9B (CSI to an 8-bit terminal), a cut sequence, an
  // overlong form, a surrogate
  EXPECT_EQ(terminal_text("\x9b"
                          "2J"),
            "\\x9b2J");
  EXPECT_EQ(terminal_text("x\xe2\x80"), "x\\xe2\\x80");
  EXPECT_EQ(terminal_text("\xc0\x9b"), "\\xc0\\x9b");
  EXPECT_EQ(terminal_text("\xed\xa0\x80"), "\\xed\\xa0\\x80");
}

TEST(TerminalText, LinesAreKeptInMessagesAndEscapedInNames) {
  EXPECT_EQ(terminal_text("line 1\n\tline 2"), "line 1\n\tline 2");
  EXPECT_EQ(terminal_text("a\nb\tc", false), "a\\x0ab\\x09c");
}

TEST(TerminalText, OtherTextIsUnchanged) {
  // ASCII, a backslash, UTF-8 of 2, 3 and 4 bytes (θ, …, U+2028 is not a control here, 🙂)
  const std::string text = "theta \\ θ … t = 0 … 1 s 🙂 \xe2\x80\xa9 \xe2\x81\xa5";
  EXPECT_EQ(terminal_text(text), text);
  EXPECT_EQ(terminal_text(""), "");
}

}  // namespace
}  // namespace ukdyn::cli
