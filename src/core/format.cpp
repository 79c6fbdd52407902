// SPDX-License-Identifier: BSD-3-Clause
// The one number formatter and join of format.hpp.
#include "ukdyn/core/format.hpp"

#include <charconv>
#include <system_error>

namespace ukdyn {

std::string format_number(double v, int significant) {
  char buf[64];
  const std::to_chars_result r =
      significant > 0 ? std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general,
                                      significant > 40 ? 40 : significant)
                      : std::to_chars(buf, buf + sizeof buf, v);
  return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("?");
}

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += separator;
    out += item;
  }
  return out;
}

std::string valid_utf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  std::size_t i = 0;
  while (i < text.size()) {
    const unsigned char lead = byte(i);
    // the sequence's length, and the range its second byte must lie in (RFC 3629, table 3-7
    // of the Unicode standard: no overlong forms, no surrogates, nothing above U+10FFFF)
    std::size_t width = 0;
    unsigned char low = 0x80, high = 0xBF;
    if (lead < 0x80) {
      width = 1;
    } else if (lead >= 0xC2 && lead <= 0xDF) {
      width = 2;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
      width = 3;
      if (lead == 0xE0) low = 0xA0;
      if (lead == 0xED) high = 0x9F;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
      width = 4;
      if (lead == 0xF0) low = 0x90;
      if (lead == 0xF4) high = 0x8F;
    }
    std::size_t good = width == 0 ? 0 : 1;
    while (good > 0 && good < width && i + good < text.size()) {
      const unsigned char b = byte(i + good);
      if (good == 1 ? (b < low || b > high) : (b < 0x80 || b > 0xBF)) break;
      ++good;
    }
    if (good == width && width > 0) {
      out.append(text.substr(i, width));
      i += width;
    } else {
      out += "\xEF\xBF\xBD";  // U+FFFD REPLACEMENT CHARACTER
      i += good > 0 ? good : 1;
    }
  }
  return out;
}

}  // namespace ukdyn
