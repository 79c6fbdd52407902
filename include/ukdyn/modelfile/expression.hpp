// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/expression.hpp
/// Symbolic expressions of the model language, differentiated exactly with GiNaC and compiled
/// once into a fast, allocation-free evaluator.
///
/// The language: numbers (`2`, `0.5`, `.5`, `1e-3`; read as exact rationals), names, + − * /
/// ^ (power), parentheses, and the functions sin, cos, tan, asin, acos, atan, atan2(y, x), sinh,
/// cosh, tanh, exp, log, sqrt, abs, and the non-smooth sign (0 at 0), heaviside (½ at 0),
/// min(a, b), max(a, b) and if(c, a, b) (a where c > 0, else b), the columns of tables
/// `table.column(x)` (add_table_column), differentiated where they are
/// differentiable (d abs(x) = sign(x) dx, d sign = d heaviside = 0, d max(a, b) = da where
/// a > b and db where a < b, d min likewise, d if(c, a, b) = da where c > 0 and db where c < 0;
/// at a tie the one-sided derivative nearer 0, and 0 between derivatives of opposite signs, as
/// abs has: docs/model-format.md, "Tie rule").
/// Precedence as in Python: `-x^2` is −(x²), `x^-2*y` is
/// (x⁻²)·y; `a^b^c` is refused as ambiguous. Names are the inputs declared when the set is made
/// (coordinates, their velocities `x_dot`, time `t`, …) and constants (parameters) whose values
/// are fixed before compiling. GiNaC types stay inside src/modelfile/expression.cpp: this header is
/// light. An ExpressionSet is not thread-safe (GiNaC's reference counts are not atomic); a compiled
/// Program shares nothing with it and may be evaluated on many threads at once.
#pragma once

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/core/types.hpp"

/// The model language's expressions (this file) and interpolated tables (modelfile/table.hpp).
namespace ukdyn::expr {

class TableColumn;

/// A syntax error or an unknown name in an expression: `position` is the 0-based character
/// offset in the expression text of the offending token (the end of the text when it ended too
/// soon), `what()` says what without repeating the position, e.g.
/// `unknown name 'thta' (did you mean 'theta'?)`.
class ParseError : public std::runtime_error {
 public:
  /// The message `what` (without the position) and the 0-based character offset `position`.
  ParseError(const std::string& what, std::size_t position)
      : std::runtime_error(what), position_(position) {}
  /// 0-based character offset into the expression text.
  std::size_t position() const { return position_; }

 private:
  std::size_t position_;
};

/// A compiled program: evaluates a fixed list of outputs from a fixed list of inputs.
/// Immutable and cheap to copy; evaluation needs a scratch buffer of scratch_size() doubles
/// (make one per thread/workspace), so it never allocates. Cost: one pass over the tape, with
/// common subexpressions computed once.
class Program {
 public:
  Program();
  ~Program();
  /// Shares the other's immutable tape (no copy of it). Cost O(1).
  Program(const Program&);
  /// Shares the other's immutable tape (no copy of it). Cost O(1).
  Program& operator=(const Program&);
  /// Takes the other's tape; the moved-from program is left empty (as default-constructed).
  Program(Program&&) noexcept;
  /// Takes the other's tape; the moved-from program is left empty.
  Program& operator=(Program&&) noexcept;

  Index inputs() const;        ///< number of inputs (the ExpressionSet's inputs)
  Index outputs() const;       ///< number of outputs
  Index scratch_size() const;  ///< doubles of scratch evaluate() needs
  Index operations() const;    ///< length of the tape (for tests and benchmarks)

  /// out[0 … outputs()) = the outputs at in[0 … inputs()). `scratch` holds scratch_size()
  /// doubles (its contents on entry do not matter). No allocation; a default-constructed
  /// Program does nothing. Cost O(operations()).
  void evaluate(const double* in, double* out, double* scratch) const;

 private:
  friend class ExpressionSet;
  struct Tape;
  std::shared_ptr<const Tape> tape_;
};

/// Handle of an expression inside an ExpressionSet.
using Expr = Index;

/// A set of symbolic expressions over named inputs and constants.
class ExpressionSet {
 public:
  /// Inputs, in the order a Program reads them (names must be unique identifiers).
  /// @throws std::invalid_argument on an empty, duplicate or malformed name, or the name of a
  /// function of the language.
  explicit ExpressionSet(std::vector<std::string> input_names);
  ~ExpressionSet();
  /// Takes over the other's inputs, constants, tables and expressions.
  ExpressionSet(ExpressionSet&&) noexcept;
  /// Takes over the other's inputs, constants, tables and expressions.
  ExpressionSet& operator=(ExpressionSet&&) noexcept;

  /// Declares a named constant (a parameter) with its value; expressions parsed afterwards may
  /// use it, and it is replaced by its value when compiling. @throws std::invalid_argument on a
  /// name that is already an input or constant (or malformed), or a value that is not finite.
  void set_constant(const std::string& name, double value);

  /// Declares a table column callable in expressions parsed afterwards as `name(x)`, `name`
  /// being `table.column` (two identifiers joined by a '.'; modelfile/table.hpp). Its
  /// derivatives are the interpolant's (a linear column's slope is a step, a step's is 0); a
  /// compiled program evaluates it with a binary search (O(log rows), no allocation); outside
  /// its range, when its extrapolation is kError, the value is NaN and the message is recorded
  /// (expr::table_range_error(), modelfile/table.hpp). The column is shared, never copied. @throws
  /// std::invalid_argument on a malformed or repeated name or a null column.
  void add_table_column(const std::string& name, std::shared_ptr<const TableColumn> column);

  /// Parses `text`. @throws ParseError (syntax errors, unknown names — the message names the
  /// name and lists close matches or the known names —, unknown functions or wrong numbers of
  /// arguments, and operations GiNaC refuses while building, such as 1/0 or log(0)).
  Expr parse(const std::string& text);

  /// A number as an expression (the shortest decimal that reads back as `value`, as an exact
  /// rational: constant(0.1) equals parse("0.1")). @throws std::invalid_argument if not finite.
  Expr constant(double value);
  /// Arithmetic on expressions. @throws std::invalid_argument on a handle not from this set.
  Expr add(Expr a, Expr b);
  /// a − b. @throws std::invalid_argument on a handle not from this set.
  Expr subtract(Expr a, Expr b);
  /// a · b. @throws std::invalid_argument on a handle not from this set.
  Expr multiply(Expr a, Expr b);
  /// −a. @throws std::invalid_argument on a handle not from this set.
  Expr negate(Expr a);

  /// d e / d (input `name`), exactly. @throws std::invalid_argument if name is not an input.
  Expr diff(Expr e, const std::string& name);

  /// The total time derivative along the motion, without acceleration terms:
  ///   D e = ∂e/∂t + Σ_i ∂e/∂q_i · q̇_i
  /// where `time` names the time input and `chain` pairs each coordinate with its velocity
  /// ({"x", "x_dot"}, …). Terms in q̈ (from velocities inside e) are left out: they are what
  /// the acceleration form A q'' = b keeps on its left. @throws std::invalid_argument on
  /// unknown names.
  Expr total_derivative(Expr e, const std::string& time,
                        const std::vector<std::pair<std::string, std::string>>& chain);

  /// True when e does not depend on `name` (an input or a constant). @throws
  /// std::invalid_argument on an unknown name.
  bool independent_of(Expr e, const std::string& name) const;
  /// The inputs e depends on, as indices into input_names(), ascending, each once. One
  /// traversal of e (names are not looked up): use it rather than independent_of() in loops
  /// over many inputs. @throws std::invalid_argument on a handle not from this set.
  std::vector<Index> inputs_of(Expr e) const;
  /// True when e is stored as the number 0 — what diff() gives for an input e does not hold —
  /// without simplifying it (O(1); is_zero() also finds x - x after normalization).
  bool is_literal_zero(Expr e) const;
  /// The sum of `terms` (0 when empty), built at once: the same expression as adding them one
  /// by one with add(), in time O(k log k) for k terms rather than O(k²).
  Expr sum(const std::vector<Expr>& terms);
  /// The terms of e as written at its top level: the summands of a sum, else e itself (not
  /// expanded: x*(1 - t) is one term). Cost O(terms).
  std::vector<Expr> terms(Expr e);

  /// True when e is identically zero (after GiNaC's normalization).
  bool is_zero(Expr e) const;
  /// e printed in the model language (for messages and reports).
  std::string to_string(Expr e) const;

  /// Compiles the outputs into a Program reading the inputs in declaration order; constants are
  /// replaced by their values. Common subexpressions are computed once, integer powers become
  /// multiplications, half-integer powers sqrt, constant subexpressions are folded, and sin and
  /// cos of one argument share a sincos call. @throws std::invalid_argument when an output has
  /// a complex constant (sqrt(-4)) or a function outside the language.
  Program compile(const std::vector<Expr>& outputs) const;
  /// True when compile({e}) is sure to succeed, found without compiling: e holds inputs,
  /// numbers that are real and finite as doubles, sums, products, powers and the language's
  /// functions, and every part of it that is not a number holds an input — then the compiler
  /// folds no constants (the only step, with complex numbers, that can fail). False says
  /// nothing (compile to know). Cost: one traversal of e, about a tenth of compiling it.
  bool compile_cannot_fail(Expr e) const;

  /// The switching functions of the non-smooth calls in `exprs`, each once (g and −g are one):
  /// the argument x of abs(x), sign(x) and heaviside(x), a − b of min(a, b) and max(a, b), and
  /// the condition c of if(c, a, b) — where the value or a derivative of the expression jumps
  /// when g changes sign (docs/simulation.md, "Switch events"). Constant ones are left out, and
  /// so are the conditions of the tie rule inside a derivative (expression_parse.cpp, kink),
  /// which act only at their if's own switch. Adds the functions to the set and returns their
  /// handles. @throws std::invalid_argument on a handle not from this set. Cost O(size of the
  /// expressions).
  std::vector<Expr> switching_functions(const std::vector<Expr>& exprs);

  /// The input names, in order.
  const std::vector<std::string>& input_names() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ukdyn::expr
