// ConstrainedOde: the first-order system x' = f(t, x), x = [q; q'; W], that the integrators see.
#include <algorithm>
#include <cmath>
#include <limits>

#include "integrator.hpp"
#include "ukdyn/forward.hpp"

namespace ukdyn::detail {

ConstrainedOde::ConstrainedOde(const System& sys, Workspace& ws)
    : sys_(sys), ws_(ws), n_(sys.dofs()), q_(sys.dofs()), qd_(sys.dofs()) {}

void ConstrainedOde::clear_failure() {
  failure_ = Status::kOk;
  failure_message_.clear();
}

void ConstrainedOde::set_window(double a, double b) {
  auto delta = [](double v) { return 1e-13 * std::max(1.0, std::abs(v)); };
  lo_ = std::isfinite(a) ? a + delta(a) : a;
  hi_ = std::isfinite(b) ? b - delta(b) : b;
}

bool ConstrainedOde::operator()(const double* x, double* dxdt, double t_in) {
  ++evaluations_;
  // one-sided at a breakpoint end of the segment
  const double t = std::min(std::max(t_in, lo_), hi_);
  // q, q' from x
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  const Status s = forward_dynamics(sys_, ws_, q_, qd_, t);
  if (s != Status::kOk) {
    if (failure_ == Status::kOk) {
      failure_ = s;
      failure_message_ = describe_status(sys_, ws_);
    }
    for (Index i = 0; i < size(); ++i) dxdt[i] = std::numeric_limits<double>::quiet_NaN();
    return false;
  }
  // x' = [q'; q''; q'ᵀ Qc_nonideal]
  Eigen::Map<VectorXd>(dxdt, n_) = qd_;
  Eigen::Map<VectorXd>(dxdt + n_, n_) = ws_.qdd;
  dxdt[2 * n_] = qd_.dot(ws_.Qc_nonideal);
  return true;
}

}  // namespace ukdyn::detail
