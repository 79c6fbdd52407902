// SPDX-License-Identifier: BSD-3-Clause
// The quadratures beside a controlled plant: simulate_controlled integrates, besides the plant,
// the control's work ∫ Qcᵀq' dt, effort ∫ QcᵀQc dt and absolute work ∫ |Qcᵀq'| dt — and with
// the robust term each row's Lyapunov bound V_i' = −gamma_i V_i + kappa_i epsilon / 2 — exactly,
// with the integrator's own stages and error control: as first-order quadratures z' = g beside
// the plant's state (detail::Quadratures, x = [q; q'; W; z]), g read from the control the force
// evaluation has just computed. (They were unit-mass auxiliary coordinates of an augmented
// system once, whose diag(M, I) every evaluation checked, factorized and solved with: 9 k
// instructions per RK4 step of the 7-DOF Panda, bench/RESULTS.md. Their integrals ∫ z dt, those
// coordinates' positions, are integrated as well, so that the adaptive methods' error control
// weighs what it weighed then and takes the same steps.) (control/controlled_plant.hpp)
#include "control/controlled_plant.hpp"

#include <cmath>
#include <vector>

#include "linalg/scale_class.hpp"

namespace ukdyn::control_detail {

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

detail::Quadratures control_quadratures(const Controller& ctrl, const ControlledPlant& st,
                                        const Eigen::Ref<const VectorXd>& q0,
                                        const Eigen::Ref<const VectorXd>& qd0, double t0) {
  const Index aux = st.aux, m_r = ctrl.requirement_rows();
  const bool robust = ctrl.robust().has_value();
  detail::Quadratures quad;
  quad.count = 2 * aux;
  quad.z0.assign(std::size_t(2 * aux), 0.0);
  quad.rate = [&st](const Workspace& ws, double, const double* z, double* z_rate) {
    st.rates(static_cast<const ControlledScratch&>(*ws.callables), z, z_rate);
  };
  if (robust) {
    ControlWorkspace cws(ctrl);
    evaluate_violations(ctrl.requirements(), cws.req, q0, qd0, t0);
    for (Index i = 0; i < m_r; ++i) {
      const bool holonomic =
          ctrl.requirement(ctrl.row_requirement(i)).kind() == ConstraintKind::kHolonomic;
      const double e = holonomic ? cws.req.phi[i] : cws.req.phi_dot[i];
      const double e_dot = holonomic ? cws.req.phi_dot[i] : 0.0;
      quad.z0[std::size_t(kBounds + i)] = ctrl.lyapunov(i, e, e_dot);
    }
  }
  return quad;
}

std::vector<double> quadrature_units(const Workspace& scales, double duration, Index aux) {
  const double force = scales.energy_unit / (scales.length_scale / 10.0),
               time = detail::scale_class(duration) / 10.0, rate = scales.rate_unit;
  std::vector<double> unit(std::size_t(2 * aux), 1.0);
  for (Index i = 0; i < aux; ++i) unit[std::size_t(i)] = rate;
  unit[std::size_t(kEffort)] = force * force * time * rate * rate;
  unit[std::size_t(aux + kEffort)] = unit[std::size_t(kEffort)] * time;
  return unit;
}

}  // namespace ukdyn::control_detail
