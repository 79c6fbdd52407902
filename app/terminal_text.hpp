// SPDX-License-Identifier: BSD-3-Clause
// Text from a model file (names, messages that quote them) on the terminal: control characters
// escaped, so that a name cannot clear the screen, retitle the window or reorder what is shown.
#pragma once

#include <string>
#include <string_view>

namespace ukdyn::cli {

/// `text` with every character a terminal would act on written as an escape: the C0 controls
/// and DEL as `\xHH` (ESC as `\x1b`), the C1 controls U+0080–U+009F and the bidirectional
/// controls U+202A–U+202E and U+2066–U+2069 as `\uHHHH`, and each byte that is not part of
/// valid UTF-8 as `\xHH` (a lone byte 0x9B is CSI to an 8-bit terminal); a backslash stays as
/// it is. Line feeds and tabs are kept when `keep_lines` is true (messages over several lines),
/// escaped otherwise (a single name). Everything else, other UTF-8 included, is unchanged.
/// Cost: O(length).
std::string terminal_text(std::string_view text, bool keep_lines = true);

}  // namespace ukdyn::cli
