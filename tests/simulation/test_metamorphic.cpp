// SPDX-License-Identifier: BSD-3-Clause
// Metamorphic tests of scale invariance (issue #29 item 2): every example model re-run in
// rescaled units gives the same motion, to 1e-8 relative, in a comparable number of steps
// (within 2×), under its own (default) settings.
//
// The rescaling is built programmatically on the loaded System, so that it applies to every
// example without hand-edited copies. With factors s (coordinates), mu (masses), tau (time) and
// c (constraint rows), the rescaled system has q~ = s q, t~ = tau t and
//     M~ = mu tau² M / s²,  Q~ = mu Q / s,  V~ = mu V,  P~ = mu P / tau,
//     phi~ = c phi,  psi~ = c psi / tau,  A~ = c A / s,  b~ = c b / tau²,
// each evaluated at the original (q, q', t) = (q~ / s, q~' tau / s, t~ / tau): its motion is
// exactly q~(t~) = s q(t~ / tau), with energies × mu — so the tolerances that the run compares
// (projection, rank, energy balance, the work channels' step-size control) must be relative to
// the model's own scales for the runs to agree. The coordinates are scaled all together
// (lengths, and angles with them: a change of every coordinate's unit), which for the models
// in Cartesian coordinates and the bodies' positions is "lengths × s". The integrators' atol is
// absolute in the units of q (not yet relative): the lengths' rescalings state it in their units
// (atol × s), as a model written in those units would; on q' it is atol times the run's rate
// decade min(1, 10^⌊log10(v / ℓ)⌋) (Workspace::rate_unit), which time × 10 divides by exactly 10
// where v / ℓ < 10.
//
// The non-ideal forces are generalized forces, C~ = mu C / s: a Coulomb contact is made anew
// from its law (same mu, mu_static and normal constraint, whose rescaled rows give
// N~ = mu N / s; its velocities, the regularization eps and the surface's, × s / tau), so that
// the simulation's stick/slip events apply as to the original; any other force is evaluated at
// the original state with the original system's reactions (rescaled_nonideal). A controlled
// model runs simulate_controlled (as run_model does) with its controller rescaled too (nominal
// model as the plant, requirements as constraint rows, robust bounds in the requirements'
// units), and its control force is compared as well, Q_c~ = mu Q_c / s. Impacts keep their
// restitution; their times scale with tau like every other.
//
// An example whose run is accurate to less than 1e-8 at its own settings is compared at a
// tolerance of its measured accuracy (inaccurate); the slow and the sensitive ones run a
// shortened t_end (duration).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kExamples = UKDYN_EXAMPLES_DIR;

// the factors of one rescaling
struct Scaling {
  const char* label;
  double s = 1.0, mu = 1.0, tau = 1.0, c = 1.0;
};

const Scaling kScalings[] = {
    {"lengths x1e3", 1e3},         {"lengths x1e-3", 1e-3}, {"masses x1e6", 1, 1e6},
    {"masses x1e-6", 1, 1e-6},     {"time x10", 1, 1, 10},  {"rows x1e8", 1, 1, 1, 1e8},
    {"rows x1e-8", 1, 1, 1, 1e-8},
};

// the original (q, q', t) of a rescaled state
struct Original {
  VectorXd q, qd;
  double t;
  Original(const Scaling& f, const Eigen::Ref<const VectorXd>& q_s,
           const Eigen::Ref<const VectorXd>& qd_s, double t_s)
      : q(q_s / f.s), qd(qd_s * (f.tau / f.s)), t(t_s / f.tau) {}
  Original(const Scaling& f, const Eigen::Ref<const VectorXd>& q_s, double t_s)
      : q(q_s / f.s), t(t_s / f.tau) {}
};

// constraint k of `sys` in the rescaled units
class ScaledConstraint final : public ConstraintModel {
 public:
  ScaledConstraint(std::shared_ptr<const System> sys, Index k, const Scaling& f)
      : sys_(std::move(sys)), model_(sys_->constraint(k).model()), f_(f) {}
  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    return model_.make_scratch(n);
  }
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                          CallableScratch* shared) const override {
    return model_.make_scratch_sharing(n, shared);
  }
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    const Original o(f_, q, qd, t);
    model_.acceleration_form(o.q, o.qd, o.t, scratch, A, b);
    A *= f_.c / f_.s;
    b *= f_.c / (f_.tau * f_.tau);
  }
  const std::vector<Index>& columns() const override { return model_.columns(); }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    const Original o(f_, q, qd, t);
    model_.acceleration_form_local(o.q, o.qd, o.t, scratch, A_local, b);
    A_local *= f_.c / f_.s;
    b *= f_.c / (f_.tau * f_.tau);
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const Original o(f_, q, qd, t);
    model_.violation(o.q, o.qd, o.t, scratch, position, velocity);
    position *= f_.c;  // phi~ = c phi (zero for the other kinds)
    velocity *= f_.c / f_.tau;
  }

 private:
  std::shared_ptr<const System> sys_;  // keeps model_ alive
  const ConstraintModel& model_;
  Scaling f_;
};

// constraint k of `o` (a system's, or a controller's requirement) in the units of f, with its
// activity interval, its Baumgarte gains (rates: / tau) and its kind of contact
Constraint rescaled_constraint(const std::shared_ptr<const System>& o, Index k, const Scaling& f) {
  const Constraint& c = o->constraint(k);
  Constraint scaled(c.name(), c.kind(), c.rows(), std::make_shared<ScaledConstraint>(o, k, f));
  const TimeInterval& when = c.active_interval();
  if (std::isfinite(when.begin) || std::isfinite(when.end)) {
    scaled.active_between(when.begin * f.tau, when.end * f.tau);
  }
  if (c.stabilization().enabled()) {
    scaled.stabilize(c.stabilization().alpha / f.tau, c.stabilization().beta / f.tau);
  }
  scaled.mark_drive(c.is_drive());
  if (c.is_unilateral()) scaled.unilateral(c.restitution());
  return scaled;
}

// the surface velocity of a Coulomb contact in the units of f: u~ = s u / tau,
// u~' = s u' / tau² at the original (q, q', t)
SurfaceVelocityFn rescaled(SurfaceVelocityFn u, const Scaling& f) {
  if (!u) return u;
  return [u = std::move(u), f](const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               Eigen::Ref<VectorXd> uo, Eigen::Ref<VectorXd> udo) {
    const Original x(f, q, qd, t);
    u(x.q, x.qd, x.t, uo, udo);
    uo *= f.s / f.tau;
    udo *= f.s / (f.tau * f.tau);
  };
}

// Non-ideal force i of `o` in the units of f, C~ = mu C / s at the original state (a
// generalized force, like Q). A Coulomb contact is made anew from its law, with the same
// coefficients and normal constraint (the rescaled one: N~ = mu N / s) and its velocities in
// the new units (regularization eps × s / tau, surface velocity as above), so that the
// simulation's stick/slip switching applies to it as to the original. Any other force may read
// the ideal reactions (a C of N_c and lambda_c, four_bar_friction's pin friction), which the
// rescaled workspace holds in its own units (N × mu / s, lambda × mu / c): it is evaluated
// with those of the original system at the original state, from a forward dynamics of the
// original in a workspace of the wrapper's own (a test's wrapper, used by one run at a time).
NonIdealForce rescaled_nonideal(const std::shared_ptr<const System>& o, Index i, const Scaling& f,
                                const SolverOptions& solver) {
  for (const FrictionContact& contact : o->friction_contacts()) {
    if (contact.force != i) continue;
    CoulombFriction law;
    law.name = o->nonideal_name(i);
    law.constraint = o->constraint(contact.normal_constraint).name();
    law.mu = contact.mu;
    law.mu_static = contact.mu_static;
    law.regularization_velocity = contact.eps * f.s / f.tau;
    if (const ContactKinematics& kin = contact.kinematics) {
      // at a contact point: v_P~ = (s / tau) v_P = J q~', so J~(q~) = J(q~ / s) and its bias
      // J~' q~' = (s / tau²) J' q' (N~ = |w·R~| / |w|² = mu N / s follows)
      law.kinematics = kin;
      law.kinematics.evaluate = [kin, f](const Eigen::Ref<const VectorXd>& q,
                                         const Eigen::Ref<const VectorXd>& qd, double t,
                                         ConstraintScratch* s, Eigen::Ref<MatrixXd> J,
                                         Eigen::Ref<VectorXd> bias) {
        const Original x(f, q, qd, t);
        kin.evaluate(x.q, x.qd, x.t, s, J, bias);
        bias *= f.s / (f.tau * f.tau);
      };
      return coulomb_friction(law);
    }
    law.coordinates = contact.coordinates;
    law.surface_velocity = rescaled(contact.surface_velocity, f);
    return coulomb_friction(law);
  }
  auto mirror = std::make_shared<Workspace>(*o, solver);
  return NonIdealForce(
      o->nonideal_name(i),
      [o, i, f, mirror](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t, const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
        const Original x(f, q, qd, t);
        forward_dynamics(*o, *mirror, x.q, x.qd, x.t);
        o->nonideal(i)(x.q, x.qd, x.t, IdealForceInfo(*o, *mirror), C);
        C *= f.mu / f.s;
      });
}

// `sys` in the units of f (see the file comment)
System rescaled(std::shared_ptr<const System> o, const Scaling& f,
                const SolverOptions& solver = {}) {
  const double mass = f.mu * f.tau * f.tau / (f.s * f.s);
  SystemBuilder b(o->coordinate_names());
  b.scratch([o] { return o->make_scratch(); });
  if (o->mass_is_block_diagonal()) {
    for (const MassBlock& blk : o->mass_blocks()) {
      if (blk.constant()) {
        b.mass_block(blk.offset, MatrixXd(mass * blk.value));
        continue;
      }
      MassBlockFn fn = [fn = blk.fn, f, mass](const Eigen::Ref<const VectorXd>& q, double t,
                                              Eigen::Ref<MatrixXd> Mk) {
        const Original x(f, q, t);
        fn(x.q, x.t, Mk);
        Mk *= mass;
      };
      if (blk.singular) {
        b.singular_mass_block(blk.offset, blk.size, fn);
      } else {
        b.mass_block(blk.offset, blk.size, fn);
      }
    }
  } else if (o->mass_is_constant()) {
    MatrixXd M(o->coordinate_count(), o->coordinate_count());
    o->mass_matrix(VectorXd::Zero(o->coordinate_count()), 0.0, M);
    b.mass_matrix(MatrixXd(mass * M));
  } else {
    b.mass_matrix(MassMatrixScratchFn([o, f, mass](const Eigen::Ref<const VectorXd>& q, double t,
                                                   CallableScratch* s, Eigen::Ref<MatrixXd> M) {
      const Original x(f, q, t);
      o->mass_matrix(x.q, x.t, s, M);
      M *= mass;
    }));
  }
  b.forces(ForceScratchFn([o, f](const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s,
                                 Eigen::Ref<VectorXd> Q) {
    const Original x(f, q, qd, t);
    o->forces(x.q, x.qd, x.t, s, Q);
    Q *= f.mu / f.s;
  }));
  if (o->has_potential()) {
    b.potential_energy(PotentialScratchFn(
        [o, f](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s) {
          const Original x(f, q, t);
          return f.mu * o->potential_energy(x.q, x.t, s);
        }));
  }
  if (o->has_external_power()) {
    b.external_power(
        PowerScratchFn([o, f](const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s) {
          const Original x(f, q, qd, t);
          return f.mu / f.tau * o->external_power(x.q, x.qd, x.t, s);
        }));
  }
  b.accounts_for_energy(o->accounts_for_energy());
  if (o->switch_count() > 0) {
    b.switching_functions(o->switch_names(), [o, f](const Eigen::Ref<const VectorXd>& q,
                                                    const Eigen::Ref<const VectorXd>& qd, double t,
                                                    CallableScratch* s, Eigen::Ref<VectorXd> g) {
      const Original x(f, q, qd, t);
      o->switching_functions(x.q, x.qd, x.t, s, g);
    });
  }
  // (the contacts' stick constraints come with their rescaled laws, below)
  std::vector<bool> stick(std::size_t(o->constraint_count()), false);
  for (const FrictionContact& contact : o->friction_contacts()) {
    stick[std::size_t(contact.stick_constraint)] = true;
  }
  for (Index k = 0; k < o->constraint_count(); ++k) {
    if (!stick[std::size_t(k)]) b.add(rescaled_constraint(o, k, f));
  }
  for (Index i = 0; i < o->nonideal_count(); ++i) b.add(rescaled_nonideal(o, i, f, solver));
  return b.build();
}

// the options of a run in the units of f. The integrators' atol is absolute in the units of q
// (docs/simulation.md, "Scales and tolerances": not yet relative), so a model written in other
// length units states it in those: atol × s (on q', atol × s times the run's rate decade, which
// the lengths' rescalings leave and time × 10 divides by 10)
SimulationOptions rescaled(SimulationOptions o, const Scaling& f) {
  o.atol *= f.s;
  o.t_start *= f.tau;
  o.t_end *= f.tau;
  o.step *= f.tau;
  o.max_step *= f.tau;
  o.output_every *= f.tau;
  for (double& t : o.output_at) t *= f.tau;
  for (double& t : o.breakpoints) t *= f.tau;
  o.baumgarte_alpha /= f.tau;
  o.baumgarte_beta /= f.tau;
  return o;
}

// `ctrl` in the units of f: its nominal model rescaled as the plant, its requirements as
// constraints (rows phi~ = c phi, A~ = c A / s, b~ = c b / tau², error-dynamics gains / tau),
// so that its force is Q_c~ = mu Q_c / s. Its law is kept: the weight N of the weighted law
// (the least Q_cᵀ N Q_c) at the original state, since scaling every Q_c by mu / s leaves the
// minimizer unchanged; the actuation S likewise (u~ = mu u / s). The robust term's bound is a
// requirement acceleration (× c / tau²), its boundary layer a requirement velocity (× c / tau).
Controller rescaled(const Controller& ctrl, const Scaling& f) {
  ControllerBuilder b(
      rescaled(std::make_shared<const System>(ctrl.model()), f, ctrl.options().solver));
  const auto req = std::make_shared<const System>(ctrl.requirements());
  for (Index k = 0; k < req->constraint_count(); ++k) b.require(rescaled_constraint(req, k, f));
  if (ctrl.law() == ControlLaw::kWeighted) {
    const Index n = ctrl.coordinate_count();
    if (ctrl.weight_is_constant()) {
      MatrixXd N(n, n);
      ctrl.weight(VectorXd::Zero(n), VectorXd::Zero(n), 0.0, N);
      b.weighted(N);
    } else {
      b.weighted(WeightFn([ctrl, f](const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double t,
                                    Eigen::Ref<MatrixXd> N) {
        const Original x(f, q, qd, t);
        ctrl.weight(x.q, x.qd, x.t, N);
      }));
    }
  }
  if (!ctrl.actuated_coordinates().empty()) {
    std::vector<std::string> names;
    for (Index i : ctrl.actuated_coordinates()) {
      names.push_back(ctrl.model().coordinate_names()[std::size_t(i)]);
    }
    b.actuated(names);
  } else if (!ctrl.fully_actuated()) {
    b.actuation(ctrl.actuation());
  }
  if (ctrl.robust()) {
    RobustControl r = *ctrl.robust();
    r.bound *= f.c / (f.tau * f.tau);
    r.boundary_layer *= f.c / f.tau;
    b.robust(r);
  }
  b.options(ctrl.options());
  return b.build();
}

// Examples whose run is accurate to less than 1e-8 at their own settings (the motion, or with
// `force` the control force), by file, with the reason, or "". The suite compares them at a
// tolerance of their own accuracy: kAccuracyFactor times the difference d_ref between the run
// and a reference run at rtol and atol / 100, and asks that d_ref be above 1e-8 (else the
// example is accurate and belongs at 1e-8). Measured (d_ref; the rescaled runs' differences):
// shaken_frame 1.2e-6 (1.1e-6 to 1.9e-6, rows x 1e±8: 0), four_bar_coulomb 1.2e-6 (1.7e-7 to
// 3.4e-6), four_bar_friction 7.7e-8 (8.9e-10 to 2.3e-7), leg_four_bar_knee's control force
// 8.5e-7 (1.4e-8 to 3.5e-7), control_uncertain_duffing's control force 8.1e-8. (rtol x (1 + 1e-6),
// the probe used before, moves a run along its own step sequence only and understates its
// error: 5.6e-9 for four_bar_friction, 3.2e-9 for the leg's force.)
std::string inaccurate(const std::string& file, bool force = false) {
  if (force) {
    if (file == "leg_four_bar_knee.yaml") {
      return "its hip's regularized Coulomb torque starts at rest, where the control force that "
             "cancels it follows the hip's rate through the regularization's steep slope: the "
             "motion is accurate to 1e-10, the force to about 1e-6";
    }
    if (file == "control_uncertain_duffing.yaml") {
      return "its robust term saturates in a boundary layer (a steep, smooth switch of the "
             "tracking error's sign): the motion is accurate to 1e-9, the force to about 1e-7";
    }
    return "";
  }
  if (file == "shaken_frame.yaml") {
    return "its ground acceleration is a 50 Hz record interpolated linearly, with a kink at every "
           "sample that dopri5's steps straddle (the samples are not breakpoints)";
  }
  if (file == "four_bar_coulomb.yaml") {
    return "its Coulomb contact on the rocker passes the rocker's dead centres, where the "
           "friction turns within a step";
  }
  if (file == "four_bar_friction.yaml") {
    return "its pin friction's sign is regularized (eps 0.01 rad/s) and stiff near rest; the "
           "rescaled runs' wrapper is not the cause: rows x 1e+-8, which go through it with the "
           "original's step sequence, agree to 9e-10";
  }
  return "";
}
constexpr double kAccuracyFactor = 5.0;  // two runs within d_ref each, with a margin

std::vector<std::string> example_files() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(kExamples)) {
    if (e.path().extension() == ".yaml") files.push_back(e.path().filename().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// the run's duration, shortened for the slow examples (CI budget: this suite well under a
// minute) and for those whose motion amplifies a perturbation of roundoff size beyond 1e-8 over
// their whole run (the Bricard loop near its singular pose, the chaotic double pendulum); each
// keeps several swings
double duration(const std::string& file, const SimulationOptions& o) {
  const std::map<std::string, double> kShort = {
      {"bricard.yaml", 1.0},
      {"double_pendulum.yaml", 3.0},
      {"double_four_bar.yaml", 3.0},
      {"double_four_bar_redundant.yaml", 3.0},
      {"double_four_bar_bodies.yaml", 3.0},
      {"double_four_bar_bodies_redundant.yaml", 3.0},
      // half a revolution: under time × 10 the integrators' atol, when it was absolute in q'
      // (now times the run's rate decade, docs/simulation.md), was ten times looser on the
      // slower velocities, which over the whole revolution left 1.09e-8
      {"rolling_disk_bodies.yaml", 0.5 * (o.t_end - o.t_start)},
      // a quarter of a second of its 2: the 33-coordinate humanoid's eight runs took 64 s,
      // and under time × 10 the atol then absolute in q' (as above) left 6.0e-8 at 2 s
      {"humanoid_zero_gravity.yaml", 0.25},
      // half of its 12 s: over the whole run four rescalings (rows x 1e±8 among them, which
      // change no tolerance) left 1.3e-8 to 1.4e-8, the spin-up's amplified roundoff
      {"turntable_block.yaml", 6.0}};
  const auto it = kShort.find(file);
  return it == kShort.end() ? o.t_end - o.t_start : it->second;
}

// max over the entries of |b / factor − a|, relative to max |a| (the motion: a = q over the
// run, factor s; the control force: a = Q_c, factor mu / s)
double relative_difference(const std::vector<double>& a, const std::vector<double>& b,
                           double factor) {
  double largest = 0.0, diff = 0.0;
  for (const double x : a) largest = std::max(largest, std::abs(x));
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    diff = std::max(diff, std::abs(b[i] / factor - a[i]));
  }
  return diff / std::max(largest, 1e-300);
}
double motion_difference(const Trajectory& a, const Trajectory& b, double s) {
  return relative_difference(a.q, b.q, s);
}

// a run of `plant` (under `ctrl`, when not null: simulate_controlled, as run_model does)
struct RunResult {
  Trajectory plant;
  std::vector<double> Qc_control;  // N × n, empty without a controller
};
RunResult run(const System& plant, const Controller* ctrl, const VectorXd& q0, const VectorXd& qd0,
              const SimulationOptions& o) {
  if (ctrl == nullptr) return {simulate(plant, q0, qd0, o), {}};
  ControlledTrajectory c = simulate_controlled(*ctrl, plant, q0, qd0, o);
  return {std::move(c.plant), std::move(c.Qc_control)};
}

class Metamorphic : public ::testing::TestWithParam<std::string> {};

TEST_P(Metamorphic, SameMotionInRescaledUnits) {
  const std::string file = GetParam();
  const Model model = load_model(kExamples + "/" + file);
  SimulationOptions o = model.options;
  o.t_end = o.t_start + duration(file, o);
  o.project_initial = model.project_initial || o.project_initial;
  const Controller* ctrl = model.controller.get();
  const RunResult base = run(model.system, ctrl, model.q0, model.qd0, o);
  ASSERT_EQ(base.plant.stats.status, Status::kOk) << file << ": " << base.plant.stats.message;
  // the tolerances: 1e-8, or an inaccurate example's own accuracy (see inaccurate)
  double motion_tolerance = 1e-8, force_tolerance = 1e-8;
  const std::string motion_why = inaccurate(file), force_why = inaccurate(file, true);
  if (!motion_why.empty() || !force_why.empty()) {
    SimulationOptions fine = o;
    fine.rtol /= 100.0;
    fine.atol /= 100.0;
    const RunResult ref = run(model.system, ctrl, model.q0, model.qd0, fine);
    ASSERT_EQ(ref.plant.stats.status, Status::kOk) << ref.plant.stats.message;
    // 5 d_ref, d_ref the difference from the reference, which must be above 1e-8
    auto own_accuracy = [&](const char* what, const std::string& why, double d_ref) {
      EXPECT_GT(d_ref, 1e-8) << file << "'s " << what << " is accurate now: compare it at 1e-8";
      std::cout << file << ": " << what << " compared at " << kAccuracyFactor * d_ref << ": " << why
                << "\n";
      return kAccuracyFactor * d_ref;
    };
    if (!motion_why.empty()) {
      motion_tolerance =
          own_accuracy("motion", motion_why, motion_difference(base.plant, ref.plant, 1.0));
    }
    if (!force_why.empty()) {
      force_tolerance = own_accuracy("control force", force_why,
                                     relative_difference(base.Qc_control, ref.Qc_control, 1.0));
    }
  }
  const auto original = std::make_shared<const System>(model.system);
  for (const Scaling& f : kScalings) {
    SCOPED_TRACE(std::string(file) + ", " + f.label);
    const System sys = rescaled(original, f, o.solver);
    const VectorXd q0 = model.q0 * f.s, qd0 = model.qd0 * (f.s / f.tau);
    std::optional<Controller> scaled_ctrl;
    if (ctrl) scaled_ctrl.emplace(rescaled(*ctrl, f));
    const RunResult r = run(sys, scaled_ctrl ? &*scaled_ctrl : nullptr, q0, qd0, rescaled(o, f));
    // (a controlled run's energy balance too: the plant's kinetic energy used to be the
    // augmented run's less z'ᵀz'/2, which lost it entirely under lengths x 1e-3 and masses x 1e6,
    // where the control's effort z' grows with the square of the forces)
    ASSERT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
    ASSERT_EQ(r.plant.t.size(), base.plant.t.size());
    EXPECT_LE(motion_difference(base.plant, r.plant, f.s), motion_tolerance);
    if (ctrl) {
      EXPECT_LE(relative_difference(base.Qc_control, r.Qc_control, f.mu / f.s), force_tolerance);
    }
    EXPECT_LE(r.plant.stats.steps, 2 * base.plant.stats.steps + 2);
    EXPECT_GE(2 * r.plant.stats.steps + 2, base.plant.stats.steps);
  }
}

// Rows written with factors whose squares under- or overflow (1e-170, 1e170): the bodies' double
// four-bar on either engine gives the motion of its unscaled rows (the rows were dropped as
// zero rows, with status ok, before the equilibration); 1 s of its 10
TEST(MetamorphicExtremes, RowFactorsBeyondTheSquaresRange) {
  const Model model = load_model(kExamples + "/double_four_bar_bodies.yaml");
  const auto original = std::make_shared<const System>(model.system);
  for (const Engine engine : {Engine::kDense, Engine::kSparse}) {
    SimulationOptions o = model.options;
    o.t_end = o.t_start + 1.0;
    o.solver.engine = engine;
    const Trajectory base = simulate(model.system, model.q0, model.qd0, o);
    ASSERT_EQ(base.stats.status, Status::kOk) << base.stats.message;
    for (const double c : {1e-170, 1e170}) {
      SCOPED_TRACE(std::string(engine == Engine::kDense ? "dense" : "sparse") + ", rows x " +
                   std::to_string(std::log10(c)));
      Scaling f{"rows"};
      f.c = c;
      const Trajectory run = simulate(rescaled(original, f), model.q0, model.qd0, o);
      ASSERT_EQ(run.stats.status, Status::kOk) << run.stats.message;
      EXPECT_LE(motion_difference(base, run, 1.0), 1e-8);
      EXPECT_EQ(run.stats.steps, base.stats.steps);
    }
  }
}

// The box of test_contact_flat_box.cpp (2 kg, half-extents 0.2 × 0.1 × 0.05 m, e = 0.3, μ = 0.5)
// dropped flat from 0.5 m while it slides at `speed` m/s, 30° to x, to 10 ms after its landing
// (four redundant corners: ContactDynamics::friction_split), in SI units
std::string oblique_box(double speed) {
  const double angle = std::numbers::pi / 6.0;
  char velocity[80];
  std::snprintf(velocity, sizeof velocity, "[%.17g, %.17g, 0]", speed * std::cos(angle),
                speed * std::sin(angle));
  return "parameters: {m: 2, g: 9.81, hx: 0.2, hy: 0.1, hz: 0.05, h0: 0.5, e: 0.3}\n"
         "bodies:\n"
         "  - {name: box, type: rigid, mass: m, inertia: [m*(hy^2+hz^2)/3, m*(hx^2+hz^2)/3, "
         "m*(hx^2+hy^2)/3], position: [0, 0, h0 + hz], velocity: " +
         std::string(velocity) +
         "}\n"
         "forces:\n  - {type: gravity, g: [0, 0, -g]}\n"
         "contacts:\n  - {name: lid, body: box, shape: box, size: [hx, hy, hz], restitution: e}\n"
         "nonideal:\n  - {friction: coulomb, constraint: lid, mu: 0.5}\n"
         "simulate: {t_end: " +
         std::to_string(std::sqrt(2.0 * 0.5 / 9.81) + 0.01) +
         ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0.005}\n";
}

// The oblique flat landing (its friction impact's LCP of four redundant corners, scaled so that
// its blocks depend neither on the units nor on the rows' factors) gives the same impulses and the
// same motion with every row × 1e±8 and in mm, g, ms, at 10, 5 and 1 m/s (it slides through, the
// pyramid's first axis along the slip; it stops): the velocities after against Coulomb's closed
// form of test_contact_flat_box.cpp (v⁺ = max(1 − Δ / |v|, 0) v, Δ = μ (1 + e) v0), each corner's
// impulse against the SI run's (Λ~ = mu tau / c Λ) to 1e-9 relative. Before the rows' factor was
// undone (Λ scaled alone by 10 / class(W_ii), its row not), rows × 1e8 left each normal row 1e8
// against the friction rows; with the pyramid along the slip, Lemke's answer of rows × 1e8 (γ ~
// 1e17, a corner pushing and separating) passed the LCP's test relative to ‖z‖, the impact was
// made plastic and the box sank: the run located the same event at one instant for ever.
TEST(MetamorphicObliqueLanding, SameLandingWithRowsTimes1e8AndInMmGMs) {
  const Scaling scalings[] = {
      {"rows x1e8", 1, 1, 1, 1e8}, {"rows x1e-8", 1, 1, 1, 1e-8}, {"mm, g, ms", 1e3, 1e3, 1e3}};
  const double e = 0.3, mu = 0.5, g = 9.81, t0 = std::sqrt(2.0 * 0.5 / g), v0 = g * t0;
  const double delta = mu * (1.0 + e) * v0;
  for (const double speed : {10.0, 5.0, 1.0}) {
    const double vx = speed * std::cos(std::numbers::pi / 6.0),
                 vy = speed * std::sin(std::numbers::pi / 6.0);
    const double keep = std::max(1.0 - delta / speed, 0.0);  // (Coulomb: Δ against the slip)
    const double ex = keep * vx, ey = keep * vy;
    const Model model = parse_model(oblique_box(speed));
    const SimulationOptions& o = model.options;
    const Trajectory base = simulate(model.system, model.q0, model.qd0, o);
    ASSERT_EQ(base.stats.status, Status::kOk) << speed << " m/s: " << base.stats.message;
    const auto velocity = [](const Trajectory& tr, const char* name) {
      const auto& names = tr.coordinate_names;
      const auto c = std::size_t(std::find(names.begin(), names.end(), name) - names.begin());
      EXPECT_LT(c, names.size()) << name;
      return tr.qd[(tr.t.size() - 1) * std::size_t(tr.n) + c];
    };
    EXPECT_NEAR(velocity(base, "box.x"), ex, 1e-9) << speed << " m/s";
    EXPECT_NEAR(velocity(base, "box.y"), ey, 1e-9) << speed << " m/s";
    // each corner's impulse by its name (lid.0 … lid.3)
    const auto impulses = [](const Trajectory& tr) {
      std::map<std::string, double> by_corner;
      for (const ContactEvent& ev : tr.stats.contact_events) {
        if (ev.kind == ContactEvent::Kind::kImpact)
          by_corner[tr.constraint_names[std::size_t(ev.constraint)]] += ev.impulse;
      }
      return by_corner;
    };
    const std::map<std::string, double> base_impulses = impulses(base);
    ASSERT_EQ(base_impulses.size(), 4u) << speed << " m/s";
    const auto original = std::make_shared<const System>(model.system);
    for (const Scaling& f : scalings) {
      SCOPED_TRACE(std::to_string(speed) + " m/s, " + f.label);
      const System sys = rescaled(original, f, o.solver);
      const Trajectory r = simulate(sys, model.q0 * f.s, model.qd0 * (f.s / f.tau), rescaled(o, f));
      ASSERT_EQ(r.stats.status, Status::kOk) << r.stats.message;
      ASSERT_EQ(r.t.size(), base.t.size());
      EXPECT_LE(motion_difference(base, r, f.s), 1e-9);
      EXPECT_NEAR(velocity(r, "box.x") * f.tau / f.s, ex, 1e-9);
      EXPECT_NEAR(velocity(r, "box.y") * f.tau / f.s, ey, 1e-9);
      const std::map<std::string, double> scaled = impulses(r);
      ASSERT_EQ(scaled.size(), 4u);
      for (const auto& [corner, impulse] : base_impulses) {
        ASSERT_EQ(scaled.count(corner), 1u) << corner;
        EXPECT_NEAR(scaled.at(corner) * f.c / (f.mu * f.tau), impulse, 1e-9 * impulse) << corner;
      }
      EXPECT_LE(r.stats.steps, 2 * base.stats.steps + 2);
      EXPECT_GE(2 * r.stats.steps + 2, base.stats.steps);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Examples, Metamorphic, ::testing::ValuesIn(example_files()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param.substr(0, p.param.size() - 5);
                           for (char& ch : n) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return n;
                         });

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
