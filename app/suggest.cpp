// SPDX-License-Identifier: BSD-3-Clause
// Did-you-mean for the command line (app/suggest.hpp).
#include "suggest.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>

namespace ukdyn::cli {
namespace {

// optimal string alignment distance (Damerau–Levenshtein without repeated edits of a substring)
std::size_t distance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

}  // namespace

std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates) {
  if (word.empty() || word.size() > 256) return "";
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  std::vector<std::string> prefixed;
  for (const std::string& c : candidates) {
    if (c.size() > 256) continue;
    const std::size_t d = distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
    if (c.size() > word.size() && c.compare(0, word.size(), word) == 0) prefixed.push_back(c);
  }
  if (best_d <= std::max<std::size_t>(1, word.size() / 3)) return best;
  if (prefixed.size() == 1) return prefixed.front();
  return "";
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string near = nearest_name(word, candidates);
  return near.empty() ? "" : " (did you mean '" + near + "'?)";
}

}  // namespace ukdyn::cli
