// SPDX-License-Identifier: BSD-3-Clause
// The sample points of an ensemble (simulation/sampling.hpp): grids, random draws and Latin
// hypercubes from std::mt19937_64's raw output, with ukdyn's own transforms.
#include "ukdyn/simulation/sampling.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include "ukdyn/core/format.hpp"

namespace ukdyn {
namespace {

// the most samples a design may have
constexpr double kMaxSamples = 1e7;

// a uniform variate in (0, 1) from the top 53 bits of one output: (k + 0.5) 2⁻⁵³
double uniform01(std::mt19937_64& rng) {
  const std::uint64_t k = rng() >> 11;
  return (double(k) + 0.5) * 0x1.0p-53;
}

// a whole number in [0, n) from the raw outputs, without bias: outputs at or above the largest
// multiple of n are drawn again
std::uint64_t below(std::mt19937_64& rng, std::uint64_t n) {
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
  while (true) {
    const std::uint64_t x = rng();
    if (x < limit) return x % n;
  }
}

// the variate of law `v` at probability u in (0, 1)
double transform(const RandomVariable& v, double u) {
  switch (v.distribution) {
    case Distribution::kUniform:
      return v.a + (v.b - v.a) * u;
    case Distribution::kNormal:
      return v.a + v.b * normal_quantile(u);
    case Distribution::kLogUniform:
      return std::exp(std::log(v.a) + (std::log(v.b) - std::log(v.a)) * u);
  }
  return 0.0;
}

const char* law_name(Distribution d) {
  switch (d) {
    case Distribution::kUniform:
      return "uniform";
    case Distribution::kNormal:
      return "normal";
    case Distribution::kLogUniform:
      return "loguniform";
  }
  return "?";
}

// a number of the command line's text, or throws naming `whole`
double number(std::string_view s, std::string_view whole, const char* form) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) {
    throw std::invalid_argument("'" + std::string(whole) + "': '" + std::string(s) +
                                "' is not a finite number (the form is " + form + ")");
  }
  return v;
}

// an identifier, or a body's coordinate: dotted identifiers (cart.x, cart.x_dot)
bool is_name(std::string_view s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool dot = c == '.' && i + 1 < s.size() && s[i - 1] != '.';
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || dot)) return false;
  }
  return true;
}

// A computed grid value as the decimal number it stands for, when that is short: 0.1 + 2 (0.4 −
// 0.1)/3 is 0.30000000000000004, and a value whose 15 significant digits read as a number of at
// most 12 (here 0.3) is taken as that number, so that --grid mu=0.1:0.4:4 runs exactly what
// --set mu=0.3 runs. A value with no short form (1/3) is kept as computed. Cost O(1).
double short_decimal(double v) {
  if (!std::isfinite(v) || v == 0.0) return v;
  char buf[40];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific, 14);
  if (ec != std::errc()) return v;
  // the mantissa's digits (d.dddddddddddddd), without trailing zeros
  const std::string_view text(buf, std::size_t(end - buf));
  const std::size_t e = text.find('e');
  std::string digits;
  for (const char c : text.substr(0, e)) {
    if (c >= '0' && c <= '9') digits += c;
  }
  while (digits.size() > 1 && digits.back() == '0') digits.pop_back();
  if (digits.size() > 12) return v;
  double out = v;
  std::from_chars(buf, end, out, std::chars_format::scientific);
  return out;
}

}  // namespace

double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) {
    throw std::invalid_argument("ukdyn::normal_quantile: p must be in (0, 1), got " +
                                format_number(p));
  }
  // Acklam's rational approximations (relative error 1.15e-9) in the central region and the tail
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                 -2.759285104469687e+02, 1.383577518672690e+02,
                                 -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                 -1.556989798598866e+02, 6.680131188771972e+01,
                                 -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                 -2.400758277161838e+00, -2.549732539343734e+00,
                                 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                                 2.445134137142996e+00, 3.754408661907416e+00};
  // the upper half by symmetry (1 − p is exact there): Φ⁻¹(p) = −Φ⁻¹(1 − p)
  if (p > 0.5) return -normal_quantile(1.0 - p);
  constexpr double p_low = 0.02425;
  double x = 0.0;
  if (p < p_low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else {
    const double q = p - 0.5, r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  // one Halley step on Φ(x) − p (Φ from erfc): full double precision
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = e * std::sqrt(2.0 * std::numbers::pi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

DesignTable make_design(const Design& design) {
  DesignTable out;
  // names: each once
  std::set<std::string> seen;
  auto add_name = [&](const std::string& name) {
    if (!seen.insert(name).second) {
      throw std::invalid_argument("ukdyn::make_design: '" + name +
                                  "' is given twice (a grid axis and a random variable each "
                                  "name a different parameter)");
    }
    out.names.push_back(name);
  };
  double points = 1.0;
  for (const GridAxis& axis : design.grid) {
    add_name(axis.name);
    if (axis.values.empty()) {
      throw std::invalid_argument("ukdyn::make_design: the grid axis '" + axis.name +
                                  "' has no values");
    }
    for (double v : axis.values) {
      if (!std::isfinite(v)) {
        throw std::invalid_argument("ukdyn::make_design: the grid axis '" + axis.name +
                                    "' has a value that is not finite: " + format_number(v));
      }
    }
    points *= double(axis.values.size());
  }
  for (const RandomVariable& v : design.random) {
    add_name(v.name);
    const std::string law = std::string(law_name(v.distribution)) + "(" + format_number(v.a) +
                            ", " + format_number(v.b) + ")";
    if (!std::isfinite(v.a) || !std::isfinite(v.b)) {
      throw std::invalid_argument("ukdyn::make_design: " + v.name + "~" + law +
                                  ": the numbers must be finite");
    }
    if (v.distribution == Distribution::kNormal ? v.b < 0.0 : v.b < v.a) {
      throw std::invalid_argument("ukdyn::make_design: " + v.name + "~" + law +
                                  (v.distribution == Distribution::kNormal
                                       ? ": the standard deviation must be >= 0"
                                       : ": the upper bound is below the lower one"));
    }
    if (v.distribution == Distribution::kLogUniform && !(v.a > 0.0)) {
      throw std::invalid_argument("ukdyn::make_design: " + v.name + "~" + law +
                                  ": a log-uniform law needs 0 < a <= b");
    }
  }
  if (!design.random.empty() && design.draws == 0) {
    throw std::invalid_argument(
        "ukdyn::make_design: random variables need a number of draws >= 1 (--samples N, n=N)");
  }
  if (design.random.empty() && design.draws > 0) {
    throw std::invalid_argument("ukdyn::make_design: " + format_number(double(design.draws)) +
                                " draws asked for, but there is no random variable to draw");
  }
  const std::size_t draws = design.random.empty() ? 1 : design.draws;
  if (points * double(draws) > kMaxSamples) {
    throw std::invalid_argument(
        "ukdyn::make_design: the design has " + format_number(points * double(draws)) +
        " samples, more than 1e7 (each sample is a run, and its row is kept in memory)");
  }

  // the draws: draws × variables, each variable's u in (0, 1), then the laws
  const std::size_t nv = design.random.size();
  std::vector<double> drawn(draws * nv);
  if (nv > 0) {
    std::mt19937_64 rng(design.seed);
    for (std::size_t j = 0; j < draws; ++j) {
      for (std::size_t k = 0; k < nv; ++k) drawn[j * nv + k] = uniform01(rng);
    }
    if (design.latin_hypercube) {
      // each variable: the strata 0 … draws−1 in a shuffled order (Fisher–Yates)
      std::vector<std::uint64_t> strata(draws);
      for (std::size_t k = 0; k < nv; ++k) {
        std::iota(strata.begin(), strata.end(), std::uint64_t(0));
        for (std::size_t i = draws; i > 1; --i) std::swap(strata[i - 1], strata[below(rng, i)]);
        for (std::size_t j = 0; j < draws; ++j) {
          drawn[j * nv + k] = (double(strata[j]) + drawn[j * nv + k]) / double(draws);
        }
      }
    }
    for (std::size_t j = 0; j < draws; ++j) {
      for (std::size_t k = 0; k < nv; ++k) {
        drawn[j * nv + k] = transform(design.random[k], drawn[j * nv + k]);
      }
    }
  }

  // the rows: grid point major (the first axis slowest), then the draws
  const std::size_t n_points = std::size_t(points);
  out.rows.reserve(n_points * draws);
  std::vector<std::size_t> index(design.grid.size(), 0);
  for (std::size_t p = 0; p < n_points; ++p) {
    // the point's index on each axis (the last axis fastest)
    std::size_t rest = p;
    for (std::size_t a = design.grid.size(); a-- > 0;) {
      index[a] = rest % design.grid[a].values.size();
      rest /= design.grid[a].values.size();
    }
    for (std::size_t j = 0; j < draws; ++j) {
      std::vector<double> row;
      row.reserve(out.names.size());
      for (std::size_t a = 0; a < design.grid.size(); ++a) {
        row.push_back(design.grid[a].values[index[a]]);
      }
      for (std::size_t k = 0; k < nv; ++k) row.push_back(drawn[j * nv + k]);
      out.rows.push_back(std::move(row));
    }
  }
  return out;
}

GridAxis parse_grid_axis(std::string_view text) {
  constexpr const char* form = "NAME=START:STOP:COUNT or NAME=V1,V2,...";
  const std::size_t eq = text.find('=');
  if (eq == std::string_view::npos || !is_name(text.substr(0, eq))) {
    throw std::invalid_argument("'" + std::string(text) + "': the form is " + form);
  }
  GridAxis axis;
  axis.name = std::string(text.substr(0, eq));
  const std::string_view rest = text.substr(eq + 1);
  if (rest.find(':') != std::string_view::npos) {
    // start:stop:count
    const std::size_t c1 = rest.find(':'), c2 = rest.find(':', c1 + 1);
    if (c2 == std::string_view::npos || rest.find(':', c2 + 1) != std::string_view::npos) {
      throw std::invalid_argument("'" + std::string(text) + "': the form is " + form);
    }
    const double start = number(rest.substr(0, c1), text, form);
    const double stop = number(rest.substr(c1 + 1, c2 - c1 - 1), text, form);
    const double count = number(rest.substr(c2 + 1), text, form);
    if (!(count >= 1.0) || count != std::floor(count) || count > kMaxSamples) {
      throw std::invalid_argument("'" + std::string(text) +
                                  "': COUNT must be a whole number from 1 to 1e7");
    }
    const std::size_t n = std::size_t(count);
    for (std::size_t i = 0; i < n; ++i) {
      // the last value is stop exactly
      axis.values.push_back(
          n == 1       ? start
          : i + 1 == n ? stop
                       : short_decimal(start + double(i) * (stop - start) / double(n - 1)));
    }
    return axis;
  }
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = rest.find(',', from);
    axis.values.push_back(number(
        rest.substr(from, comma == std::string_view::npos ? rest.npos : comma - from), text, form));
    if (comma == std::string_view::npos) break;
    from = comma + 1;
  }
  return axis;
}

RandomVariable parse_random_variable(std::string_view text) {
  constexpr const char* form = "NAME~uniform(A,B), NAME~normal(MEAN,SD) or NAME~loguniform(A,B)";
  const std::size_t tilde = text.find('~');
  const std::size_t open = text.find('(');
  if (tilde == std::string_view::npos || open == std::string_view::npos || open < tilde ||
      text.empty() || text.back() != ')' || !is_name(text.substr(0, tilde))) {
    throw std::invalid_argument("'" + std::string(text) + "': the form is " + form);
  }
  RandomVariable v;
  v.name = std::string(text.substr(0, tilde));
  std::string_view law = text.substr(tilde + 1, open - tilde - 1);
  while (!law.empty() && law.back() == ' ') law.remove_suffix(1);
  if (law == "uniform") {
    v.distribution = Distribution::kUniform;
  } else if (law == "normal") {
    v.distribution = Distribution::kNormal;
  } else if (law == "loguniform" || law == "log-uniform" || law == "log_uniform") {
    v.distribution = Distribution::kLogUniform;
  } else {
    throw std::invalid_argument("'" + std::string(text) + "': unknown law '" + std::string(law) +
                                "' (the laws are uniform, normal and loguniform)");
  }
  const std::string_view args = text.substr(open + 1, text.size() - open - 2);
  const std::size_t comma = args.find(',');
  if (comma == std::string_view::npos || args.find(',', comma + 1) != std::string_view::npos) {
    throw std::invalid_argument("'" + std::string(text) + "': the form is " + form);
  }
  v.a = number(args.substr(0, comma), text, form);
  v.b = number(args.substr(comma + 1), text, form);
  return v;
}

}  // namespace ukdyn
