// ExpressionSet: the symbolic expressions of a model (see expression.hpp); parsing is in
// expression_parse.cpp, compilation in expression_compile.cpp.

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

#include "expression_internal.hpp"
#include "ukdyn/status.hpp"

namespace ukdyn::expr {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// ExpressionSet

ExpressionSet::ExpressionSet(std::vector<std::string> input_names)
    : impl_(std::make_unique<Impl>()) {
  for (const auto& name : input_names) {
    impl_->declare(name, "ExpressionSet");
    impl_->input_symbols.push_back(impl_->symbols.at(name));
    impl_->input_index.emplace(name, impl_->input_symbols.size() - 1);
    impl_->symbol_index.emplace(impl_->input_symbols.back(), impl_->input_symbols.size() - 1);
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
  return impl_->add(parse_expression(text, impl_->symbols, impl_->known, impl_->constant_values));
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
  // D e = ∂e/∂t + Σ ∂e/∂q_i · q̇_i   (no ∂e/∂q̇_i · q̈_i), summed at once; the terms of the
  // q_i that e does not hold are 0 and left out (the same sum)
  const std::vector<Index> in_e = inputs_of(e);
  GiNaC::exvector d{f.diff(GiNaC::ex_to<GiNaC::symbol>(t))};
  for (const auto& [q, qd] : chain) {
    const auto qi = impl_->input_index.find(q);
    if (qi == impl_->input_index.end()) impl_->input(q, "total_derivative");  // throws
    const GiNaC::ex& qds = impl_->input(qd, "total_derivative");
    if (!std::binary_search(in_e.begin(), in_e.end(), Index(qi->second))) continue;
    d.push_back(f.diff(GiNaC::ex_to<GiNaC::symbol>(impl_->input_symbols[qi->second])) * qds);
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
  const GiNaC::ex& x = impl_->at(e, "inputs_of");
  std::vector<Index> found;
  // a symbol in x, or a subtree: each node is visited once per occurrence, as by has()
  std::vector<GiNaC::ex> stack{x};
  while (!stack.empty()) {
    const GiNaC::ex y = std::move(stack.back());
    stack.pop_back();
    if (GiNaC::is_a<GiNaC::symbol>(y)) {
      const auto it = impl_->symbol_index.find(y);
      if (it != impl_->symbol_index.end()) found.push_back(Index(it->second));
      continue;
    }
    for (std::size_t k = y.nops(); k-- > 0;) stack.push_back(y.op(k));
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  return found;
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

bool ExpressionSet::is_zero(Expr e) const {
  const GiNaC::ex x = impl_->at(e, "is_zero").expand();
  return x.is_zero() || GiNaC::normal(x).is_zero();
}

std::string ExpressionSet::to_string(Expr e) const {
  std::ostringstream os;
  os << impl_->at(e, "to_string");
  return os.str();
}

const std::vector<std::string>& ExpressionSet::input_names() const {
  return impl_->input_names;
}

}  // namespace ukdyn::expr
