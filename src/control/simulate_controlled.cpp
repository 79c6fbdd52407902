// SPDX-License-Identifier: BSD-3-Clause
// Controlled simulation: the plant (a System that may differ from the controller's nominal
// model) under the control force, run by simulate(). The control is evaluated inside the plant's
// force callable with the control workspace in the controlled system's per-workspace scratch
// (ControlledScratch), so an evaluation allocates nothing and one controlled System serves
// several threads, each with its own Workspace; the run's control statistics are read from that
// scratch after the run.
//
// simulate_controlled integrates, besides the plant, the control's work ∫ Qcᵀq' dt, effort
// ∫ QcᵀQc dt and absolute work ∫ |Qcᵀq'| dt — and with the robust term each row's Lyapunov
// bound V_i' = −gamma_i V_i + kappa_i epsilon / 2 — exactly, with the integrator's own stages
// and error control: as first-order quadratures z' = g beside the plant's state
// (detail::Quadratures, x = [q; q'; W; z]), g read from the control the force evaluation has
// just computed. (They were unit-mass auxiliary coordinates of an augmented system once, whose
// diag(M, I) every evaluation checked, factorized and solved with: 9 k instructions per RK4
// step of the 7-DOF Panda, bench/RESULTS.md. Their integrals ∫ z dt, those coordinates'
// positions, are integrated as well, so that the adaptive methods' error control weighs what
// it weighed then and takes the same steps.)
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "control/contact_modes.hpp"
#include "control/control_at_start.hpp"
#include "control/internal.hpp"
#include "dynamics/internal.hpp"
#include "linalg/scale_class.hpp"
#include "simulation/energy_balance.hpp"
#include "simulation/observed_run.hpp"
#include "simulation/sample_grid.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

namespace {

// the quadratures z: work, effort, absolute work, then one bound state per requirement row
constexpr Index kWork = 0, kEffort = 1, kWorkAbs = 2, kBounds = 3;

struct ControlledScratch;
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

// --- the control inside the plant's force ------------------------------------------------------

// The controlled plant's description (immutable, shared by the controlled system's callables):
// the controller and the plant, n plant coordinates and aux quadratures (simulate_controlled's;
// 0 for controlled_system).
struct ControlledPlant {
  ControlledPlant(const Controller& c, const System& p, Index aux_count)
      : ctrl(c), plant(p), n(p.coordinate_count()), aux(aux_count) {}

  // Q ← Q_plant(q, q', t) + Qc_control; NaN when the control fails
  void force(ControlledScratch& w, const Eigen::Ref<const VectorXd>& q,
             const Eigen::Ref<const VectorXd>& qd, double t, Eigen::Ref<VectorXd> Q) const;
  // z' = (Qcᵀq', QcᵀQc, |Qcᵀq'|, −gamma_i V_i + kappa_i epsilon / 2) of the control that the
  // last force() computed (z: the aux quadratures, V_i = z[kBounds + i]), then y' = z for
  // their integrals y (the aux quadratures after them). O(n + m_r).
  void rates(const ControlledScratch& w, const double* z, double* z_rate) const;
  void note_not_met(ControlledScratch& w, double t) const;

  Controller ctrl;
  System plant;
  Index n, aux;
  UnitSystem units;  // the run's (SimulationOptions::units), for its notes
};

// The controlled system's per-workspace scratch (its CallableScratch): the control workspace,
// the plant's own scratch, and the run's control statistics. When the plant is the
// controller's model (the same description, as when no mismatch is simulated), the plant's
// callables use the model workspace's scratch: the plant's evaluation and the model's, at the
// same state, then share what the callables keep per state (a tree's kinematics, M and Q).
struct ControlledScratch final : CallableScratch {
  explicit ControlledScratch(const ControlledPlant& p)
      : cws(p.ctrl),
        own_plant(p.plant.id() == p.ctrl.model().id() ? nullptr : p.plant.make_scratch()),
        plant(own_plant ? own_plant.get() : cws.model.callables.get()),
        contacts(p.ctrl),
        q_last(p.n),
        qd_last(p.n) {
    stats.first_not_met = std::numeric_limits<double>::quiet_NaN();
    contacts.set_units(p.units);
  }
  ControlWorkspace cws;
  std::unique_ptr<CallableScratch> own_plant;  // the plant's callables' scratch (may be null)
  CallableScratch* plant;                      // own_plant, or the model workspace's
  // the unilateral contacts: the run's modes (its workspace's activity_override, set when the
  // run starts; null outside simulate_controlled) mirrored into the model's
  control_detail::ContactModes contacts;
  const std::vector<signed char>* run_modes = nullptr;
  // the run's workspace of the controlled system, whose callables are this scratch (set when
  // the run starts, cleared when it ends; null outside simulate_controlled): its evaluation
  // factorizes M before it asks for Q, and the control adopts that factor
  const Workspace* run_ws = nullptr;
  VectorXd q_last, qd_last;  // (n) the state of the last control evaluation, at t_last
  double t_last = 0.0;
  bool evaluated = false;  // q_last, qd_last, t_last and cws hold an evaluation
  ControlStatistics stats;
  std::string failure;       // describe_control_status() of the latest failing evaluation,
  double failure_t = 0.0;    // at this time (a failed run reports it only from its last step)
  std::string pull_failure;  // (ContactModes::settle) a requirement that needs a contact to pull
  std::string slip_note;     // (ContactModes::slip) the first stick a requirement broke,
  double slip_t = 0.0;       // at this time
  bool stick_noted = false;  // stats.not_met_message says why a stick held
  // (ContactModes::hold_sliding) the first requirement met only with a sliding contact held,
  // whose control the run applied with the contact sliding, at this time; said in
  // stats.not_met_message once (held_noted)
  std::string held_note;
  double held_t = 0.0;
  bool held_noted = false;
};

// Whether the last assembly of the requirements in c evaluated every violation the samples
// report (phi, psi of each holonomic or nonholonomic requirement: active and stabilized, so that
// assemble_constraints called its violation(); an inactive one's would be stale). O(K).
bool violations_assembled(const Controller& ctrl, const ControlWorkspace& c) {
  const System& req = ctrl.requirements();
  for (Index k = 0; k < req.constraint_count(); ++k) {
    if (req.constraint(k).kind() == ConstraintKind::kAcceleration) continue;
    if (!c.req.active[std::size_t(k)] || !c.req.stabilization[std::size_t(k)].enabled()) {
      return false;
    }
  }
  return true;
}

CallableScratch* plant_scratch(CallableScratch* controlled) {
  auto* w = dynamic_cast<ControlledScratch*>(controlled);
  return w != nullptr ? w->plant : nullptr;
}

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
    s = control_detail::compute_control_in(ctrl, cws, q, qd, t, own ? w.run_ws : nullptr);
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
    w.failure = describe_control_status(ctrl, cws);
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

void ControlledPlant::rates(const ControlledScratch& w, const double* z, double* z_rate) const {
  const ControlWorkspace& cws = w.cws;
  // z' = (Qcᵀq', QcᵀQc, |Qcᵀq'|, −gamma_i V_i + kappa_i epsilon / 2)
  z_rate[kWork] = cws.power;
  z_rate[kEffort] = cws.Qc_control.squaredNorm();
  z_rate[kWorkAbs] = std::abs(cws.power);
  if (const auto& r = ctrl.robust(); r && aux > kBounds) {
    for (Index i = 0; i < ctrl.requirement_rows(); ++i) {
      z_rate[kBounds + i] =
          -ctrl.robust_rate(i) * z[kBounds + i] + 0.5 * cws.kappa[i] * r->boundary_layer;
    }
  }
  // y' = z: the positions of the auxiliary coordinates that z once were (see the top), for
  // the error control alone
  for (Index i = 0; i < aux; ++i) z_rate[aux + i] = z[i];
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
    stats.not_met_message =
        control_detail::describe_control_status(ctrl, w.cws, stats.held_control);
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

// sigma_min / sigma_max of the active requirement rows A_r at (q, q', t), NaN without rows
double requirement_gap(const Controller& ctrl, ControlWorkspace& cws,
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t) {
  compute_control(ctrl, cws, q, qd, t);
  MatrixXd rows(cws.req.active_rows, cws.req.A.cols());
  Index k = 0;
  for (Index i = 0; i < cws.req.A.rows() && k < rows.rows(); ++i) {
    if (cws.req.A.row(i).squaredNorm() > 0.0) rows.row(k++) = cws.req.A.row(i);
  }
  if (k == 0) return std::numeric_limits<double>::quiet_NaN();
  const VectorXd sv = Eigen::JacobiSVD<MatrixXd>(rows.topRows(k)).singularValues();
  return sv[0] > 0.0 ? sv[sv.size() - 1] / sv[0] : 0.0;
}

// A controlled run whose step size collapsed: when the requirement rows have (nearly) lost
// rank where the control was last evaluated, that is the likely cause, and it replaces the
// driver's general diagnosis (its time in the run's unit, time_unit).
void diagnose_requirements(const ControlledPlant& st, const ControlledScratch& w,
                           const Eigen::Ref<const VectorXd>& q0,
                           const Eigen::Ref<const VectorXd>& qd0, double t0,
                           const std::string& time_unit, RunStatistics& stats) {
  if (stats.status != Status::kIntegratorFailure || w.stats.evaluations == 0) return;
  ControlWorkspace cws(st.ctrl);
  const double start = requirement_gap(st.ctrl, cws, q0, qd0, t0);
  const double now = requirement_gap(st.ctrl, cws, w.q_last, w.qd_last, w.t_last);
  if (!(now < 1e-4) || start < 100.0 * now) return;
  std::string& m = stats.message;
  for (const char* cause : {". Likely cause", ". The step size collapsed"}) {
    if (const auto at = m.find(cause); at != std::string::npos) m.erase(at);
  }
  char gaps[160];
  std::snprintf(gaps, sizeof gaps,
                "sigma_min / sigma_max of the requirement rows %.3g at t = %g %s, %.3g at the "
                "start",
                now, w.t_last, time_unit.c_str(), start);
  m += std::string(". Likely cause: the requirements lost rank (") + gaps +
       "): they cannot all be met there — a path that leaves the reachable set, or passes a "
       "singular configuration of the mechanism (an arm stretched out). Try: a requirement that "
       "stays inside the workspace, fewer requirement rows, or actuated coordinates and a "
       "weighted law that tolerate the loss (docs/control.md)";
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

// The plant with the control in its force. shared: the plant's constraints evaluate with the
// plant's scratch (simulate_controlled's run: a tree's kinematics shared with the plant's M and
// Q); else with their own, as controlled_system has always made them.
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

// The unit of each quadrature of a controlled run (z, then y = ∫ z dt; see simulate_controlled)
// in the explicit methods' step-size control. The effort ∫ |Qc|² dt is weighed in a unit of its
// own, from the plant's run scales (set_run_scales) and the run's duration T:
//   effort  (E_u / ℓ_u)² τ r²,   its integral  (E_u / ℓ_u)² τ² r²,
// E_u the energy unit (Workspace::energy_unit), ℓ_u the length (the class length_scale over 10),
// E_u / ℓ_u a generalized force, τ = class(T) / 10 a time (detail::scale_class) and r the rate
// decade (Workspace::rate_unit): 1 for a model in SI units whose E lies in [0.316, 316] J, ℓ and
// T in [0.0316, 31.6] and v / ℓ in [1, 10) per second. Weighed as q' (atol · r), the effort, 10⁹
// times its SI number in g, mm, ms, asked at the jump of a contact's release under control for
// steps below the roundoff of t (docs/contact.md, "Contacts under control"). The factor r² is
// measured, not derived: (E_u / ℓ_u)² τ alone (the effort's SI-consistent unit) runs the lift but
// loosens the steps of a body the control holds in place in mm, after its stiffness switch to
// BDF, until the friction its stick carries is 7.5e-7 N instead of 0 (ControlSlip.
// BodyHeldAtItsCentre…, which passes from r² = 1e-8 of it down; the lift runs up to 1e-8 of it).
// The others keep the weights they had as auxiliary coordinates, z as q' (r) and y as q (1): the
// work's integrand q'ᵀ Qc is continuous where q' is. (τ is not the class of ℓ / v: v's mass
// scale 1ᵀ M 1 / n mixes a body's mass and its inertia, whose units differ.) O(aux).
std::vector<double> quadrature_units(const Workspace& scales, double duration, Index aux) {
  const double force = scales.energy_unit / (scales.length_scale / 10.0),
               time = detail::scale_class(duration) / 10.0, rate = scales.rate_unit;
  std::vector<double> unit(std::size_t(2 * aux), 1.0);
  for (Index i = 0; i < aux; ++i) unit[std::size_t(i)] = rate;
  unit[std::size_t(kEffort)] = force * force * time * rate * rate;
  unit[std::size_t(aux + kEffort)] = unit[std::size_t(kEffort)] * time;
  return unit;
}

}  // namespace

System controlled_system(const Controller& ctrl, const System& plant) {
  require_same_plant(ctrl, plant, "ukdyn::controlled_system");
  // the controller's model follows the run's contact modes, which only simulate_controlled
  // hands it
  for (const Constraint& c : plant.constraints()) {
    if (c.is_unilateral()) {
      throw std::invalid_argument(
          "ukdyn::controlled_system: the constraint '" + c.name() +
          "' is unilateral; a controlled plant with contacts runs in simulate_controlled, whose "
          "controller holds the contacts the run holds (docs/contact.md, \"Contacts under "
          "control\")");
    }
  }
  return build_controlled(std::make_shared<ControlledPlant>(ctrl, plant, 0), false);
}

ControlledTrajectory simulate_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink) {
  return control_detail::run_controlled(ctrl, plant, q0, qd0, options, sample_sink, nullptr);
}

control_detail::ControlAtStart control_detail::control_at_start(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options) {
  ControlAtStart start;
  // stopped once the first sample is recorded; nothing kept, nothing reported on the way
  SimulationOptions o = options;
  o.should_stop = [] { return true; };
  o.sample_sink = nullptr;
  o.progress = nullptr;
  run_controlled(
      ctrl, plant, q0, qd0, o, [](const ControlledTrajectory&) {}, &start);
  return start;
}

ControlledTrajectory control_detail::run_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink,
    ControlAtStart* start) {
  const char* who = "ukdyn::simulate_controlled";
  require_same_plant(ctrl, plant, who);
  const Index n = plant.coordinate_count(), m_r = ctrl.requirement_rows();
  if (q0.size() != n || qd0.size() != n) {
    throw std::invalid_argument(std::string(who) + ": q0 and qd0 need n = " + format_number(n) +
                                " entries, got " + format_number(q0.size()) + " and " +
                                format_number(qd0.size()));
  }
  const bool robust = ctrl.robust().has_value();
  const Index aux = kBounds + (robust ? m_r : 0);
  const auto st = [&] {
    auto p = std::make_shared<ControlledPlant>(ctrl, plant, aux);
    p->units = options.units;
    return std::shared_ptr<const ControlledPlant>(std::move(p));
  }();
  const System sys = build_controlled(st, true);

  // the quadratures z (work, effort, absolute work, bounds), from (0, 0, 0, V_i(0)), their
  // rates from the control of the run's evaluation at each stage; then their integrals y from
  // 0 (as when they were coordinates: a run's steps then stay what they were where its scales
  // did not count them); each weighed by the error control in its unit (quadrature_units,
  // below)
  detail::Quadratures quad;
  quad.count = 2 * aux;
  quad.velocities = aux;
  quad.z0.assign(std::size_t(2 * aux), 0.0);
  quad.rate = [&st = *st](const Workspace& ws, double, const double* z, double* z_rate) {
    st.rates(static_cast<const ControlledScratch&>(*ws.callables), z, z_rate);
  };
  if (robust) {
    ControlWorkspace cws(ctrl);
    evaluate_violations(ctrl.requirements(), cws.req, q0, qd0, options.t_start);
    for (Index i = 0; i < m_r; ++i) {
      const bool holonomic =
          ctrl.requirement(ctrl.row_requirement(i)).kind() == ConstraintKind::kHolonomic;
      const double e = holonomic ? cws.req.phi[i] : cws.req.phi_dot[i];
      const double e_dot = holonomic ? cws.req.phi_dot[i] : 0.0;
      quad.z0[std::size_t(kBounds + i)] = ctrl.lyapunov(i, e, e_dot);
    }
  }
  // the requirements' switching times are breakpoints of the dynamics
  SimulationOptions o = options;
  for (const Constraint& c : ctrl.requirements().constraints()) {
    for (double t : {c.active_interval().begin, c.active_interval().end}) {
      if (std::isfinite(t)) o.breakpoints.push_back(t);
    }
  }
  // (the run's own balance misses the control's work: the plant's is checked below)
  o.energy_balance_tolerance = std::numeric_limits<double>::infinity();
  const double tolerance = plant.accounts_for_energy() ? checked_energy_balance_tolerance(options)
                                                       : std::numeric_limits<double>::infinity();

  // the names; the samples go into `run` (kept) or into `one` (each passed to the sink)
  ControlledTrajectory run;
  Trajectory& tr = run.plant;
  tr.coordinate_names = plant.coordinate_names();
  run.row_names = ctrl.row_names();
  run.robust = robust;
  const bool streamed = bool(sample_sink);
  ControlledTrajectory one;
  if (!streamed) {
    // kept in memory: the plant's values and the control's per sample, bounded as simulate()
    // bounds its own (the controlled run itself streams into `run`, one sample at a time)
    const double per_sample =
        double(1 + 5 * n + plant.constraint_rows() + 2 * plant.constraint_count() + 9 + 2 * n +
               (robust ? 3 : 2) * m_r + 4);
    const std::string bound =
        "of a controlled run kept in memory (kMaxStoredValues = 2^28 "
        "values, " +
        format_number(long(per_sample)) + " per sample)";
    (void)detail::SampleGrid(
        options, std::min(kMaxStreamedSamples, std::floor(kMaxStoredValues / per_sample)),
        bound.c_str());
  }
  ControlledTrajectory& out = streamed ? one : run;
  detail::EnergyBalance balance;  // the plant's, with the control's work
  ControlWorkspace cws(ctrl);
  control_detail::ContactModes sample_contacts(ctrl);
  const Workspace* run_ws = nullptr;               // the run's (its modes), once it starts
  const ControlledScratch* run_scratch = nullptr;  // the run's control, once it starts
  std::string pull;
  control_detail::BoundWatch bounds(ctrl, options.t_start);  // |error| against error_bound
  VectorXd q(n), qd(n), qdd(n);
  o.sample_sink = [&](const Trajectory& s) {
    // the plant's sample, and the quadratures z at it
    if (streamed) {
      if (one.plant.coordinate_names.empty()) {
        one.plant.coordinate_names = tr.coordinate_names;
        one.plant.constraint_names = s.constraint_names;
        one.plant.constraint_rows = s.constraint_rows;
        one.plant.constraint_kinds = s.constraint_kinds;
        one.plant.unilateral = s.unilateral;
        one.plant.n = n;
        one.plant.m = s.m;
        one.row_names = run.row_names;
        one.robust = robust;
      }
      for (auto* f : sample_fields(one)) f->clear();
    }
    Trajectory& p = out.plant;
    const double t = s.t[0];
    p.t.push_back(t);
    for (auto [to, from] : {std::pair{&p.q, &s.q},
                            {&p.qd, &s.qd},
                            {&p.qdd, &s.qdd},
                            {&p.Qc_ideal, &s.Qc_ideal},
                            {&p.Qc_nonideal, &s.Qc_nonideal}}) {
      to->insert(to->end(), from->begin(), from->begin() + n);
    }
    for (auto [to, from] : {std::pair{&p.lambda, &s.lambda},
                            {&p.lambda_total, &s.lambda_total},
                            {&p.position_violation, &s.position_violation},
                            {&p.velocity_violation, &s.velocity_violation},
                            {&p.potential_energy, &s.potential_energy},
                            {&p.work_nonideal, &s.work_nonideal},
                            {&p.work_ideal, &s.work_ideal},
                            {&p.work_drive, &s.work_drive},
                            {&p.work_external, &s.work_external}}) {
      to->insert(to->end(), from->begin(), from->end());
    }
    const double* z = quad.sample.data();
    q = Eigen::Map<const VectorXd>(s.q.data(), n);
    qd = Eigen::Map<const VectorXd>(s.qd.data(), n);
    qdd = Eigen::Map<const VectorXd>(s.qdd.data(), n);
    // (the control at the run's first sample with the run's modes, settled as the run's own
    // evaluations settle them: control_at_start's)
    if (start != nullptr && !start->evaluated && run_ws != nullptr) {
      start->evaluated = true;
      ControlWorkspace c0(ctrl);
      control_detail::ContactModes modes(ctrl);
      modes.set_units(options.units);
      modes.mirror(run_ws, c0);
      ControlStatus s0 = compute_control(ctrl, c0, q, qd, t);
      start->status = s0;
      // (a requirement that needs a contact to pull: the run stops, saying pull_failure)
      if (modes.settle(ctrl, c0, q, qd, t, s0, start->pull_failure)) {
        start->status = s0;
        start->held = modes.held_sliding();
        if (s0 != ControlStatus::kOk)
          start->description = control_detail::describe_control_status(ctrl, c0, start->held);
        start->unactuated = explain_unactuated_requirements(ctrl, c0);
        if (modes.slipped() < 0) start->stick_note = modes.stick_note(ctrl);
        if (modes.held_sliding()) start->stick_note = modes.held_note(ctrl);
      }
    }
    // the control at the sample (evaluated afresh at the sample's state)
    // (with the run's contact modes, as in the run's evaluations). The run evaluated the
    // control at the sample's state just before (the sample's q''): without contacts, whose
    // modes the sample settles on its own, its results are this evaluation's, bit for bit
    const ControlWorkspace* at_sample = nullptr;
    if (run_scratch != nullptr && !sample_contacts.any() && run_scratch->t_last == t &&
        std::memcmp(q.data(), run_scratch->q_last.data(), sizeof(double) * std::size_t(n)) == 0 &&
        std::memcmp(qd.data(), run_scratch->qd_last.data(), sizeof(double) * std::size_t(n)) == 0 &&
        (run_scratch->cws.status == ControlStatus::kOk ||
         run_scratch->cws.status == ControlStatus::kRequirementsNotMet)) {
      at_sample = &run_scratch->cws;
    } else {
      sample_contacts.mirror(run_ws, cws);
      ControlStatus cs = compute_control(ctrl, cws, q, qd, t);
      sample_contacts.settle(ctrl, cws, q, qd, t, cs, pull);
      at_sample = &cws;
    }
    // T = q'ᵀ M q' / 2 of the plant: the run's (its M is the plant's, z not being coordinates)
    const double T = s.kinetic_energy[0];
    const double V = s.potential_energy[0];
    p.kinetic_energy.push_back(T);
    p.energy.push_back(T + V);
    p.work_control.push_back(z[kWork]);
    // the impacts' work Σ (T⁺ − T⁻), kept when the plant has contacts (their jumps leave z')
    const double impact = s.work_impact.empty() ? 0.0 : s.work_impact[0];
    if (!s.work_impact.empty()) p.work_impact.push_back(impact);
    const double works[6] = {s.work_nonideal[0], s.work_ideal[0], s.work_drive[0],
                             s.work_external[0], z[kWork],        impact};
    p.energy_balance_residual.push_back(balance.add(t, T, V, T + V, works));

    const ControlWorkspace& c = *at_sample;
    // errors: phi (holonomic), psi (nonholonomic), A_r q'' − b_r (acceleration form); phi and
    // psi are those the run's assembly of the requirements just evaluated at this state (the
    // same violation() call) when every such requirement was active and stabilized there
    const VectorXd accel_residual = c.req.A * qdd - c.req.b;
    const bool assembled = &c != &cws && violations_assembled(ctrl, c);
    if (!assembled) evaluate_violations(ctrl.requirements(), cws.req, q, qd, t);
    const Workspace& v = assembled ? c.req : cws.req;
    for (Index i = 0; i < m_r; ++i) {
      switch (ctrl.requirement(ctrl.row_requirement(i)).kind()) {
        case ConstraintKind::kHolonomic:
          out.error.push_back(v.phi[i]);
          out.error_rate.push_back(v.phi_dot[i]);
          break;
        case ConstraintKind::kNonholonomic:
          out.error.push_back(v.phi_dot[i]);
          out.error_rate.push_back(0.0);
          break;
        case ConstraintKind::kAcceleration:
          out.error.push_back(accel_residual[i]);
          out.error_rate.push_back(0.0);
          break;
      }
    }
    out.Qc_control.insert(out.Qc_control.end(), c.Qc_control.data(), c.Qc_control.data() + n);
    out.Qc_robust.insert(out.Qc_robust.end(), c.Qc_robust.data(), c.Qc_robust.data() + n);
    out.control_power.push_back(c.Qc_control.dot(qd));
    out.control_work.push_back(z[kWork]);
    out.control_effort.push_back(z[kEffort]);
    out.control_work_abs.push_back(z[kWorkAbs]);
    for (Index i = 0; robust && i < m_r; ++i) {
      out.error_bound.push_back(std::sqrt(std::max(z[kBounds + i], 0.0) / ctrl.robust_scale(i)));
      bounds.add(t, i, out.error[out.error.size() - std::size_t(m_r - i)], out.error_bound.back());
    }
    if (streamed) sample_sink(one);
  };
  // the control statistics, read from the run's workspace (its ControlledScratch) at the end
  std::optional<ControlledScratch> after;
  // the run's rate decade (the integrators' atol on q' and on z, Workspace::rate_unit): the
  // plant's own, from its state, as when z were auxiliary coordinates of an augmented system
  // (whose unit masses and integrands, which move with the model's units, it must not count)
  double plant_rate = 1.0;
  {
    Workspace scales(plant);
    set_run_scales(plant, scales, q0, qd0, o.t_start, o.t_end - o.t_start);
    plant_rate = scales.rate_unit;
    quad.unit = quadrature_units(scales, o.t_end - o.t_start, aux);
  }
  const Trajectory full = detail::simulate_observed(
      sys, q0, qd0, o,
      [&](const Workspace& ws) {
        after.emplace(*st);
        auto& w = static_cast<ControlledScratch&>(*ws.callables);
        w.run_ws = nullptr;
        after->stats = w.stats;
        after->failure = w.failure;
        after->failure_t = w.failure_t;
        after->slip_note = w.slip_note;
        after->held_note = w.held_note;
        after->q_last = w.q_last;
        after->qd_last = w.qd_last;
        after->t_last = w.t_last;
      },
      [&](Workspace& ws) {
        // the contacts' modes of each workspace of the run (the plant's constraint indices: the
        // controlled system keeps them), for the control's model in its evaluations: the run's
        // own (the first; also the samples'), then the branch check's, whose modes are a copy
        // of the run's (it used to evaluate the control with every contact held)
        auto& scratch = static_cast<ControlledScratch&>(*ws.callables);
        scratch.run_modes = &ws.activity_override;
        scratch.run_ws = &ws;  // (its own evaluation, whose factor of M the control may adopt)
        if (run_scratch == nullptr) {
          run_ws = &ws;
          run_scratch = &scratch;
        }
      },
      plant_rate, &quad);
  const ControlledScratch& w = *after;

  // the names, the statistics and the plant's energy balance
  tr.constraint_names = full.constraint_names;
  tr.constraint_rows = full.constraint_rows;
  tr.constraint_kinds = full.constraint_kinds;
  tr.unilateral = full.unilateral;
  tr.n = n;
  tr.m = full.m;
  tr.stats = full.stats;
  if (!w.slip_note.empty()) tr.stats.notes.push_back(w.slip_note);
  if (!w.held_note.empty()) tr.stats.notes.push_back(w.held_note);
  // requirements without dynamics that start unmet stay unmet (u21 05)
  if (const std::string why = explain_uncorrected_requirements(ctrl, q0, qd0, options.t_start,
                                                               options.initial_tolerance,
                                                               options.t_end - options.t_start);
      !why.empty())
    tr.stats.notes.push_back(why);
  diagnose_requirements(*st, w, q0, qd0, options.t_start, options.units.time, tr.stats);
  run.control = w.stats;
  bounds.finish(run.control, tr.stats, options.units.time);
  balance.finish(tr.stats, tolerance, options.units);
  // the controller's failure, where it failed in the run's last step (evaluations there lie at
  // or after the last sample; one before it was avoided by a smaller step, and the run failed
  // for its own reason, said by its own message): the run's status is then the controller's
  // (its NaN force made the run's evaluation report a non-finite Q, which the user never gave)
  if (!w.failure.empty() && tr.stats.status != Status::kOk &&
      tr.stats.status != Status::kEnergyBalance && tr.stats.status != Status::kInterrupted &&
      w.failure_t >= tr.stats.t_reached) {
    tr.stats.status = Status::kControlFailed;
    tr.stats.message = "the controller failed: " + w.failure;
  }
  return run;
}

ControlledTrajectory simulate_controlled(const Controller& ctrl, const System& plant,
                                         const Eigen::Ref<const VectorXd>& q0,
                                         const Eigen::Ref<const VectorXd>& qd0,
                                         const SimulationOptions& options) {
  if (!options.sample_sink) return simulate_controlled(ctrl, plant, q0, qd0, options, nullptr);
  // the plant's part of each sample to the options' sink
  SimulationOptions o = options;
  o.sample_sink = nullptr;
  return simulate_controlled(ctrl, plant, q0, qd0, o,
                             [&](const ControlledTrajectory& s) { options.sample_sink(s.plant); });
}

std::vector<std::vector<double>*> sample_fields(ControlledTrajectory& run) {
  return {&run.plant.t,
          &run.plant.q,
          &run.plant.qd,
          &run.plant.qdd,
          &run.plant.Qc_ideal,
          &run.plant.Qc_nonideal,
          &run.plant.lambda,
          &run.plant.lambda_total,
          &run.plant.position_violation,
          &run.plant.velocity_violation,
          &run.plant.kinetic_energy,
          &run.plant.potential_energy,
          &run.plant.energy,
          &run.plant.work_nonideal,
          &run.plant.work_ideal,
          &run.plant.work_drive,
          &run.plant.work_external,
          &run.plant.work_control,
          &run.plant.work_impact,
          &run.plant.energy_balance_residual,
          &run.error,
          &run.error_rate,
          &run.error_bound,
          &run.Qc_control,
          &run.Qc_robust,
          &run.control_power,
          &run.control_effort,
          &run.control_work_abs,
          &run.control_work};
}

std::vector<CsvColumn> control_csv_columns(const ControlledTrajectory& run) {
  const Index N = run.samples(), n = run.plant.n, m_r = Index(run.row_names.size());
  if (Index(run.error.size()) != N * m_r || Index(run.Qc_control.size()) != N * n ||
      Index(run.control_power.size()) != N || Index(run.control_effort.size()) != N ||
      Index(run.control_work_abs.size()) != N || Index(run.control_work.size()) != N ||
      (run.robust && Index(run.error_bound.size()) != N * m_r)) {
    throw std::invalid_argument(
        "ukdyn::control_csv_columns: inconsistent controlled trajectory "
        "(one from simulate_controlled() always is consistent)");
  }
  std::vector<CsvColumn> cols;
  auto matrix = [&](const std::string& prefix, const std::vector<double>& f,
                    const std::vector<std::string>& names) {
    const Index width = Index(names.size());
    for (Index i = 0; i < width; ++i) {
      CsvColumn c{prefix + names[std::size_t(i)], {}};
      c.values.reserve(std::size_t(N));
      for (Index j = 0; j < N; ++j) c.values.push_back(f[std::size_t(j * width + i)]);
      cols.push_back(std::move(c));
    }
  };
  matrix("error.", run.error, run.row_names);
  if (run.robust) matrix("error_bound.", run.error_bound, run.row_names);
  matrix("Qc_control.", run.Qc_control, run.plant.coordinate_names);
  if (run.robust) matrix("Qc_robust.", run.Qc_robust, run.plant.coordinate_names);
  cols.push_back({"control_power", run.control_power});
  cols.push_back({"control_effort", run.control_effort});
  cols.push_back({"control_work_abs", run.control_work_abs});
  cols.push_back({"control_work", run.control_work});
  return cols;
}

void write_csv(const ControlledTrajectory& run, const std::string& path) {
  write_csv(run.plant, path, control_csv_columns(run));
}

}  // namespace ukdyn
