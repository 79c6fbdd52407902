// SPDX-License-Identifier: BSD-3-Clause
// ukdyn.System, ukdyn.Solver and ukdyn.Solution: the fundamental equation one evaluation at a
// time (forward_dynamics, dynamics/forward.hpp) for users who write their own loops.
#include <chrono>
#include <cmath>

#include "common.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::python {
namespace {

/// One evaluation's results, copied out of the workspace (what Solver.solve returns). Its
/// arrays are views of these copies, so they stay valid after the next evaluation.
struct Solution {
  double t = 0.0;
  VectorXd qdd, Qc, Qc_ideal, Qc_nonideal, lambda, lambda_nonideal, C, a, Q, e, b;
  MatrixXd A;
  Index rank = 0, active_rows = 0;
  Residuals residuals;
  Status status = Status::kOk;
  std::string message;
};

/// A System with a Workspace and the input buffers of q and q' (sized once, so that an
/// evaluation from Python allocates nothing in C++).
class Solver {
 public:
  Solver(SystemHandle h, const SolverOptions& options)
      : h_(std::move(h)),
        ws_(h_.system, options),
        q_(VectorXd::Zero(h_.system.coordinate_count())),
        qd_(VectorXd::Zero(h_.system.coordinate_count())) {}

  // forward_dynamics at (q, q', t); raises a pending exception of the system's callables
  Status evaluate(py::handle q, py::handle qd, double t, const char* who) {
    read_into(q, who, "q", q_);
    read_into(qd, who, "q_dot", qd_);
    const Status s = forward_dynamics(h_.system, ws_, q_, qd_, t);
    h_.raise_pending();
    return s;
  }

  Solution snapshot(double t) const {
    Solution r;
    r.t = t;
    r.qdd = ws_.qdd;
    r.Qc = ws_.Qc;
    r.Qc_ideal = ws_.Qc_ideal;
    r.Qc_nonideal = ws_.Qc_nonideal;
    r.lambda = ws_.lambda;
    r.lambda_nonideal = ws_.lambda_nonideal;
    r.C = ws_.C;
    r.a = ws_.a;
    r.Q = ws_.Q;
    r.e = ws_.e;
    r.b = ws_.b;
    r.A = ws_.is_sparse() ? MatrixXd() : ws_.A;
    r.rank = ws_.rank;
    r.active_rows = ws_.active_rows;
    r.residuals = ws_.residuals;
    r.status = ws_.status;
    if (ws_.status != Status::kOk) r.message = describe_status(h_.system, ws_);
    return r;
  }

  // mean seconds of one forward_dynamics at (q, q', t) over `repeats` calls, in C++ alone (the
  // reference of python/bench_python.py for the per-call overhead of solve from Python)
  double time_cpp(py::handle q, py::handle qd, double t, long repeats) {
    read_into(q, "Solver._time_cpp", "q", q_);
    read_into(qd, "Solver._time_cpp", "q_dot", qd_);
    const auto start = std::chrono::steady_clock::now();
    for (long i = 0; i < repeats; ++i) forward_dynamics(h_.system, ws_, q_, qd_, t);
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    h_.raise_pending();
    return elapsed.count() / double(repeats);
  }

  const SystemHandle& handle() const { return h_; }
  const Workspace& ws() const { return ws_; }
  double t_last = 0.0;

 private:
  SystemHandle h_;
  Workspace ws_;
  VectorXd q_, qd_;
};

const char* kind_name(ConstraintKind k) { return to_string(k); }

py::dict residuals_dict(const Residuals& r) {
  py::dict d;
  d["constraint"] = r.constraint;
  d["gauss"] = r.gauss;
  d["virtual_work"] = r.virtual_work;
  return d;
}

// a Solution's vector as a view owned by the Python Solution object
template <VectorXd Solution::*field>
py::array solution_vector(py::object self) {
  const Solution& s = self.cast<const Solution&>();
  return view_vector(s.*field, self);
}

// a Solver's workspace vector as a read-only view (valid until the solver is gone; overwritten
// by the next evaluation)
template <VectorXd Workspace::*field>
py::array live_vector(py::object self) {
  const Solver& s = self.cast<const Solver&>();
  return view_vector(s.ws().*field, self);
}

}  // namespace

void bind_solver(py::module_& m) {
  py::class_<SystemHandle>(m, "System", R"doc(
An immutable constrained mechanical system M(q,t) q'' = Q(q,q',t) + Qc with constraints
A q'' = b and non-ideal work vector C (the C++ ukdyn::System). Made by a model
(`Model.system`) or from Python callables (`ukdyn.from_callables`). Cheap to copy.
)doc")
      .def_property_readonly(
          "coordinate_count", [](const SystemHandle& h) { return h.system.coordinate_count(); },
          "n, the number of coordinates.")
      .def_property_readonly(
          "constraint_rows", [](const SystemHandle& h) { return h.system.constraint_rows(); },
          "m, the rows of all constraints.")
      .def_property_readonly(
          "coordinates", [](const SystemHandle& h) { return h.system.coordinate_names(); },
          "The coordinate names (n).")
      .def_property_readonly(
          "constraints",
          [](const SystemHandle& h) {
            py::list out;
            for (const Constraint& c : h.system.constraints()) out.append(c.name());
            return out;
          },
          "The constraint names (K), in the order of their rows in A and of Solution.lambda_.")
      .def(
          "constraint_info",
          [](const SystemHandle& h) {
            py::list out;
            for (Index k = 0; k < h.system.constraint_count(); ++k) {
              const Constraint& c = h.system.constraint(k);
              py::dict d;
              d["name"] = c.name();
              d["kind"] = kind_name(c.kind());
              d["rows"] = c.rows();
              d["row_offset"] = h.system.row_offset(k);
              d["active"] = py::make_tuple(c.active_interval().begin, c.active_interval().end);
              out.append(d);
            }
            return out;
          },
          "One dict per constraint: name, kind ('holonomic', 'nonholonomic', 'acceleration'), "
          "rows, row_offset (its first row in A), active (the interval it acts on).")
      .def_property_readonly(
          "nonideal_forces",
          [](const SystemHandle& h) {
            py::list out;
            for (Index i = 0; i < h.system.nonideal_count(); ++i)
              out.append(h.system.nonideal_name(i));
            return out;
          },
          "The names of the non-ideal forces whose C vectors are summed.")
      .def_property_readonly(
          "mass_is_constant", [](const SystemHandle& h) { return h.system.mass_is_constant(); },
          "True when M was given as a constant matrix (factorized once).")
      .def(
          "mass_matrix",
          [](const SystemHandle& h, py::handle q, double t) {
            VectorXd qv;
            read_vector(q, h.system.coordinate_count(), "System.mass_matrix", "q", qv);
            MatrixXd M(h.system.coordinate_count(), h.system.coordinate_count());
            h.system.mass_matrix(qv, t, M);
            h.raise_pending();
            return copy_matrix(M);
          },
          py::arg("q"), py::arg("t") = 0.0, "M(q, t) (n × n). Cost: one evaluation of M.")
      .def(
          "forces",
          [](const SystemHandle& h, py::handle q, py::handle qd, double t) {
            VectorXd qv, qdv;
            read_vector(q, h.system.coordinate_count(), "System.forces", "q", qv);
            read_vector(qd, h.system.coordinate_count(), "System.forces", "q_dot", qdv);
            VectorXd Q = VectorXd::Zero(h.system.coordinate_count());
            h.system.forces(qv, qdv, t, Q);
            h.raise_pending();
            return copy_vector(Q);
          },
          py::arg("q"), py::arg("q_dot"), py::arg("t") = 0.0,
          "Q(q, q', t) (n), the impressed force. Cost: one evaluation of Q.")
      .def(
          "potential_energy",
          [](const SystemHandle& h, py::handle q, double t) {
            VectorXd qv;
            read_vector(q, h.system.coordinate_count(), "System.potential_energy", "q", qv);
            const double V = h.system.potential_energy(qv, t);
            h.raise_pending();
            return V;
          },
          py::arg("q"), py::arg("t") = 0.0, "V(q, t), or 0 when the system has none.")
      .def(
          "solver",
          [](const SystemHandle& h, py::kwargs kw) {
            SolverOptions o;
            py::dict d = kw;
            apply_solver_options(o, d);
            if (py::len(d) > 0) {
              throw std::invalid_argument("System.solver: unknown setting '" +
                                          std::string(py::str(d.begin()->first)) +
                                          "' (known: " + solver_option_names() + ")");
            }
            return std::make_unique<Solver>(h, o);
          },
          R"doc(A Solver for this system (a workspace: every buffer allocated once).

Keyword settings (SolverOptions, dynamics/workspace.hpp): rank_threshold, sparse_rank_threshold,
consistency_tolerance, symmetry_tolerance, compute_residuals, sparse_threshold,
engine ('auto', 'dense', 'sparse'), algorithm ('default', 'textbook').
Raises ValueError for an unknown setting or a value out of range.)doc")
      .def("__repr__", [](const SystemHandle& h) {
        return "<ukdyn.System n=" + ukdyn::format_number(h.system.coordinate_count()) +
               " m=" + ukdyn::format_number(h.system.constraint_rows()) +
               " constraints=" + ukdyn::format_number(h.system.constraint_count()) + ">";
      });

  py::class_<Solution>(m, "Solution", R"doc(
The results of one evaluation of the fundamental equation (Solver.solve), copied out of the
workspace: they stay valid after later evaluations. Glossary as in the C++ headers: a = M⁻¹Q,
e = b − A a, Qc = Qc_ideal + Qc_nonideal.
)doc")
      .def_readonly("t", &Solution::t, "The time of the evaluation.")
      .def_property_readonly("qdd", &solution_vector<&Solution::qdd>,
                             "q'', the constrained acceleration (n), eq. (9).")
      .def_property_readonly("Qc", &solution_vector<&Solution::Qc>,
                             "The total constraint force Qc_ideal + Qc_nonideal (n).")
      .def_property_readonly("Qc_ideal", &solution_vector<&Solution::Qc_ideal>,
                             "The ideal constraint force Aᵀ lambda (n), eq. (11).")
      .def_property_readonly("Qc_nonideal", &solution_vector<&Solution::Qc_nonideal>,
                             "The non-ideal constraint force (n), eq. (12).")
      .def_property_readonly("lambda_", &solution_vector<&Solution::lambda>,
                             "The minimum-norm multipliers of the ideal force (m), G⁺ e.")
      .def_property_readonly("multipliers", &solution_vector<&Solution::lambda>,
                             "Alias of lambda_.")
      .def_property_readonly("lambda_nonideal", &solution_vector<&Solution::lambda_nonideal>,
                             "Multipliers with Qc_nonideal = C + Aᵀ lambda_nonideal (m).")
      .def_property_readonly("C", &solution_vector<&Solution::C>,
                             "The non-ideal work vector C, the sum of the system's forces (n).")
      .def_property_readonly("a", &solution_vector<&Solution::a>,
                             "The unconstrained acceleration a = M⁻¹ Q (n).")
      .def_property_readonly("Q", &solution_vector<&Solution::Q>, "The impressed force Q (n).")
      .def_property_readonly("e", &solution_vector<&Solution::e>, "The error signal b − A a (m).")
      .def_property_readonly("b", &solution_vector<&Solution::b>,
                             "The constraints' right-hand side b (m); zero on inactive rows.")
      .def_property_readonly(
          "A", [](py::object self) { return view_matrix(self.cast<const Solution&>().A, self); },
          "The constraint matrix A (m × n; 0 × 0 with the sparse engine).")
      .def_readonly("rank", &Solution::rank, "The numerical rank of A.")
      .def_readonly("active_rows", &Solution::active_rows, "Rows of the active constraints.")
      .def_property_readonly(
          "residuals", [](const Solution& s) { return residuals_dict(s.residuals); },
          "{'constraint': ‖A q'' − b‖, 'gauss': stationarity of Gauss's function, "
          "'virtual_work': ‖Qc − C − Aᵀ(lambda + lambda_nonideal)‖} (dynamics/workspace.hpp, "
          "Residuals).")
      .def_property_readonly(
          "status", [](const Solution& s) { return to_string(s.status); },
          "The outcome: 'ok' or what failed (core/status.hpp).")
      .def_property_readonly(
          "ok", [](const Solution& s) { return s.status == Status::kOk; },
          "True when the status is 'ok'.")
      .def_readonly("message", &Solution::message,
                    "describe_status(): what failed, where and when ('' when ok).")
      .def("__repr__", [](const Solution& s) {
        return std::string("<ukdyn.Solution t=") + ukdyn::format_number(s.t) + " status='" +
               to_string(s.status) + "' rank=" + ukdyn::format_number(s.rank) + ">";
      });

  py::class_<Solver>(m, "Solver", R"doc(
A system and its workspace (the C++ ukdyn::Workspace): evaluates the fundamental equation at one
state at a time. Make it once (System.solver(), Model.solver()) and call solve() in your loop.
solve() returns a Solution (copies); evaluate() returns only the status and leaves the results in
the solver's live arrays (qdd, Qc, ...: read-only views of the workspace, overwritten by the
next evaluation) — the fastest path. Not thread-safe: one solver per thread.
)doc")
      .def(py::init([](const SystemHandle& h, py::kwargs kw) {
             SolverOptions o;
             py::dict d = kw;
             apply_solver_options(o, d);
             if (py::len(d) > 0)
               throw std::invalid_argument("Solver: unknown setting '" +
                                           std::string(py::str(d.begin()->first)) + "'");
             return std::make_unique<Solver>(h, o);
           }),
           py::arg("system"), "Solver(system, **settings): see System.solver().")
      .def(
          "solve",
          [](Solver& s, py::handle q, py::handle qd, double t, bool check) {
            s.evaluate(q, qd, t, "Solver.solve");
            s.t_last = t;
            if (check) throw_if_failed(s.handle().system, s.ws());
            return s.snapshot(t);
          },
          py::arg("q"), py::arg("q_dot"), py::arg("t") = 0.0, py::arg("check") = true,
          R"doc(Evaluates the constrained motion at (q, q', t) (forward_dynamics, dynamics/forward.hpp).

q, q_dot: n numbers each (a contiguous float64 array is read without conversion).
Returns a Solution: q'', Qc, Qc_ideal, Qc_nonideal, the multipliers, rank, residuals, status.
Raises ValueError for inputs of the wrong size; ukdyn.SolveError (message of
describe_status) when the evaluation fails and check is True (with check=False the failing
status is returned in the Solution); the exception of a Python callable of the system.
Cost: one evaluation, O(n³/3 + m n² + m² n), plus the copies.)doc")
      .def(
          "evaluate",
          [](Solver& s, py::handle q, py::handle qd, double t) {
            s.t_last = t;
            return to_string(s.evaluate(q, qd, t, "Solver.evaluate"));
          },
          py::arg("q"), py::arg("q_dot"), py::arg("t") = 0.0,
          "Evaluates at (q, q', t) like solve() but returns only the status ('ok', ...); the "
          "results are in the live arrays (qdd, Qc, ...). Never raises for a numerical failure.")
      .def("_time_cpp", &Solver::time_cpp, py::arg("q"), py::arg("q_dot"), py::arg("t"),
           py::arg("repeats"),
           "Mean seconds of one evaluation over `repeats` calls made in C++ (for benchmarks).")
      .def_property_readonly(
          "system", [](const Solver& s) { return s.handle(); }, "The system.")
      .def_property_readonly("qdd", &live_vector<&Workspace::qdd>, "Live view of q'' (n).")
      .def_property_readonly("Qc", &live_vector<&Workspace::Qc>, "Live view of Qc (n).")
      .def_property_readonly("Qc_ideal", &live_vector<&Workspace::Qc_ideal>,
                             "Live view of Qc_ideal (n).")
      .def_property_readonly("Qc_nonideal", &live_vector<&Workspace::Qc_nonideal>,
                             "Live view of Qc_nonideal (n).")
      .def_property_readonly("lambda_", &live_vector<&Workspace::lambda>,
                             "Live view of the multipliers (m).")
      .def_property_readonly("C", &live_vector<&Workspace::C>, "Live view of C (n).")
      .def_property_readonly("a", &live_vector<&Workspace::a>, "Live view of a = M⁻¹Q (n).")
      .def_property_readonly("Q", &live_vector<&Workspace::Q>, "Live view of Q (n).")
      .def_property_readonly("b", &live_vector<&Workspace::b>, "Live view of b (m).")
      .def_property_readonly(
          "M", [](py::object self) { return view_matrix(self.cast<const Solver&>().ws().M, self); },
          "Live view of M (n × n; 0 × 0 with the sparse engine).")
      .def_property_readonly(
          "A", [](py::object self) { return view_matrix(self.cast<const Solver&>().ws().A, self); },
          "Live view of A (m × n; 0 × 0 with the sparse engine).")
      .def_property_readonly(
          "rank", [](const Solver& s) { return s.ws().rank; }, "Rank of A at the last evaluation.")
      .def_property_readonly(
          "status", [](const Solver& s) { return to_string(s.ws().status); },
          "Status of the last evaluation.")
      .def_property_readonly(
          "message",
          [](const Solver& s) {
            return s.ws().status == Status::kOk ? std::string()
                                                : describe_status(s.handle().system, s.ws());
          },
          "describe_status() of the last evaluation ('' when ok).")
      .def_property_readonly(
          "residuals", [](const Solver& s) { return residuals_dict(s.ws().residuals); },
          "Residuals of the last evaluation (see Solution.residuals).")
      .def_property_readonly(
          "is_sparse", [](const Solver& s) { return s.ws().is_sparse(); },
          "True when the sparse engine evaluates this system.")
      .def_property_readonly(
          "counters",
          [](const Solver& s) {
            py::dict d;
            d["evaluations"] = s.ws().counters.evaluations;
            d["rank_deficient"] = s.ws().counters.rank_deficient;
            d["failures"] = s.ws().counters.failures;
            return d;
          },
          "Counters over the solver's life: evaluations, rank_deficient, failures.");
}

}  // namespace ukdyn::python
