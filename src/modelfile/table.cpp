// SPDX-License-Identifier: BSD-3-Clause
// A table column interpolated between its rows (modelfile/table.hpp): step, linear and the
// not-a-knot cubic spline, with the range check or the extrapolation.

#include "ukdyn/modelfile/table.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "ukdyn/core/format.hpp"

namespace ukdyn::expr {

const char* to_string(Interpolation i) {
  switch (i) {
    case Interpolation::kStep:
      return "step";
    case Interpolation::kLinear:
      return "linear";
    case Interpolation::kCubic:
      return "cubic";
  }
  return "?";
}

const char* to_string(Extrapolation e) {
  switch (e) {
    case Extrapolation::kError:
      return "error";
    case Extrapolation::kHold:
      return "hold";
    case Extrapolation::kLinear:
      return "linear";
  }
  return "?";
}

namespace {

// The second derivatives M_i of the not-a-knot cubic spline through (x_i, y_i), n >= 4: the
// continuity of S'' at the interior rows,
//   h_{i−1} M_{i−1} + 2 (h_{i−1} + h_i) M_i + h_i M_{i+1} = 6 (d_i − d_{i−1}),  i = 1 … n − 2,
// d_i = (y_{i+1} − y_i)/h_i, with M_0 and M_{n−1} eliminated by the continuity of S''' at x_1
// and x_{n−2}: M_0 = ((h_0 + h_1) M_1 − h_0 M_2)/h_1, and likewise at the end. A tridiagonal
// system of n − 2 rows, solved by elimination without pivoting (Thomas). Cost O(n).
std::vector<double> not_a_knot(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size(), k = n - 2;
  std::vector<double> h(n - 1), d(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    h[i] = x[i + 1] - x[i];
    d[i] = (y[i + 1] - y[i]) / h[i];
  }
  std::vector<double> lower(k), diag(k), upper(k), rhs(k);
  for (std::size_t r = 0; r < k; ++r) {
    const std::size_t i = r + 1;
    lower[r] = h[i - 1];
    diag[r] = 2.0 * (h[i - 1] + h[i]);
    upper[r] = h[i];
    rhs[r] = 6.0 * (d[i] - d[i - 1]);
  }
  diag[0] += h[0] * (h[0] + h[1]) / h[1];
  upper[0] -= h[0] * h[0] / h[1];
  const double ha = h[n - 3], hb = h[n - 2];
  diag[k - 1] += hb * (hb + ha) / ha;
  lower[k - 1] -= hb * hb / ha;
  for (std::size_t r = 1; r < k; ++r) {
    const double w = lower[r] / diag[r - 1];
    diag[r] -= w * upper[r - 1];
    rhs[r] -= w * rhs[r - 1];
  }
  std::vector<double> m(n);
  m[k] = rhs[k - 1] / diag[k - 1];
  for (std::size_t r = k - 1; r-- > 0;) m[r + 1] = (rhs[r] - upper[r] * m[r + 2]) / diag[r];
  m[0] = ((h[0] + h[1]) * m[1] - h[0] * m[2]) / h[1];
  m[n - 1] = ((hb + ha) * m[n - 2] - hb * m[n - 3]) / ha;
  return m;
}

}  // namespace

TableColumn::TableColumn(std::string name, std::vector<double> x, std::vector<double> y,
                         Interpolation interpolation, Extrapolation extrapolation,
                         std::string source)
    : name_(std::move(name)),
      source_(std::move(source)),
      x_(std::move(x)),
      y_(std::move(y)),
      interpolation_(interpolation),
      extrapolation_(extrapolation) {
  const std::string who = "table column '" + name_ + "'";
  if (x_.size() != y_.size()) {
    throw std::invalid_argument(who + ": " + format_number(x_.size()) + " abscissae but " +
                                format_number(y_.size()) + " values");
  }
  const std::size_t least = interpolation_ == Interpolation::kCubic ? 4 : 2;
  if (x_.size() < least) {
    throw std::invalid_argument(who + ": " + format_number(x_.size()) + " rows; " +
                                to_string(interpolation_) + " interpolation needs at least " +
                                format_number(least));
  }
  for (std::size_t i = 0; i < x_.size(); ++i) {
    if (!std::isfinite(x_[i]) || !std::isfinite(y_[i])) {
      throw std::invalid_argument(who + ": row " + format_number(i) + " holds " +
                                  format_number(std::isfinite(x_[i]) ? y_[i] : x_[i]) +
                                  " (values must be finite)");
    }
    if (i > 0 && !(x_[i] > x_[i - 1])) {
      throw std::invalid_argument(who + ": the abscissa is not strictly increasing at row " +
                                  format_number(i) + " (" + format_number(x_[i]) + " after " +
                                  format_number(x_[i - 1]) + ")");
    }
  }
  if (interpolation_ == Interpolation::kCubic) m_ = not_a_knot(x_, y_);
}

int TableColumn::degree() const {
  switch (interpolation_) {
    case Interpolation::kStep:
      return 0;
    case Interpolation::kLinear:
      return 1;
    case Interpolation::kCubic:
      return 3;
  }
  return 0;
}

std::size_t TableColumn::interval(double x) const {
  const auto it = std::upper_bound(x_.begin(), x_.end(), x);
  const std::size_t after = std::size_t(it - x_.begin());  // first row beyond x
  return std::min(after == 0 ? 0 : after - 1, x_.size() - 2);
}

double TableColumn::piece(std::size_t i, double x, int order) const {
  if (order < 0) return std::nan("");
  const double t = x - x_[i], h = x_[i + 1] - x_[i];
  switch (interpolation_) {
    case Interpolation::kStep:
      if (order > 0) return 0.0;
      return x >= x_.back() ? y_.back() : y_[i];
    case Interpolation::kLinear: {
      const double slope = (y_[i + 1] - y_[i]) / h;
      return order == 0 ? y_[i] + slope * t : order == 1 ? slope : 0.0;
    }
    case Interpolation::kCubic: {
      const double m0 = m_[i], m1 = m_[i + 1], third = (m1 - m0) / h;
      switch (order) {
        case 0: {
          const double b = (y_[i + 1] - y_[i]) / h - h * (2.0 * m0 + m1) / 6.0;
          return y_[i] + t * (b + t * (0.5 * m0 + t * third / 6.0));
        }
        case 1: {
          const double b = (y_[i + 1] - y_[i]) / h - h * (2.0 * m0 + m1) / 6.0;
          return b + t * (m0 + 0.5 * t * third);
        }
        case 2:
          return m0 + t * third;
        case 3:
          return third;
        default:
          return 0.0;
      }
    }
  }
  return 0.0;
}

double TableColumn::evaluate(double x, int order) const {
  if (std::isnan(x)) return x;
  const double lo = x_.front(), hi = x_.back();
  if (x >= lo && x <= hi) return piece(interval(x), x, order);
  // within a few roundoffs of an end: at it (an integrator's last step to t_end = hi computes
  // t + h, which may round past hi)
  const double slack = 8.0 * std::numeric_limits<double>::epsilon() *
                       std::max({std::fabs(lo), std::fabs(hi), hi - lo});
  if (x >= lo - slack && x <= hi + slack) {
    const double at = std::clamp(x, lo, hi);
    return piece(interval(at), at, order);
  }
  const bool below = x < lo;
  const double end = below ? lo : hi;
  const std::size_t i = below ? 0 : x_.size() - 2;
  switch (extrapolation_) {
    case Extrapolation::kError:
      break;
    case Extrapolation::kHold:
      return order == 0 ? piece(i, end, 0) : 0.0;
    case Extrapolation::kLinear:
      if (order == 0) return piece(i, end, 0) + piece(i, end, 1) * (x - end);
      return order == 1 ? piece(i, end, 1) : 0.0;
  }
  throw TableRangeError("table column '" + name_ + "'" +
                        (source_.empty() ? std::string() : " (from " + source_ + ")") +
                        " evaluated at " + format_number(x) + ", outside its rows' range [" +
                        format_number(lo) + ", " + format_number(hi) +
                        "] (extrapolation: error; give the table extrapolation: hold or linear "
                        "to extend it)");
}

namespace {
thread_local std::string range_error;
}  // namespace

const std::string& table_range_error() { return range_error; }
void clear_table_range_error() { range_error.clear(); }

double TableColumn::evaluate_in_run(double x, int order) const noexcept {
  try {
    return evaluate(x, order);
  } catch (const std::exception& e) {
    try {
      if (range_error.empty()) range_error = e.what();
    } catch (...) {  // (no memory for the message: the NaN says enough)
    }
    return std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace ukdyn::expr
