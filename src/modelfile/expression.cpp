// SPDX-License-Identifier: BSD-3-Clause
// ExpressionSet: the symbolic expressions of a model (see modelfile/expression.hpp); parsing is in
// modelfile/expression_parse.cpp, compilation in modelfile/expression_compile.cpp.

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

#include "modelfile/expression_internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn::expr {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// ExpressionSet

ExpressionSet::ExpressionSet(std::vector<std::string> input_names)
    : impl_(std::make_unique<Impl>()) {
  impl_->input_symbols.reserve(input_names.size());
  impl_->input_index.reserve(input_names.size());
  impl_->known.reserve(input_names.size());
  impl_->symbol_index.reserve(input_names.size());
  for (const auto& name : input_names) {
    impl_->input_symbols.push_back(impl_->declare(name, "ExpressionSet"));
    impl_->input_index.emplace(name, impl_->input_symbols.size() - 1);
    impl_->symbol_index.emplace_hint(impl_->symbol_index.end(), impl_->input_symbols.back(),
                                     impl_->input_symbols.size() - 1);
  }
  impl_->input_names = std::move(input_names);
}

ExpressionSet::~ExpressionSet() = default;
ExpressionSet::ExpressionSet(ExpressionSet&&) noexcept = default;
ExpressionSet& ExpressionSet::operator=(ExpressionSet&&) noexcept = default;

void ExpressionSet::set_constant(const std::string& name, double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument("ukdyn::expr::ExpressionSet::set_constant: the value of '" + name +
                                "' must be finite, got " + format_number(value));
  }
  impl_->declare(name, "set_constant");
  impl_->constant_values[impl_->symbols.at(name)] = exact(value);
}

Expr ExpressionSet::parse(const std::string& text) {
  return impl_->add(parse_expression(text, impl_->symbols, impl_->known, impl_->constant_values,
                                     impl_->table_names));
}

void ExpressionSet::add_table_column(const std::string& name,
                                     std::shared_ptr<const TableColumn> column) {
  const std::string where = "ukdyn::expr::ExpressionSet::add_table_column: ";
  const std::size_t dot = name.find('.');
  if (dot == std::string::npos || !is_identifier(name.substr(0, dot)) ||
      !is_identifier(name.substr(dot + 1))) {
    throw std::invalid_argument(where + "'" + name +
                                "' is not a table column's name (table.column, two names)");
  }
  if (column == nullptr) throw std::invalid_argument(where + "no column for '" + name + "'");
  if (impl_->table_names.count(name) != 0) {
    throw std::invalid_argument(where + "'" + name + "' is already declared");
  }
  impl_->table_names.emplace(name, TableCallee{GiNaC::realsymbol(name), column->degree()});
  impl_->table_columns.emplace(name, std::move(column));
}

Expr ExpressionSet::constant(double value) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(
        "ukdyn::expr::ExpressionSet::constant: the value must be finite, "
        "got " +
        format_number(value));
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
Expr ExpressionSet::negate(Expr a) { return impl_->add(-impl_->at(a, "negate")); }

namespace {

// the indices of the inputs (by symbol_index) that x holds, ascending, each once
std::vector<std::size_t> gather_inputs(const GiNaC::ex& x, const SymbolIndex& symbol_index) {
  std::vector<std::size_t> found;
  std::vector<GiNaC::ex> stack{x};
  while (!stack.empty()) {
    const GiNaC::ex y = std::move(stack.back());
    stack.pop_back();
    if (GiNaC::is_a<GiNaC::symbol>(y)) {
      const auto it = symbol_index.find(y);
      if (it != symbol_index.end()) found.push_back(it->second);
      continue;
    }
    for (std::size_t k = y.nops(); k-- > 0;) stack.push_back(y.op(k));
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  return found;
}

}  // namespace

// ∂f/∂(input i), f the expression of handle e. A long sum is differentiated through the terms
// that hold the input only (found once per sum): GiNaC differentiates a sum term by term and
// drops the terms whose derivative is 0, so the sum of the other terms differentiates to the
// same expression — in O(terms holding it) rather than O(terms).
GiNaC::ex ExpressionSet::Impl::derivative(Expr e, const GiNaC::ex& f, std::size_t i) {
  const GiNaC::symbol& x = GiNaC::ex_to<GiNaC::symbol>(input_symbols[i]);
  constexpr std::size_t kLongSum = 16;
  if (!GiNaC::is_exactly_a<GiNaC::add>(f) || f.nops() < kLongSum) return f.diff(x);
  auto it = terms_holding.find(e);
  if (it == terms_holding.end()) {
    std::unordered_map<std::size_t, std::vector<std::size_t>> index;
    for (std::size_t k = 0; k < f.nops(); ++k) {
      for (const std::size_t input : gather_inputs(f.op(k), symbol_index))
        index[input].push_back(k);
    }
    it = terms_holding.emplace(e, std::move(index)).first;
  }
  const auto terms = it->second.find(i);
  if (terms == it->second.end()) return GiNaC::ex(0);
  GiNaC::exvector v;
  v.reserve(terms->second.size());
  for (const std::size_t k : terms->second) v.push_back(f.op(k));
  // the sum of those terms as built, not evaluated (one term stays a sum of one term)
  GiNaC::add& sum = GiNaC::dynallocate<GiNaC::add>(v);
  const GiNaC::ptr<GiNaC::basic> keep(sum);  // freed on return
  return sum.diff(x);
}

Expr ExpressionSet::diff(Expr e, const std::string& name) {
  impl_->input(name, "diff");  // throws unless an input
  // ∂e/∂x
  const GiNaC::ex& f = impl_->at(e, "diff");
  return impl_->add(impl_->derivative(e, f, impl_->input_index.at(name)));
}

// the chain total_derivative resolved last: at the same address, of the same length, with the
// same entries for the inputs `in_e` holds (the only entries an expression's derivative reads);
// a chain with a coordinate listed twice is compared whole
bool ExpressionSet::Impl::same_chain(const std::vector<std::pair<std::string, std::string>>& chain,
                                     const std::vector<Index>& in_e) const {
  if (&chain != chain_address || chain.size() != chain_names.size()) return false;
  if (velocity_of.empty()) return chain == chain_names;
  for (const Index k : in_e) {
    const std::ptrdiff_t at = chain_position_of[std::size_t(k)];
    if (at >= 0 && chain[std::size_t(at)] != chain_names[std::size_t(at)]) return false;
  }
  return true;
}

Expr ExpressionSet::total_derivative(
    const Expr e, const std::string& time,
    const std::vector<std::pair<std::string, std::string>>& chain) {
  const GiNaC::ex& f = impl_->at(e, "total_derivative");
  const GiNaC::ex& t = impl_->input(time, "total_derivative");
  // D e = ∂e/∂t + Σ ∂e/∂q_i · q̇_i   (no ∂e/∂q̇_i · q̈_i), summed at once; the terms of the
  // q_i that e does not hold are 0 and left out (the same sum)
  // the chain by input indices, looked up once while the same chain comes back (a model passes
  // one chain for all its expressions: the same vector, its entries for the inputs e holds
  // unchanged; comparing the whole chain on every call was O(n) a call, O(n²) a model)
  const std::vector<Index> in_e = inputs_of(e);
  if (!impl_->same_chain(chain, in_e)) {
    std::vector<std::pair<std::size_t, std::size_t>> resolved;
    for (const auto& [q, qd] : chain) {
      impl_->input(q, "total_derivative");  // throws unless an input
      impl_->input(qd, "total_derivative");
      resolved.emplace_back(impl_->input_index.at(q), impl_->input_index.at(qd));
    }
    impl_->chain_address = &chain;
    impl_->chain_names = chain;
    impl_->velocity_of.assign(impl_->input_symbols.size(), -1);
    impl_->chain_position_of.assign(impl_->input_symbols.size(), -1);
    for (std::size_t k = 0; k < resolved.size(); ++k) {
      const auto [qi, qdi] = resolved[k];
      // a coordinate listed twice counts twice, as the sum over the chain does
      if (impl_->velocity_of[qi] >= 0) {
        impl_->velocity_of.clear();
        break;
      }
      impl_->velocity_of[qi] = std::ptrdiff_t(qdi);
      impl_->chain_position_of[qi] = std::ptrdiff_t(k);
    }
    impl_->chain_indices = std::move(resolved);
  }
  GiNaC::exvector d{f.diff(GiNaC::ex_to<GiNaC::symbol>(t))};
  if (!impl_->velocity_of.empty() || impl_->chain_indices.empty()) {
    // through the inputs e holds
    for (const Index k : in_e) {
      if (const std::ptrdiff_t qdi =
              impl_->velocity_of.empty() ? -1 : impl_->velocity_of[std::size_t(k)];
          qdi >= 0)
        d.push_back(impl_->derivative(e, f, std::size_t(k)) *
                    impl_->input_symbols[std::size_t(qdi)]);
    }
  } else {
    for (const auto& [qi, qdi] : impl_->chain_indices) {
      if (!std::binary_search(in_e.begin(), in_e.end(), Index(qi))) continue;
      d.push_back(impl_->derivative(e, f, qi) * impl_->input_symbols[qdi]);
    }
  }
  if (d.size() == 1) return impl_->add(d.front());
  return impl_->add(GiNaC::dynallocate<GiNaC::add>(d));
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

std::vector<Index> ExpressionSet::inputs_of(Expr e) const {
  // each node is visited once per occurrence, as by has()
  const std::vector<std::size_t> found =
      gather_inputs(impl_->at(e, "inputs_of"), impl_->symbol_index);
  return std::vector<Index>(found.begin(), found.end());
}

bool ExpressionSet::is_literal_zero(Expr e) const {
  const GiNaC::ex& x = impl_->at(e, "is_literal_zero");
  return GiNaC::is_exactly_a<GiNaC::numeric>(x) && x.is_zero();
}

Expr ExpressionSet::sum(const std::vector<Expr>& terms) {
  GiNaC::exvector v;
  v.reserve(terms.size());
  for (Expr t : terms) v.push_back(impl_->at(t, "sum"));
  if (v.empty()) return impl_->add(GiNaC::ex(0));
  return impl_->add(GiNaC::dynallocate<GiNaC::add>(v));
}

std::vector<Expr> ExpressionSet::terms(Expr e) {
  const GiNaC::ex x = impl_->at(e, "terms");
  if (!GiNaC::is_exactly_a<GiNaC::add>(x)) return {e};
  std::vector<Expr> out;
  out.reserve(x.nops());
  for (std::size_t i = 0; i < x.nops(); ++i) out.push_back(impl_->add(x.op(i)));
  return out;
}

namespace {

// true when x holds a power whose exponent is not a number ≥ 0 (a denominator that is not a
// number, or an exponent that is not a number): only then may normal() find a sum that expand()
// leaves non-zero to be 0. Without one, the expanded x (function arguments included) is a
// polynomial in its atoms (symbols, function calls with expanded arguments, powers with
// fractional exponents) with numeric coefficients, which GiNaC keeps canonical. Iterative: no
// recursion on the nesting.
bool has_denominator(const GiNaC::ex& x) {
  std::vector<GiNaC::ex> stack{x};
  while (!stack.empty()) {
    const GiNaC::ex y = std::move(stack.back());
    stack.pop_back();
    if (GiNaC::is_a<GiNaC::power>(y)) {
      const GiNaC::ex& p = y.op(1);
      if (!GiNaC::is_a<GiNaC::numeric>(p) || GiNaC::ex_to<GiNaC::numeric>(p).is_negative() ||
          !GiNaC::ex_to<GiNaC::numeric>(p).is_real())
        return true;
    }
    for (std::size_t k = y.nops(); k-- > 0;) stack.push_back(y.op(k));
  }
  return false;
}

}  // namespace

bool ExpressionSet::is_zero(Expr e) const {
  // (function arguments expanded too, as normal() normalizes them)
  const GiNaC::ex x = impl_->at(e, "is_zero").expand(GiNaC::expand_options::expand_function_args);
  // normal() of a sum of N terms adds them one by one (O(N²)): only when it can matter
  return x.is_zero() || (has_denominator(x) && GiNaC::normal(x).is_zero());
}

std::string ExpressionSet::to_string(Expr e) const {
  std::ostringstream os;
  os << impl_->at(e, "to_string");
  return os.str();
}

const std::vector<std::string>& ExpressionSet::input_names() const { return impl_->input_names; }

std::vector<Expr> ExpressionSet::switching_functions(const std::vector<Expr>& exprs) {
  std::vector<GiNaC::ex> found;
  // g once: neither g nor −g found before (GiNaC distributes −1 over a sum, so −(a − b) is b − a),
  // and not a number
  std::unordered_set<GiNaC::ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> known;
  const auto note = [&](const GiNaC::ex& g) {
    if (GiNaC::is_a<GiNaC::numeric>(g) || known.count(g) != 0) return;
    known.insert(g);
    known.insert(-g);
    found.push_back(g);
  };
  // each shared subexpression visited once (GiNaC shares subtrees: a derivative repeats its
  // argument's pieces)
  std::unordered_set<GiNaC::ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> seen;
  std::vector<GiNaC::ex> stack;
  for (const Expr e : exprs) stack.push_back(impl_->at(e, "switching_functions"));
  while (!stack.empty()) {
    const GiNaC::ex x = stack.back();
    stack.pop_back();
    if (GiNaC::is_a<GiNaC::numeric>(x) || GiNaC::is_a<GiNaC::symbol>(x)) continue;
    if (!seen.insert(x).second) continue;
    if (GiNaC::is_a<GiNaC::function>(x)) {
      const std::string name = GiNaC::ex_to<GiNaC::function>(x).get_name();
      if (name == "lang_abs" || name == "sign" || name == "heaviside") {
        note(x.op(0));
      } else if (name == "min" || name == "max") {
        note(x.op(0) - x.op(1));
      } else if (name == "if") {
        note(x.op(0));
        // a derivative's tie rule if(c, da, if(kink_tie(c), minmod(da, db), db))
        // (expression_parse.cpp, kink): its inner condition switches with c, and minmod's min
        // and max act only at c = 0
        const GiNaC::ex& rest = x.op(2);
        if (GiNaC::is_a<GiNaC::function>(rest) &&
            GiNaC::ex_to<GiNaC::function>(rest).get_name() == "if" &&
            rest.op(0).is_equal(kink_tie(x.op(0)))) {
          stack.push_back(x.op(0));
          stack.push_back(x.op(1));
          stack.push_back(rest.op(2));
          continue;
        }
      }
    }
    for (std::size_t i = 0; i < x.nops(); ++i) stack.push_back(x.op(i));
  }
  std::vector<Expr> out;
  out.reserve(found.size());
  for (GiNaC::ex& g : found) out.push_back(impl_->add(std::move(g)));
  return out;
}

}  // namespace ukdyn::expr
