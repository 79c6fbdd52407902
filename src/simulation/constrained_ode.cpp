// SPDX-License-Identifier: BSD-3-Clause
// ConstrainedOde: the first-order system x' = f(t, x), x = [q; q'; W; z], that the integrators
// see, W the work channels of the energy balance, z a caller's quadratures.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "simulation/contact_events.hpp"
#include "simulation/integrator.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn::detail {

WorkLayout::WorkLayout(const System& sys, bool quiet_channels, const Quadratures* quad)
    : quiet(quiet_channels) {
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (sys.constraint(k).is_drive()) drives.push_back(k);
  }
  if (sys.constraint_count() > 0) ideal = count++;
  if (!drives.empty()) drive = count++;
  if (sys.has_external_power()) external = count++;
  if (quad != nullptr && quad->count > 0) {
    quadrature = count;
    count += quad->count;
    quadrature_units.assign(std::size_t(quad->count), 1.0);
    if (!quad->unit.empty()) {
      UKDYN_CHECK(Index(quad->unit.size()) == quad->count,
                  "WorkLayout: Quadratures::unit must have count entries (or none)");
      quadrature_units = quad->unit;
    }
  }
}

double constraint_power(const System& sys, const Workspace& ws, Index k,
                        const Eigen::Ref<const VectorXd>& qd, VectorXd& scratch) {
  return ws.engine->constraint_power(sys, ws, k, qd, scratch);
}

ConstrainedOde::ConstrainedOde(const System& sys, Workspace& ws, bool quiet,
                               double off_manifold_tolerance, const Quadratures* quad)
    : sys_(sys),
      ws_(ws),
      n_(sys.coordinate_count()),
      works_(sys, quiet, quad),
      quad_(works_.quadrature >= 0 ? quad : nullptr),
      rare_(works_.drive >= 0 || quad_ != nullptr),
      channels_(rare_),
      share_(VectorXd::Zero(sys.coordinate_count())),
      violation_rows_(std::size_t(sys.constraint_rows()), 0),
      off_manifold_tolerance_(off_manifold_tolerance) {
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    if (c.kind() == ConstraintKind::kAcceleration) continue;
    for (Index i = 0; i < c.rows(); ++i) violation_rows_[std::size_t(sys.row_offset(k) + i)] = 1;
  }
}

bool ConstrainedOde::explained_by_violation(const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, double t) {
  if (!(off_manifold_tolerance_ > 0.0)) return false;
  // r = A q'' − b (the part of e outside range(A), the rows that cannot all hold)
  ws_.engine->constraint_residual(ws_, ws_.qdd, ws_.tmp_m);
  const double r_max = ws_.tmp_m.cwiseAbs().maxCoeff();
  if (!(r_max > 0.0)) return false;
  // phi, phi' (psi) of every row at this state
  evaluate_violations(sys_, ws_, q, qd, t);
  // largest violation among the rows carrying r; none may be of acceleration form
  double violation = 0.0;
  for (Index i = 0; i < ws_.tmp_m.size(); ++i) {
    if (std::abs(ws_.tmp_m[i]) < kResidualShare * r_max) continue;
    if (!violation_rows_[std::size_t(i)]) return false;
    // (relative to each row's scale, as the projections measure it)
    violation = std::max({violation, std::abs(ws_.phi[i]) / ws_.phi_scale[i],
                          std::abs(ws_.phi_dot[i]) / ws_.phi_dot_scale[i]});
  }
  return violation > off_manifold_tolerance_;
}

void ConstrainedOde::clear_failure() {
  failure_ = Status::kOk;
  failure_message_.clear();
}

Status ConstrainedOde::take_failure(std::string& description) {
  const Status s = failure_;
  // describe_status() says "<status> at t = <time>[ in …]: …": the time is the trial stage's
  description = failure_message_;
  if (const auto at = description.find(" at t = "); at != std::string::npos) {
    const auto end = description.find_first_of(" :", at + 8);
    description.erase(at, end == std::string::npos ? std::string::npos : end - at);
  }
  clear_failure();
  return s;
}

std::string left_domain(const char* method, double t, double h, const std::string& description) {
  char text[320];
  std::snprintf(text, sizeof text,
                "%s: no step beyond t = %.17g succeeds: every attempt, down to the smallest "
                "step (h = %.3g), reaches a state where the model cannot be evaluated (the "
                "solution leaves the model's domain there): ",
                method, t, h);
  return text + description;
}

void ConstrainedOde::set_window(double a, double b) {
  auto delta = [](double v) { return 1e-13 * std::max(1.0, std::abs(v)); };
  lo_ = std::isfinite(a) ? a + delta(a) : a;
  hi_ = std::isfinite(b) ? b - delta(b) : b;
}

// (out of line: a run without drives, quadratures and contacts, the common one, pays only for
// the test)
void ConstrainedOde::rare_channels(const double* x, double* dxdt, double t, double drive) const {
  double* w = dxdt + 2 * n_;
  if (works_.drive >= 0) w[works_.drive] = works_.scale(works_.drive, ws_.energy_unit) * drive;
  // z' = g(q, q', t, z), after the evaluation that g reads
  if (quad_ != nullptr) quad_->rate(ws_, t, x + 2 * n_ + works_.quadrature, w + works_.quadrature);
  if (screen_) screen_(t, x);
}

bool ConstrainedOde::operator()(const double* x, double* dxdt, double t_in) {
  ++evaluations_;
  // one-sided at a breakpoint end of the segment
  const double t = std::min(std::max(t_in, lo_), hi_);
  // q, q' from x (views: no copy)
  const Eigen::Map<const VectorXd> q(x, n_), qd(x + n_, n_);
  Status s = forward_dynamics(sys_, ws_, q, qd, t);
  // off the manifold, an inconsistency its violation explains: the least-squares q''
  if (s == Status::kInconsistentConstraints && explained_by_violation(q, qd, t)) {
    ++least_squares_;
    ws_.status = s = Status::kOk;
  }
  if (s != Status::kOk) {
    if (failure_ == Status::kOk) {
      failure_ = s;
      failure_message_ = describe_status(sys_, ws_);
    }
    for (Index i = 0; i < size(); ++i) dxdt[i] = std::numeric_limits<double>::quiet_NaN();
    return false;
  }
  // x' = [q'; q''; q'ᵀ Qc_nonideal; q'ᵀ Qc_ideal − P_drive; P_drive; P_ext; g] (without
  // non-ideal forces Qc_nonideal is zero, and so is its power)
  Eigen::Map<VectorXd>(dxdt, n_) = qd;
  Eigen::Map<VectorXd>(dxdt + n_, n_) = ws_.qdd;
  double* w = dxdt + 2 * n_;
  const double unit = ws_.energy_unit;
  w[works_.nonideal] = sys_.nonideal_count() > 0
                           ? works_.scale(works_.nonideal, unit) * qd.dot(ws_.Qc_nonideal)
                           : 0.0;
  double drive = 0.0;
  for (Index k : works_.drives) {
    if (ws_.active[std::size_t(k)]) drive += constraint_power(sys_, ws_, k, qd, share_);
  }
  // (in the energy unit, the quiet channels scaled by 2⁻³², see WorkLayout)
  if (works_.ideal >= 0) {
    w[works_.ideal] = works_.scale(works_.ideal, unit) * (qd.dot(ws_.Qc_ideal) - drive);
  }
  if (works_.external >= 0) {
    w[works_.external] =
        works_.scale(works_.external, unit) * sys_.external_power(q, qd, t, ws_.callables.get());
  }
  // the unilateral contacts' release screen, then P_drive, the quadratures z' = g(q, q', t, z)
  // and the slip screen (one test for all: most runs have none)
  if (rare_) [[unlikely]] {
    if (contacts_ != nullptr) contacts_->screen(t);
    if (channels_) rare_channels(x, dxdt, t, drive);
  }
  return true;
}

}  // namespace ukdyn::detail
