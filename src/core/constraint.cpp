// SPDX-License-Identifier: BSD-3-Clause
// Constraint: a named, typed, possibly time-limited group of rows; the acceleration form; the
// small helpers of the automatically differentiated kinds (core/autodiff.hpp).
#include "ukdyn/core/constraint.hpp"

#include <stdexcept>
#include <utility>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

const char* to_string(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::kHolonomic:
      return "holonomic";
    case ConstraintKind::kNonholonomic:
      return "nonholonomic";
    case ConstraintKind::kAcceleration:
      return "acceleration";
  }
  return "unknown";
}

std::unique_ptr<ConstraintScratch> ConstraintModel::make_scratch(Index) const { return nullptr; }

const std::vector<Index>& ConstraintModel::columns() const {
  static const std::vector<Index> kAll;  // empty: every coordinate
  return kAll;
}

void ConstraintModel::acceleration_form_local(const Eigen::Ref<const VectorXd>&,
                                              const Eigen::Ref<const VectorXd>&, double,
                                              ConstraintScratch*, Eigen::Ref<MatrixXd>,
                                              Eigen::Ref<VectorXd>) const {
  throw std::logic_error(
      "ukdyn::ConstraintModel: a model that declares columns() must implement "
      "acceleration_form_local");
}

void ConstraintModel::acceleration_form(const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& qd, double t,
                                        ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                                        Eigen::Ref<VectorXd> b) const {
  const std::vector<Index>& cols = columns();
  if (cols.empty()) {
    throw std::logic_error(
        "ukdyn::ConstraintModel: a dense model (no columns()) must implement acceleration_form");
  }
  const Index k = Index(cols.size());
  acceleration_form_local(q, qd, t, scratch, A.leftCols(k), b);
  // scatter column j to cols[j], last first: cols[j] >= j and increasing, so a column is moved
  // before anything is written over it
  Index next = A.cols();  // columns >= next are final
  for (Index j = k - 1; j >= 0; --j) {
    const Index c = cols[std::size_t(j)];
    for (Index z = c + 1; z < next; ++z) A.col(z).setZero();
    if (c != j) A.col(c) = A.col(j);
    next = c;
  }
  for (Index z = 0; z < next; ++z) A.col(z).setZero();
}

void ConstraintModel::violation(const Eigen::Ref<const VectorXd>&,
                                const Eigen::Ref<const VectorXd>&, double, ConstraintScratch*,
                                Eigen::Ref<VectorXd> position,
                                Eigen::Ref<VectorXd> velocity) const {
  position.setZero();
  velocity.setZero();
}

Constraint::Constraint(std::string name, ConstraintKind kind, Index rows,
                       std::shared_ptr<const ConstraintModel> model)
    : name_(std::move(name)), kind_(kind), rows_(rows), model_(std::move(model)) {
  if (name_.empty()) throw std::invalid_argument("ukdyn::Constraint: the name must not be empty");
  if (rows_ <= 0) {
    throw std::invalid_argument("ukdyn::Constraint '" + name_ + "': rows must be positive, got " +
                                format_number(rows_));
  }
  if (!model_) throw std::invalid_argument("ukdyn::Constraint '" + name_ + "': null model");
}

Constraint& Constraint::active_between(double begin, double end) {
  if (!(begin <= end)) {
    throw std::invalid_argument("ukdyn::Constraint::active_between('" + name_ +
                                "'): need begin <= end, got [" + format_number(begin) + ", " +
                                format_number(end) + "]");
  }
  if (unilateral_) {
    throw std::invalid_argument("ukdyn::Constraint::active_between('" + name_ +
                                "'): the constraint is unilateral, and a unilateral constraint "
                                "with an interval of activity is not supported (a contact acts "
                                "for the whole run)");
  }
  active_ = TimeInterval{begin, end};
  return *this;
}

Constraint& Constraint::stabilize(double alpha, double beta) {
  if (!(alpha >= 0.0 && beta >= 0.0)) {
    throw std::invalid_argument("ukdyn::Constraint::stabilize('" + name_ +
                                "'): gains must be >= 0, got alpha = " + format_number(alpha) +
                                ", beta = " + format_number(beta));
  }
  stabilization_ = Stabilization{alpha, beta};
  return *this;
}

namespace {
// acceleration form: the user's callable writes A and b itself
class AccelerationModel final : public ConstraintModel {
 public:
  explicit AccelerationModel(AccelerationFormFn fn) : fn_(std::move(fn)) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch*, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    fn_(q, qd, t, A, b);
  }

 private:
  AccelerationFormFn fn_;
};
}  // namespace

Constraint acceleration_constraint(std::string name, Index rows, AccelerationFormFn fn) {
  if (!fn) {
    throw std::invalid_argument("ukdyn::acceleration_constraint('" + name +
                                "'): the callable is empty");
  }
  return Constraint(std::move(name), ConstraintKind::kAcceleration, rows,
                    std::make_shared<AccelerationModel>(std::move(fn)));
}

namespace ad {

void set_constant(Vec<Jet>& x, const Eigen::Ref<const VectorXd>& v) {
  for (Index i = 0; i < v.size(); ++i) {
    x[i].value() = v[i];
    x[i].derivatives().setZero();
  }
}

void seed_second_order(Vec<Dual2>& x, const Eigen::Ref<const VectorXd>& q,
                       const Eigen::Ref<const VectorXd>& qd) {
  // x_i(s) = q_i + s q'_i: value q_i, first derivative q'_i, second derivative 0
  for (Index i = 0; i < q.size(); ++i) {
    x[i].value() = Dual(q[i], Dual::DerType::Constant(qd[i]));
    x[i].derivatives()[0] = Dual(qd[i], Dual::DerType::Zero());
  }
}

Dual2 seed_time_second_order(double t) {
  // t(s) = t + s
  Dual2 t2;
  t2.value() = Dual(t, Dual::DerType::Constant(1.0));
  t2.derivatives()[0] = Dual(1.0, Dual::DerType::Zero());
  return t2;
}

}  // namespace ad
}  // namespace ukdyn
