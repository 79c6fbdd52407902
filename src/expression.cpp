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

const std::vector<std::string>& ExpressionSet::input_names() const {
  return impl_->input_names;
}

}  // namespace ukdyn::expr
