// SPDX-License-Identifier: BSD-3-Clause
// integrate_bdf: one segment with SUNDIALS CVODE (variable-order BDF, Newton iteration, dense
// direct linear solver with CVODE's difference-quotient Jacobian), drift control through
// CVODE's projection interface (CVodeSetProjFn) calling SegmentHooks::after_step, and events
// (SegmentHooks::find_event) located on CVODE's interpolant of each step, as with the explicit
// methods' dense output.
//
// CVODE calls the projection function after the corrector has converged and before the error
// test, so after_step also sees step attempts that the error test then rejects; CVODE restores
// its history after a rejection, so such a correction is discarded with the step.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "simulation/integrator.hpp"
#include "ukdyn/core/format.hpp"

static_assert(std::is_same_v<sunrealtype, double>, "ukdyn needs SUNDIALS built with double");

namespace ukdyn::detail {
namespace {

constexpr const char* kWho = "ukdyn::detail::integrate_bdf";
// error test failures allowed in one step attempt (CVODE's default: 7)
constexpr int kMaxErrorTestFailures = 20;

// owners of the SUNDIALS objects: each is freed on every path, in reverse order of creation
struct FreeContext {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct FreeVector {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct FreeMatrix {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct FreeSolver {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct FreeCvode {
  void operator()(void* mem) const { CVodeFree(&mem); }
};
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, FreeContext>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, FreeVector>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, FreeMatrix>;
using SolverPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, FreeSolver>;
using CvodePtr = std::unique_ptr<void, FreeCvode>;

// what the C callbacks reach through CVODE's user data
struct Callbacks {
  ConstrainedOde& ode;
  SegmentHooks& hooks;
  std::vector<double> corrected;  // (2n + 1) the copy of ycur handed to after_step
  bool rhs_failed = false;        // the ode refused an evaluation
  // the last evaluation refused (a state outside the model's domain: CVODE retries the step
  // smaller), its status and its description without time (ConstrainedOde::take_failure)
  Status outside = Status::kOk;
  std::string outside_description;
  // the time of the last evaluation that succeeded: a failure a few rounding units after it has
  // pinned the domain's boundary to the resolution of t (CVODE would go on with steps that
  // t + h = t cannot advance, up to max_steps)
  double t_ok = std::numeric_limits<double>::quiet_NaN();
  // redundant constraints: f is evaluated at the state projected onto the constraints,
  // x' = f(π(x)) (same solution from a consistent state). Off the constraints a row that is
  // redundant only on them (functionally dependent) regains a tiny pivot, which the rank
  // decision keeps or drops by the size of the violation: f off the manifold is then
  // discontinuous at the scale of CVODE's difference quotients, its Jacobian is noise, and the
  // Newton iteration fails (the bodies double four-bar with a redundant crank: ~10⁵ steps per
  // 0.1 s, against 382 steps for 1 s with projected evaluations)
  bool project_evaluations = false;
  std::vector<double> projected;  // (2n + 1) the projected copy
  // a step reached a singular configuration (rank_margin < kSingularMargin) from a regular one
  bool singular = false, regular = false;
  Status hook_status = Status::kOk;  // after_step asked to stop
  std::string cvode_message;         // CVODE's last error, "function: message"
  std::exception_ptr exception;      // thrown by a callback, rethrown once CVODE has returned
};

// x' = f(t, x). A failed evaluation (a state outside the model's domain: M not positive
// definite, a NaN) is recoverable (positive): CVODE retries the step smaller, and gives up only
// when that keeps failing (CV_REPTD_RHSFUNC_ERR, CV_FIRST_RHSFUNC_ERR). An exception is not
// (negative): CVODE stops at once.
int rhs(sunrealtype t, N_Vector x, N_Vector dxdt, void* data) {
  auto& cb = *static_cast<Callbacks*>(data);
  try {
    const double* xs = N_VGetArrayPointer(x);
    if (cb.project_evaluations) {
      std::copy(xs, xs + cb.projected.size(), cb.projected.begin());
      if (cb.hooks.project_stage(t, cb.projected.data())) xs = cb.projected.data();
    }
    if (cb.ode(xs, N_VGetArrayPointer(dxdt), t)) {
      cb.outside = Status::kOk;
      cb.t_ok = t;
      return 0;
    }
    cb.outside = cb.ode.take_failure(cb.outside_description);
    // (a failure in the same step attempt as the success, at the same t, is a Newton iterate
    // outside the domain: retried)
    const double gap = t - cb.t_ok;
    const bool pinned =
        gap > 0.0 && gap <= 4.0 * std::numeric_limits<double>::epsilon() * std::abs(t);
    return pinned ? -1 : 1;
  } catch (...) {
    cb.exception = std::current_exception();
  }
  cb.rhs_failed = true;
  return -1;
}

// corr = after_step(ycur) − ycur, zero when the hook left the state alone
int project(sunrealtype t, N_Vector ycur, N_Vector corr, sunrealtype /*eps_proj*/, N_Vector err,
            void* data) {
  auto& cb = *static_cast<Callbacks*>(data);
  const double* y = N_VGetArrayPointer(ycur);
  double* c = N_VGetArrayPointer(corr);
  const std::size_t size = cb.corrected.size();
  std::copy(y, y + size, cb.corrected.begin());
  bool changed = false;
  Status s = Status::kOk;
  try {
    s = cb.hooks.after_step(t, cb.corrected.data(), changed);
  } catch (...) {
    cb.exception = std::current_exception();
    s = Status::kIntegratorFailure;
  }
  if (s != Status::kOk) {
    cb.hook_status = s;
    return -1;
  }
  // (the last evaluation was at the corrector's last iterate, the state of this step)
  const double margin = cb.ode.workspace().rank_margin;
  if (margin < kSingularMargin && cb.regular && cb.hooks.project_stage) {
    cb.singular = true;
    return -1;
  }
  if (margin >= kSingularMargin) cb.regular = true;
  for (std::size_t i = 0; i < size; ++i) c[i] = changed ? cb.corrected[i] - y[i] : 0.0;
  // approaching a singular configuration, the error estimate as the projected solution sees
  // it: without its components normal to the constraints, which the projection removes (left
  // as it is elsewhere, where the steps are those of CVODE without error projection)
  if (err != nullptr && cb.hooks.project_error && margin < kTangentialMargin) {
    try {
      cb.hooks.project_error(t, cb.corrected.data(), N_VGetArrayPointer(err));
    } catch (...) {
      cb.exception = std::current_exception();
      return -1;
    }
  }
  return 0;
}

// keeps CVODE's last error for the result's message and prints nothing; warnings are dropped
void record_error(int code, const char* /*module*/, const char* function, char* msg, void* data) {
  if (code == CV_WARNING) return;
  auto& cb = *static_cast<Callbacks*>(data);
  try {
    cb.cvode_message = std::string(function ? function : "CVODE") + ": " + (msg ? msg : "");
  } catch (...) {
    // out of memory while describing an error: keep the flag name only
  }
}

// "CV_CONV_FAILURE" for a flag (CVODE allocates the name with malloc)
std::string flag_name(int flag) {
  const std::unique_ptr<char, decltype(&std::free)> name(CVodeGetReturnFlagName(flag), &std::free);
  return name ? std::string(name.get()) : "CVODE flag " + format_number(flag);
}

std::string time_text(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", t);
  return buf;
}

// a set-up call that can only fail on bad options or exhausted memory (tier 1)
void require(int flag, const char* call, const Callbacks& cb) {
  if (flag >= 0) return;
  throw std::invalid_argument(std::string(kWho) + ": " + call + " failed (" + flag_name(flag) +
                              (cb.cvode_message.empty() ? "" : ": " + cb.cvode_message) +
                              "); check rtol > 0, atol >= 0, max_step >= 0 and max_steps > 0");
}

// t and t' are the same time to within rounding (CVODE refuses to step over such a gap)
bool same_time(double t, double t_other) {
  return std::abs(t_other - t) <=
         4.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), std::abs(t_other));
}

}  // namespace

SegmentResult integrate_bdf(ConstrainedOde& ode, std::vector<double>& x, double t0, double t1,
                            const SampleTimes& outputs, const SimulationOptions& options,
                            SegmentHooks& hooks, double first_step) {
  const Index size = ode.size();
  UKDYN_CHECK(Index(x.size()) == size, "integrate_bdf: x must have ode.size() entries");
  UKDYN_CHECK(t1 > t0, "integrate_bdf: the segment must have t1 > t0");
  SegmentResult result;
  result.t_reached = t0;
  const long max_steps = std::min(options.max_steps, hooks.max_steps);

  // a segment shorter than rounding: nothing to integrate, the outputs see x
  if (same_time(t0, t1)) {
    for (const double tout : outputs) {
      if (!hooks.output) break;
      const Status s = hooks.output(tout, x.data());
      if (s != Status::kOk) {
        result.status = s;
        result.t_reached = tout;
        return result;
      }
    }
    result.t_reached = t1;
    return result;
  }

  Callbacks cb{ode, hooks, std::vector<double>(std::size_t(size))};
  // constraints redundant at the start (rank below the active rows): projected evaluations
  if (hooks.project_stage) {
    std::vector<double> f(static_cast<std::size_t>(size));
    if (ode(x.data(), f.data(), t0) && ode.workspace().rank < ode.workspace().active_rows) {
      cb.project_evaluations = true;
      cb.projected.assign(std::size_t(size), 0.0);
    }
    ode.clear_failure();  // (a failure here is CVODE's first evaluation's to report)
  }

  // context, state, dense matrix and dense solver (y0 is copied by CVodeInit; y is then the
  // output vector, which CVODE also uses as scratch inside its steps)
  SUNContext raw_context = nullptr;
  UKDYN_CHECK(SUNContext_Create(nullptr, &raw_context) == 0 && raw_context != nullptr,
              "integrate_bdf: SUNContext_Create failed");
  const ContextPtr context(raw_context);
  const VectorPtr y(N_VNew_Serial(sunindextype(size), context.get()));
  UKDYN_CHECK(y != nullptr, "integrate_bdf: N_VNew_Serial failed");
  double* y_data = N_VGetArrayPointer(y.get());
  std::copy(x.begin(), x.end(), y_data);
  const MatrixPtr jacobian(SUNDenseMatrix(sunindextype(size), sunindextype(size), context.get()));
  UKDYN_CHECK(jacobian != nullptr, "integrate_bdf: SUNDenseMatrix failed");
  const SolverPtr solver(SUNLinSol_Dense(y.get(), jacobian.get(), context.get()));
  UKDYN_CHECK(solver != nullptr, "integrate_bdf: SUNLinSol_Dense failed");

  // BDF with Newton iteration (CVODE's default nonlinear solver) on the dense solver; no
  // Jacobian function, so CVODE forms it by difference quotients
  const CvodePtr cvode(CVodeCreate(CV_BDF, context.get()));
  UKDYN_CHECK(cvode != nullptr, "integrate_bdf: CVodeCreate failed");
  void* mem = cvode.get();
  require(CVodeSetErrHandlerFn(mem, record_error, &cb), "CVodeSetErrHandlerFn", cb);
  require(CVodeInit(mem, rhs, t0, y.get()), "CVodeInit", cb);
  require(CVodeSetUserData(mem, &cb), "CVodeSetUserData", cb);
  // atol on q' times the run's rate decade (Workspace::rate_unit) and on a caller's quadrature
  // z_i times its unit (WorkLayout::quadrature_units), as the explicit methods' StepControl: a
  // vector of tolerances only where one of them is not 1. (The quadratures once took atol · rate
  // for the integrals of velocity kind and atol for the others: a controlled arm in mm, g, ms
  // lifted off a rough floor then stalled at its release, where the effort's integrand, ~0
  // weighed at 1e-12, jumped by 1e7: CVODE asked for steps below the roundoff of t.)
  const WorkLayout& works = ode.works();
  const double rate = ode.workspace().rate_unit;
  const bool units = std::any_of(works.quadrature_units.begin(), works.quadrature_units.end(),
                                 [](double u) { return u != 1.0; });
  VectorPtr atol;
  if (rate != 1.0 || units) {
    atol.reset(N_VNew_Serial(sunindextype(size), context.get()));
    UKDYN_CHECK(atol != nullptr, "integrate_bdf: N_VNew_Serial failed");
    double* a = N_VGetArrayPointer(atol.get());
    const Index n = ode.coordinate_count();
    const Index z = works.quadrature >= 0 ? 2 * n + works.quadrature : size;
    for (Index i = 0; i < size; ++i) {
      const std::size_t j = std::size_t(i - z);
      a[i] = i >= n && i < 2 * n ? options.atol * rate
             : i >= z && j < works.quadrature_units.size()
                 ? options.atol * works.quadrature_units[j]
                 : options.atol;
    }
    require(CVodeSVtolerances(mem, options.rtol, atol.get()), "CVodeSVtolerances", cb);
  } else {
    require(CVodeSStolerances(mem, options.rtol, options.atol), "CVodeSStolerances", cb);
  }
  require(CVodeSetLinearSolver(mem, solver.get(), jacobian.get()), "CVodeSetLinearSolver", cb);

  // first step, largest step, never past the segment end; a first step far too large for a
  // stiff transient takes ~1 error test failure per factor 10 (CVODE's default of 7 failures
  // gives up at 1e-6 of it), so allow more
  if (first_step > 0.0) {
    require(CVodeSetInitStep(mem, first_step), "CVodeSetInitStep", cb);
    require(CVodeSetMaxErrTestFails(mem, kMaxErrorTestFailures), "CVodeSetMaxErrTestFails", cb);
  }
  if (options.max_step > 0.0) {
    require(CVodeSetMaxStep(mem, options.max_step), "CVodeSetMaxStep", cb);
  }
  require(CVodeSetStopTime(mem, t1), "CVodeSetStopTime", cb);

  // drift control: after_step as CVODE's projection, every step; the error estimate is
  // projected where the rank margin is below kTangentialMargin (see project)
  if (hooks.after_step) {
    require(CVodeSetProjFn(mem, project), "CVodeSetProjFn", cb);
    require(CVodeSetProjErrEst(mem, hooks.project_error ? SUNTRUE : SUNFALSE), "CVodeSetProjErrEst",
            cb);
  }

  // after CVODE returned `flag` < 0: x = the last accepted state zn[0] at tn (the initial state
  // before any step), and why it stopped: the ode, the hook (which describes its own failure to
  // the driver, so no message), or CVODE itself
  auto stopped = [&](int flag) {
    long taken = 0;
    CVodeGetNumSteps(mem, &taken);
    double tn = t0;
    if (taken > 0 && CVodeGetCurrentTime(mem, &tn) == CV_SUCCESS &&
        CVodeGetDky(mem, tn, 0, y.get()) == CV_SUCCESS) {
      std::copy(y_data, y_data + size, x.begin());
      result.t_reached = tn;
    }
    if (cb.singular) {
      result.singular = true;  // (status kOk: the driver crosses with dopri5)
    } else if (cb.outside != Status::kOk) {
      // the last evaluation, of a step CVODE could not shrink further, was outside the domain
      double h = 0.0;
      CVodeGetCurrentStep(mem, &h);
      result.status = cb.outside;
      result.message = left_domain("bdf", result.t_reached, h, cb.outside_description);
    } else if (cb.rhs_failed && ode.failed()) {
      result.status = ode.failure();
      result.message = ode.failure_message();
    } else if (cb.hook_status != Status::kOk) {
      result.status = cb.hook_status;
    } else {
      result.status = Status::kIntegratorFailure;
      result.message = "CVODE " + flag_name(flag) + " at t = " + time_text(result.t_reached) +
                       (cb.cvode_message.empty() ? "" : ": " + cb.cvode_message);
    }
  };

  // an output hook's refusal ends the segment there
  auto emit = [&](double tout, const double* state) -> bool {
    if (!hooks.output) return true;
    const Status s = hooks.output(tout, state);
    if (s == Status::kOk) return true;
    result.status = s;  // the hook describes its failure to the driver
    result.t_reached = tout;
    return false;
  };

  if (hooks.find_event) {
    // one step at a time, each checked by hooks.find_event on CVODE's interpolant of the step
    // (CVodeGetDky, valid on [t_n − h, t_n]); outputs come from the same interpolant
    const VectorPtr dky(N_VNew_Serial(sunindextype(size), context.get()));
    UKDYN_CHECK(dky != nullptr, "integrate_bdf: N_VNew_Serial failed");
    const double* dky_data = N_VGetArrayPointer(dky.get());
    const SegmentHooks::Dense dense = [&](double s, double* out) {
      UKDYN_CHECK(CVodeGetDky(mem, s, 0, dky.get()) == CV_SUCCESS,
                  "integrate_bdf: CVodeGetDky outside the last step");
      std::copy(dky_data, dky_data + size, out);
    };
    std::vector<double> x_old = x;
    std::vector<double> out(std::size_t(size), 0.0);
    double t_old = t0;
    std::size_t next = 0;
    // outputs within rounding of t0 see the initial state
    while (next < outputs.size() && same_time(t0, outputs[next])) {
      if (!emit(outputs[next++], x.data())) return result;
    }
    while (t_old < t1) {
      long taken = 0;
      CVodeGetNumSteps(mem, &taken);
      if (taken >= max_steps) {
        result.status = Status::kIntegratorFailure;
        result.message = "bdf: step limit max_steps = " + format_number(max_steps) +
                         " reached at t = " + time_text(t_old);
        break;
      }
      double t_new = t_old;
      const int flag = CVode(mem, t1, y.get(), &t_new, CV_ONE_STEP);
      if (cb.exception) std::rethrow_exception(cb.exception);
      if (flag < 0) {
        stopped(flag);
        break;
      }
      const double te = hooks.find_event(t_old, x_old.data(), t_new, y_data, dense);
      const double until = std::isnan(te) ? t_new : te;
      bool going = true;
      for (; going && next < outputs.size() && outputs[next] <= until; ++next) {
        dense(outputs[next], out.data());
        going = emit(outputs[next], out.data());
      }
      if (!going) break;
      if (!std::isnan(te)) {
        dense(te, x.data());
        result.t_reached = te;
        result.event = true;
        break;
      }
      std::copy(y_data, y_data + size, x_old.begin());
      t_old = t_new;
      x = x_old;
      result.t_reached = t_new;
    }
  } else {
    // x(tout) by CVODE (dense output inside the steps taken); false when it stopped early
    auto advance = [&](double tout) -> bool {
      // at most the steps still allowed by options.max_steps (CVODE counts them per call)
      long taken = 0;
      CVodeGetNumSteps(mem, &taken);
      if (taken >= max_steps) {
        // (CVODE counts its limit per call: one more step per output time otherwise)
        result.status = Status::kIntegratorFailure;
        result.message = "bdf: step limit max_steps = " + format_number(max_steps) +
                         " reached at t = " + time_text(result.t_reached);
        return false;
      }
      require(CVodeSetMaxNumSteps(mem, max_steps - taken), "CVodeSetMaxNumSteps", cb);
      double t_returned = result.t_reached;
      const int flag = CVode(mem, tout, y.get(), &t_returned, CV_NORMAL);
      if (cb.exception) std::rethrow_exception(cb.exception);
      if (flag >= 0) {
        std::copy(y_data, y_data + size, x.begin());
        result.t_reached = t_returned;
        return true;
      }
      stopped(flag);
      return false;
    };

    // each output time in turn, then the segment end
    bool going = true;
    for (std::size_t i = 0; going && i < outputs.size(); ++i) {
      const double tout = outputs[i];
      UKDYN_CHECK(tout > t0 && tout <= t1 && (i == 0 || tout >= outputs[i - 1]),
                  "integrate_bdf: outputs must be ascending and inside (t0, t1]");
      // an output within rounding of t0 sees the initial state (CVODE refuses so short a first
      // step); any other is reached by CVODE
      if (!(result.t_reached == t0 && same_time(t0, tout))) going = advance(tout);
      if (going) going = emit(tout, x.data());
    }
    if (going && result.t_reached < t1) going = advance(t1);
    if (going) result.t_reached = t1;
  }

  // statistics
  long steps = 0, error_fails = 0, convergence_fails = 0;
  double last_step = 0.0;
  CVodeGetNumSteps(mem, &steps);
  CVodeGetNumErrTestFails(mem, &error_fails);
  CVodeGetNumNonlinSolvConvFails(mem, &convergence_fails);
  CVodeGetLastStep(mem, &last_step);
  result.steps = steps;
  result.rejected = error_fails + convergence_fails;
  result.last_step = last_step;
  return result;
}

}  // namespace ukdyn::detail
