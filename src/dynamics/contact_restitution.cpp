// SPDX-License-Identifier: BSD-3-Clause
// with_restitution_law: a unilateral constraint whose impacts follow Poisson's law
// (docs/contact.md, "Poisson's restitution"). The law rides on the constraint's model: a model that
// forwards every evaluation to the original one and carries the law, which the impact reads
// (impact.cpp).
#include "ukdyn/dynamics/contact_restitution.hpp"

#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace ukdyn {

namespace {

// the constraint's own model, with the law of its impacts
class LawModel final : public ConstraintModel {
 public:
  LawModel(std::shared_ptr<const ConstraintModel> inner, RestitutionLaw law)
      : inner_(std::move(inner)), law_(law) {}
  RestitutionLaw law() const { return law_; }
  const std::shared_ptr<const ConstraintModel>& inner() const { return inner_; }

  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    return inner_->make_scratch(n);
  }
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                          CallableScratch* shared) const override {
    return inner_->make_scratch_sharing(n, shared);
  }
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    inner_->acceleration_form(q, qd, t, scratch, A, b);
  }
  const std::vector<Index>& columns() const override { return inner_->columns(); }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    inner_->acceleration_form_local(q, qd, t, scratch, A_local, b);
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    inner_->violation(q, qd, t, scratch, position, velocity);
  }

 private:
  std::shared_ptr<const ConstraintModel> inner_;
  RestitutionLaw law_;
};

}  // namespace

const char* to_string(RestitutionLaw law) {
  return law == RestitutionLaw::kPoisson ? "poisson" : "newton";
}

Constraint with_restitution_law(const Constraint& contact, RestitutionLaw law) {
  if (!contact.is_unilateral()) {
    throw std::invalid_argument("ukdyn::with_restitution_law: constraint '" + contact.name() +
                                "' is not unilateral: a law of restitution needs a contact "
                                "(call Constraint::unilateral(e) first)");
  }
  // the model: the one a law already wraps, else the constraint's own (Constraint shares its
  // model but does not hand out its pointer: a copy of the constraint keeps it alive)
  std::shared_ptr<const ConstraintModel> model;
  if (const auto* wrapped = dynamic_cast<const LawModel*>(&contact.model())) {
    model = wrapped->inner();
  } else {
    auto keep = std::make_shared<const Constraint>(contact);
    model = std::shared_ptr<const ConstraintModel>(keep, &keep->model());
  }
  Constraint out(contact.name(), contact.kind(), contact.rows(),
                 std::make_shared<LawModel>(std::move(model), law));
  const TimeInterval& active = contact.active_interval();
  if (active.begin != TimeInterval{}.begin || active.end != TimeInterval{}.end)
    out.active_between(active.begin, active.end);
  if (contact.stabilization().enabled())
    out.stabilize(contact.stabilization().alpha, contact.stabilization().beta);
  out.mark_drive(contact.is_drive());
  out.unilateral(contact.restitution());
  return out;
}

RestitutionLaw restitution_law(const Constraint& c) {
  const auto* wrapped = dynamic_cast<const LawModel*>(&c.model());
  return wrapped ? wrapped->law() : RestitutionLaw::kNewton;
}

}  // namespace ukdyn
