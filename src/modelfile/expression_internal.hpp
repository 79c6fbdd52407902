// SPDX-License-Identifier: BSD-3-Clause
// Internal to the expression engine (modelfile/expression.hpp): what its parser
// (modelfile/expression_parse.cpp), its compiler and tape (modelfile/expression_compile.cpp) and
// ExpressionSet (modelfile/expression.cpp) share.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <ginac/ginac.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/expression.hpp"
#include "ukdyn/modelfile/table.hpp"

namespace ukdyn::expr {
namespace detail {

// ---------------------------------------------------------------------------------------------
// the tape

// One operation of the register machine: s[dst] = code(s[a], s[b]). Unary operations read a
// only (b = a). kSinCos writes two registers: s[dst] = sin s[a], s[b] = cos s[a]. The
// non-smooth functions: kSign (−1, 0, 1), kHeaviside (0, ½ at 0, 1), kMin, kMax; if(c, a, b)
// is compiled as kPickIf(c, a) + kPickElse(c, b), where kPickIf is s[b] when s[a] > 0 and 0
// otherwise, kPickElse the other way round: exactly a or b (a sum with an exact 0), and an
// infinite or NaN value of the branch not taken does not leak into the result.
// kIf is the language function (three arguments), never on a tape. kTable evaluates a table
// column: s[dst] = the tape's table call b (a column and a derivative order) at s[a]; its b is
// that call's index, not a register.
// clang-format off
enum class Code : std::uint8_t {
  kAdd, kSub, kMul, kDiv, kNeg, kRecip, kSqrt, kPow,
  kSin, kCos, kSinCos, kTan, kAsin, kAcos, kAtan, kAtan2,
  kSinh, kCosh, kTanh, kExp, kLog, kAbs,
  kSign, kHeaviside, kMin, kMax, kPickIf, kPickElse, kIf, kTable,
};
// clang-format on

struct Op {
  Code code;
  std::int32_t dst, a, b;
};

// a function of the language: its name, number of arguments and tape operation
struct FunctionInfo {
  const char* name;
  int arity;
  Code code;
};

// the function called `name`, or null (modelfile/expression_functions.cpp)
const FunctionInfo* find_function(const std::string& name);
// the names of the language's functions
std::vector<std::string> function_names();
// the GiNaC expression of a call of a language function (args: f.arity of them)
GiNaC::ex call(const FunctionInfo& f, const GiNaC::exvector& args);
// 1 − abs(sign(c)): 1 where c = 0, else 0 (NaN for a NaN c) — the condition of the tie branch
// in the derivative of a kink, if(c, da, if(kink_tie(c), minmod(da, db), db))
// (expression_parse.cpp, kink)
GiNaC::ex kink_tie(const GiNaC::ex& c);
// a letter or '_', then letters, digits, '_'
bool is_identifier(const std::string& s);
// "a, b, c" (at most 20, then "…")
std::string listing(const std::vector<std::string>& names);
// the shortest decimal that reads back as v, as an exact rational
GiNaC::numeric exact(double v);
// A table column's call `table.column(x)` is the GiNaC function table(c, d, p, x)
// (modelfile/expression_functions.cpp): c is the column's symbol (a realsymbol named
// "table.column", which is neither an input nor a constant), d the order of the derivative, p
// the degree of the interpolant's pieces; d table(c, d, p, x) = table(c, d + 1, p, x) dx, and 0
// once d + 1 > p.
struct TableCallee {
  GiNaC::ex symbol;  // c
  int degree = 0;    // p
};
using TableNames = std::map<std::string, TableCallee>;  // "table.column" → its callee
// the expression table(c, d, p, x)
GiNaC::ex table_call(const TableCallee& callee, int order, const GiNaC::ex& x);
// true when e is a call of a table column (then e.op(0) is c, e.op(1) d, e.op(3) x)
bool is_table_call(const GiNaC::ex& e);

// `text` parsed into GiNaC over `names` (known: the names in declaration order, for
// suggestions; values: the constants' values, which must leave every operation defined; tables:
// the table columns callable by name). Throws ParseError.
GiNaC::ex parse_expression(const std::string& text, const std::map<std::string, GiNaC::ex>& names,
                           const std::vector<std::string>& known, const GiNaC::exmap& values,
                           const TableNames& tables);

}  // namespace detail

namespace detail {
// a table column's derivative of some order, as a tape calls it (kTable)
struct TableCall {
  std::shared_ptr<const TableColumn> column;
  int order = 0;
  double operator()(double x) const { return column->evaluate_in_run(x, order); }
};
}  // namespace detail

struct Program::Tape {
  Index inputs = 0;  // of the set: the length of `in`
  // the inputs the program reads, increasing: scratch[i] = in[read[i]]; all of them (read
  // empty) when it reads every input (copied at once). A small program of a model with 10⁴
  // coordinates (a constraint between two) copies its two inputs, not 2·10⁴ + 1.
  std::vector<std::int32_t> read;
  Index slots_read = 0;                    // scratch slots of the inputs: read.size() or inputs
  std::vector<double> constants;           // copied to scratch[slots_read …] on each evaluation
  std::vector<detail::Op> ops;             // in execution order, on physical slots
  std::vector<std::int32_t> output_slots;  // out[k] = scratch[output_slots[k]]
  Index scratch = 0;                       // inputs read + constants + registers
  std::vector<detail::TableCall> tables;   // what the kTable ops call (by their b)
};

// input symbol → its index
using SymbolIndex =
    std::unordered_map<GiNaC::ex, std::size_t, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

struct ExpressionSet::Impl {
  std::vector<std::string> input_names;
  std::vector<GiNaC::ex> input_symbols;                      // realsymbols, in input order
  std::unordered_map<std::string, std::size_t> input_index;  // input name → its index
  // input symbol → its index (symbols hash and compare by serial number, not by name; a hash
  // table: looked up once per symbol of every expression traversed, never iterated)
  SymbolIndex symbol_index;
  std::map<std::string, GiNaC::ex> symbols;  // inputs and constants by name
  std::vector<std::string> known;            // inputs then constants, in declaration order
  GiNaC::exmap constant_values;              // constant symbol → its exact value
  std::vector<GiNaC::ex> expressions;        // by handle
  // the table columns (add_table_column): callable by name, and by their symbol (the compiler)
  detail::TableNames table_names;
  std::map<std::string, std::shared_ptr<const TableColumn>> table_columns;
  // of the long sums differentiated so far (by handle): input index → the terms that hold it
  std::unordered_map<Expr, std::unordered_map<std::size_t, std::vector<std::size_t>>> terms_holding;

  // the last chain of total_derivative: where the caller keeps it (a model passes the same
  // vector for all its expressions: recognised by its address and length, and the entries the
  // expression uses checked, in O(inputs of the expression) rather than O(chain)), by names and
  // by input indices
  const void* chain_address = nullptr;
  std::vector<std::pair<std::string, std::string>> chain_names;
  std::vector<std::pair<std::size_t, std::size_t>> chain_indices;
  // input index → its entry's position in that chain, or −1 (with velocity_of)
  std::vector<std::ptrdiff_t> chain_position_of;
  // input index → the index of its velocity in that chain, or −1; empty when a coordinate is
  // listed twice
  std::vector<std::ptrdiff_t> velocity_of;

  // ∂f/∂(input i) where f is the expression of handle e (modelfile/expression.cpp)
  GiNaC::ex derivative(Expr e, const GiNaC::ex& f, std::size_t i);
  // `chain` is the chain resolved last, as far as an expression holding `in_e` reads it
  // (modelfile/expression.cpp)
  bool same_chain(const std::vector<std::pair<std::string, std::string>>& chain,
                  const std::vector<Index>& in_e) const;

  Expr add(GiNaC::ex e) {
    expressions.push_back(std::move(e));
    return Expr(expressions.size() - 1);
  }

  const GiNaC::ex& at(Expr e, const char* who) const {
    if (e < 0 || std::size_t(e) >= expressions.size()) {
      throw std::invalid_argument(std::string("ukdyn::expr::ExpressionSet::") + who +
                                  ": no expression with handle " + format_number(e) +
                                  " (the set holds " + format_number(expressions.size()) +
                                  "; handles come from this set's parse(), constant(), …)");
    }
    return expressions[std::size_t(e)];
  }

  const GiNaC::ex& input(const std::string& name, const char* who) const {
    if (const auto it = input_index.find(name); it != input_index.end())
      return input_symbols[it->second];
    throw std::invalid_argument(std::string("ukdyn::expr::ExpressionSet::") + who + ": '" + name +
                                "' is not an input (the inputs are " +
                                detail::listing(input_names) + ")");
  }

  // throws unless `name` can be declared
  // (the message's prefix is built only on failure: a model of 10⁵ coordinates declares 2·10⁵
  // names)
  void check_new_name(const std::string& name, const char* who) const {
    const auto where = [who] { return std::string("ukdyn::expr::ExpressionSet::") + who; };
    if (!detail::is_identifier(name)) {
      throw std::invalid_argument(where() + ": '" + name +
                                  "' is not a name (a letter or '_', then letters, digits, '_')");
    }
    if (detail::find_function(name) != nullptr) {
      throw std::invalid_argument(where() + ": '" + name + "' is a function of the language");
    }
    if (symbols.count(name) != 0) {
      throw std::invalid_argument(where() + ": '" + name + "' is already declared");
    }
  }

  // declares `name` (throws unless it can be), returns its symbol
  const GiNaC::ex& declare(const std::string& name, const char* who) {
    check_new_name(name, who);
    const GiNaC::ex& symbol = symbols.emplace(name, GiNaC::realsymbol(name)).first->second;
    known.push_back(name);
    return symbol;
  }
};

}  // namespace ukdyn::expr
