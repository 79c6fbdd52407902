// SPDX-License-Identifier: BSD-3-Clause
// detail::simulate_observed (dynamics/internal.hpp) with a second observer, `started`, called
// with the run's workspace once it is made, before the first evaluation, and with each workspace
// the run makes later (the branch check's, Run::branch_workspace): the controlled plant's scratch
// of each then points at that workspace's contact modes (ws.activity_override; the branch
// check's copies the run's), which its controller's model mirrors
// (control/simulate_controlled.cpp, docs/contact.md "Contacts under control"). rate_unit > 0
// replaces the rate decade that set_run_scales finds (Workspace::rate_unit): a controlled plant's
// own. `quad`: integrals of the caller's (Quadratures, below) integrated with the run.
#pragma once

#include <functional>
#include <vector>

#include "dynamics/internal.hpp"

namespace ukdyn::detail {

// A caller's integrals z' = g(q, q', t, z), integrated after the work channels in
// x = [q; q'; W; z] with the plant's own stages and error control (a controlled run's work,
// effort and bounds of the control: control/controlled_quadratures.cpp). First-order: z is not a
// coordinate, so M, the constraints and their factor stay the system's own. Stored unscaled;
// every method's error control (the explicit methods' and BDF's) weighs z_i in a unit of its own:
// its atol is atol · unit_i (docs/simulation.md, "Scales and tolerances"), so that an integral
// whose integrand is 10⁹ times larger in the model's units (the control's effort ∫ |Qc|² dt in g,
// mm, ms) does not ask for steps below the roundoff of t where that integrand jumps.
struct Quadratures {
  Index count = 0;
  // (count, or empty: 1 each) the unit of each z_i in the run (1 for a model in SI units): the
  // explicit methods compare its error with atol · unit_i + rtol · (|z_i| + h |z_i'|), BDF
  // (CVODE) takes atol · unit_i as its absolute tolerance. (BDF once weighed them as q' or q, as
  // before the units: the controlled arm in mm, g, ms stalled at its release, the effort's
  // integrand jumping by ~1e7 at a weight of 1e-12; ControlLift.…UnderBdf…)
  std::vector<double> unit;
  // g after forward_dynamics evaluated ws at (q, q', t) (the callables' scratch holds that
  // evaluation): z (count) in, z' (count) out
  std::function<void(const Workspace& ws, double t, const double* z, double* z_rate)> rate;
  std::vector<double> z0;      // (count) z at the start
  std::vector<double> sample;  // (count) z at the sample being recorded (Run::record)
};

// quad: integrals integrated beside the run (Quadratures; null: none)
Trajectory simulate_observed(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                             const Eigen::Ref<const VectorXd>& qd0,
                             const SimulationOptions& options,
                             const std::function<void(const Workspace&)>& finished,
                             const std::function<void(Workspace&)>& started, double rate_unit = 0.0,
                             Quadratures* quad = nullptr);

}  // namespace ukdyn::detail
