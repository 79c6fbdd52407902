// SPDX-License-Identifier: BSD-3-Clause
// ContactEvents: impacts and releases of unilateral contacts, located and applied
// (docs/contact.md, "In a run").
#include "simulation/contact_events.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::detail {

namespace {
std::string format_t(double v) { return format_short(v); }
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// the units of contact k's gap and gap rate: the units of the classes of its row's scales
// (Workspace::phi_scale, set_run_scales: the classes of ‖a‖ ℓ and ‖a‖ v, 10 for a model in SI
// units; their unit class / 10 is 1 there), so that kTouchGap and the closing speed below are
// relative to the model's lengths and speeds (docs/simulation.md, "Scales and tolerances")
double gap_scale(const System& sys, const Workspace& ws, Index k) {
  return 0.1 * ws.phi_scale[sys.row_offset(k)];
}
double gap_rate_scale(const System& sys, const Workspace& ws, Index k) {
  return 0.1 * ws.phi_dot_scale[sys.row_offset(k)];
}

// the message of contact k's gap g, or else its rate gd, not finite at t: `whose` gap is …
// `where` (…) `after` — status, time, constraint and value, as describe_status says them
std::string nonfinite_gap(const System& sys, Index k, double t, double g, double gd,
                          const char* whose, const char* where, const char* after) {
  const bool gap = !std::isfinite(g);
  const double v = gap ? g : gd;
  return std::string(to_string(Status::kNonFiniteInput)) + " at t = " + format_t(t) +
         " in phi of constraint '" + sys.constraint(k).name() + "': " + whose + " gap" +
         (gap ? "" : " rate") + " is " + (std::isnan(v) ? "nan" : format_t(v)) + where +
         " (its expression outside its domain: the square root or logarithm of a negative "
         "number, a division by zero)" +
         after;
}
}  // namespace

ContactEvents::ContactEvents(const System& sys, Workspace& ws, std::size_t x_size, double span)
    : sys_(sys),
      ws_(ws),
      dyn_(sys),
      n_(sys.coordinate_count()),
      closed_(dyn_.contacts().size(), 0),
      pushes_(dyn_.contacts().size(), 0),
      fastest_(dyn_.contacts().size(), 0.0),
      impacts_(dyn_.contacts().size(), 0),
      left_(dyn_.contacts().size(), kNaN),
      pulled_(dyn_.contacts().size(), kNaN),
      moving_(dyn_.contacts().size(), 0),
      position_(std::size_t(sys.constraint_count()), dyn_.contacts().size()),
      q_(n_),
      qd_(n_),
      xs_(Index(x_size)),
      qd_before_(n_),
      span_(span) {
  for (std::size_t i = 0; i < dyn_.contacts().size(); ++i) {
    position_[std::size_t(dyn_.contacts()[i])] = i;
  }
  closed_rows_.reserve(dyn_.contacts().size());
}

void ContactEvents::apply() {
  closed_rows_.clear();
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    const Index k = dyn_.contacts()[i];
    ws_.activity_override[std::size_t(k)] = closed_[i] ? 1 : 0;
    if (closed_[i]) closed_rows_.push_back(sys_.row_offset(k));
  }
}

double ContactEvents::value(Index i, bool gap, double t, const double* x) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  const Index k = dyn_.contacts()[std::size_t(i)];
  if (gap) {
    double g = 0.0, gd = 0.0;
    dyn_.gap(sys_, ws_, k, q_, qd_, t, g, gd);
    return g;
  }
  // the multiplier of the closed contact (Qc = Aᵀ lambda; pushes when > 0)
  if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return kNaN;
  return multiplier(k);
}

double ContactEvents::multiplier(Index k) const {
  // the whole reaction: the ideal share and what non-ideal forces (friction pressing on the
  // contact: a rod on a rough floor) add to it (docs/contact.md, "Friction")
  const Index row = sys_.row_offset(k);
  return ws_.lambda[row] + ws_.lambda_nonideal[row];
}

double ContactEvents::largest_load() const {
  double largest = 0.0;
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    if (closed_[i]) largest = std::max(largest, std::abs(multiplier(dyn_.contacts()[i])));
  }
  return largest;
}

double ContactEvents::impact_level(Index k, double g, double gd) const {
  // 0, or −kTouchGap when the step starts at a gap within roundoff below 0 (after a release) or
  // touching at a rate of roundoff (an unloaded contact: its gap and rate, combinations of the
  // closed contacts' at the roundoff of the drift control, cross 0 either way in every step —
  // they were taken for impacts at 1e-16 m/s, "separating" ones included); below where it
  // started when that gap opens, g' > 0, after an impact: else each flight of an accumulation
  // of impacts would fall up to kTouchGap further than it rose, and never come to rest — a
  // sphere's gap z − r has the roundoff of z
  const double touch = kTouchGap * gap_scale(sys_, ws_, k);
  const bool still = std::abs(gd) <= still_rate(k);
  if (!(g < 0.0) && !(still && g <= touch)) return 0.0;
  return gd > 0.0 && !still ? std::max(g, -touch) : -touch;
}

double ContactEvents::still_rate(Index k) const {
  // the class of ‖a‖ v of the row / 10 — or the speed of the contact's own impacts, the same
  // number in any units: ‖a‖ adds the columns of lengths and of angles (mm and mm/rad in a
  // plank's gap y + s sin θ), and the class of a plank in mm, g, ms was 1000 times its speeds
  // (1000 mm/ms against 1 m/s in SI units), which took the 9.4e-7 mm/ms at which its supports
  // left the 20th impact of an accumulation for roundoff, closed them while they separated
  // and left it floating up at that rate (u23 3). The fastest impact of the current sequence
  // when it is slower than the class, but not below 1e-6 of it (roundoff of the run's speeds)
  const double unit = gap_rate_scale(sys_, ws_, k);
  const double fastest = fastest_[position_[std::size_t(k)]];
  return kStillRate * (fastest > 0.0 ? std::clamp(fastest, 1e-6 * unit, unit) : unit);
}

double ContactEvents::locate(double t0, double t1, const SegmentHooks::Dense& dense, Index i,
                             bool gap, double level) {
  // bisection to a bracket of 1e-14 |t|: lo on the old side (f >= level), hi across
  double lo = t0, hi = t1;
  const double width = 1e-14 * std::max(1.0, std::abs(t1));
  for (int it = 0; it < 200 && hi - lo > width; ++it) {
    const double mid = 0.5 * (lo + hi);
    dense(mid, xs_.data());
    const double f = value(i, gap, mid, xs_.data());
    if (f >= level) {
      lo = mid;
    } else {
      hi = mid;  // (NaN too: treated as across)
    }
  }
  // an impact restarts on the old side (g >= 0: the jump then sends it back); a release just
  // across (lambda < 0: the LCP there opens it)
  return gap ? (lo > t0 ? lo : hi) : hi;
}

double ContactEvents::search(double t0, const double* x0, double t1, const double* x1,
                             const SegmentHooks::Dense& dense) {
  double first = kNaN;
  event_ = -1;
  nonfinite_event_.clear();
  // the closed contacts that still push in the step's last evaluation (read before any
  // evaluation here overwrites it)
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    pushes_[i] =
        closed_[i] && ws_.status == Status::kOk && multiplier(dyn_.contacts()[i]) > 0.0 ? 1 : 0;
  }
  std::string nonfinite;
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    double te = kNaN;
    nonfinite.clear();
    if (!closed_[i]) {
      // an impact: the gap falls below impact_level
      double g0 = 0.0, gd0 = 0.0, g1 = 0.0, gd1 = 0.0;
      finite_gap(Index(i), t0, x0, g0, gd0);
      const double level = impact_level(dyn_.contacts()[i], g0, gd0);
      // (an open gap or rate that turns non-finite — its expression out of its domain — is no
      // row of the evaluation, so nothing else sees it: the impacts up to the last finite time
      // are located, else the run stops there)
      // (an opening gap: touching or within kTouchGap of it, and g' > 0, after a release or an
      // impact)
      const Index k = dyn_.contacts()[i];
      const bool opening = g0 <= kTouchGap * gap_scale(sys_, ws_, k) && gd0 > still_rate(k);
      double tf = t1;
      if (!finite_gap(Index(i), t1, x1, g1, gd1)) {
        tf = last_finite(t0, x0, t1, x1, dense, Index(i), g1, nonfinite);
      }
      if (g1 < level) {
        te = g0 < level ? t0 : locate(t0, tf, dense, Index(i), true, level);
        // (a moving surface may have crossed before: the first crossing)
        if (te > t0 && moving(Index(i), t1, x0)) {
          if (const double ts = sweep(t0, gd0, te, dense, Index(i), level); ts < te) te = ts;
        }
        nonfinite.clear();
      } else if (!nonfinite.empty()) {
        te = tf;
      } else if (const double ts = moving(Index(i), t1, x0) && !(g0 < level)
                                       ? sweep(t0, gd0, t1, dense, Index(i), level)
                                       : kNaN;
                 !std::isnan(ts)) {
        // a moving surface that sweeps through the body within the step
        te = ts;
      } else if (const double tm = dip(t0, gd0, t1, gd1, dense, Index(i), level); !std::isnan(tm)) {
        // a gap that closes and opens again within the step (two spheres passing through each
        // other in free flight, where one smooth step spans the whole overlap)
        te = g0 < level ? t0 : locate(t0, tm, dense, Index(i), true, level);
      } else {
        continue;
      }
      // an opening gap is hit again only once it turns back (it approaches at the crossing, or
      // at the step's end across its level): a crossing of its level where it still opens is the
      // step's error or its interpolant's at the scale of the opening (BDF's first-order steps: a
      // chord whose gap dips by ~(Δθ)², and a position error of rtol, both far above the gap's rise
      // of 1e-14 in a step after a release at g' ~ 1e-9, or after the last impacts of an
      // accumulation at g' ~ 1e-5), and the restart there found it again in every step, ~1e-12 s
      // apart (the ladder, the rocking block, the cam follower, the bouncing ball under BDF)
      if (opening && nonfinite.empty() && !(g1 < level && gd1 < -still_rate(k)) &&
          !approaches(Index(i), t0, x0, te, dense)) {
        continue;
      }
    } else {
      te = release(t0, x0, t1, x1, dense, Index(i));
      if (std::isnan(te)) continue;
    }
    if (std::isnan(first) || te < first) {
      first = te;
      event_ = Index(i);
      nonfinite_event_ = nonfinite;
    }
  }
  // (the stages up to t1 are screened; a later one — of a rejected longer step — waits for the
  // step that reaches it)
  any_pulled_ = false;
  for (double& p : pulled_) {
    if (!(p > t1)) p = kNaN;
    any_pulled_ = any_pulled_ || !std::isnan(p);
  }
  return first;
}

void ContactEvents::screen_pulls(double t) {
  double largest = -1.0;  // (the largest load, once a multiplier is negative)
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    if (!closed_[i]) continue;
    const double lambda = multiplier(dyn_.contacts()[i]);
    if (!(lambda < 0.0)) continue;
    if (largest < 0.0) largest = largest_load();
    if (lambda < -kUnloaded * largest && !(pulled_[i] <= t)) {
      pulled_[i] = t;
      any_pulled_ = true;
    }
  }
}

bool ContactEvents::pulls(Index i, double t, const double* x) {
  // (the evaluation first, then the largest load of that same evaluation)
  const double lambda = value(i, false, t, x);
  return lambda < -kUnloaded * largest_load();
}

double ContactEvents::release(double t0, const double* x0, double t1, const double* x1,
                              const SegmentHooks::Dense& dense, Index i) {
  // a release: the multiplier turns negative, beyond roundoff of zero (kUnloaded: a corner of a
  // box on four corners at rest carries 0 N, 7e-16 N below it). The step's evaluations screen
  // it: its last one and its stages (screen: a force pulse within one long step of a body at
  // rest, whose state and so whose step size does not see the pulse); no evaluation while it
  // pushes at all of them. The state at t1 decides, else a stage that pulled, confirmed on the
  // dense output at its time (a stage state is not the solution: one of a rejected step, or
  // CVODE's Newton iterates). Bisection then locates where it crossed zero.
  // (the step's end first: where it pulls, the release is located as before the stages were
  // screened, bit for bit)
  const std::size_t c = std::size_t(i);
  double tp = !pushes_[c] && pulls(i, t1, x1) ? t1 : kNaN;
  if (const double ts = pulled_[c]; std::isnan(tp) && ts >= t0 && ts <= t1) {
    dense(ts, xs_.data());
    if (pulls(i, ts, xs_.data())) tp = ts;
  }
  if (std::isnan(tp)) return kNaN;
  // (a multiplier of an indeterminate split that some split holds pushing: no release; x1 or
  // the stage's dense state at tp)
  if (held_ && held_(dyn_.contacts()[c], tp, tp == t1 ? x1 : xs_.data())) return kNaN;
  return value(i, false, t0, x0) < 0.0 ? t0 : locate(t0, tp, dense, i, false, 0.0);
}

bool ContactEvents::moving(Index i, double t, const double* x) {
  if (moving_[std::size_t(i)]) return true;
  // ∂g/∂t: the gap rate at (q, q' = 0, t)
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_.setZero();
  double g = 0.0, gd = 0.0;
  dyn_.gap(sys_, ws_, dyn_.contacts()[std::size_t(i)], q_, qd_, t, g, gd);
  moving_[std::size_t(i)] = std::isfinite(gd) && gd != 0.0 ? 1 : 0;
  return moving_[std::size_t(i)];
}

double ContactEvents::sweep(double t0, double gd0, double t1, const SegmentHooks::Dense& dense,
                            Index i, double level) {
  // the gap at kSweepPoints equally spaced interior points (t0's gap >= level): the first below
  // level is located from the point before it; a rate that falls at one point and rises at the
  // next brackets a dip (dip)
  double lo = t0, gd_lo = gd0, g = 0.0, gd = 0.0;
  for (int j = 1; j <= kSweepPoints; ++j) {
    const double s = t0 + (t1 - t0) * double(j) / double(kSweepPoints + 1);
    dense(s, xs_.data());
    if (!finite_gap(i, s, xs_.data(), g, gd)) return kNaN;  // (the step's end test sees it)
    if (g < level) return locate(lo, s, dense, i, true, level);
    if (const double tm = dip(lo, gd_lo, s, gd, dense, i, level); !std::isnan(tm)) {
      return locate(lo, tm, dense, i, true, level);
    }
    lo = s;
    gd_lo = gd;
  }
  return kNaN;
}

double ContactEvents::dip(double t0, double gd0, double t1, double gd1,
                          const SegmentHooks::Dense& dense, Index i, double level) {
  // the gap falls at t0 and rises at t1: bisection on the sign of its rate g' along the dense
  // output for the minimum in between (to 1e-10 of the step: the gap is flat there)
  if (!(gd0 < 0.0 && gd1 > 0.0)) return kNaN;
  double lo = t0, hi = t1, g = 0.0, gd = 0.0;
  for (int it = 0; it < 40 && hi - lo > 1e-10 * (t1 - t0); ++it) {
    const double mid = 0.5 * (lo + hi);
    dense(mid, xs_.data());
    if (!finite_gap(i, mid, xs_.data(), g, gd)) return kNaN;
    (gd < 0.0 ? lo : hi) = mid;
  }
  dense(lo, xs_.data());
  if (!finite_gap(i, lo, xs_.data(), g, gd)) return kNaN;
  return g < level ? lo : kNaN;
}

bool ContactEvents::approaches(Index i, double t0, const double* x0, double t,
                               const SegmentHooks::Dense& dense) {
  double g = 0.0, gd = 0.0;
  if (t > t0) {
    dense(t, xs_.data());
    if (!finite_gap(i, t, xs_.data(), g, gd)) return true;  // (the step's end test sees it)
  } else if (!finite_gap(i, t0, x0, g, gd)) {
    return true;
  }
  return gd < -still_rate(dyn_.contacts()[std::size_t(i)]);
}

bool ContactEvents::finite_gap(Index i, double t, const double* x, double& g, double& gd) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  dyn_.gap(sys_, ws_, dyn_.contacts()[std::size_t(i)], q_, qd_, t, g, gd);
  return std::isfinite(g) && std::isfinite(gd);
}

double ContactEvents::last_finite(double t0, const double* x0, double t1, const double* x1,
                                  const SegmentHooks::Dense& dense, Index i, double& g,
                                  std::string& message) {
  // bisection to a bracket of 1e-14 |t|: lo finite (or t0), hi not
  double lo = t0, hi = t1, gd = 0.0, g_hi = 0.0, gd_hi = 0.0;
  if (!finite_gap(i, t0, x0, g_hi, gd_hi)) {
    hi = t0;
  } else {
    finite_gap(i, t1, x1, g_hi, gd_hi);
    const double width = 1e-14 * std::max(1.0, std::abs(t1));
    for (int it = 0; it < 200 && hi - lo > width; ++it) {
      const double mid = 0.5 * (lo + hi);
      dense(mid, xs_.data());
      double gm = 0.0, gdm = 0.0;
      if (finite_gap(i, mid, xs_.data(), gm, gdm)) {
        lo = mid;
      } else {
        hi = mid;
        g_hi = gm;
        gd_hi = gdm;
      }
    }
  }
  if (lo > t0) {
    dense(lo, xs_.data());
    finite_gap(i, lo, xs_.data(), g, gd);
  } else {
    finite_gap(i, t0, x0, g, gd);
  }
  message = nonfinite_gap(sys_, dyn_.contacts()[std::size_t(i)], hi, g_hi, gd_hi,
                          "the open unilateral contact's", " there",
                          ", so its impacts cannot be found: the run stops just before it, the "
                          "samples up to there kept");
  return lo;
}

bool ContactEvents::handle(double t, double* x, RunStatistics& stats) {
  if (!nonfinite_event_.empty()) {
    failure_ = nonfinite_event_;
    nonfinite_ = true;
    return false;
  }
  // chattering: the last kChatterEvents impacts and releases within kChatterSpan of the run's
  // span (the sticks and slips listed beside them are not counted)
  if (listed_ >= std::size_t(kChatterEvents)) {
    const double since = recent_[listed_ % std::size_t(kChatterEvents)];
    if (t - since <= kChatterSpan * span_ && !converging()) {
      failure_ = "contacts: " + format_number(kChatterEvents) +
                 " impacts and releases between t = " + format_t(since) + " and " + format_t(t) +
                 ", within " + format_t(kChatterSpan) +
                 " of the run's time span (chattering; docs/contact.md, \"In a run\")";
      return false;
    }
  }
  // the same instant again and again: the contacts touching there and the time
  if (std::abs(t - instant_) <= 1e-14 * std::max(1.0, std::abs(t))) {
    ++instant_events_;
  } else {
    instant_ = t;
    instant_events_ = 1;
  }
  if (instant_events_ > kSameInstantEvents) {
    failure_ = "contacts: " + format_number(kSameInstantEvents) +
               " events handled at t = " + format_t(t) + " (at " + touching_names(t, x) +
               ") without the run moving on: the contacts' answer leaves the same event there "
               "(a contact penetrated and receding, or released and held again); "
               "docs/contact.md, \"In a run\"";
    return false;
  }
  return resolve(t, x, event_, stats);
}

bool ContactEvents::takes_part(std::size_t i, Index event, double g) const {
  return closed_[i] || Index(i) == event ||
         !(g > kTouchGap * gap_scale(sys_, ws_, dyn_.contacts()[i]));
}

std::string ContactEvents::touching_names(double t, const double* x) {
  std::string names;
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    const Index k = dyn_.contacts()[i];
    double g = 0.0, gd = 0.0;
    finite_gap(Index(i), t, x, g, gd);
    if (!takes_part(i, event_, g)) continue;
    names += (names.empty() ? "'" : ", '") + sys_.constraint(k).name() + "' (gap " + format_t(g) +
             ", rate " + format_t(gd) + (closed_[i] ? ", closed)" : ", open)");
  }
  return names.empty() ? std::string("no touching contact") : "the contacts " + names;
}

bool ContactEvents::start(double t, VectorXd& q, VectorXd& qd, double tolerance,
                          RunStatistics& stats) {
  q_ = q;
  qd_ = qd;
  std::vector<std::string> penetrated;
  std::string lines;
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    const Index k = dyn_.contacts()[i];
    double g = 0.0, gd = 0.0;
    dyn_.gap(sys_, ws_, k, q_, qd_, t, g, gd);
    if (!std::isfinite(g) || !std::isfinite(gd)) {
      // (the run stops before its first sample, as for a bilateral constraint's)
      failure_ =
          nonfinite_gap(sys_, k, t, g, gd, "the unilateral contact's", " at the initial state", "");
      nonfinite_ = true;
      std::fill(closed_.begin(), closed_.end(), 0);
      apply();
      return false;
    }
    if (g < -std::max(tolerance, kTouchGap) * gap_scale(sys_, ws_, k)) {
      penetrated.push_back(sys_.constraint(k).name());
      lines += (lines.empty() ? "" : "; ") + std::string("the unilateral constraint '") +
               sys_.constraint(k).name() + "' is penetrated: its gap is " + format_t(g);
    }
  }
  if (!penetrated.empty()) {
    throw InconsistentInitialState(
        InconsistentInitialState::Cause::kPenetrated,
        "ukdyn::simulate: inconsistent initial conditions at t = " + format_t(t) + ": " + lines +
            " (a unilateral constraint needs a gap >= 0)",
        penetrated);
  }
  std::fill(closed_.begin(), closed_.end(), 0);
  xs_.head(n_) = q;
  xs_.segment(n_, n_) = qd;
  if (!resolve(t, xs_.data(), -1, stats)) {
    std::vector<std::string> at;
    for (const Index k : dyn_.failure_contacts()) at.push_back(sys_.constraint(k).name());
    throw ContactStartError("ukdyn::simulate: the initial state's contacts: " + failure_,
                            std::move(at));
  }
  qd = xs_.segment(n_, n_);
  // the gaps that depend explicitly on t (moving surfaces: sweep), seen at the initial positions
  // at 65 times over the run's span (a step's end finds the others)
  for (std::size_t i = 0; i < closed_.size(); ++i) {
    for (int j = 0; j <= 64 && !moving(Index(i), t + span_ * double(j) / 64.0, q.data()); ++j) {
    }
  }
  // an impact at the start changes the initial state itself: the energy balance starts from the
  // state after it (the event keeps its energy_change), with no impact work before the first
  // sample — else E(0) after the impact and W = ΔT leave a residual −ΔT for the whole run
  impact_work_ = 0.0;
  return true;
}

bool ContactEvents::resolve(double t, double* x, Index event, RunStatistics& stats) {
  Eigen::Map<VectorXd> q(x, n_), qd(x + n_, n_);
  const std::size_t K = closed_.size();
  qd_before_ = qd;
  // the touching contacts (closed, the event's, or an open gap within kTouchGap) and their g'
  std::vector<Index> touching, set;
  std::vector<std::size_t> which;
  std::vector<double> v_minus;
  bool approaching = false;
  for (std::size_t i = 0; i < K; ++i) {
    const Index k = dyn_.contacts()[i];
    double g = 0.0, gd = 0.0;
    dyn_.gap(sys_, ws_, k, q, qd, t, g, gd);
    if (!takes_part(i, event, g)) continue;
    which.push_back(i);
    set.push_back(k);
    v_minus.push_back(gd);
    // (an approach at a rate of roundoff is none: no impact, the LCP below decides the mode)
    approaching = approaching || (!closed_[i] && gd < -still_rate(k));
  }
  const Index m = Index(set.size());
  if (m == 0) {
    apply();
    return true;
  }
  const double v_scale =
      std::max(1e-300, Eigen::Map<const VectorXd>(v_minus.data(), m).cwiseAbs().maxCoeff());
  // the release of a closed contact: only the closed set changes
  const bool release = event >= 0 && closed_[std::size_t(event)];
  if (!dyn_.prepare(sys_, ws_, q, qd, t, set, approaching && !release)) {
    failure_ = "contacts at t = " + format_t(t) + ": the mass matrix is not positive definite";
    return false;
  }
  if (approaching && !release) {
    // the impact: Newton's restitution per contact; e = 0 below the rest speed
    VectorXd e(m);
    std::vector<bool> rests(std::size_t(m), false), held(std::size_t(m), false);
    std::vector<double> left_at(std::size_t(m), 0.0);  // (held) g'⁺ before it was held
    double rest_fastest = 0.0;  // the fastest impact of the sequences that rest here (0: none)
    // (the fastest landing whose flight the integrator could not follow: set_flight_tolerance)
    double unresolved_speed = 0.0;
    std::vector<double> apex(std::size_t(m), 0.0);  // (unresolved) the flight's estimated apex
    for (Index j = 0; j < m; ++j) {
      const std::size_t i = which[std::size_t(j)];
      const double speed = -v_minus[std::size_t(j)];
      e[j] = sys_.constraint(set[std::size_t(j)]).restitution();
      if (speed > 0.0 && !closed_[i]) {
        fastest_[i] = std::max(fastest_[i], speed);
        // (the flight since it last left, its apex ≈ speed × time / 4; an approach at a rate of
        // roundoff is no landing to judge: still_rate)
        const double flight = t - left_[i], height = 0.25 * speed * flight;
        const bool unresolved =
            flight_rtol_ > 0.0 && flight > 0.0 && speed > still_rate(set[std::size_t(j)]) &&
            height < kUnresolvedFlight * flight_rtol_ * gap_scale(sys_, ws_, set[std::size_t(j)]);
        // (e = 0 too: a plastic corner of a rocking block rests, and its group with it)
        if (speed < kRestFraction * fastest_[i] || unresolved) {
          e[j] = 0.0;
          rests[std::size_t(j)] = true;
          rest_fastest = std::max(rest_fastest, fastest_[i]);
          if (unresolved) {
            unresolved_speed = std::max(unresolved_speed, speed);
            apex[std::size_t(j)] = height;
          }
        }
      }
    }
    const VectorXd vm = Eigen::Map<const VectorXd>(v_minus.data(), m);
    const VectorXd qd_minus = qd;
    const double T_minus = dyn_.kinetic_energy(qd);
    if (!dyn_.impact(sys_, ws_, q, qd, t, vm, e)) {
      failure_ = "contacts at t = " + format_t(t) + ": " +
                 (dyn_.failure().empty()
                      ? std::string("the impact's LCP has no solution (Siconos lcp_lexicolemke)")
                      : dyn_.failure());
      return false;
    }
    // energy is never created: an impact whose contacts would put energy in (Newton's law with
    // several contacts can, and friction with restitution) is redone with the largest fraction
    // s of its restitutions (e_i s, s in [0, 1)) that puts none in, found by bisection; s = 0 is
    // the plastic impact, which dissipates. (It was made plastic at once: a cliff in a sweep of
    // e, a rough corner's rebound dropping to 0 at e = 0.99417.) The test is on the contacts'
    // own work W_c, on the velocities relative to their surfaces (ContactDynamics::
    // contact_work), not on T⁺ − T⁻: a moving surface (a vibrating table, a driven paddle) may
    // give the body kinetic energy by an admissible impact.
    double dT = dyn_.kinetic_energy_change(qd, qd_minus);
    double W_c = dyn_.contact_work(vm, qd, qd_minus);
    const auto gains = [&](double work, double change) {
      return work > 1e-12 * std::max({T_minus, T_minus + change, 1e-300});
    };
    if (gains(W_c, dT)) {
      const VectorXd e_full = e;
      // the impact with restitutions e_full · s into qd; false when its LCP has no solution
      const auto redo = [&](double s) {
        qd = qd_minus;
        e = s * e_full;
        if (!dyn_.impact(sys_, ws_, q, qd, t, vm, e)) return false;
        dT = dyn_.kinetic_energy_change(qd, qd_minus);
        W_c = dyn_.contact_work(vm, qd, qd_minus);
        return true;
      };
      // W_c(s) is continuous where the impact's modes are; lo keeps none gained, hi gains;
      // qd holds the impact of s = lo when the last one solved was (else it is solved again)
      double lo = 0.0, hi = 1.0;
      bool at_lo = false;
      for (int i = 0; i < 60 && hi - lo > 1e-15; ++i) {
        const double s = 0.5 * (lo + hi);
        at_lo = redo(s) && !gains(W_c, dT);
        if (at_lo)
          lo = s;
        else
          hi = s;
      }
      if (!at_lo && !redo(lo)) {
        failure_ = "contacts at t = " + format_t(t) + ": the " +
                   (lo > 0.0 ? "reduced restitution's" : "plastic") +
                   " impact's LCP has no solution (Siconos lcp_lexicolemke)";
        return false;
      }
      if (stats.notes.size() < 20) {
        stats.notes.push_back(
            "t = " + format_t(t) + ": an impact with restitution" +
            std::string(dyn_.friction_impulse().sum() > 0.0 ? " and friction" : "") +
            " would have created energy; it was made with " +
            (lo > 0.0 ? format_number(lo, 6) + " of its restitution (the largest fraction that "
                                               "creates none)"
                      : std::string("restitution 0 (plastic)")) +
            ", docs/contact.md");
      }
    }
    if (rest_fastest > 0.0) {
      // group rest: the touching contacts that leave this impact slower than the rest criterion
      // (kRestFraction of the sequence's fastest impact, theirs or the resting contact's) are
      // held at g' = 0 with it — a rocking block's other corner, which every plastic impact
      // lifts at r times the landing speed, so that no contact's own sequence ever ends (each
      // is released at the other's impacts), and the impacts accumulate at t∞ (docs/contact.md,
      // "Rest")
      // (an unresolved landing under BDF holds the normals leaving slower than it came; the
      // slip it stops stays at the rest criterion's roundoff, still: the hold's impulse is not
      // checked against the friction cone)
      std::vector<Index> rows;
      VectorXd still(m);
      for (Index j = 0; j < m; ++j) {
        const std::size_t i = which[std::size_t(j)];
        const double v = dyn_.v_after()[j];
        still[j] = kRestFraction * std::max(fastest_[i], rest_fastest);
        if (v <= std::max(still[j], unresolved_speed)) {
          rows.push_back(j);
          held[std::size_t(j)] = v > still_rate(set[std::size_t(j)]);
          left_at[std::size_t(j)] = v;
        }
      }
      if (std::any_of(held.begin(), held.end(), [](bool h) { return h; })) {
        dyn_.hold(qd, qd_minus, rows, still);
        dT = dyn_.kinetic_energy_change(qd, qd_minus);
      }
    }
    impact_work_ += dT;
    bool first = true;
    for (Index j = 0; j < m; ++j) {
      const std::size_t i = which[std::size_t(j)];
      if (!(dyn_.lambda()[j] > 0.0) && !held[std::size_t(j)]) continue;
      ContactEvent ev;
      ev.t = t;
      ev.constraint = set[std::size_t(j)];
      ev.kind = rests[std::size_t(j)] || held[std::size_t(j)] ? ContactEvent::Kind::kRest
                                                              : ContactEvent::Kind::kImpact;
      // (a closed contact held at rest was still, g'⁻ = 0: its roundoff, either sign, would
      // count it as a landing in a sweep's impacts)
      ev.speed_before = held[std::size_t(j)] && closed_[i] ? 0.0 : vm[j];
      ev.speed_after = dyn_.v_after()[j];
      ev.impulse = dyn_.lambda()[j];
      ev.energy_change = first ? dT : 0.0;
      first = false;
      list(ev, stats);
      ++impacts_[i];
      if (rests[std::size_t(j)] && stats.notes.size() < 20) {
        const std::string why =
            apex[std::size_t(j)] > 0.0
                ? "its flight before, about " + format_t(apex[std::size_t(j)]) +
                      " high (the gap's unit), is below what BDF follows at rtol " +
                      format_t(flight_rtol_) + ": impact speed " + format_t(-vm[j]) +
                      ", its fastest " + format_t(fastest_[i])
                : "impact speed " + format_t(-vm[j]) + " below " + format_t(kRestFraction) +
                      " of its fastest, " + format_t(fastest_[i]);
        stats.notes.push_back("t = " + format_t(t) + " " + units_.time + ": contact '" +
                              sys_.constraint(ev.constraint).name() + "' came to rest after " +
                              format_number(impacts_[i]) +
                              " impacts (an accumulation point: " + why + " (the gap's unit per " +
                              units_.time + "); docs/contact.md, \"Rest\")");
      }
      if (held[std::size_t(j)] && stats.notes.size() < 20) {
        stats.notes.push_back("t = " + format_t(t) + " " + units_.time + ": contact '" +
                              sys_.constraint(ev.constraint).name() +
                              "' held at rest with the contacts that came "
                              "to rest there (it would have left at " +
                              format_t(left_at[std::size_t(j)]) + "; impulse " +
                              format_t(ev.impulse) + (ev.impulse < 0.0 ? ", pulling" : "") +
                              "); docs/contact.md, \"Rest\")");
      }
    }
    for (Index j = 0; j < m; ++j) v_minus[std::size_t(j)] = dyn_.v_after()[j];
  }
  // the closed set: the touching contacts that do not separate (g' ≈ 0) and push (the LCP of
  // the accelerations)
  std::vector<Index> candidates;
  std::vector<std::size_t> cand_which;
  const std::vector<unsigned char> was_closed = closed_;
  // (K) 1 unless the LCP leaves the contact unloaded without separating (λ = 0, g'' ≈ 0)
  std::vector<unsigned char> separates(K, 1);
  for (Index j = 0; j < m; ++j) {
    const std::size_t i = which[std::size_t(j)];
    closed_[i] = 0;
    // (g'⁺ still: roundoff of this instant's speeds, or of the contact's own — its sequence's
    // fastest impact, not the row's class: a support that leaves the 20th impact of an
    // accumulation at 1e-6 of the first is separating, in any units; still_rate)
    if (v_minus[std::size_t(j)] <=
        std::max(still_rate(set[std::size_t(j)]), kStillRate * v_scale)) {
      candidates.push_back(set[std::size_t(j)]);
      cand_which.push_back(i);
    }
  }
  if (!candidates.empty()) {
    if (!dyn_.prepare(sys_, ws_, q, qd, t, candidates) ||
        !dyn_.accelerations(sys_, ws_, q, qd, t)) {
      failure_ = "contacts at t = " + format_t(t) + ": " +
                 (dyn_.failure().empty() ? std::string("the LCP of the closed contacts has no "
                                                       "solution (Siconos lcp_lexicolemke)")
                                         : dyn_.failure());
      return false;
    }
    // (g'' = w of a contact left open: roundoff of its free acceleration at a vertex of
    // redundant contacts — the contact stays touching, unloaded)
    const double roundoff = kUnloaded * dyn_.free_gap_acceleration().cwiseAbs().maxCoeff();
    for (std::size_t j = 0; j < candidates.size(); ++j) {
      closed_[cand_which[j]] = dyn_.lambda()[Index(j)] > 0.0 ? 1 : 0;
      separates[cand_which[j]] = dyn_.slack()[Index(j)] > roundoff ? 1 : 0;
    }
    if (release && closed_[std::size_t(event)] &&
        !hold_pushes(t, q, qd, candidates, dyn_.contacts()[std::size_t(event)])) {
      return false;
    }
  }
  // a closed contact that opens: a release, when it separates — the located release's own
  // contact (its multiplier turned negative), one that leaves at g' > 0 (after an impact) or
  // whose g'' the LCP makes positive; one merely left unloaded at a vertex of redundant
  // contacts, still touching, is no event (docs/contact.md, "Redundant contacts")
  // (every contact that opens at this instant is listed, with the force it carried before)
  std::vector<Index> opened;
  std::vector<std::size_t> opened_which;
  for (Index j = 0; j < m; ++j) {
    const std::size_t i = which[std::size_t(j)];
    if (!was_closed[i] || closed_[i]) continue;
    if (!(release && Index(i) == event) && !separates[i]) continue;
    opened.push_back(set[std::size_t(j)]);
    opened_which.push_back(std::size_t(j));
  }
  std::vector<double> force;
  if (!opened.empty()) forces_before(t, q, was_closed, opened, force);
  for (std::size_t r = 0; r < opened.size(); ++r) {
    const std::size_t j = opened_which[r], i = which[j];
    ContactEvent ev;
    ev.t = t;
    ev.constraint = opened[r];
    ev.kind = ContactEvent::Kind::kRelease;
    ev.speed_before = ev.speed_after = v_minus[j];
    ev.force_before = force[r];
    list(ev, stats);
    // (its next impacts are a new sequence, the rest criterion comparing with their fastest —
    // unless an impact at this instant sends it off, g' > 0: a rocking block's corner, lifted by
    // the other's landing, whose impacts continue one sequence of the block's)
    if (!(approaching && !release && v_minus[j] > still_rate(opened[r]))) {
      fastest_[i] = 0.0;
      impacts_[i] = 0;
    }
  }
  // (the flights that start here: a contact left open that separates — it leaves the impact,
  // or the LCP gives it g'' > 0 from g' ≈ 0 after a plastic landing or a release)
  for (Index j = 0; j < m; ++j) {
    const std::size_t i = which[std::size_t(j)];
    if (!closed_[i] && (separates[i] || (release && Index(i) == event))) left_[i] = t;
  }
  apply();
  return true;
}

void ContactEvents::list(const ContactEvent& ev, RunStatistics& stats) {
  stats.contact_events.push_back(ev);
  const double speed = ev.kind == ContactEvent::Kind::kRelease ? kNaN : -ev.speed_before;
  // (the ring grows with the events up to kChatterEvents, then turns: a run with few events
  // does not zero its 160 kB — 0.3 ms, as long as the ladder's whole run without them)
  if (recent_.size() < std::size_t(kChatterEvents)) {
    recent_.push_back(ev.t);
    recent_speed_.push_back(speed);
  } else {
    recent_[listed_ % recent_.size()] = ev.t;
    recent_speed_[listed_ % recent_.size()] = speed;
  }
  ++listed_;
}

bool ContactEvents::converging() const {
  // the oldest and the newest impact of the ring (releases have no speed)
  const std::size_t size = recent_speed_.size();
  double oldest = kNaN, newest = kNaN;
  for (std::size_t a = 0; a < size && std::isnan(oldest); ++a)
    oldest = recent_speed_[(listed_ + a) % size];
  for (std::size_t a = 1; a <= size && std::isnan(newest); ++a)
    newest = recent_speed_[(listed_ + size - a) % size];
  return newest < kConverging * oldest;
}

void ContactEvents::forces_before(double t, const Eigen::Ref<const VectorXd>& q,
                                  const std::vector<unsigned char>& was_closed,
                                  const std::vector<Index>& opened, std::vector<double>& force) {
  // the run's evaluation with the modes before the event: the multiplier each opened contact
  // had (the release criterion's own quantity)
  for (std::size_t i = 0; i < was_closed.size(); ++i) {
    ws_.activity_override[std::size_t(dyn_.contacts()[i])] = was_closed[i] ? 1 : 0;
  }
  const bool ok = forward_dynamics(sys_, ws_, q, qd_before_, t) == Status::kOk;
  force.assign(opened.size(), kNaN);
  for (std::size_t r = 0; r < opened.size() && ok; ++r) force[r] = multiplier(opened[r]);
}

bool ContactEvents::hold_pushes(double t, const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd,
                                const std::vector<Index>& candidates, Index k) {
  // the LCP holds the contact whose multiplier located the release: with the decided modes its
  // multiplier in the plant must push again (another contact's change can make it), or the
  // same release fires again at this instant, for ever — the plant's multiplier and the LCP's λ
  // disagree in sign (under control: the control computed with the contact held loads it
  // differently from the control's answer to its force that the LCP anticipates)
  apply();
  if (forward_dynamics(sys_, ws_, q, qd, t) != Status::kOk) return true;
  const double held = multiplier(k);
  if (!(held < -kUnloaded * largest_load())) return true;
  double lcp = 0.0;
  for (std::size_t j = 0; j < candidates.size(); ++j) {
    if (candidates[j] == k) lcp = dyn_.lambda()[Index(j)];
  }
  failure_ = "contacts at t = " + format_t(t) + ": the contact '" + sys_.constraint(k).name() +
             "' is released by its multiplier in the plant, " + format_t(held) +
             " (pulling, with the contact held), but held by the LCP of the accelerations, " +
             "lambda = " + format_t(lcp) +
             " (pushing): the two disagree in sign, so the release and the hold alternate at "
             "this instant (docs/contact.md, \"Contacts under control\": the control computed "
             "with the contact held loads it otherwise than the control's answer to its force "
             "that the LCP anticipates; a law other than Gauss, or the Gauss law where the "
             "uncontrolled reaction pulls)";
  return false;
}

}  // namespace ukdyn::detail
