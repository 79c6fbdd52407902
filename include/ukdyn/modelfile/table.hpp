// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/table.hpp
/// Measured data as a function of one argument: a column of a table (a model file's `tables:`
/// section, docs/model-format.md "Tables") interpolated between its rows, called in expressions
/// as `table.column(x)` (ExpressionSet::add_table_column).
///
/// For rows (x_i, y_i), i = 0 … n − 1, with x strictly increasing and h_i = x_{i+1} − x_i:
///   step    y(x) = y_i on [x_i, x_{i+1})                     (a zero-order hold; C⁻¹)
///   linear  y(x) = y_i + (y_{i+1} − y_i)/h_i · (x − x_i)       (C⁰; its slope jumps at the rows)
///   cubic   the not-a-knot cubic spline (C², and its third derivative continuous at x_1 and
///           x_{n−2}): error O(h⁴) for smooth data, and exact for a cubic polynomial
/// Outside [x_0, x_{n−1}]: an error (Extrapolation::kError, the default), the end value held
/// (kHold: derivatives 0), or the end's tangent line continued (kLinear).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace ukdyn::expr {

/// How a column is interpolated between its rows.
enum class Interpolation { kStep, kLinear, kCubic };
/// What a column gives outside its rows' range.
enum class Extrapolation { kError, kHold, kLinear };

/// The name used in model files ("step", "linear", "cubic"; "error", "hold", "linear").
const char* to_string(Interpolation i);
/// The name used in model files ("error", "hold", "linear").
const char* to_string(Extrapolation e);

/// A table column evaluated outside its range with Extrapolation::kError: what() names the
/// table, the column, the value and the range.
class TableRangeError : public std::domain_error {
 public:
  using std::domain_error::domain_error;
};

/// One interpolated column. Immutable once made (its coefficients computed by the constructor),
/// so one column serves any number of threads; evaluation allocates nothing. Cost: O(n) to make,
/// O(log n) an evaluation (binary search for the interval).
class TableColumn {
 public:
  /// `name` is how messages call it ("ground.acc"); `source` where its data came from (a file
  /// name, or "" — for messages). @throws std::invalid_argument when x and y differ in length,
  /// hold fewer than 2 rows (4 for kCubic), a value that is not finite, or x is not strictly
  /// increasing (the message gives the row, 0-based).
  TableColumn(std::string name, std::vector<double> x, std::vector<double> y,
              Interpolation interpolation = Interpolation::kLinear,
              Extrapolation extrapolation = Extrapolation::kError, std::string source = "");

  /// The `order`-th derivative of the interpolant at x (order 0: the value). Within a row
  /// interval [x_i, x_{i+1}) the interval's polynomial (the last row belongs to the last
  /// interval); derivatives beyond the polynomial's degree are 0. NaN for a NaN x. An x within
  /// 8 roundoffs (8 ε max(|x_0|, |x_{n−1}|, x_{n−1} − x_0)) of an end counts as at that end.
  /// @throws TableRangeError outside [x_0, x_{n−1}] with Extrapolation::kError.
  double evaluate(double x, int order = 0) const;

  /// evaluate() as a compiled Program calls it: outside the range with Extrapolation::kError,
  /// NaN — the run then stops with a non-finite force, the samples before it kept — and the
  /// TableRangeError's message recorded for this thread (table_range_error()). No allocation
  /// but the message's, once.
  double evaluate_in_run(double x, int order) const noexcept;

  /// The degree of the pieces: 0 (step), 1 (linear), 3 (cubic).
  int degree() const;
  const std::string& name() const { return name_; }  ///< "table.column"
  /// The rows' abscissae x_i (strictly increasing).
  const std::vector<double>& x() const { return x_; }
  /// The rows' values y_i.
  const std::vector<double>& y() const { return y_; }
  Interpolation interpolation() const { return interpolation_; }  ///< between the rows
  Extrapolation extrapolation() const { return extrapolation_; }  ///< outside the rows' range

 private:
  // the interval i with x_i <= x < x_{i+1} (x within the range; the last row: n − 2)
  std::size_t interval(double x) const;
  // the order-th derivative of interval i's polynomial at x
  double piece(std::size_t i, double x, int order) const;

  std::string name_, source_;
  std::vector<double> x_, y_;
  // cubic: the second derivatives at the rows (n); empty otherwise
  std::vector<double> m_;
  Interpolation interpolation_;
  Extrapolation extrapolation_;
};

/// The message of the first range error a Program met on this thread since
/// clear_table_range_error() (TableColumn::evaluate_in_run), or "". run_model() clears it
/// before a run and puts it first in the failed run's message.
const std::string& table_range_error();
/// Forgets this thread's recorded range error: table_range_error() reads "" until the next.
void clear_table_range_error();

}  // namespace ukdyn::expr
