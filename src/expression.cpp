// Expressions of the model language: a parser with positions and suggestions, exact derivatives
// with GiNaC, and compilation of the expression DAG into a flat register tape with
// common-subexpression elimination (see expression.hpp).
//
// The parser is a small recursive-descent parser that builds GiNaC expressions directly rather
// than GiNaC::parser: GiNaC's parser reports no positions (line and column are always 0), lets a
// unary minus after an operator swallow the rest of the expression (it reads x^-2+y as
// x^(-2+y) and 2/-x*y as -2/(x*y)), and accepts I, Pi and {lists}, which are not in the
// language. Decimal numbers become exact rationals (0.1 is 1/10), so derivatives and
// is_zero() are exact; they are rounded to double once, when compiling.
#include "ukdyn/expression.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <ginac/ginac.h>

#include "ukdyn/status.hpp"

namespace ukdyn::expr {

namespace {

// ---------------------------------------------------------------------------------------------
// the tape

// One operation of the register machine: s[dst] = code(s[a], s[b]). Unary operations read a
// only (b = a). kSinCos writes two registers: s[dst] = sin s[a], s[b] = cos s[a].
// clang-format off
enum class Code : std::uint8_t {
  kAdd, kSub, kMul, kDiv, kNeg, kRecip, kSqrt, kPow,
  kSin, kCos, kSinCos, kTan, kAsin, kAcos, kAtan, kAtan2,
  kSinh, kCosh, kTanh, kExp, kLog, kAbs,
};
// clang-format on

struct Op {
  Code code;
  std::int32_t dst, a, b;
};

bool is_unary(Code c) {
  return !(c == Code::kAdd || c == Code::kSub || c == Code::kMul || c == Code::kDiv ||
           c == Code::kPow || c == Code::kAtan2);
}
bool is_commutative(Code c) {
  return c == Code::kAdd || c == Code::kMul;
}

// executes one operation on the register file s
// clang-format off
inline void step(const Op& op, double* s) {
  switch (op.code) {
    case Code::kAdd: s[op.dst] = s[op.a] + s[op.b]; break;
    case Code::kSub: s[op.dst] = s[op.a] - s[op.b]; break;
    case Code::kMul: s[op.dst] = s[op.a] * s[op.b]; break;
    case Code::kDiv: s[op.dst] = s[op.a] / s[op.b]; break;
    case Code::kNeg: s[op.dst] = -s[op.a]; break;
    case Code::kRecip: s[op.dst] = 1.0 / s[op.a]; break;
    case Code::kSqrt: s[op.dst] = std::sqrt(s[op.a]); break;
    case Code::kPow: s[op.dst] = std::pow(s[op.a], s[op.b]); break;
    case Code::kSin: s[op.dst] = std::sin(s[op.a]); break;
    case Code::kCos: s[op.dst] = std::cos(s[op.a]); break;
    case Code::kSinCos: {
      // sin and cos of the same argument in one call (glibc's sincos)
      const double x = s[op.a];
      ::sincos(x, &s[op.dst], &s[op.b]);
      break;
    }
    case Code::kTan: s[op.dst] = std::tan(s[op.a]); break;
    case Code::kAsin: s[op.dst] = std::asin(s[op.a]); break;
    case Code::kAcos: s[op.dst] = std::acos(s[op.a]); break;
    case Code::kAtan: s[op.dst] = std::atan(s[op.a]); break;
    case Code::kAtan2: s[op.dst] = std::atan2(s[op.a], s[op.b]); break;
    case Code::kSinh: s[op.dst] = std::sinh(s[op.a]); break;
    case Code::kCosh: s[op.dst] = std::cosh(s[op.a]); break;
    case Code::kTanh: s[op.dst] = std::tanh(s[op.a]); break;
    case Code::kExp: s[op.dst] = std::exp(s[op.a]); break;
    case Code::kLog: s[op.dst] = std::log(s[op.a]); break;
    case Code::kAbs: s[op.dst] = std::fabs(s[op.a]); break;
  }
}
// clang-format on

// ---------------------------------------------------------------------------------------------
// the language's functions

struct FunctionInfo {
  const char* name;
  int arity;
  Code code;
};

constexpr std::array<FunctionInfo, 14> kFunctions{{
    {"sin", 1, Code::kSin},
    {"cos", 1, Code::kCos},
    {"tan", 1, Code::kTan},
    {"asin", 1, Code::kAsin},
    {"acos", 1, Code::kAcos},
    {"atan", 1, Code::kAtan},
    {"atan2", 2, Code::kAtan2},
    {"sinh", 1, Code::kSinh},
    {"cosh", 1, Code::kCosh},
    {"tanh", 1, Code::kTanh},
    {"exp", 1, Code::kExp},
    {"log", 1, Code::kLog},
    {"sqrt", 1, Code::kSqrt},
    {"abs", 1, Code::kAbs},
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
      return GiNaC::abs(a[0]);
    default:
      break;
  }
  UKDYN_CHECK(false, "expression: a language function without a GiNaC counterpart");
  return {};
}

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

std::vector<std::string> function_names() {
  std::vector<std::string> names;
  for (const auto& f : kFunctions) names.emplace_back(f.name);
  return names;
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
  Parser(const std::string& text, const std::map<std::string, GiNaC::ex>& names,
         const std::vector<std::string>& known)
      : text_(text), names_(names), known_(known) {
    next();
  }

  GiNaC::ex parse() {
    if (token_.kind == Kind::kEnd) fail("empty expression", token_.position);
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
      while (pos_ < text_.size() &&
             (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_')) {
        ++pos_;
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
    fail(std::string("unexpected character '") + c + "'", start);
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

  GiNaC::ex expression() {
    GiNaC::ex e = term();
    while (is("+") || is("-")) {
      const bool plus = is("+");
      const std::size_t at = token_.position;
      next();
      const GiNaC::ex rhs = term();
      e = build([&] { return plus ? e + rhs : e - rhs; }, at);
    }
    return e;
  }

  GiNaC::ex term() {
    GiNaC::ex e = unary();
    while (is("*") || is("/")) {
      const bool times = is("*");
      const std::size_t at = token_.position;
      next();
      const GiNaC::ex rhs = unary();
      e = build([&] { return times ? e * rhs : e / rhs; }, at);
    }
    return e;
  }

  // in_exponent: the operand right of a '^', which may not hold another '^' unparenthesized
  GiNaC::ex unary(bool in_exponent = false) {
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
    const GiNaC::ex base = primary();
    if (!is("^")) return base;
    if (in_exponent) fail("a^b^c is ambiguous: write (a^b)^c or a^(b^c)", token_.position);
    const std::size_t at = token_.position;
    next();
    const GiNaC::ex exponent = unary(true);
    return build([&] { return GiNaC::pow(base, exponent); }, at);
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
            fail("expected ')' to close the '(' at position " + std::to_string(t.position) +
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
      const long e = std::strtol(s.c_str() + i + 1, nullptr, 10);
      if (std::abs(e) > 400) fail("number '" + s + "' is out of range", t.position);
      exponent += e;
    }
    return decimal(digits, exponent);
  }

  GiNaC::ex name(const Token& t) const {
    const auto it = names_.find(t.text);
    if (it != names_.end()) return it->second;
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

  GiNaC::ex function_call(const Token& t) {
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
                   std::to_string(open) + "), got " + describe(token_),
               token_.position);
        }
        next();
      }
    }
    next();  // ')'
    if (int(args.size()) != f->arity) {
      fail(t.text + " takes " + std::to_string(f->arity) +
               (f->arity == 1 ? " argument" : " arguments") + ", got " +
               std::to_string(args.size()),
           t.position);
    }
    return build([&] { return call(*f, args); }, t.position);
  }

  const std::string& text_;
  const std::map<std::string, GiNaC::ex>& names_;
  const std::vector<std::string>& known_;
  std::size_t pos_ = 0;
  Token token_;
};

// ---------------------------------------------------------------------------------------------
// the compiler: GiNaC DAG → SSA tape (value numbering) → registers

using ExMemo =
    std::unordered_map<GiNaC::ex, std::int32_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

class Compiler {
 public:
  // values 0 … n_inputs−1 are the inputs; `inputs` maps their symbols to them
  Compiler(Index n_inputs, const std::vector<GiNaC::ex>& input_symbols)
      : n_inputs_(std::int32_t(n_inputs)), constant_of_(std::size_t(n_inputs)) {
    for (std::int32_t i = 0; i < n_inputs_; ++i) memo_.emplace(input_symbols[std::size_t(i)], i);
  }

  // the value of e (memoized on e: shared subtrees are compiled once)
  std::int32_t compile(const GiNaC::ex& e) {
    const auto hit = memo_.find(e);
    if (hit != memo_.end()) return hit->second;
    const std::int32_t v = compile_new(e);
    memo_.emplace(e, v);
    return v;
  }

  // the tape computing `outputs` (values) with registers reused once dead
  template <class Tape>
  void finish(const std::vector<std::int32_t>& outputs, Tape& tape) {
    fuse_sin_cos();
    const std::int32_t n_values = std::int32_t(constant_of_.size());

    // physical slots: inputs, then constants, then registers
    std::vector<std::int32_t> slot(std::size_t(n_values), -1);
    for (std::int32_t i = 0; i < n_inputs_; ++i) slot[std::size_t(i)] = i;
    for (std::int32_t v = 0; v < n_values; ++v) {
      if (const auto& c = constant_of_[std::size_t(v)]) {
        slot[std::size_t(v)] = n_inputs_ + std::int32_t(tape.constants.size());
        tape.constants.push_back(*c);
      }
    }
    const std::int32_t first_register = n_inputs_ + std::int32_t(tape.constants.size());

    // last reading op of each value (outputs live to the end)
    constexpr std::int32_t kForever = INT32_MAX;
    std::vector<std::int32_t> last_use(std::size_t(n_values), -1);
    for (std::int32_t k = 0; k < std::int32_t(ops_.size()); ++k) {
      const Op& op = ops_[std::size_t(k)];
      last_use[std::size_t(op.a)] = k;
      if (!is_unary(op.code)) last_use[std::size_t(op.b)] = k;
    }
    for (const std::int32_t v : outputs) last_use[std::size_t(v)] = kForever;

    // linear scan: an operand's register is free once its last reader has read it (the same op
    // may write it: every op reads its operands before it writes)
    std::vector<std::int32_t> free_registers;
    std::int32_t n_registers = 0;
    const auto release = [&](std::int32_t v, std::int32_t k) {
      if (v >= n_inputs_ && !constant_of_[std::size_t(v)] && last_use[std::size_t(v)] == k) {
        free_registers.push_back(slot[std::size_t(v)]);
        last_use[std::size_t(v)] = -2;  // released
      }
    };
    const auto assign = [&](std::int32_t v) {
      if (!free_registers.empty()) {
        slot[std::size_t(v)] = free_registers.back();
        free_registers.pop_back();
      } else {
        slot[std::size_t(v)] = first_register + n_registers++;
      }
    };
    tape.ops.reserve(ops_.size());
    for (std::int32_t k = 0; k < std::int32_t(ops_.size()); ++k) {
      const Op& op = ops_[std::size_t(k)];
      Op out = op;
      out.a = slot[std::size_t(op.a)];
      out.b = op.code == Code::kSinCos ? 0 : slot[std::size_t(op.b)];
      release(op.a, k);
      if (!is_unary(op.code)) release(op.b, k);
      assign(op.dst);
      out.dst = slot[std::size_t(op.dst)];
      if (op.code == Code::kSinCos) {
        assign(op.b);
        out.b = slot[std::size_t(op.b)];
        if (last_use[std::size_t(op.b)] == -1) release(op.b, -1);
      }
      if (last_use[std::size_t(op.dst)] == -1) release(op.dst, -1);  // never read
      tape.ops.push_back(out);
    }
    for (const std::int32_t v : outputs) tape.output_slots.push_back(slot[std::size_t(v)]);
    tape.scratch = Index(first_register) + n_registers;
  }

 private:
  std::int32_t compile_new(const GiNaC::ex& e) {
    using GiNaC::is_a;
    if (is_a<GiNaC::numeric>(e)) return constant(GiNaC::ex_to<GiNaC::numeric>(e));
    if (is_a<GiNaC::constant>(e)) return constant_of(GiNaC::evalf(e));
    if (is_a<GiNaC::add>(e)) return compile_add(e);
    if (is_a<GiNaC::mul>(e)) return compile_mul(e);
    if (is_a<GiNaC::power>(e)) return compile_power(e.op(0), e.op(1));
    if (is_a<GiNaC::function>(e)) {
      const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
      const FunctionInfo* f = find_function(name);
      if (f == nullptr || std::size_t(f->arity) != e.nops()) {
        throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: the function '" + name +
                                    "' (in " + printed(e) + ") cannot be compiled");
      }
      const std::int32_t a = compile(e.op(0));
      return f->arity == 2 ? emit(f->code, a, compile(e.op(1))) : emit(f->code, a);
    }
    if (is_a<GiNaC::symbol>(e)) {
      throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: '" + printed(e) +
                                  "' is neither an input nor a constant with a value");
    }
    throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: cannot compile " +
                                printed(e));
  }

  static std::string printed(const GiNaC::ex& e) {
    std::ostringstream os;
    os << e;
    return os.str();
  }

  // a constant value (deduplicated)
  std::int32_t constant(double value) {
    std::uint64_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    const auto hit = constants_.find(bits);
    if (hit != constants_.end()) return hit->second;
    const std::int32_t v = new_value();
    constant_of_[std::size_t(v)] = value;
    constants_.emplace(bits, v);
    return v;
  }
  std::int32_t constant(const GiNaC::numeric& n) {
    if (!n.is_real()) {
      throw std::invalid_argument(
          "ukdyn::expr::ExpressionSet::compile: the expression has the complex value " +
          printed(n) + " (e.g. sqrt or log of a negative number)");
    }
    return constant(n.to_double());
  }
  std::int32_t constant_of(const GiNaC::ex& e) {
    if (!GiNaC::is_a<GiNaC::numeric>(e)) {
      throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: cannot compile " +
                                  printed(e));
    }
    return constant(GiNaC::ex_to<GiNaC::numeric>(e));
  }

  std::int32_t new_value() {
    constant_of_.emplace_back();
    return std::int32_t(constant_of_.size() - 1);
  }
  bool is_constant(std::int32_t v, double value) const {
    return constant_of_[std::size_t(v)] && *constant_of_[std::size_t(v)] == value;
  }

  // the value code(a, b), folded when the operands are constant, shared when computed before
  std::int32_t emit(Code code, std::int32_t a, std::int32_t b = -1) {
    if (is_unary(code)) b = a;
    if (is_commutative(code) && b < a) std::swap(a, b);
    const auto& ca = constant_of_[std::size_t(a)];
    const auto& cb = constant_of_[std::size_t(b)];
    if (ca && cb) {
      double s[3] = {*ca, *cb, 0.0};
      step(Op{code, 2, 0, 1}, s);
      return constant(s[2]);
    }
    // x·1 = x, x + 0 = x, x − 0 = x, x / 1 = x
    if ((code == Code::kMul && is_constant(a, 1.0)) ||
        (code == Code::kAdd && is_constant(a, 0.0))) {
      return b;
    }
    if (((code == Code::kMul || code == Code::kDiv) && is_constant(b, 1.0)) ||
        ((code == Code::kAdd || code == Code::kSub) && is_constant(b, 0.0))) {
      return a;
    }
    const auto key = std::make_tuple(code, a, b);
    const auto hit = ops_memo_.find(key);
    if (hit != ops_memo_.end()) return hit->second;
    const std::int32_t v = new_value();
    ops_.push_back(Op{code, v, a, b});
    ops_memo_.emplace(key, v);
    return v;
  }

  // c·rest with the numeric factor c split off
  static std::pair<GiNaC::numeric, GiNaC::ex> split_coefficient(const GiNaC::ex& e) {
    if (GiNaC::is_a<GiNaC::numeric>(e)) return {GiNaC::ex_to<GiNaC::numeric>(e), 1};
    if (GiNaC::is_a<GiNaC::mul>(e)) {
      const GiNaC::ex last = e.op(e.nops() - 1);
      if (GiNaC::is_a<GiNaC::numeric>(last)) {
        const auto& c = GiNaC::ex_to<GiNaC::numeric>(last);
        return {c, e / c};
      }
    }
    return {1, e};
  }

  // Σ c_i·t_i: positive terms added, negative ones subtracted (no negations)
  std::int32_t compile_add(const GiNaC::ex& e) {
    std::vector<std::pair<bool, std::int32_t>> terms;  // (negative, |c_i|·t_i)
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const auto [c, rest] = split_coefficient(e.op(i));
      if (c.is_real() && c.is_negative()) {
        terms.emplace_back(true, scaled(-c, rest));
      } else {
        terms.emplace_back(false, scaled(c, rest));
      }
    }
    std::stable_partition(terms.begin(), terms.end(), [](const auto& t) { return !t.first; });
    std::int32_t sum = -1;
    for (const auto& [negative, v] : terms) {
      if (sum < 0) {
        sum = negative ? emit(Code::kNeg, v) : v;
      } else {
        sum = emit(negative ? Code::kSub : Code::kAdd, sum, v);
      }
    }
    return sum;
  }

  // c·rest
  std::int32_t scaled(const GiNaC::numeric& c, const GiNaC::ex& rest) {
    if (c.is_equal(1)) return compile(rest);
    if (rest.is_equal(1)) return constant(c);
    return emit(Code::kMul, constant(c), compile(rest));
  }

  // c · Π numerator factors / Π denominator factors (one division)
  std::int32_t compile_mul(const GiNaC::ex& e) {
    GiNaC::numeric c = 1;
    std::int32_t numerator = -1, denominator = -1;
    const auto times = [&](std::int32_t& product, std::int32_t v) {
      product = product < 0 ? v : emit(Code::kMul, product, v);
    };
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const GiNaC::ex f = e.op(i);
      if (GiNaC::is_a<GiNaC::numeric>(f)) {
        c *= GiNaC::ex_to<GiNaC::numeric>(f);
      } else if (GiNaC::is_a<GiNaC::power>(f) && GiNaC::is_a<GiNaC::numeric>(f.op(1)) &&
                 GiNaC::ex_to<GiNaC::numeric>(f.op(1)).is_real() &&
                 GiNaC::ex_to<GiNaC::numeric>(f.op(1)).is_negative()) {
        times(denominator, compile_power(f.op(0), -f.op(1)));
      } else {
        times(numerator, compile(f));
      }
    }
    const bool negative = c.is_real() && c.is_negative();
    if (negative) c = -c;
    if (!c.is_equal(1)) times(numerator, constant(c));
    std::int32_t r = numerator;
    if (denominator >= 0) {
      r = numerator >= 0 ? emit(Code::kDiv, numerator, denominator)
                         : emit(Code::kRecip, denominator);
    }
    if (r < 0) r = constant(1.0);
    return negative ? emit(Code::kNeg, r) : r;
  }

  // b^n for an integer n ≥ 1 by repeated squaring: b^2 = b·b (never pow)
  std::int32_t integer_power(std::int32_t b, long n) {
    if (n == 1) return b;
    if (n % 2 == 0) {
      const std::int32_t h = integer_power(b, n / 2);
      return emit(Code::kMul, h, h);
    }
    return emit(Code::kMul, integer_power(b, n - 1), b);
  }

  // base^exponent: integers by multiplication (negative: one division), halves with sqrt,
  // anything else with pow
  std::int32_t compile_power(const GiNaC::ex& base, const GiNaC::ex& exponent) {
    if (GiNaC::is_a<GiNaC::numeric>(exponent)) {
      const auto& p = GiNaC::ex_to<GiNaC::numeric>(exponent);
      constexpr long kLargest = 1L << 20;  // beyond this, pow is faster and as accurate
      if (p.is_rational() && GiNaC::abs(p.numer()).compare(GiNaC::numeric(kLargest)) <= 0 &&
          (p.denom().is_equal(1) || p.denom().is_equal(2))) {
        const long k = p.numer().to_long();
        if (k == 0) return constant(1.0);
        const std::int32_t b = compile(base);
        std::int32_t r;
        if (p.denom().is_equal(1)) {
          r = integer_power(b, std::labs(k));
        } else {
          // b^(k/2) = b^((|k|−1)/2) · sqrt(b)
          const std::int32_t root = emit(Code::kSqrt, b);
          const long m = (std::labs(k) - 1) / 2;
          r = m == 0 ? root : emit(Code::kMul, integer_power(b, m), root);
        }
        return k < 0 ? emit(Code::kRecip, r) : r;
      }
    }
    return emit(Code::kPow, compile(base), compile(exponent));
  }

  // sin(a) and cos(a) both needed: one sincos call computes both
  void fuse_sin_cos() {
    std::vector<bool> dropped(ops_.size(), false);
    std::map<std::int32_t, std::size_t> sin_at, cos_at;  // argument → op index
    for (std::size_t k = 0; k < ops_.size(); ++k) {
      if (ops_[k].code == Code::kSin) sin_at.emplace(ops_[k].a, k);
      if (ops_[k].code == Code::kCos) cos_at.emplace(ops_[k].a, k);
    }
    for (const auto& [a, ks] : sin_at) {
      const auto c = cos_at.find(a);
      if (c == cos_at.end()) continue;
      // the earlier op computes both: its results are defined before either is read
      const std::size_t kc = c->second, first = std::min(ks, kc);
      const std::int32_t s_value = ops_[ks].dst, c_value = ops_[kc].dst;
      ops_[first] = Op{Code::kSinCos, s_value, a, c_value};
      dropped[std::max(ks, kc)] = true;
    }
    std::size_t w = 0;
    for (std::size_t k = 0; k < ops_.size(); ++k) {
      if (!dropped[k]) ops_[w++] = ops_[k];
    }
    ops_.resize(w);
  }

  std::int32_t n_inputs_;
  std::vector<std::optional<double>> constant_of_;   // per value: its value if constant
  std::map<std::uint64_t, std::int32_t> constants_;  // bits of a constant → value
  std::vector<Op> ops_;                              // SSA: dst is a value
  std::map<std::tuple<Code, std::int32_t, std::int32_t>, std::int32_t> ops_memo_;
  ExMemo memo_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Program

struct Program::Tape {
  Index inputs = 0;
  std::vector<double> constants;           // copied to scratch[inputs …] on each evaluation
  std::vector<Op> ops;                     // in execution order, on physical slots
  std::vector<std::int32_t> output_slots;  // out[k] = scratch[output_slots[k]]
  Index scratch = 0;                       // inputs + constants + registers
};

Program::Program() = default;
Program::~Program() = default;
Program::Program(const Program&) = default;
Program& Program::operator=(const Program&) = default;
Program::Program(Program&&) noexcept = default;
Program& Program::operator=(Program&&) noexcept = default;

Index Program::inputs() const {
  return tape_ ? tape_->inputs : 0;
}
Index Program::outputs() const {
  return tape_ ? Index(tape_->output_slots.size()) : 0;
}
Index Program::scratch_size() const {
  return tape_ ? tape_->scratch : 0;
}
Index Program::operations() const {
  return tape_ ? Index(tape_->ops.size()) : 0;
}

void Program::evaluate(const double* in, double* out, double* scratch) const {
  if (!tape_) return;
  const Tape& t = *tape_;
  double* const s = scratch;
  // s = [in | constants | registers]
  std::copy_n(in, t.inputs, s);
  std::copy(t.constants.begin(), t.constants.end(), s + t.inputs);
  for (const Op& op : t.ops) step(op, s);
  const std::size_t n_out = t.output_slots.size();
  for (std::size_t k = 0; k < n_out; ++k) out[k] = s[t.output_slots[k]];
}

// ---------------------------------------------------------------------------------------------
// ExpressionSet

struct ExpressionSet::Impl {
  std::vector<std::string> input_names;
  std::vector<GiNaC::ex> input_symbols;      // realsymbols, in input order
  std::map<std::string, GiNaC::ex> symbols;  // inputs and constants by name
  std::vector<std::string> known;            // inputs then constants, in declaration order
  GiNaC::exmap constant_values;              // constant symbol → its exact value
  std::vector<GiNaC::ex> expressions;        // by handle

  Expr add(GiNaC::ex e) {
    expressions.push_back(std::move(e));
    return Expr(expressions.size() - 1);
  }

  const GiNaC::ex& at(Expr e, const char* who) const {
    if (e < 0 || std::size_t(e) >= expressions.size()) {
      throw std::invalid_argument(std::string("ukdyn::expr::ExpressionSet::") + who +
                                  ": no expression with handle " + std::to_string(e) +
                                  " (the set holds " + std::to_string(expressions.size()) +
                                  "; handles come from this set's parse(), constant(), …)");
    }
    return expressions[std::size_t(e)];
  }

  const GiNaC::ex& input(const std::string& name, const char* who) const {
    for (std::size_t i = 0; i < input_names.size(); ++i) {
      if (input_names[i] == name) return input_symbols[i];
    }
    throw std::invalid_argument(std::string("ukdyn::expr::ExpressionSet::") + who + ": '" + name +
                                "' is not an input (the inputs are " + listing(input_names) + ")");
  }

  // throws unless `name` can be declared
  void check_new_name(const std::string& name, const char* who) const {
    const std::string where = std::string("ukdyn::expr::ExpressionSet::") + who;
    if (!is_identifier(name)) {
      throw std::invalid_argument(where + ": '" + name +
                                  "' is not a name (a letter or '_', then letters, digits, '_')");
    }
    if (find_function(name) != nullptr) {
      throw std::invalid_argument(where + ": '" + name + "' is a function of the language");
    }
    if (symbols.count(name) != 0) {
      throw std::invalid_argument(where + ": '" + name + "' is already declared");
    }
  }

  void declare(const std::string& name, const char* who) {
    check_new_name(name, who);
    symbols.emplace(name, GiNaC::realsymbol(name));
    known.push_back(name);
  }
};

ExpressionSet::ExpressionSet(std::vector<std::string> input_names)
    : impl_(std::make_unique<Impl>()) {
  for (const auto& name : input_names) {
    impl_->declare(name, "ExpressionSet");
    impl_->input_symbols.push_back(impl_->symbols.at(name));
  }
  impl_->input_names = std::move(input_names);
}

ExpressionSet::~ExpressionSet() = default;
ExpressionSet::ExpressionSet(ExpressionSet&&) noexcept = default;
ExpressionSet& ExpressionSet::operator=(ExpressionSet&&) noexcept = default;

void ExpressionSet::set_constant(const std::string& name, double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument("ukdyn::expr::ExpressionSet::set_constant: the value of '" + name +
                                "' must be finite, got " + std::to_string(value));
  }
  impl_->declare(name, "set_constant");
  impl_->constant_values[impl_->symbols.at(name)] = exact(value);
}

Expr ExpressionSet::parse(const std::string& text) {
  return impl_->add(Parser(text, impl_->symbols, impl_->known).parse());
}

Expr ExpressionSet::constant(double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(
        "ukdyn::expr::ExpressionSet::constant: the value must be finite, "
        "got " +
        std::to_string(value));
  }
  return impl_->add(exact(value));
}

Expr ExpressionSet::add(Expr a, Expr b) {
  return impl_->add(impl_->at(a, "add") + impl_->at(b, "add"));
}
Expr ExpressionSet::subtract(Expr a, Expr b) {
  return impl_->add(impl_->at(a, "subtract") - impl_->at(b, "subtract"));
}
Expr ExpressionSet::multiply(Expr a, Expr b) {
  return impl_->add(impl_->at(a, "multiply") * impl_->at(b, "multiply"));
}
Expr ExpressionSet::negate(Expr a) {
  return impl_->add(-impl_->at(a, "negate"));
}

Expr ExpressionSet::diff(Expr e, const std::string& name) {
  const GiNaC::ex& x = impl_->input(name, "diff");
  // ∂e/∂x
  return impl_->add(impl_->at(e, "diff").diff(GiNaC::ex_to<GiNaC::symbol>(x)));
}

Expr ExpressionSet::total_derivative(
    const Expr e, const std::string& time,
    const std::vector<std::pair<std::string, std::string>>& chain) {
  const GiNaC::ex& f = impl_->at(e, "total_derivative");
  const GiNaC::ex& t = impl_->input(time, "total_derivative");
  // D e = ∂e/∂t + Σ ∂e/∂q_i · q̇_i   (no ∂e/∂q̇_i · q̈_i)
  GiNaC::ex d = f.diff(GiNaC::ex_to<GiNaC::symbol>(t));
  for (const auto& [q, qd] : chain) {
    const GiNaC::ex& qs = impl_->input(q, "total_derivative");
    const GiNaC::ex& qds = impl_->input(qd, "total_derivative");
    d += f.diff(GiNaC::ex_to<GiNaC::symbol>(qs)) * qds;
  }
  return impl_->add(d);
}

bool ExpressionSet::independent_of(Expr e, const std::string& name) const {
  const auto it = impl_->symbols.find(name);
  if (it == impl_->symbols.end()) {
    throw std::invalid_argument(
        "ukdyn::expr::ExpressionSet::independent_of: '" + name +
        "' is neither an input nor a constant (known names: " + listing(impl_->known) + ")");
  }
  return !impl_->at(e, "independent_of").has(it->second);
}

bool ExpressionSet::is_zero(Expr e) const {
  const GiNaC::ex x = impl_->at(e, "is_zero").expand();
  return x.is_zero() || GiNaC::normal(x).is_zero();
}

std::string ExpressionSet::to_string(Expr e) const {
  std::ostringstream os;
  os << impl_->at(e, "to_string");
  return os.str();
}

Program ExpressionSet::compile(const std::vector<Expr>& outputs) const {
  Compiler compiler(Index(impl_->input_names.size()), impl_->input_symbols);
  std::vector<std::int32_t> values;
  values.reserve(outputs.size());
  for (const Expr o : outputs) {
    // constants → their values, then the DAG → tape
    values.push_back(compiler.compile(impl_->at(o, "compile").subs(impl_->constant_values)));
  }
  auto tape = std::make_shared<Program::Tape>();
  tape->inputs = Index(impl_->input_names.size());
  compiler.finish(values, *tape);
  Program p;
  p.tape_ = std::move(tape);
  return p;
}

const std::vector<std::string>& ExpressionSet::input_names() const {
  return impl_->input_names;
}

}  // namespace ukdyn::expr
