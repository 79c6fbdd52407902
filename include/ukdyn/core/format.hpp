// SPDX-License-Identifier: BSD-3-Clause
/// @file format.hpp
/// Text of numbers and lists in messages: the one formatter of the library, its command line
/// and its Python module, so that every message prints numbers the same way.
#pragma once

#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ukdyn {

/// A number as messages print it. significant = 0 (the default): the shortest text that reads
/// back as the same double (std::to_chars; "0.1", "-0", "1e-12", "inf", "nan"), never a
/// fixed six decimals that show a small number as "0.000000". significant > 0: that many
/// significant digits, as printf's %g ("1.8e-12" for 3). Cost O(1), allocates the string.
std::string format_number(double v, int significant = 0);

/// An integer as messages print it (every digit). Cost O(digits).
template <class Int, std::enable_if_t<std::is_integral_v<Int>, int> = 0>
std::string format_number(Int v) {
  return std::to_string(v);
}

/// The items joined by `separator` ("a, b, c"); empty for none. Cost O(total length).
std::string join(const std::vector<std::string>& items, std::string_view separator = ", ");

/// `text` as valid UTF-8: every byte that does not belong to a well-formed UTF-8 sequence
/// (a stray continuation byte, a sequence cut short, an overlong form, a surrogate, a code
/// point above U+10FFFF) becomes U+FFFD. Messages quote what a user wrote through it, so that
/// a terminal, a JSON record and Python (whose str must be valid UTF-8) can all show them.
/// Cost O(length), allocates the string.
std::string valid_utf8(std::string_view text);

}  // namespace ukdyn
