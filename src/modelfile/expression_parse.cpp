// SPDX-License-Identifier: BSD-3-Clause
// The model language's parser (see modelfile/expression.hpp): a small recursive-descent parser with
// positions and suggestions in its errors, building GiNaC expressions directly rather than with
// GiNaC::parser: GiNaC's parser reports no positions (line and column are always 0), lets a
// unary minus after an operator swallow the rest of the expression (it reads x^-2+y as
// x^(-2+y) and 2/-x*y as -2/(x*y)), and accepts I, Pi and {lists}, which are not in the
// language. Decimal numbers become exact rationals (0.1 is 1/10), so derivatives and
// is_zero() are exact; they are rounded to double once, when compiling.

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
// names and suggestions

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// Levenshtein distance (insertions, deletions, substitutions), O(|a| |b|)
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string lowercase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// up to three of `known` close to `name` (same letters up to case, or a few edits away, but not
// as many edits as the name has characters), closest first
std::vector<std::string> close_matches(const std::string& name,
                                       const std::vector<std::string>& known) {
  const std::size_t limit = name.size() <= 3 ? 1 : name.size() <= 6 ? 2 : 3;
  std::vector<std::pair<std::size_t, std::string>> found;
  for (const auto& k : known) {
    const std::size_t d = lowercase(k) == lowercase(name) ? 0 : edit_distance(name, k);
    if (d == 0 || (d <= limit && d < name.size())) found.emplace_back(d, k);
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> out;
  for (std::size_t i = 0; i < found.size() && i < 3; ++i) out.push_back(found[i].second);
  return out;
}

// "'a'", "'a' or 'b'", "'a', 'b' or 'c'"
std::string quoted_alternatives(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) s += i + 1 == names.size() ? " or " : ", ";
    s += "'" + names[i] + "'";
  }
  return s;
}

// "a, b, c" (at most 20, then "…")
std::string listing(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size() && i < 20; ++i) s += (i > 0 ? ", " : "") + names[i];
  if (names.size() > 20) s += ", …";
  return s.empty() ? "none" : s;
}

// ---------------------------------------------------------------------------------------------
// numbers

// the exact rational written in decimal as digits · 10^exponent10
GiNaC::numeric decimal(const std::string& digits, long exponent10) {
  GiNaC::numeric n(digits.c_str());
  const GiNaC::numeric ten(10);
  return exponent10 >= 0 ? n * ten.power(exponent10) : n / ten.power(-exponent10);
}

// the shortest decimal that reads back as v, as an exact rational (so constant(0.1) is 1/10,
// like the text "0.1")
GiNaC::numeric exact(double v) {
  if (std::isfinite(v) && v == std::trunc(v) && std::fabs(v) < 9.0e15) {
    return GiNaC::numeric(static_cast<long>(v));
  }
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  UKDYN_CHECK(r.ec == std::errc(), "expression: to_chars failed");
  // d.ddddde±xx
  const std::string text(buf, r.ptr);
  const std::size_t e = text.find('e');
  std::string mantissa = text.substr(0, e);
  long exponent = std::strtol(text.c_str() + e + 1, nullptr, 10);
  const std::size_t dot = mantissa.find('.');
  if (dot != std::string::npos) {
    exponent -= long(mantissa.size() - dot - 1);
    mantissa.erase(dot, 1);
  }
  return decimal(mantissa, exponent);
}

// A bound of the bits of the exact numbers in `e` (a product multiplies its factors' numbers, a
// power of numbers raises them): what GiNaC would compute if `e` were raised to an integer
// power, since (2 x)^n is 2^n x^n and (2^(1/2))^n is 2^(n/2) for it.
double numeric_bits(const GiNaC::ex& e) {
  if (GiNaC::is_a<GiNaC::numeric>(e)) {
    const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(e);
    if (!n.is_rational()) return 64.0;
    return double(std::max(n.numer().int_length(), n.denom().int_length()));
  }
  if (GiNaC::is_a<GiNaC::power>(e) && GiNaC::is_a<GiNaC::numeric>(e.op(1))) {
    const GiNaC::numeric p = GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(e.op(1)));
    const double magnitude = p.is_real() && p < GiNaC::numeric(1L << 30) ? p.to_double() : 1e30;
    return numeric_bits(e.op(0)) * std::max(1.0, magnitude);
  }
  if (GiNaC::is_a<GiNaC::mul>(e)) {
    double bits = 0.0;
    for (std::size_t i = 0; i < e.nops(); ++i) bits += numeric_bits(e.op(i));
    return bits;
  }
  return 0.0;
}

// ---------------------------------------------------------------------------------------------
// the parser
//
//   expression := term (('+' | '-') term)*
//   term       := unary (('*' | '/') unary)*
//   unary      := ('+' | '-') unary | power
//   power      := primary ['^' unary]          (a^b^c and a^-b^c are refused as ambiguous)
//   primary    := number | name | function '(' expression (',' expression)* ')'
//               | '(' expression ')'
// so -x^2 = -(x^2), x^-2*y = (x^-2)*y and 2*-x+y = 2*(-x)+y, as in Python and Fortran.

enum class Kind { kNumber, kName, kOperator, kEnd };

struct Token {
  Kind kind = Kind::kEnd;
  std::string text;
  std::size_t position = 0;
};

class Parser {
 public:
  // Deepest nesting of parentheses, calls and signs: the parser and GiNaC recurse on it.
  static constexpr int kMaxDepth = 100;
  // Stack a level of nesting may need below where parse() starts, while parsing (six frames a
  // level) and after it (GiNaC differentiates, compares and destroys an expression by recursing
  // once per level, and so does the compiler, modelfile/expression_compile.cpp). Measured by
  // reading models with their expression nested d deep on threads of decreasing stacks (every
  // kind of nesting of tests/modelfile/test_expression_nesting.cpp, in the potential, the kinetic
  // energy and a constraint): the smallest stack that reads grows by at most 1.56 kB a level
  // (function calls; 1.1 kB for parentheses). 2 kB a level are asked for, on top of the reserve
  // that stack_floor() keeps below.
  static constexpr std::size_t kStackPerLevel = 2048;
  // Largest exact number a power may make (GiNaC computes 10^(10^9) digit by digit); a double
  // holds at most 2^1024, so nothing of use is refused.
  static constexpr double kMaxPowerBits = 4096.0;

  Parser(const std::string& text, const std::map<std::string, GiNaC::ex>& names,
         const std::vector<std::string>& known, const GiNaC::exmap& values,
         const TableNames& tables)
      : text_(text), names_(names), known_(known), values_(values), tables_(tables) {
    next();
  }

  GiNaC::ex parse() {
    if (token_.kind == Kind::kEnd) fail("empty expression", token_.position);
    const char here = 0;
    stack_at_start_ = ukdyn::detail::stack_left(&here, floor_);
    GiNaC::ex e = expression();
    if (token_.kind != Kind::kEnd) {
      fail("unexpected " + describe(token_) + " (missing operator?)", token_.position);
    }
    return e;
  }

 private:
  [[noreturn]] static void fail(const std::string& what, std::size_t position) {
    throw ParseError(what, position);
  }

  static std::string describe(const Token& t) {
    switch (t.kind) {
      case Kind::kNumber:
        return "number '" + t.text + "'";
      case Kind::kName:
        return "name '" + t.text + "'";
      case Kind::kOperator:
        return "'" + t.text + "'";
      case Kind::kEnd:
        break;
    }
    return "end of expression";
  }

  bool is(const char* op) const { return token_.kind == Kind::kOperator && token_.text == op; }

  // reads the next token into token_
  void next() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    token_ = Token{Kind::kEnd, "", pos_};
    if (pos_ >= text_.size()) return;
    const auto digit = [&](std::size_t i) {
      return i < text_.size() && std::isdigit(static_cast<unsigned char>(text_[i]));
    };
    const std::size_t start = pos_;
    const char c = text_[pos_];
    if (digit(pos_) || (c == '.' && digit(pos_ + 1))) {
      // digits ['.' digits] [('e' | 'E') ['+' | '-'] digits]
      while (digit(pos_)) ++pos_;
      if (pos_ < text_.size() && text_[pos_] == '.') {
        ++pos_;
        while (digit(pos_)) ++pos_;
      }
      if (pos_ < text_.size() && (text_[pos_] == 'e' || text_[pos_] == 'E')) {
        std::size_t k = pos_ + 1;
        if (k < text_.size() && (text_[k] == '+' || text_[k] == '-')) ++k;
        if (digit(k)) {
          pos_ = k;
          while (digit(pos_)) ++pos_;
        }
      }
      token_ = Token{Kind::kNumber, text_.substr(start, pos_ - start), start};
      return;
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      const auto name_char = [&](std::size_t i) {
        return i < text_.size() &&
               (std::isalnum(static_cast<unsigned char>(text_[i])) || text_[i] == '_');
      };
      while (name_char(pos_)) ++pos_;
      // a table column: table.column (one '.', a name on either side)
      if (pos_ + 1 < text_.size() && text_[pos_] == '.' &&
          (std::isalpha(static_cast<unsigned char>(text_[pos_ + 1])) || text_[pos_ + 1] == '_')) {
        ++pos_;
        while (name_char(pos_)) ++pos_;
      }
      token_ = Token{Kind::kName, text_.substr(start, pos_ - start), start};
      return;
    }
    if (std::strchr("+-*/^(),", c) != nullptr) {
      if (c == '*' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '*') {
        fail("'**' is not an operator: write powers with '^' (x^2)", start);
      }
      ++pos_;
      token_ = Token{Kind::kOperator, std::string(1, c), start};
      return;
    }
    // the whole character (a UTF-8 sequence of 1 to 4 bytes), never a piece of one
    const auto lead = static_cast<unsigned char>(c);
    std::size_t width = lead < 0xC0 ? 1 : lead < 0xE0 ? 2 : lead < 0xF0 ? 3 : 4;
    std::size_t end = start + 1;
    while (end < text_.size() && end < start + width &&
           (static_cast<unsigned char>(text_[end]) & 0xC0) == 0x80) {
      ++end;
    }
    fail("unexpected character '" + valid_utf8(text_.substr(start, end - start)) + "'", start);
  }

  // GiNaC evaluates as it builds (1/0, log(0) throw): report such errors at `position`
  template <class F>
  static GiNaC::ex build(F&& f, std::size_t position) {
    try {
      return f();
    } catch (const std::exception& e) {
      fail(std::string("cannot evaluate: ") + e.what(), position);
    }
  }

  // e with the constants' values (those compile() puts in): an operation may divide by zero or
  // take log(0) with them though not with their symbols, like 1/(L - 1) with L = 1. Checked here,
  // where the position is known, as each operation is built from operands already checked (in
  // compile's substitution, GiNaC would also leak the objects it was building).
  GiNaC::ex valued(const GiNaC::ex& e, std::size_t position) const {
    if (values_.empty()) return e;
    return build([&] { return e.subs(values_); }, position);
  }

  static std::string printed(const GiNaC::ex& e) {
    std::ostringstream os;
    os << e;
    return os.str();
  }

  // e as printed, shortened to about 60 characters (for messages)
  // text longer than 60 characters cut to its first 57 and "..."
  static std::string shortened(std::string s) {
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
  }

  static std::string brief(const GiNaC::ex& e) {
    const std::string s = shortened(printed(e));
    const bool compound =
        !GiNaC::is_a<GiNaC::symbol>(e) && !GiNaC::is_a<GiNaC::function>(e) &&
        !(GiNaC::is_a<GiNaC::numeric>(e) && GiNaC::ex_to<GiNaC::numeric>(e).is_integer() &&
          !GiNaC::ex_to<GiNaC::numeric>(e).is_negative());
    return compound ? "(" + s + ")" : s;
  }

  // true when e depends on an input (a symbol that is not a constant)
  bool has_input(const GiNaC::ex& e) const {
    for (auto i = e.preorder_begin(); i != e.preorder_end(); ++i) {
      if (GiNaC::is_a<GiNaC::symbol>(*i) && values_.find(*i) == values_.end()) return true;
    }
    return false;
  }

  // base^exponent, as GiNaC computes it when the constants get their values (compile() substitutes
  // them, and so does valued()): refused when an exact number of more than kMaxPowerBits bits, so
  // lc^(10^90) with lc = 0.3 as well as 10^(10^90)
  void check_power_size(const GiNaC::ex& base, const GiNaC::ex& exponent, std::size_t at) const {
    const GiNaC::ex p = valued(exponent, at);
    if (!GiNaC::is_a<GiNaC::numeric>(p) || !GiNaC::ex_to<GiNaC::numeric>(p).is_real()) return;
    const GiNaC::numeric magnitude = GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(p));
    const GiNaC::ex b = valued(base, at);
    const double bits = std::min(numeric_bits(b), 1e15);
    if (bits > 1.0 &&
        magnitude * GiNaC::numeric(long(bits)) > GiNaC::numeric(long(kMaxPowerBits))) {
      fail("the power makes a number too large to compute exactly (over " +
               format_number(int(kMaxPowerBits)) + " bits)" +
               (p.is_equal(exponent) && b.is_equal(base) ? "" : " with the parameters' values"),
           at);
    }
  }

  // base^exponent and its first two derivatives (the model takes no more) with the constants'
  // values: 0^p needs p > 0, and the derivatives of b^p where b is 0 need p a whole number,
  // since they hold b^(p - 1), b^(p - 2) and, when p is not constant, log(b)
  void check_power(const GiNaC::ex& base, const GiNaC::ex& exponent, std::size_t at) const {
    if (!valued(base, at).is_zero()) return;
    const GiNaC::ex p = valued(exponent, at);
    const bool numeric = GiNaC::is_a<GiNaC::numeric>(p);
    const bool positive = numeric && GiNaC::ex_to<GiNaC::numeric>(p).is_positive();
    const bool with_values = !base.is_zero() || !exponent.is_equal(p);
    if (!positive) {
      fail("cannot evaluate: 0^" + (numeric ? printed(p) : "(" + printed(p) + ")") +
               (with_values ? " with the parameters' values" : ""),
           at);
    }
    if ((has_input(base) || has_input(exponent)) && !GiNaC::ex_to<GiNaC::numeric>(p).is_integer()) {
      fail("cannot differentiate: the base of this power is 0 with the parameters' values, and " +
               printed(p) + " is not a whole number",
           at);
    }
  }

  // A constant sub-expression (no input) with the constants' values must be a finite real
  // double: acos(2) and (-8)^(1/3) are complex, exp(1000) and 10^400 overflow. `what` names it
  // in the message ("acos(...)", "the power"). Evaluated with GiNaC's evalf (about 17 digits,
  // its float exponent does not overflow); exp, sinh and cosh of more than 1000 are refused
  // before, unevaluated. Cost: one evalf of the sub-expression.
  void check_constant_value(const GiNaC::ex& e, const std::string& what, std::size_t at) const {
    if (has_input(e)) return;
    const GiNaC::ex v = valued(e, at);
    const bool with_values = !v.is_equal(e);
    const std::string suffix = with_values ? " with the parameters' values" : "";
    GiNaC::ex f;
    try {
      f = GiNaC::evalf(v);
    } catch (const std::exception& error) {
      fail("cannot evaluate " + what + suffix + ": " + error.what(), at);
    }
    if (!GiNaC::is_a<GiNaC::numeric>(f)) return;  // not a number (cannot happen: no symbols)
    const GiNaC::numeric n = GiNaC::ex_to<GiNaC::numeric>(f);
    if (!n.is_real()) {
      fail("cannot evaluate: " + what + " is complex" + suffix + " (" + printed(f) + ")", at);
    }
    if (GiNaC::abs(n) > GiNaC::numeric(std::numeric_limits<double>::max())) {
      fail("cannot evaluate: " + what + " overflows a double" + suffix + " (about " + printed(f) +
               "; a double holds magnitudes up to about 1.8e308)",
           at);
    }
  }

  // the distance from x to the nearest of a + k pi (k whole), and x's roundoff when the value is
  // rounded to a double: within a few roundoffs, a double argument cannot tell the two apart
  static bool within_roundoff_of(const GiNaC::numeric& x, const GiNaC::numeric& a) {
    const GiNaC::numeric pi = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(GiNaC::Pi));
    const double turns = ((x - a) / pi).to_double();
    if (!(std::fabs(turns) < 1e15)) return false;  // beyond where a double resolves a period
    const GiNaC::numeric k(long(std::llround(turns)));
    const GiNaC::numeric distance = GiNaC::abs(x - a - k * pi);
    const double scale = std::max(1.0, std::fabs(x.to_double()));
    return distance <= GiNaC::numeric(8.0 * std::numeric_limits<double>::epsilon() * scale);
  }

  // tan(x) with x a constant at a pole (pi/2 + k pi) to within roundoff: a double computes a
  // large finite number (tan(pi/2) is 1.633e16) that is only noise
  void check_pole(const FunctionInfo& f, const GiNaC::exvector& args, std::size_t at) const {
    if (f.code != Code::kTan || has_input(args[0])) return;
    GiNaC::ex x;
    try {
      x = GiNaC::evalf(valued(args[0], at));
    } catch (const std::exception&) {
      return;  // reported by check_constant_value
    }
    if (!GiNaC::is_a<GiNaC::numeric>(x) || !GiNaC::ex_to<GiNaC::numeric>(x).is_real()) return;
    const GiNaC::numeric half_pi = GiNaC::ex_to<GiNaC::numeric>(GiNaC::evalf(GiNaC::Pi / 2));
    if (within_roundoff_of(GiNaC::ex_to<GiNaC::numeric>(x), half_pi)) {
      fail(
          "cannot evaluate: tan is at its pole (pi/2 + k pi) to within roundoff: its argument "
          "is " +
              printed(x) +
              (valued(args[0], at).is_equal(args[0]) ? "" : " with the parameters' values") +
              ", and a double gives a meaningless large number there",
          at);
    }
  }

  // f(args) as written, for messages: GiNaC's value of the call may be a simplification of it
  // (sqrt(-1) is I: the message said "(I) is complex (I)")
  std::string written(const FunctionInfo& f, const GiNaC::exvector& args) const {
    std::string text = std::string(f.name) + "(";
    for (std::size_t a = 0; a < args.size(); ++a)
      text += (a ? ", " : "") + shortened(printed(args[a]));
    return text + ")";
  }

  // f(args) with the constants' values: log(0) and tan(acos(0)) are undefined, and sqrt and abs
  // at 0, asin and acos at 1 or -1 and atan2 at (0, 0) have no derivative
  void check_call(const FunctionInfo& f, const GiNaC::exvector& args, std::size_t at) const {
    if (f.code == Code::kSqrt) check_power(args[0], GiNaC::numeric(1, 2), at);
    if (values_.empty()) {  // as built; a constant: finite and real, away from a pole
      if (std::none_of(args.begin(), args.end(),
                       [&](const GiNaC::ex& a) { return has_input(a); })) {
        check_pole(f, args, at);
        const GiNaC::ex value = build([&] { return call(f, args); }, at);
        check_constant_value(value, written(f, args), at);
      }
      return;
    }
    GiNaC::exvector v;
    bool inputs = false;
    for (const auto& a : args) {
      v.push_back(valued(a, at));
      inputs = inputs || has_input(a);
    }
    const GiNaC::ex value = build([&] { return call(f, v); }, at);
    if (!inputs) {
      // a constant: finite and real, away from a pole; no derivative taken
      check_pole(f, args, at);
      check_constant_value(value, written(f, args), at);
      return;
    }
    const std::string name = f.name;
    if (f.code == Code::kAbs && v[0].is_zero()) {
      fail("cannot differentiate: the argument of abs is 0 with the parameters' values", at);
    }
    if ((f.code == Code::kAsin || f.code == Code::kAcos) &&
        (v[0].is_equal(GiNaC::ex(1)) || v[0].is_equal(GiNaC::ex(-1)))) {
      fail("cannot differentiate: the argument of " + name + " is " + printed(v[0]) +
               " with the parameters' values",
           at);
    }
    if (f.code == Code::kAtan2 && v[0].is_zero() && v[1].is_zero()) {
      fail("cannot differentiate: both arguments of atan2 are 0 with the parameters' values", at);
    }
  }

  // a + b − c … is summed at once (the same expression as term by term, but adding a term to a
  // sum of k terms copies them: a sum of N terms would take O(N²))
  GiNaC::ex expression() {
    GiNaC::ex e = term();
    if (!is("+") && !is("-")) return e;
    GiNaC::exvector terms{e};
    const std::size_t first = token_.position;
    while (is("+") || is("-")) {
      const bool plus = is("+");
      next();
      GiNaC::ex rhs = term();
      terms.push_back(plus ? rhs : -rhs);
    }
    return build([&] { return GiNaC::ex(GiNaC::dynallocate<GiNaC::add>(terms)); }, first);
  }

  GiNaC::ex term() {
    GiNaC::ex e = unary();
    while (is("*") || is("/")) {
      const bool times = is("*");
      const std::size_t at = token_.position;
      next();
      const GiNaC::ex rhs = unary();
      if (!times && valued(rhs, at).is_zero()) {
        fail(std::string("cannot evaluate: division by zero") +
                 (rhs.is_zero() ? "" : " with the parameters' values"),
             at);
      }
      e = build([&] { return times ? e * rhs : e / rhs; }, at);
      // a product of numbers (1e300*1e300, 1/1e-400): exact here, a double holds it?
      if (GiNaC::is_a<GiNaC::numeric>(e)) {
        check_constant_value(e, times ? "the product" : "the quotient", at);
      }
      // a product adds the exponents of a common base: x^a * x^(b - a) is x^b
      const bool product = GiNaC::is_a<GiNaC::mul>(e);
      for (std::size_t i = 0; i < (product ? e.nops() : 1); ++i) {
        const GiNaC::ex f = product ? e.op(i) : e;
        if (GiNaC::is_a<GiNaC::power>(f)) check_power_size(f.op(0), f.op(1), at);
      }
    }
    return e;
  }

  // in_exponent: the operand right of a '^', which may not hold another '^' unparenthesized
  GiNaC::ex unary(bool in_exponent = false) {
    // every nested operand passes here: count the depth
    if (depth_ == kMaxDepth) {
      fail("the expression nests more than " + format_number(kMaxDepth) +
               " deep (parentheses, function calls and signs)",
           token_.position);
    }
    // the stack the nesting needs, while parsing (what is left here) and after it (a budget per
    // level from where parsing started), against this thread's stack
    const char here = 0;
    if (ukdyn::detail::stack_left(&here, floor_) == 0 ||
        stack_at_start_ / kStackPerLevel <= std::size_t(depth_)) {
      fail("the expression nests too deep for this process's stack (" + format_number(depth_) +
               " levels of parentheses, function calls and signs here; raise the stack limit, "
               "ulimit -s, or write it in steps)",
           token_.position);
    }
    ++depth_;
    GiNaC::ex e = signed_operand(in_exponent);
    --depth_;
    return e;
  }

  GiNaC::ex signed_operand(bool in_exponent) {
    if (is("+")) {
      next();
      return unary(in_exponent);
    }
    if (is("-")) {
      next();
      return -unary(in_exponent);
    }
    return power(in_exponent);
  }

  GiNaC::ex power(bool in_exponent) {
    GiNaC::ex base = primary();
    if (!is("^")) return base;
    if (in_exponent) fail("a^b^c is ambiguous: write (a^b)^c or a^(b^c)", token_.position);
    const std::size_t at = token_.position;
    next();
    const GiNaC::ex exponent = unary(true);
    check_power_size(base, exponent, at);
    check_power(base, exponent, at);
    GiNaC::ex e = build([&] { return GiNaC::pow(base, exponent); }, at);
    // (the message printed only for a constant: a power of an input is not checked)
    if (!has_input(e))
      check_constant_value(e, "the power " + brief(base) + "^" + brief(exponent), at);
    return e;
  }

  GiNaC::ex primary() {
    const Token t = token_;
    switch (t.kind) {
      case Kind::kNumber:
        next();
        return number(t);
      case Kind::kName:
        next();
        return is("(") ? function_call(t) : name(t);
      case Kind::kOperator:
        if (t.text == "(") {
          next();
          GiNaC::ex e = expression();
          if (!is(")")) {
            fail("expected ')' to close the '(' at position " + format_number(t.position) +
                     ", got " + describe(token_),
                 token_.position);
          }
          next();
          return e;
        }
        fail("unexpected " + describe(t), t.position);
      case Kind::kEnd:
        break;
    }
    fail("unexpected end of expression", t.position);
  }

  static GiNaC::ex number(const Token& t) {
    // mantissa digits and the power of ten
    const std::string& s = t.text;
    std::string digits;
    long exponent = 0;
    std::size_t i = 0;
    bool fraction = false;
    for (; i < s.size() && s[i] != 'e' && s[i] != 'E'; ++i) {
      if (s[i] == '.') {
        fraction = true;
      } else {
        digits += s[i];
        if (fraction) --exponent;
      }
    }
    if (i < s.size()) {
      // ['+' | '-'] digits, saturated: strtol's LONG_MIN for 1e-9223372036854775809 has no abs()
      std::size_t k = i + 1;
      const bool negative = s[k] == '-';
      if (s[k] == '+' || s[k] == '-') ++k;
      long e = 0;
      for (; k < s.size() && e <= 400; ++k) e = 10 * e + (s[k] - '0');
      if (e > 400) fail("number '" + s + "' is out of range", t.position);
      exponent += negative ? -e : e;
    }
    // a number no double holds is refused where it is written (it would evaluate to inf)
    if (!std::isfinite(std::strtod(s.c_str(), nullptr))) {
      fail("number '" + s + "' is too large: it exceeds the largest double (about 1.8e308)",
           t.position);
    }
    return decimal(digits, exponent);
  }

  // the table columns' names (for suggestions)
  std::vector<std::string> table_names() const {
    std::vector<std::string> out;
    for (const auto& [name, callee] : tables_) out.push_back(name);
    return out;
  }

  // a name with a '.' that is not a table column
  [[noreturn]] void unknown_column(const Token& t) const {
    std::string underscored = t.text;
    std::replace(underscored.begin(), underscored.end(), '.', '_');
    if (names_.count(underscored) != 0) {
      fail("unknown table column '" + t.text + "' (did you mean '" + underscored +
               "'? a body's coordinates are written with '_' in expressions)",
           t.position);
    }
    const auto names = table_names();
    const auto close = close_matches(t.text, names);
    fail("unknown table column '" + t.text + "' (" +
             (!close.empty()  ? "did you mean " + quoted_alternatives(close) + "?"
              : names.empty() ? std::string("the model has no tables: section")
                              : "the tables' columns are " + listing(names)) +
             ")",
         t.position);
  }

  GiNaC::ex name(const Token& t) const {
    const auto it = names_.find(t.text);
    if (it != names_.end()) return it->second;
    if (tables_.count(t.text) != 0) {
      fail("'" + t.text + "' is a table column: write " + t.text + "(x), x its argument (t, …)",
           t.position);
    }
    if (t.text.find('.') != std::string::npos) unknown_column(t);
    if (find_function(t.text) != nullptr) {
      fail("'" + t.text + "' is a function: write " + t.text + "(...)", t.position);
    }
    const auto close = close_matches(t.text, known_);
    if (!close.empty()) {
      fail("unknown name '" + t.text + "' (did you mean " + quoted_alternatives(close) + "?)",
           t.position);
    }
    fail("unknown name '" + t.text + "' (known names: " + listing(known_) + ")", t.position);
  }

  // table.column(x)
  GiNaC::ex table_call_of(const Token& t) {
    const auto callee = tables_.find(t.text);
    if (callee == tables_.end()) unknown_column(t);
    const std::size_t open = token_.position;
    next();  // '('
    if (is(")")) fail(t.text + " takes 1 argument, got 0", t.position);
    const GiNaC::ex x = expression();
    if (!is(")")) {
      fail(is(",") ? t.text + " takes 1 argument, got more"
                   : "expected ')' to close the '(' of " + t.text + " at position " +
                         format_number(open) + ", got " + describe(token_),
           token_.position);
    }
    next();  // ')'
    return table_call(callee->second, 0, x);
  }

  GiNaC::ex function_call(const Token& t) {
    if (t.text.find('.') != std::string::npos || tables_.count(t.text) != 0) {
      return table_call_of(t);
    }
    const FunctionInfo* f = find_function(t.text);
    if (f == nullptr) {
      if (names_.count(t.text) != 0) {
        fail("'" + t.text + "' is not a function (missing '*' before '('?)", t.position);
      }
      const auto close = close_matches(t.text, function_names());
      fail("unknown function '" + t.text + "' (" +
               (close.empty() ? "the functions are " + listing(function_names())
                              : "did you mean " + quoted_alternatives(close) + "?") +
               ")",
           t.position);
    }
    const std::size_t open = token_.position;
    next();  // '('
    GiNaC::exvector args;
    if (!is(")")) {
      while (true) {
        args.push_back(expression());
        if (is(")")) break;
        if (!is(",")) {
          fail("expected ',' or ')' in the arguments of " + t.text + " (opened at position " +
                   format_number(open) + "), got " + describe(token_),
               token_.position);
        }
        next();
      }
    }
    next();  // ')'
    if (int(args.size()) != f->arity) {
      fail(t.text + " takes " + format_number(f->arity) +
               (f->arity == 1 ? " argument" : " arguments") + ", got " + format_number(args.size()),
           t.position);
    }
    check_call(*f, args, t.position);
    return build([&] { return call(*f, args); }, t.position);
  }

  const std::string& text_;
  const std::map<std::string, GiNaC::ex>& names_;
  const std::vector<std::string>& known_;
  const GiNaC::exmap& values_;
  const TableNames& tables_;
  std::size_t pos_ = 0;
  int depth_ = 0;  // of unary() calls
  // the lowest stack address the nesting may reach (ukdyn::detail::stack_floor, once a thread:
  // on the main thread it reads /proc/self/maps), and the stack left above it when parse()
  // started
  const char* floor_ = [] {
    thread_local const char* const floor = ukdyn::detail::stack_floor();
    return floor;
  }();
  std::size_t stack_at_start_ = SIZE_MAX;
  Token token_;
};

GiNaC::ex parse_expression(const std::string& text, const std::map<std::string, GiNaC::ex>& names,
                           const std::vector<std::string>& known, const GiNaC::exmap& values,
                           const TableNames& tables) {
  return Parser(text, names, known, values, tables).parse();
}

}  // namespace ukdyn::expr::detail
