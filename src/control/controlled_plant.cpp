// SPDX-License-Identifier: BSD-3-Clause
// The controlled plant: the plant's force with the control in it (ControlledPlant::force: the
// control at the state, the contacts' modes settled with the requirements, the event's LCP
// anticipated) and the controlled System built from the plant, its constraints on the plant's
// scratch (control/controlled_plant.hpp).
#include "control/controlled_plant.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "control/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"

namespace ukdyn::control_detail {

namespace {

CallableScratch* plant_scratch(CallableScratch* controlled);

// --- plant constraints with the plant's scratch ------------------------------------------------

struct PlantConstraintScratch final : ConstraintScratch {
  explicit PlantConstraintScratch(std::unique_ptr<ConstraintScratch> in) : inner(std::move(in)) {}
  std::unique_ptr<ConstraintScratch> inner;
};

// The plant's constraint, its scratch sharing the plant's (inside the controlled system's).
class PlantConstraintModel final : public ConstraintModel {
 public:
  PlantConstraintModel(Constraint inner, Index n) : inner_(std::move(inner)), n_(n) {}

  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    return std::make_unique<PlantConstraintScratch>(inner_.model().make_scratch(n_));
  }
  // the plant's constraint shares the plant's scratch (inside the controlled system's)
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index,
                                                          CallableScratch* shared) const override {
    return std::make_unique<PlantConstraintScratch>(
        inner_.model().make_scratch_sharing(n_, plant_scratch(shared)));
  }

  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = static_cast<PlantConstraintScratch&>(*s);
    inner_.model().acceleration_form(q, qd, t, w.inner.get(), A, b);
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = static_cast<PlantConstraintScratch&>(*s);
    inner_.model().violation(q, qd, t, w.inner.get(), position, velocity);
  }

 private:
  Constraint inner_;
  Index n_;
};

Constraint on_plant_scratch(const Constraint& c, Index n) {
  Constraint out(c.name(), c.kind(), c.rows(), std::make_shared<PlantConstraintModel>(c, n));
  const TimeInterval& iv = c.active_interval();
  if (iv.begin != TimeInterval{}.begin || iv.end != TimeInterval{}.end) {
    out.active_between(iv.begin, iv.end);
  }
  if (c.stabilization().enabled()) out.stabilize(c.stabilization().alpha, c.stabilization().beta);
  out.mark_drive(c.is_drive());
  // a contact stays one, with its law of restitution
  if (c.is_unilateral()) {
    out.unilateral(c.restitution());
    if (restitution_law(c) != RestitutionLaw::kNewton)
      out = with_restitution_law(out, restitution_law(c));
  }
  return out;
}

CallableScratch* plant_scratch(CallableScratch* controlled) {
  auto* w = dynamic_cast<ControlledScratch*>(controlled);
  return w != nullptr ? w->plant : nullptr;
}

}  // namespace

void ControlledPlant::force(ControlledScratch& w, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double t,
                            Eigen::Ref<VectorXd> Q) const {
  ControlWorkspace& cws = w.cws;
  ControlStatistics& stats = w.stats;
  plant.forces(q, qd, t, w.plant, Q);
  // the controller's model holds the contacts the run holds
  // the control at (q, q', t). A run evaluates the state of each sample twice, for the sample
  // and for the next step's first stage: without contacts (whose modes the run may have changed
  // in between) the control there is the last one, bit for bit, and is not evaluated again
  ControlStatus s = cws.status;
  const bool again = w.evaluated && !w.contacts.any() && t == w.t_last &&
                     std::memcmp(q.data(), w.q_last.data(), sizeof(double) * std::size_t(n)) == 0 &&
                     std::memcmp(qd.data(), w.qd_last.data(), sizeof(double) * std::size_t(n)) == 0;
  if (!again) {
    w.contacts.mirror(w.run_ws, cws);
    const bool own = w.run_ws != nullptr && w.run_ws->callables.get() == &w;
    s = compute_control_in(ctrl, cws, q, qd, t, own ? w.run_ws : nullptr);
  }
  ++stats.evaluations;
  w.evaluated = true;
  // where the control was last evaluated (a failed run's diagnosis looks there)
  w.q_last = q;
  w.qd_last = qd;
  w.t_last = t;
  // a requirement that lifts a contact opens it; one that needs it to pull stops the run
  if (!w.contacts.settle(ctrl, cws, q, qd, t, s, w.pull_failure)) {
    // (the latest: a failing trial evaluation that a smaller step avoided is no diagnosis of
    // a failure later in the run)
    w.failure = w.pull_failure;
    w.failure_t = t;
    Q.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  // (the earliest evaluation that broke a stick: a located release's, not its step's end)
  if (w.contacts.slipped() > 0 && (w.slip_note.empty() || t < w.slip_t)) {
    w.slip_note = w.contacts.stick_note(ctrl);
    w.slip_t = t;
  }
  if (w.contacts.held_sliding() && (w.held_note.empty() || t < w.held_t)) {
    w.held_note = w.contacts.held_note(ctrl);
    w.held_t = t;
  }
  // an event's q''_free (contacts the run held, released for its LCP): the control answers
  // their forces
  w.contacts.anticipate(ctrl, cws, w.run_modes, q, qd, t, s);
  if (s != ControlStatus::kOk && s != ControlStatus::kRequirementsNotMet) {
    w.failure = ukdyn::describe_control_status(ctrl, cws);
    w.failure_t = t;
    Q.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  if (s == ControlStatus::kRequirementsNotMet) note_not_met(w, t);
  for (Index i = 0; i < cws.kappa.size(); ++i)
    stats.max_kappa = std::max(stats.max_kappa, cws.kappa[i]);
  // Q += Qc_control
  Q += cws.Qc_control;
}

void ControlledPlant::note_not_met(ControlledScratch& w, double t) const {
  ControlStatistics& stats = w.stats;
  ++stats.not_met;
  for (Index i = 0; i < w.cws.residual.size(); ++i) {
    if (!w.cws.met[std::size_t(i)]) {
      stats.max_residual = std::max(stats.max_residual, std::abs(w.cws.residual[i]));
    }
  }
  if (stats.not_met == 1) {
    stats.first_not_met = t;
    // (once; saying what was applied: the held control where a sliding contact was held)
    stats.held_control = w.contacts.held_sliding();
    stats.not_met_message = describe_control_status(ctrl, w.cws, stats.held_control);
  }
  // (a stuck contact that a requirement needs to slide, held by static friction: why, once)
  if (w.contacts.slipped() < 0 && !w.stick_noted) {
    w.stick_noted = true;
    stats.not_met_message += "; " + w.contacts.stick_note(ctrl);
  }
  // (a requirement met only with a sliding contact held: why, once)
  if (w.contacts.held_sliding() && !w.held_noted) {
    w.held_noted = true;
    stats.not_met_message += "; " + w.contacts.held_note(ctrl);
  }
}

void require_same_plant(const Controller& ctrl, const System& plant, const char* who) {
  const System& model = ctrl.model();
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(std::string(who) + ": the plant and the controller's model " +
                                what +
                                " (the nominal model must describe the same mechanism, "
                                "with the parameters the controller believes)");
  };
  if (plant.coordinate_names() != model.coordinate_names()) fail("have different coordinates");
  if (plant.constraint_count() != model.constraint_count()) {
    fail("have different physical constraints (" + format_number(plant.constraint_count()) +
         " and " + format_number(model.constraint_count()) + ")");
  }
  for (Index k = 0; k < plant.constraint_count(); ++k) {
    if (plant.constraint(k).name() != model.constraint(k).name() ||
        plant.constraint(k).rows() != model.constraint(k).rows()) {
      fail("differ in constraint " + format_number(k) + " ('" + plant.constraint(k).name() +
           "' and '" + model.constraint(k).name() + "')");
    }
    if (plant.constraint(k).is_unilateral() != model.constraint(k).is_unilateral()) {
      fail("differ in constraint '" + plant.constraint(k).name() + "': it is unilateral in " +
           (plant.constraint(k).is_unilateral() ? "the plant" : "the model") + " only");
    }
  }
}

System build_controlled(const std::shared_ptr<const ControlledPlant>& st, bool shared) {
  const System& plant = st->plant;
  const Index n = plant.coordinate_count();
  SystemBuilder b(plant.coordinate_names());
  // every workspace of the controlled system gets its own control workspace and plant scratch
  b.scratch([st]() -> std::unique_ptr<CallableScratch> {
    return std::make_unique<ControlledScratch>(*st);
  });
  const auto scratch = [](CallableScratch* s) -> ControlledScratch& {
    return static_cast<ControlledScratch&>(*s);
  };
  // the plant's M, factorized along its mass tree (if any)
  if (!plant.mass_tree().empty()) b.mass_tree(plant.mass_tree());
  if (plant.mass_is_constant()) {
    MatrixXd M = MatrixXd::Identity(n, n);
    plant.mass_matrix(VectorXd::Zero(n), 0.0, M);
    b.mass_matrix(M);
  } else {
    b.mass_matrix([st, scratch](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s,
                                Eigen::Ref<MatrixXd> M) {
      st->plant.mass_matrix(q, t, scratch(s).plant, M);
    });
  }
  // Q = Q_plant + Qc_control
  b.forces([st, scratch](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, CallableScratch* s,
                         Eigen::Ref<VectorXd> Q) { st->force(scratch(s), q, qd, t, Q); });
  // the plant's switching functions (the sign changes of its non-smooth terms): located as
  // events as in the plant's own runs
  if (plant.switch_count() > 0) {
    b.switching_functions(
        plant.switch_names(),
        [st, scratch](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      double t, CallableScratch* s, Eigen::Ref<VectorXd> g) {
          st->plant.switching_functions(q, qd, t, scratch(s).plant, g);
        });
  }
  if (plant.has_potential()) {
    b.potential_energy(
        [st, scratch](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s) {
          return st->plant.potential_energy(q, t, scratch(s).plant);
        });
  }
  // the plant's external power (the control's work is integrated apart, in z)
  if (plant.has_external_power()) {
    b.external_power([st, scratch](const Eigen::Ref<const VectorXd>& q,
                                   const Eigen::Ref<const VectorXd>& qd, double t,
                                   CallableScratch* s) {
      return st->plant.external_power(q, qd, t, scratch(s).plant);
    });
  }
  // the physical constraints; the stick constraints of Coulomb contacts come again with their
  // contacts below (last, in the same order, so every index stays the plant's)
  const auto& contacts = plant.friction_contacts();
  auto contact_of_force = [&](Index i) -> const FrictionContact* {
    for (const auto& c : contacts) {
      if (c.force == i) return &c;
    }
    return nullptr;
  };
  for (Index k = 0; k < plant.constraint_count(); ++k) {
    const bool stick = std::any_of(contacts.begin(), contacts.end(), [k](const FrictionContact& c) {
      return c.stick_constraint == k;
    });
    if (!stick) b.add(shared ? on_plant_scratch(plant.constraint(k), n) : plant.constraint(k));
  }
  // the non-ideal forces, with the same indices; a Coulomb contact stays one (its sliding
  // velocity, sticking and slipping need the system to know it)
  for (Index i = 0; i < plant.nonideal_count(); ++i) {
    if (const FrictionContact* c = contact_of_force(i)) {
      CoulombFriction spec;
      spec.constraint = plant.constraint(c->normal_constraint).name();
      spec.mu = c->mu;
      spec.mu_static = c->mu_static;
      spec.coordinates = c->coordinates;
      spec.kinematics = c->kinematics;
      spec.regularization_velocity = c->eps;
      spec.name = plant.nonideal_name(i);
      spec.surface_velocity = c->surface_velocity;
      b.add(coulomb_friction(spec));
      continue;
    }
    // the plant's force, with the plant's scratch (IdealForceInfo::scratch)
    NonIdealFn fn = plant.nonideal(i);
    b.add(NonIdealForce(
        plant.nonideal_name(i),
        NonIdealFn([fn, scratch](const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t,
                                 const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C) {
          const IdealForceInfo plant_ideal(ideal, scratch(ideal.scratch()).plant);
          fn(q, qd, t, plant_ideal, C);
        })));
  }
  return b.build();
}

}  // namespace ukdyn::control_detail
