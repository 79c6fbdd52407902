// SPDX-License-Identifier: BSD-3-Clause
// Control characters escaped for the terminal (terminal_text.hpp).
#include "terminal_text.hpp"

#include <cstdint>
#include <cstdio>

namespace ukdyn::cli {
namespace {

// "\xHH" or "\uHHHH"
void append_escape(std::string& out, const char* format, unsigned value) {
  char buf[16];
  std::snprintf(buf, sizeof buf, format, value);
  out += buf;
}

// the length of the valid UTF-8 sequence at text[i] (0: not valid), its code point in `cp`
std::size_t utf8_sequence(std::string_view text, std::size_t i, char32_t& cp) {
  const auto byte = [&](std::size_t k) { return std::uint8_t(text[k]); };
  const std::uint8_t b0 = byte(i);
  std::size_t len = 0;
  char32_t min = 0;
  if (b0 >= 0xC2 && b0 <= 0xDF) {
    len = 2, cp = b0 & 0x1Fu, min = 0x80;
  } else if (b0 >= 0xE0 && b0 <= 0xEF) {
    len = 3, cp = b0 & 0x0Fu, min = 0x800;
  } else if (b0 >= 0xF0 && b0 <= 0xF4) {
    len = 4, cp = b0 & 0x07u, min = 0x10000;
  } else {
    return 0;
  }
  if (i + len > text.size()) return 0;
  for (std::size_t k = 1; k < len; ++k) {
    if ((byte(i + k) & 0xC0u) != 0x80u) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3Fu);
  }
  // overlong forms, surrogates and code points past U+10FFFF are not valid UTF-8
  if (cp < min || (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return 0;
  return len;
}

}  // namespace

std::string terminal_text(std::string_view text, bool keep_lines) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto b = std::uint8_t(text[i]);
    // ASCII: the C0 controls and DEL escaped (line feeds and tabs kept in messages)
    if (b < 0x80) {
      if ((b < 0x20 || b == 0x7F) && !(keep_lines && (b == '\n' || b == '\t'))) {
        append_escape(out, "\\x%02x", b);
      } else {
        out += char(b);
      }
      ++i;
      continue;
    }
    // UTF-8: C1 and bidirectional controls escaped, invalid bytes escaped one by one
    char32_t cp = 0;
    const std::size_t len = utf8_sequence(text, i, cp);
    if (len == 0) {
      append_escape(out, "\\x%02x", b);
      ++i;
      continue;
    }
    const bool control = (cp >= 0x80 && cp <= 0x9F) || (cp >= 0x202A && cp <= 0x202E) ||
                         (cp >= 0x2066 && cp <= 0x2069);
    if (control) {
      append_escape(out, "\\u%04x", unsigned(cp));
    } else {
      out.append(text.substr(i, len));
    }
    i += len;
  }
  return out;
}

}  // namespace ukdyn::cli
