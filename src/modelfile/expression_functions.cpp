// SPDX-License-Identifier: BSD-3-Clause
// The model language's functions (see modelfile/expression.hpp): abs and the non-smooth
// functions registered with GiNaC (their values, derivatives and printing), the table of the
// language's functions and the GiNaC expression of a call. The parser is in
// modelfile/expression_parse.cpp.

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <ginac/ginac.h>

#include "modelfile/expression_internal.hpp"
#include "modelfile/stack_floor.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn::expr::detail {

// ---------------------------------------------------------------------------------------------
// the language's functions

// abs and the non-smooth functions are GiNaC functions of our own, registered under their names in
// the language (GiNaC's step and csgn have no derivative, so diff() would leave D[0](step)(x),
// which cannot be compiled). Each folds when its arguments are real numbers (if(c, a, b) when c is)
// and has the derivative where it exists: sign(x) for abs (GiNaC's own abs has x/abs(x), NaN at 0,
// where a potential F·abs(x) has the force 0 by symmetry), 0 for sign and heaviside, and the
// derivative of the branch taken for max, min and if, with abs's rule at a tie (kink below).
DECLARE_FUNCTION_1P(lang_abs)
DECLARE_FUNCTION_1P(lang_sign)
DECLARE_FUNCTION_1P(lang_heaviside)
DECLARE_FUNCTION_2P(lang_min)
DECLARE_FUNCTION_2P(lang_max)
DECLARE_FUNCTION_3P(lang_if)
DECLARE_FUNCTION_4P(lang_table)

GiNaC::ex kink_tie(const GiNaC::ex& c) { return 1 - lang_abs(lang_sign(c)); }

namespace {

// x as a real number, or null
const GiNaC::numeric* real_number(const GiNaC::ex& x) {
  if (!GiNaC::is_exactly_a<GiNaC::numeric>(x)) return nullptr;
  const auto& n = GiNaC::ex_to<GiNaC::numeric>(x);
  return n.is_real() ? &n : nullptr;
}

GiNaC::ex abs_eval(const GiNaC::ex& x) {
  if (GiNaC::is_exactly_a<GiNaC::numeric>(x)) return GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(x));
  return lang_abs(x).hold();
}
GiNaC::ex abs_evalf(const GiNaC::ex& x) { return abs_eval(x); }
GiNaC::ex abs_deriv(const GiNaC::ex& x, unsigned) { return lang_sign(x); }
void abs_print(const GiNaC::ex& x, const GiNaC::print_context& c) {
  c.s << "abs(";
  x.print(c);
  c.s << ")";
}

GiNaC::ex sign_eval(const GiNaC::ex& x) {
  if (const auto* n = real_number(x))
    return GiNaC::numeric(n->is_zero() ? 0 : n->is_positive() ? 1 : -1);
  return lang_sign(x).hold();
}
GiNaC::ex sign_evalf(const GiNaC::ex& x) { return sign_eval(x); }
GiNaC::ex sign_deriv(const GiNaC::ex&, unsigned) { return 0; }

GiNaC::ex heaviside_eval(const GiNaC::ex& x) {
  if (const auto* n = real_number(x)) {
    return n->is_zero() ? GiNaC::numeric(1, 2) : GiNaC::numeric(n->is_positive() ? 1 : 0);
  }
  return lang_heaviside(x).hold();
}
GiNaC::ex heaviside_evalf(const GiNaC::ex& x) { return heaviside_eval(x); }
GiNaC::ex heaviside_deriv(const GiNaC::ex&, unsigned) { return 0; }

// The derivative of a function that is a where c > 0 and b where c < 0, from the one-sided
// derivatives da and db:
//   kink(c, da, db) = if(c, da, if(1 − abs(sign(c)), minmod(da, db), db)),
//   minmod(u, v) = max(min(u, v), 0) + min(max(u, v), 0)
// At the tie c = 0 (where 1 − abs(sign(c)) = 1, and only there: a NaN c gives db, as if(c, …)
// does) it is the one-sided derivative nearer 0, and 0 when they have opposite signs (the
// least-norm subgradient): abs's rule (d abs = sign, 0 at 0), so a mass at rest at the kink of
// max(x, −x), if(x, x, −x) or F·max(x, 0) sees the force 0 and stays at rest — the tie rule b′
// gave it ±F and it chattered. Elsewhere the value is exactly da or db (picked, adding exact
// zeros). When da and db are the same expression (a smooth join) it folds to da.
GiNaC::ex kink(const GiNaC::ex& c, const GiNaC::ex& da, const GiNaC::ex& db) {
  if (da.is_equal(db)) return da;
  const GiNaC::ex minmod = lang_max(lang_min(da, db), 0) + lang_min(lang_max(da, db), 0);
  return lang_if(c, da, lang_if(kink_tie(c), minmod, db));
}

GiNaC::ex min_eval(const GiNaC::ex& a, const GiNaC::ex& b) {
  const auto *na = real_number(a), *nb = real_number(b);
  if (na != nullptr && nb != nullptr) return *nb < *na ? b : a;
  if (a.is_equal(b)) return a;
  return lang_min(a, b).hold();
}
GiNaC::ex min_evalf(const GiNaC::ex& a, const GiNaC::ex& b) { return min_eval(a, b); }
// d min(a, b) = kink(b − a, da, db): the derivative of the branch taken, picked like if's value,
// so a derivative that is infinite where its branch is not taken does not leak
GiNaC::ex min_deriv(const GiNaC::ex& a, const GiNaC::ex& b, const GiNaC::symbol& s) {
  return kink(b - a, a.diff(s), b.diff(s));
}

GiNaC::ex max_eval(const GiNaC::ex& a, const GiNaC::ex& b) {
  const auto *na = real_number(a), *nb = real_number(b);
  if (na != nullptr && nb != nullptr) return *nb > *na ? b : a;
  if (a.is_equal(b)) return a;
  return lang_max(a, b).hold();
}
GiNaC::ex max_evalf(const GiNaC::ex& a, const GiNaC::ex& b) { return max_eval(a, b); }
// d max(a, b) = kink(a − b, da, db)
GiNaC::ex max_deriv(const GiNaC::ex& a, const GiNaC::ex& b, const GiNaC::symbol& s) {
  return kink(a - b, a.diff(s), b.diff(s));
}

GiNaC::ex if_eval(const GiNaC::ex& c, const GiNaC::ex& a, const GiNaC::ex& b) {
  if (const auto* n = real_number(c)) return n->is_positive() ? a : b;
  if (a.is_equal(b)) return a;
  return lang_if(c, a, b).hold();
}
GiNaC::ex if_evalf(const GiNaC::ex& c, const GiNaC::ex& a, const GiNaC::ex& b) {
  return if_eval(c, a, b);
}
// d if(c, a, b) = kink(c, da, db): the condition contributes nothing where it is differentiable
GiNaC::ex if_deriv(const GiNaC::ex& c, const GiNaC::ex& a, const GiNaC::ex& b,
                   const GiNaC::symbol& s) {
  return kink(c, a.diff(s), b.diff(s));
}

// table(c, d, p, x) (expression_internal.hpp): held (a constant x is evaluated by the compiler,
// which has the column); its derivative in x is the next order's, 0 beyond the degree p; c, d
// and p are numbers or the column's symbol, whose derivative is 0
GiNaC::ex table_eval(const GiNaC::ex& c, const GiNaC::ex& d, const GiNaC::ex& p,
                     const GiNaC::ex& x) {
  return lang_table(c, d, p, x).hold();
}
GiNaC::ex table_deriv(const GiNaC::ex& c, const GiNaC::ex& d, const GiNaC::ex& p,
                      const GiNaC::ex& x, unsigned param) {
  if (param != 3) return 0;
  const int next = GiNaC::ex_to<GiNaC::numeric>(d).to_int() + 1;
  if (next > GiNaC::ex_to<GiNaC::numeric>(p).to_int()) return 0;
  return lang_table(c, next, p, x);
}
// table.column(x), its derivatives with primes: table.column'(x), table.column''(x), …
void table_print(const GiNaC::ex& c, const GiNaC::ex& d, const GiNaC::ex&, const GiNaC::ex& x,
                 const GiNaC::print_context& pc) {
  pc.s << GiNaC::ex_to<GiNaC::symbol>(c).get_name()
       << std::string(std::size_t(GiNaC::ex_to<GiNaC::numeric>(d).to_int()), '\'') << "(";
  x.print(pc);
  pc.s << ")";
}

}  // namespace

// registered as "lang_abs" (GiNaC has its own "abs", and warns on a second function of that
// name), printed as abs(...)
unsigned lang_abs_SERIAL::serial =
    GiNaC::function::register_new(GiNaC::function_options("lang_abs", 1)
                                      .eval_func(abs_eval)
                                      .evalf_func(abs_evalf)
                                      .derivative_func(abs_deriv)
                                      .print_func<GiNaC::print_context>(abs_print));
unsigned lang_sign_SERIAL::serial = GiNaC::function::register_new(GiNaC::function_options("sign", 1)
                                                                      .eval_func(sign_eval)
                                                                      .evalf_func(sign_evalf)
                                                                      .derivative_func(sign_deriv));
unsigned lang_heaviside_SERIAL::serial =
    GiNaC::function::register_new(GiNaC::function_options("heaviside", 1)
                                      .eval_func(heaviside_eval)
                                      .evalf_func(heaviside_evalf)
                                      .derivative_func(heaviside_deriv));
unsigned lang_min_SERIAL::serial =
    GiNaC::function::register_new(GiNaC::function_options("min", 2)
                                      .eval_func(min_eval)
                                      .evalf_func(min_evalf)
                                      .expl_derivative_func(min_deriv));
unsigned lang_max_SERIAL::serial =
    GiNaC::function::register_new(GiNaC::function_options("max", 2)
                                      .eval_func(max_eval)
                                      .evalf_func(max_evalf)
                                      .expl_derivative_func(max_deriv));
unsigned lang_if_SERIAL::serial = GiNaC::function::register_new(
    GiNaC::function_options("if", 3).eval_func(if_eval).evalf_func(if_evalf).expl_derivative_func(
        if_deriv));

unsigned lang_table_SERIAL::serial =
    GiNaC::function::register_new(GiNaC::function_options("table", 4)
                                      .eval_func(table_eval)
                                      .derivative_func(table_deriv)
                                      .print_func<GiNaC::print_context>(table_print));

GiNaC::ex table_call(const TableCallee& callee, int order, const GiNaC::ex& x) {
  return lang_table(callee.symbol, order, callee.degree, x);
}

bool is_table_call(const GiNaC::ex& e) {
  return GiNaC::is_a<GiNaC::function>(e) &&
         GiNaC::ex_to<GiNaC::function>(e).get_serial() == lang_table_SERIAL::serial;
}

constexpr std::array<FunctionInfo, 19> kFunctions{{
    {"sin", 1, Code::kSin},     {"cos", 1, Code::kCos},
    {"tan", 1, Code::kTan},     {"asin", 1, Code::kAsin},
    {"acos", 1, Code::kAcos},   {"atan", 1, Code::kAtan},
    {"atan2", 2, Code::kAtan2}, {"sinh", 1, Code::kSinh},
    {"cosh", 1, Code::kCosh},   {"tanh", 1, Code::kTanh},
    {"exp", 1, Code::kExp},     {"log", 1, Code::kLog},
    {"sqrt", 1, Code::kSqrt},   {"abs", 1, Code::kAbs},
    {"sign", 1, Code::kSign},   {"heaviside", 1, Code::kHeaviside},
    {"min", 2, Code::kMin},     {"max", 2, Code::kMax},
    {"if", 3, Code::kIf},
}};

const FunctionInfo* find_function(const std::string& name) {
  for (const auto& f : kFunctions) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

// the GiNaC expression of a call of a language function
GiNaC::ex call(const FunctionInfo& f, const GiNaC::exvector& a) {
  switch (f.code) {
    case Code::kSin:
      return GiNaC::sin(a[0]);
    case Code::kCos:
      return GiNaC::cos(a[0]);
    case Code::kTan:
      return GiNaC::tan(a[0]);
    case Code::kAsin:
      return GiNaC::asin(a[0]);
    case Code::kAcos:
      return GiNaC::acos(a[0]);
    case Code::kAtan:
      return GiNaC::atan(a[0]);
    case Code::kAtan2:
      return GiNaC::atan2(a[0], a[1]);
    case Code::kSinh:
      return GiNaC::sinh(a[0]);
    case Code::kCosh:
      return GiNaC::cosh(a[0]);
    case Code::kTanh:
      return GiNaC::tanh(a[0]);
    case Code::kExp:
      return GiNaC::exp(a[0]);
    case Code::kLog:
      return GiNaC::log(a[0]);
    case Code::kSqrt:
      return GiNaC::sqrt(a[0]);
    case Code::kAbs:
      return lang_abs(a[0]);
    case Code::kSign:
      return lang_sign(a[0]);
    case Code::kHeaviside:
      return lang_heaviside(a[0]);
    case Code::kMin:
      return lang_min(a[0], a[1]);
    case Code::kMax:
      return lang_max(a[0], a[1]);
    case Code::kIf:
      return lang_if(a[0], a[1], a[2]);
    default:
      break;
  }
  UKDYN_CHECK(false, "expression: a language function without a GiNaC counterpart");
  return {};
}

// the names of the language's functions, in the table's order
std::vector<std::string> function_names() {
  std::vector<std::string> names;
  names.reserve(kFunctions.size());
  for (const auto& f : kFunctions) names.emplace_back(f.name);
  return names;
}

}  // namespace ukdyn::expr::detail
