// SPDX-License-Identifier: BSD-3-Clause
// Did-you-mean for the command line: the nearest of a list of names to a mistyped word.
#pragma once

#include <string>
#include <vector>

namespace ukdyn::cli {

/// The candidate nearest to `word` by optimal-string-alignment distance (insertions, deletions,
/// substitutions and swaps of neighbours), if it is near enough to be a typo of it: at most
/// max(1, |word| / 3) edits, or `word` a prefix of exactly one candidate. Empty when none is.
/// Cost O(|word| · Σ|candidate|).
std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates);

/// " (did you mean 'X'?)" for the nearest candidate, or "" when none is near.
std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace ukdyn::cli
