// SPDX-License-Identifier: BSD-3-Clause
// The controlled plant (not installed): the plant (a System that may differ from the controller's
// nominal model) with the control in its force, as simulate_controlled runs it. The control is
// evaluated inside the plant's force callable with the control workspace in the controlled
// system's per-workspace scratch (ControlledScratch), so an evaluation allocates nothing and one
// controlled System serves several threads, each with its own Workspace; the run's control
// statistics are read from that scratch after the run.
//
// Its stages, one file each: controlled_plant.cpp (the plant's force with the control in it, the
// controlled System built from the plant), controlled_quadratures.cpp (the control's work,
// effort and bounds integrated beside the plant), controlled_reports.cpp (the run's columns and
// its failure's diagnosis); the run itself is simulate_controlled.cpp.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "control/contact_modes.hpp"
#include "simulation/observed_run.hpp"
#include "ukdyn/control/control.hpp"

namespace ukdyn::control_detail {

// the quadratures z: work, effort, absolute work, then one bound state per requirement row
inline constexpr Index kWork = 0, kEffort = 1, kWorkAbs = 2, kBounds = 3;

struct ControlledScratch;

// --- the control inside the plant's force ------------------------------------------------------

// The controlled plant's description (immutable, shared by the controlled system's callables):
// the controller and the plant, n plant coordinates and aux quadratures (simulate_controlled's;
// 0 for controlled_system).
struct ControlledPlant {
  ControlledPlant(const Controller& c, const System& p, Index aux_count)
      : ctrl(c), plant(p), n(p.coordinate_count()), aux(aux_count) {}

  // Q ← Q_plant(q, q', t) + Qc_control; NaN when the control fails (controlled_plant.cpp).
  // Cost: one compute_control and settle's, anticipate's
  void force(ControlledScratch& w, const Eigen::Ref<const VectorXd>& q,
             const Eigen::Ref<const VectorXd>& qd, double t, Eigen::Ref<VectorXd> Q) const;
  // z' = (Qcᵀq', QcᵀQc, |Qcᵀq'|, −gamma_i V_i + kappa_i epsilon / 2) of the control that the
  // last force() computed (z: the aux quadratures, V_i = z[kBounds + i]), then y' = z for
  // their integrals y (the aux quadratures after them) (controlled_quadratures.cpp). O(n + m_r).
  void rates(const ControlledScratch& w, const double* z, double* z_rate) const;
  // a requirement not met at t: the run's statistics of it (stats.not_met, max_residual, the
  // first one's time and message, the stick and held notes once). O(m_r)
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

// The plant's description and the controller's model agree (the same coordinates, physical
// constraints of the same names, rows and kinds), else std::invalid_argument naming `who` and
// the difference (controlled_plant.cpp). O(constraints).
void require_same_plant(const Controller& ctrl, const System& plant, const char* who);

// The plant with the control in its force (controlled_plant.cpp). shared: the plant's
// constraints evaluate with the plant's scratch (simulate_controlled's run: a tree's kinematics
// shared with the plant's M and Q); else with their own, as controlled_system has always made
// them. Cost: the plant's description copied (allocates).
System build_controlled(const std::shared_ptr<const ControlledPlant>& st, bool shared);

// The quadratures of a controlled run (controlled_quadratures.cpp): z = (work, effort, absolute
// work, each bound's V_i) from (0, 0, 0, V_i(0)) at (q0, q0', t0), z' from st.rates with the
// control the run's evaluation has just computed (its ControlledScratch), then their integrals
// y = ∫ z dt from 0; each weighed in its unit (quadrature_units). Cost: with
// the robust term, the requirements' violations at the start (one evaluation).
detail::Quadratures control_quadratures(const Controller& ctrl, const ControlledPlant& st,
                                        const Eigen::Ref<const VectorXd>& q0,
                                        const Eigen::Ref<const VectorXd>& qd0, double t0);

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
// (controlled_quadratures.cpp)
std::vector<double> quadrature_units(const Workspace& scales, double duration, Index aux);

// A controlled run whose step size collapsed: when the requirement rows have (nearly) lost
// rank where the control was last evaluated, that is the likely cause, and it replaces the
// driver's general diagnosis in stats.message (its time in the run's unit, time_unit)
// (controlled_reports.cpp). Cost: two evaluations of compute_control and two SVDs of the
// requirement rows (allocates), only for a run that failed so.
void diagnose_requirements(const ControlledPlant& st, const ControlledScratch& w,
                           const Eigen::Ref<const VectorXd>& q0,
                           const Eigen::Ref<const VectorXd>& qd0, double t0,
                           const std::string& time_unit, RunStatistics& stats);

}  // namespace ukdyn::control_detail
