// SPDX-License-Identifier: BSD-3-Clause
// ukdyn.Controller, ukdyn.ControlSolver and ukdyn.ControlSolution: exact tracking control
// (control/control.hpp) one evaluation at a time.
#include "common.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::python {
namespace {

/// One control evaluation's results, copied out of the workspace.
struct ControlSolution {
  double t = 0.0;
  VectorXd Qc_control, Qc_nominal, Qc_robust, u, e, residual, qdd, Qc_physical, s, kappa;
  std::vector<bool> met;
  Index rank = 0, rows_not_met = 0;
  double power = 0.0;
  ControlStatus status = ControlStatus::kOk;
  std::string message;
};

/// A Controller with its ControlWorkspace and input buffers (sized once).
class ControlSolver {
 public:
  explicit ControlSolver(ControllerHandle h)
      : h_(std::move(h)),
        ws_(*h_.controller),
        q_(VectorXd::Zero(h_.controller->coordinate_count())),
        qd_(VectorXd::Zero(h_.controller->coordinate_count())) {}

  ControlStatus evaluate(py::handle q, py::handle qd, double t) {
    read_into(q, "ControlSolver.compute", "q", q_);
    read_into(qd, "ControlSolver.compute", "q_dot", qd_);
    const ControlStatus st = compute_control(*h_.controller, ws_, q_, qd_, t);
    h_.raise_pending();
    return st;
  }

  ControlSolution snapshot(double t) const {
    ControlSolution r;
    r.t = t;
    r.Qc_control = ws_.Qc_control;
    r.Qc_nominal = ws_.Qc_nominal;
    r.Qc_robust = ws_.Qc_robust;
    r.u = ws_.u;
    r.e = ws_.e;
    r.residual = ws_.residual;
    r.qdd = ws_.qdd;
    r.Qc_physical = ws_.Qc_physical;
    r.s = ws_.s;
    r.kappa = ws_.kappa;
    r.met.assign(ws_.met.begin(), ws_.met.end());
    r.rank = ws_.rank;
    r.rows_not_met = ws_.rows_not_met;
    r.power = ws_.power;
    r.status = ws_.status;
    if (ws_.status != ControlStatus::kOk) r.message = describe_control_status(*h_.controller, ws_);
    return r;
  }

  const ControllerHandle& handle() const { return h_; }
  const ControlWorkspace& ws() const { return ws_; }

 private:
  ControllerHandle h_;
  ControlWorkspace ws_;
  VectorXd q_, qd_;
};

template <VectorXd ControlSolution::*field>
py::array solution_vector(py::object self) {
  return view_vector(self.cast<const ControlSolution&>().*field, self);
}

}  // namespace

void bind_control(py::module_& m) {
  py::class_<ControllerHandle>(m, "Controller", R"doc(
An immutable tracking controller (the C++ ukdyn::Controller, control/control.hpp; docs/control.md): the
nominal model of the plant, the requirements with their error dynamics, the law (Gauss or
weighted), the actuated coordinates and the robust settings. A model file's `control:`
section makes one (Model.controller); ukdyn.from_sympy(requirements=...) writes that section.
)doc")
      .def_property_readonly(
          "coordinate_count",
          [](const ControllerHandle& h) { return h.controller->coordinate_count(); },
          "n, the plant's coordinates.")
      .def_property_readonly(
          "requirement_rows",
          [](const ControllerHandle& h) { return h.controller->requirement_rows(); },
          "m_r, the rows of all requirements.")
      .def_property_readonly(
          "row_names", [](const ControllerHandle& h) { return h.controller->row_names(); },
          "Names of the requirement rows ('<requirement>' or "
          "'<requirement>.<row>'), the CSV's error.<row> columns.")
      .def_property_readonly(
          "requirements",
          [](const ControllerHandle& h) {
            py::list out;
            for (Index k = 0; k < h.controller->requirement_count(); ++k)
              out.append(h.controller->requirement(k).name());
            return out;
          },
          "The requirement names.")
      .def_property_readonly(
          "law", [](const ControllerHandle& h) { return to_string(h.controller->law()); },
          "'gauss' or 'weighted'.")
      .def_property_readonly(
          "actuators", [](const ControllerHandle& h) { return h.controller->actuators(); },
          "k, the columns of the actuation matrix S (n when fully actuated).")
      .def_property_readonly(
          "fully_actuated",
          [](const ControllerHandle& h) { return h.controller->fully_actuated(); },
          "True when every coordinate is actuated (S = I).")
      .def_property_readonly(
          "actuation",
          [](const ControllerHandle& h) { return copy_matrix(h.controller->actuation()); },
          "The actuation matrix S (n × k; a copy).")
      .def_property_readonly(
          "robust",
          [](const ControllerHandle& h) -> py::object {
            const auto& r = h.controller->robust();
            if (!r) return py::none();
            py::dict d;
            d["bound"] = r->bound;
            d["relative_bound"] = r->relative_bound;
            d["gain_uncertainty"] = r->gain_uncertainty;
            d["boundary_layer"] = r->boundary_layer;
            return d;
          },
          "The robust settings as a dict, or None.")
      .def_property_readonly(
          "model",
          [](const ControllerHandle& h) {
            return SystemHandle{h.controller->model(), nullptr};
          },
          "The nominal model (a System) the controller computes with.")
      .def(
          "solver", [](const ControllerHandle& h) { return std::make_unique<ControlSolver>(h); },
          "A ControlSolver (a control workspace, every buffer allocated once).")
      .def("__repr__", [](const ControllerHandle& h) {
        return "<ukdyn.Controller law='" + std::string(to_string(h.controller->law())) +
               "' rows=" + ukdyn::format_number(h.controller->requirement_rows()) + ">";
      });

  py::class_<ControlSolution>(m, "ControlSolution", R"doc(
The results of one control evaluation (ControlSolver.compute), copied out of the workspace.
Glossary of control/control.hpp: e = b_r − A_r a_p, Qc_control = Qc_nominal + Qc_robust = S u (+ S u_robust).
)doc")
      .def_readonly("t", &ControlSolution::t, "The time of the evaluation.")
      .def_property_readonly("Qc_control", &solution_vector<&ControlSolution::Qc_control>,
                             "The control force to apply (n), Qc_nominal + Qc_robust.")
      .def_property_readonly("Qc_nominal", &solution_vector<&ControlSolution::Qc_nominal>,
                             "The law's force for e (n), eq. (25) and its weighted form.")
      .def_property_readonly("Qc_robust", &solution_vector<&ControlSolution::Qc_robust>,
                             "The robust term (n; zero without robust settings).")
      .def_property_readonly("u", &solution_vector<&ControlSolution::u>,
                             "The actuator forces of Qc_nominal (k).")
      .def_property_readonly("e", &solution_vector<&ControlSolution::e>,
                             "The error signal b_r − A_r a_p (m_r).")
      .def_property_readonly("residual", &solution_vector<&ControlSolution::residual>,
                             "Per requirement row, (X Qc_nominal − e)_i: zero where met (m_r).")
      .def_property_readonly("qdd", &solution_vector<&ControlSolution::qdd>,
                             "The nominal model's acceleration under the control (n).")
      .def_property_readonly("Qc_physical", &solution_vector<&ControlSolution::Qc_physical>,
                             "The physical constraints' force under the control (n).")
      .def_property_readonly("s", &solution_vector<&ControlSolution::s>,
                             "The robust term's sliding variable (m_r).")
      .def_property_readonly("kappa", &solution_vector<&ControlSolution::kappa>,
                             "The robust gain (m_r).")
      .def_readonly("met", &ControlSolution::met, "Per requirement row: met? (m_r booleans).")
      .def_readonly("rank", &ControlSolution::rank, "Rank of the requirement rows.")
      .def_readonly("rows_not_met", &ControlSolution::rows_not_met, "Rows not met.")
      .def_readonly("power", &ControlSolution::power, "The control power Qc_controlᵀ q'.")
      .def_property_readonly(
          "status", [](const ControlSolution& s) { return to_string(s.status); },
          "'ok', 'requirements not met' (a least-squares force) or a failure.")
      .def_property_readonly(
          "ok", [](const ControlSolution& s) { return s.status == ControlStatus::kOk; },
          "True when every requirement is met.")
      .def_readonly("message", &ControlSolution::message, "describe_control_status() ('' when ok).")
      .def("__repr__", [](const ControlSolution& s) {
        return std::string("<ukdyn.ControlSolution t=") + ukdyn::format_number(s.t) + " status='" +
               to_string(s.status) + "'>";
      });

  py::class_<ControlSolver>(m, "ControlSolver", R"doc(
A Controller and its ControlWorkspace: compute_control (control/control.hpp) one state at a time.
Not thread-safe: one per thread.
)doc")
      .def(py::init<ControllerHandle>(), py::arg("controller"))
      .def(
          "compute",
          [](ControlSolver& s, py::handle q, py::handle qd, double t, bool check) {
            const ControlStatus st = s.evaluate(q, qd, t);
            if (check && st != ControlStatus::kOk && st != ControlStatus::kRequirementsNotMet) {
              // a numerical failure, as Solver.solve reports one: ukdyn.SolveError
              const Status why = st == ControlStatus::kModelFailed      ? s.ws().model.status
                                 : st == ControlStatus::kNonFiniteInput ? Status::kNonFiniteInput
                                 : st == ControlStatus::kNonFiniteResult
                                     ? Status::kNonFiniteResult
                                     : Status::kMassNotPositiveDefinite;
              throw SolveError(why, describe_control_status(*s.handle().controller, s.ws()));
            }
            return s.snapshot(t);
          },
          py::arg("q"), py::arg("q_dot"), py::arg("t") = 0.0, py::arg("check") = true,
          R"doc(The control force at (q, q', t) (compute_control, control/control.hpp).

Returns a ControlSolution. Requirements that cannot all be met are not an error (status
'requirements not met', the least-squares force; see met and residual). Raises ValueError for
inputs of the wrong size and, when check is True, ukdyn.SolveError (describe_control_status;
its status is the nominal model's, or non-finite input/result, or "mass matrix not positive
definite" for a weight N that is not) when the evaluation fails. Cost: one forward_dynamics of the nominal model and
O(n² m_r + n m_r²).)doc")
      .def_property_readonly(
          "controller", [](const ControlSolver& s) { return s.handle(); }, "The controller.");
  // the warnings of a run's control statistics (the dict of Result.control), as `ukdyn run`
  // prints them: ukdyn.simulate raises them as UserWarning
  m.def(
      "_control_warnings",
      [](const py::dict& c, const std::string& time_unit) {
        ControlStatistics s;
        auto number = [&](const char* key, double fallback) {
          return c.contains(key) && !c[key].is_none() ? c[key].cast<double>() : fallback;
        };
        s.evaluations = long(number("evaluations", 0.0));
        s.not_met = long(number("not_met", 0.0));
        s.max_residual = number("max_residual", 0.0);
        s.first_not_met = number("first_not_met", 0.0);
        if (c.contains("not_met_message"))
          s.not_met_message = c["not_met_message"].cast<std::string>();
        s.bound_exceeded_at = number("bound_exceeded_at", s.bound_exceeded_at);
        s.bound_worst_ratio = number("bound_worst_ratio", 0.0);
        s.bound_worst_time = number("bound_worst_time", s.bound_worst_time);
        if (c.contains("bound_worst_row"))
          s.bound_worst_row = c["bound_worst_row"].cast<std::string>();
        return control_warnings(s, time_unit);
      },
      py::arg("control"), py::arg("time_unit"),
      "control_warnings (control/control.hpp) of a Result.control dict: one line per warning.");
}

}  // namespace ukdyn::python
