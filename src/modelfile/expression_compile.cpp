// SPDX-License-Identifier: BSD-3-Clause
// The model language's compiler: a GiNaC expression DAG → a flat register tape with
// common-subexpression elimination, and its evaluation (Program) — see modelfile/expression.hpp.

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
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <ginac/ginac.h>

#include "modelfile/expression_internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn::expr {

namespace {
using namespace detail;

// (kTable reads a only: its b is the index of a table call)
bool is_unary(Code c) {
  return !(c == Code::kAdd || c == Code::kSub || c == Code::kMul || c == Code::kDiv ||
           c == Code::kPow || c == Code::kAtan2 || c == Code::kMin || c == Code::kMax ||
           c == Code::kPickIf || c == Code::kPickElse);
}
bool is_commutative(Code c) { return c == Code::kAdd || c == Code::kMul; }

// executes one operation on the register file s (`tables`: the tape's table calls)
// clang-format off
inline void step(const Op& op, double* s, const TableCall* tables) {
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
    case Code::kSign: s[op.dst] = s[op.a] > 0.0 ? 1.0 : s[op.a] < 0.0 ? -1.0 : s[op.a]; break;
    case Code::kHeaviside: s[op.dst] = s[op.a] > 0.0 ? 1.0 : s[op.a] < 0.0 ? 0.0 : s[op.a] == 0.0 ? 0.5 : s[op.a]; break;
    case Code::kMin: s[op.dst] = s[op.b] < s[op.a] ? s[op.b] : s[op.a]; break;
    case Code::kMax: s[op.dst] = s[op.b] > s[op.a] ? s[op.b] : s[op.a]; break;
    case Code::kPickIf: s[op.dst] = s[op.a] > 0.0 ? s[op.b] : 0.0; break;
    case Code::kPickElse: s[op.dst] = s[op.a] > 0.0 ? 0.0 : s[op.b]; break;
    case Code::kIf: break;  // compiled as kPickIf + kPickElse
    case Code::kTable: if (tables != nullptr) s[op.dst] = tables[op.b](s[op.a]); break;  // (never folded)
  }
}
// clang-format on

// ---------------------------------------------------------------------------------------------
// the compiler: GiNaC DAG → SSA tape (value numbering) → registers

using ExMemo =
    std::unordered_map<GiNaC::ex, std::int32_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

class Compiler {
 public:
  // `inputs` maps the inputs' symbols to their indices (0 … n_inputs−1); an input becomes a
  // value when the expression first holds it, so that compiling costs O(the expression), not
  // O(n_inputs): a model with 10⁵ coordinates compiles 10⁵ one-input programs
  // `tables`: the set's table columns by name (table.column)
  Compiler(Index n_inputs, const SymbolIndex& inputs,
           const std::map<std::string, std::shared_ptr<const TableColumn>>& tables)
      : n_inputs_(std::int32_t(n_inputs)), inputs_(inputs), tables_(tables) {}

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

    // physical slots: the inputs read (all of them, or those the ops and outputs read), in the
    // order of their indices, then constants, then registers
    std::vector<char> is_read(std::size_t(n_values), 0);
    const auto mark = [&](std::int32_t v) {
      if (v >= 0 && input_of_[std::size_t(v)] >= 0) is_read[std::size_t(v)] = 1;
    };
    for (const Op& op : ops_) {
      mark(op.a);
      if (!is_unary(op.code)) mark(op.b);
    }
    for (const std::int32_t v : outputs) mark(v);
    std::vector<std::pair<std::int32_t, std::int32_t>> read;  // (input index, value)
    for (std::int32_t v = 0; v < n_values; ++v)
      if (is_read[std::size_t(v)]) read.emplace_back(input_of_[std::size_t(v)], v);
    std::sort(read.begin(), read.end());
    std::vector<std::int32_t> slot(std::size_t(n_values), -1);
    std::int32_t slots_read = 0;
    for (const auto& [i, v] : read) {
      slot[std::size_t(v)] = slots_read++;
      tape.read.push_back(i);
    }
    if (slots_read == n_inputs_) tape.read.clear();  // every input: copied at once
    tape.slots_read = slots_read;
    for (std::int32_t v = 0; v < n_values; ++v) {
      if (const auto& c = constant_of_[std::size_t(v)]) {
        slot[std::size_t(v)] = slots_read + std::int32_t(tape.constants.size());
        tape.constants.push_back(*c);
      }
    }
    const std::int32_t first_register = slots_read + std::int32_t(tape.constants.size());

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
      if (input_of_[std::size_t(v)] < 0 && !constant_of_[std::size_t(v)] &&
          last_use[std::size_t(v)] == k) {
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
      out.b = op.code == Code::kSinCos  ? 0
              : op.code == Code::kTable ? op.b
                                        : slot[std::size_t(op.b)];
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
    tape.tables = table_calls_;
  }

 private:
  std::int32_t compile_new(const GiNaC::ex& e) {
    using GiNaC::is_a;
    if (is_a<GiNaC::numeric>(e)) return constant(GiNaC::ex_to<GiNaC::numeric>(e));
    if (is_a<GiNaC::symbol>(e)) {
      if (const auto it = inputs_.find(e); it != inputs_.end()) {
        // (memoized by compile(): one value per input)
        const std::int32_t v = new_value();
        input_of_[std::size_t(v)] = std::int32_t(it->second);
        return v;
      }
    }
    if (is_a<GiNaC::constant>(e)) return constant_of(GiNaC::evalf(e));
    if (is_a<GiNaC::add>(e)) return compile_add(e);
    if (is_a<GiNaC::mul>(e)) return compile_mul(e);
    if (is_a<GiNaC::power>(e)) return compile_power(e.op(0), e.op(1));
    if (is_table_call(e)) return compile_table(e);
    if (is_a<GiNaC::function>(e)) {
      const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
      // (the language's abs is registered with GiNaC as lang_abs: expression_parse.cpp)
      const FunctionInfo* f = find_function(name == "lang_abs" ? "abs" : name);
      if (f == nullptr || std::size_t(f->arity) != e.nops()) {
        throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: the function '" + name +
                                    "' (in " + printed(e) + ") cannot be compiled");
      }
      const std::int32_t a = compile(e.op(0));
      if (f->code == Code::kIf) {
        // if(c, a, b) = (c > 0 ? a : 0) + (c > 0 ? 0 : b): exactly a or b
        return emit(Code::kAdd, emit(Code::kPickIf, a, compile(e.op(1))),
                    emit(Code::kPickElse, a, compile(e.op(2))));
      }
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

  // table(c, d, p, x): a kTable op calling the column c's derivative d (each call once on the
  // tape's list), folded when x is constant (then a range error is a compile error)
  std::int32_t compile_table(const GiNaC::ex& e) {
    const std::string& name = GiNaC::ex_to<GiNaC::symbol>(e.op(0)).get_name();
    const auto column = tables_.find(name);
    if (column == tables_.end()) {
      throw std::invalid_argument("ukdyn::expr::ExpressionSet::compile: the table column '" + name +
                                  "' is not of this set");
    }
    const TableCall call{column->second, GiNaC::ex_to<GiNaC::numeric>(e.op(1)).to_int()};
    const std::int32_t x = compile(e.op(3));
    if (const auto& cx = constant_of_[std::size_t(x)]) {
      try {
        return constant(call.column->evaluate(*cx, call.order));
      } catch (const TableRangeError& error) {
        throw std::invalid_argument(std::string("ukdyn::expr::ExpressionSet::compile: ") +
                                    error.what());
      }
    }
    std::int32_t index = -1;
    for (std::size_t k = 0; k < table_calls_.size(); ++k) {
      if (table_calls_[k].column == call.column && table_calls_[k].order == call.order)
        index = std::int32_t(k);
    }
    if (index < 0) {
      index = std::int32_t(table_calls_.size());
      table_calls_.push_back(call);
    }
    const auto key = std::make_tuple(Code::kTable, x, index);
    const auto hit = ops_memo_.find(key);
    if (hit != ops_memo_.end()) return hit->second;
    const std::int32_t v = new_value();
    ops_.push_back(Op{Code::kTable, v, x, index});
    ops_memo_.emplace(key, v);
    return v;
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
    input_of_.push_back(-1);
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
      step(Op{code, 2, 0, 1}, s, nullptr);
      // a constant part the evaluation would compute as NaN or Inf (the parser refuses those it
      // sees where they are written; this catches what only the rounding to double makes so)
      if (!std::isfinite(s[2])) {
        throw std::invalid_argument(
            "ukdyn::expr::ExpressionSet::compile: a constant part of the expression is not a "
            "finite number in double precision (" +
            format_number(s[0]) + (is_unary(code) ? "" : ", " + format_number(s[1])) + " give " +
            format_number(s[2]) + ")");
      }
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

  // A structural key of e that is the same in every process, and the same for e and −e.
  // GiNaC orders the operands of sums and products by hashes that depend on addresses (they
  // change with ASLR from run to run), and picks the sign of a sum by that order too ((x1 − x2)²
  // in one run is (x2 − x1)² in the next). The compiler visits operands in the order of this
  // key instead, so a model evaluates to the same bits in every run: terms that flip sign
  // between runs keep their place, and a flipped value is an exact negation of the other.
  std::uint64_t key(const GiNaC::ex& e) {
    const auto hit = keys_.find(e);
    if (hit != keys_.end()) return hit->second;
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over bytes and operand keys
    const auto mix_bytes = [&h](std::string_view bytes) {
      for (const char c : bytes) {
        h ^= std::uint8_t(c);
        h *= 1099511628211ull;
      }
    };
    const auto mix = [&h](std::uint64_t k) {
      for (int i = 0; i < 8; ++i) {
        h ^= (k >> (8 * i)) & 0xffu;
        h *= 1099511628211ull;
      }
    };
    using GiNaC::is_a;
    if (is_a<GiNaC::numeric>(e)) {
      mix_bytes("n");
      mix_bytes(printed(GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(e))));
    } else if (is_a<GiNaC::symbol>(e)) {
      mix_bytes("s");
      mix_bytes(GiNaC::ex_to<GiNaC::symbol>(e).get_name());
    } else if (is_a<GiNaC::add>(e) || is_a<GiNaC::mul>(e)) {
      // commutative: the operands' keys in sorted order; a product's sign is left out, and
      // ±1·f is f
      const bool product = is_a<GiNaC::mul>(e);
      std::vector<std::uint64_t> ks;
      ks.reserve(e.nops());
      for (std::size_t i = 0; i < e.nops(); ++i) {
        const GiNaC::ex f = e.op(i);
        if (product && is_a<GiNaC::numeric>(f) &&
            GiNaC::abs(GiNaC::ex_to<GiNaC::numeric>(f)).is_equal(1))
          continue;
        ks.push_back(key(f));
      }
      if (product && ks.size() == 1) {
        h = ks.front();
      } else {
        mix_bytes(product ? "*" : "+");
        std::sort(ks.begin(), ks.end());
        for (const std::uint64_t k : ks) mix(k);
      }
    } else if (is_a<GiNaC::function>(e)) {
      mix_bytes("f");
      const std::string name = GiNaC::ex_to<GiNaC::function>(e).get_name();
      mix_bytes(name == "lang_abs" ? std::string("abs") : name);
      for (std::size_t i = 0; i < e.nops(); ++i) mix(key(e.op(i)));
    } else if (is_a<GiNaC::power>(e)) {
      mix_bytes("^");
      mix(key(e.op(0)));
      mix(key(e.op(1)));
    } else {
      // constants (pi) and anything else: as printed
      mix_bytes(GiNaC::ex_to<GiNaC::basic>(e).class_name());
      mix_bytes(printed(e));
    }
    keys_.emplace(e, h);
    return h;
  }

  // the operands of a sum or a product in the order of their keys
  std::vector<GiNaC::ex> ordered_operands(const GiNaC::ex& e) {
    std::vector<std::pair<std::uint64_t, GiNaC::ex>> ops;
    ops.reserve(e.nops());
    for (std::size_t i = 0; i < e.nops(); ++i) ops.emplace_back(key(e.op(i)), e.op(i));
    std::stable_sort(ops.begin(), ops.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<GiNaC::ex> out;
    out.reserve(ops.size());
    for (auto& o : ops) out.push_back(std::move(o.second));
    return out;
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

  // Σ c_i·t_i: positive terms added, negative ones subtracted (a negation only when the first
  // term in key order is negative)
  std::int32_t compile_add(const GiNaC::ex& e) {
    std::vector<std::pair<bool, std::int32_t>> terms;  // (negative, |c_i|·t_i)
    for (const GiNaC::ex& term : ordered_operands(e)) {
      const auto [c, rest] = split_coefficient(term);
      if (c.is_real() && c.is_negative()) {
        terms.emplace_back(true, scaled(-c, rest));
      } else {
        terms.emplace_back(false, scaled(c, rest));
      }
    }
    // (in key order, whatever the signs: a sum whose terms flip sign between runs is then an
    // exact negation, not a reassociation)
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
    for (const GiNaC::ex& f : ordered_operands(e)) {
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
  const SymbolIndex& inputs_;
  const std::map<std::string, std::shared_ptr<const TableColumn>>& tables_;
  std::vector<TableCall> table_calls_;               // the tape's (kTable's b)
  std::vector<std::optional<double>> constant_of_;   // per value: its value if constant
  std::vector<std::int32_t> input_of_;               // per value: its input's index, or −1
  std::map<std::uint64_t, std::int32_t> constants_;  // bits of a constant → value
  std::vector<Op> ops_;                              // SSA: dst is a value
  // (code, a, b) → the value computing it (looked up, never iterated: a hash table)
  struct OpKeyHash {
    std::size_t operator()(const std::tuple<Code, std::int32_t, std::int32_t>& k) const {
      const auto [c, a, b] = k;
      return std::hash<std::uint64_t>()((std::uint64_t(std::uint32_t(a)) << 32 | std::uint32_t(b)) *
                                            0x9e3779b97f4a7c15ull ^
                                        std::uint64_t(c));
    }
  };
  std::unordered_map<std::tuple<Code, std::int32_t, std::int32_t>, std::int32_t, OpKeyHash>
      ops_memo_;
  ExMemo memo_;
  std::unordered_map<GiNaC::ex, std::uint64_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> keys_;
};

}  // namespace

Program::Program() = default;
Program::~Program() = default;
Program::Program(const Program&) = default;
Program& Program::operator=(const Program&) = default;
Program::Program(Program&&) noexcept = default;
Program& Program::operator=(Program&&) noexcept = default;

Index Program::inputs() const { return tape_ ? tape_->inputs : 0; }
Index Program::outputs() const { return tape_ ? Index(tape_->output_slots.size()) : 0; }
Index Program::scratch_size() const { return tape_ ? tape_->scratch : 0; }
Index Program::operations() const { return tape_ ? Index(tape_->ops.size()) : 0; }

void Program::evaluate(const double* in, double* out, double* scratch) const {
  if (!tape_) return;
  const Tape& t = *tape_;
  double* const s = scratch;
  // s = [inputs read | constants | registers]
  if (t.read.empty()) {
    std::copy_n(in, t.slots_read, s);
  } else {
    for (std::size_t i = 0; i < t.read.size(); ++i) s[i] = in[t.read[i]];
  }
  std::copy(t.constants.begin(), t.constants.end(), s + t.slots_read);
  const TableCall* const tables = t.tables.data();
  for (const Op& op : t.ops) step(op, s, tables);
  const std::size_t n_out = t.output_slots.size();
  for (std::size_t k = 0; k < n_out; ++k) out[k] = s[t.output_slots[k]];
}

// Every value the compiler makes for a part of e that holds an input is not a constant (by
// induction: emit folds only two constants, and its shortcuts x·1, x + 0 return the operand that
// is not); so when every part that is not a number holds an input, constants meet only numbers
// that are real and finite (Compiler::constant cannot fail) and nothing is folded — except the
// negation of a negative number term (finite again). Constants' symbols are excluded (they are
// not inputs), so compile's substitution leaves e as it is.
bool ExpressionSet::compile_cannot_fail(Expr e) const {
  // (node, visited): a node is pushed before its operands, and judged after them
  struct Open {
    GiNaC::ex x;
    bool expanded;
  };
  std::vector<Open> stack{{impl_->at(e, "compile_cannot_fail"), false}};
  std::vector<char> holds;  // per operand judged and not yet taken: holds an input
  while (!stack.empty()) {
    Open& top = stack.back();
    const GiNaC::ex& x = top.x;
    // (the classes by their exact type, cheaper than is_a's dynamic_cast; symbols last: the
    // inputs are realsymbols, a class derived from symbol)
    if (GiNaC::is_exactly_a<GiNaC::numeric>(x)) {
      const GiNaC::numeric& n = GiNaC::ex_to<GiNaC::numeric>(x);
      if (!n.is_real() || !std::isfinite(n.to_double())) return false;
      holds.push_back(0);
      stack.pop_back();
      continue;
    }
    const bool sum_product_power = GiNaC::is_exactly_a<GiNaC::add>(x) ||
                                   GiNaC::is_exactly_a<GiNaC::mul>(x) ||
                                   GiNaC::is_exactly_a<GiNaC::power>(x);
    if (!sum_product_power && GiNaC::is_a<GiNaC::symbol>(x)) {
      if (impl_->symbol_index.find(x) == impl_->symbol_index.end()) return false;
      holds.push_back(1);
      stack.pop_back();
      continue;
    }
    const std::size_t n_ops = x.nops();
    if (!top.expanded) {
      if (sum_product_power) {
        // operands below
      } else if (GiNaC::is_a<GiNaC::function>(x)) {
        // a function the compiler knows, with its number of arguments (Compiler::compile_new)
        const std::string name = GiNaC::ex_to<GiNaC::function>(x).get_name();
        const detail::FunctionInfo* f = detail::find_function(name == "lang_abs" ? "abs" : name);
        if (f == nullptr || std::size_t(f->arity) != n_ops) return false;
      } else {
        return false;  // a constant such as pi, or anything else: compile to know
      }
      top.expanded = true;
      const GiNaC::ex copy = x;  // (the stack grows: top is not valid after a push)
      for (std::size_t k = n_ops; k-- > 0;) stack.push_back({copy.op(k), false});
      continue;
    }
    // its operands are judged: it holds an input when one of them does
    bool any = false;
    for (std::size_t k = 0; k < n_ops; ++k) any = any || holds[holds.size() - 1 - k] != 0;
    if (!any) return false;  // a constant part that is not a number
    holds.resize(holds.size() - n_ops);
    holds.push_back(1);
    stack.pop_back();
  }
  return holds.size() == 1 && holds.front() != 0;
}

Program ExpressionSet::compile(const std::vector<Expr>& outputs) const {
  Compiler compiler(Index(impl_->input_names.size()), impl_->symbol_index, impl_->table_columns);
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

}  // namespace ukdyn::expr
