// SPDX-License-Identifier: BSD-3-Clause
// Systems and controllers from Python callables (the slow, flexible path of docs/python.md):
// M, Q, V, the constraints' A and b, and C are Python functions, called with the GIL held from
// whatever thread runs the C++ code. A Python exception inside one is kept (CallbackErrors), the
// callable writes NaN so that the evaluation stops, and the exception is raised again when the
// C++ call returns.
#include <cmath>
#include <limits>

#include "common.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// runs body() with the GIL; a Python exception (or a conversion error) is stored in errs and
// poison() fills the outputs with NaN; after a stored exception nothing more is called
template <class Body, class Poison>
void call_python(CallbackErrors& errs, Body&& body, Poison&& poison) {
  // (not at interpreter exit: then the outputs are NaN, which stops the run)
  const AcquiredGil gil;
  if (!gil.held() || errs.error) {
    poison();
    return;
  }
  try {
    body();
  } catch (py::error_already_set& e) {
    errs.error.emplace(std::move(e));
    poison();
  } catch (const std::invalid_argument& e) {
    PyErr_SetString(PyExc_ValueError, e.what());
    errs.error.emplace();
    poison();
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
    errs.error.emplace();
    poison();
  }
}

// one acceleration-form constraint (name, rows, A(q, q', t), b(q, q', t), begin, end)
Constraint make_constraint(const py::tuple& spec, std::shared_ptr<CallbackErrors> errs,
                           const char* who) {
  if (spec.size() != 6) throw std::invalid_argument(std::string(who) + ": bad constraint spec");
  const std::string name = spec[0].cast<std::string>();
  const Index rows = spec[1].cast<Index>();
  py::object A_fn = spec[2], b_fn = spec[3];
  const std::string what_A = "constraint '" + name + "': A(q, q_dot, t)";
  const std::string what_b = "constraint '" + name + "': b(q, q_dot, t)";
  Constraint c = acceleration_constraint(
      name, rows,
      [errs, A_fn, b_fn, what_A, what_b](const Eigen::Ref<const VectorXd>& q,
                                         const Eigen::Ref<const VectorXd>& qd, double t,
                                         Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) {
        call_python(
            *errs,
            [&] {
              py::array_t<double> qa = copy_vector(q), qda = copy_vector(qd);
              read_matrix_into(A_fn(qa, qda, t), "ukdyn callable", what_A.c_str(), A);
              read_into(b_fn(qa, qda, t), "ukdyn callable", what_b.c_str(), b);
            },
            [&] {
              A.setConstant(kNaN);
              b.setConstant(kNaN);
            });
      });
  const double begin = spec[4].cast<double>(), end = spec[5].cast<double>();
  if (std::isfinite(begin) || std::isfinite(end)) c.active_between(begin, end);
  return c;
}

SystemHandle from_callables(const std::vector<std::string>& coordinates, py::object M, py::object Q,
                            py::object V, const py::list& constraints, const py::list& nonideal,
                            py::object P) {
  auto errs = std::make_shared<CallbackErrors>();
  const Index n = Index(coordinates.size());
  SystemBuilder b(coordinates);
  // M: a constant matrix or M(q, t)
  if (PyCallable_Check(M.ptr())) {
    b.mass_matrix([errs, M](const Eigen::Ref<const VectorXd>& q, double t,
                            Eigen::Ref<MatrixXd> out) {
      call_python(
          *errs, [&] { read_matrix_into(M(copy_vector(q), t), "ukdyn callable", "M(q, t)", out); },
          [&] { out.setConstant(kNaN); });
    });
  } else {
    MatrixXd Mc = read_matrix(M, "from_callables", "M");
    if (Mc.rows() != n || Mc.cols() != n) {
      throw std::invalid_argument("from_callables: M must be " + ukdyn::format_number(n) + " × " +
                                  ukdyn::format_number(n) + " (got " +
                                  ukdyn::format_number(Mc.rows()) + " × " +
                                  ukdyn::format_number(Mc.cols()) + ")");
    }
    b.mass_matrix(Mc);
  }
  if (!Q.is_none()) {
    b.forces([errs, Q](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<VectorXd> out) {
      call_python(
          *errs,
          [&] {
            read_into(Q(copy_vector(q), copy_vector(qd), t), "ukdyn callable", "Q(q, q_dot, t)",
                      out);
          },
          [&] { out.setConstant(kNaN); });
    });
  }
  if (!V.is_none()) {
    b.potential_energy([errs, V](const Eigen::Ref<const VectorXd>& q, double t) {
      double value = kNaN;
      call_python(
          *errs, [&] { value = read_number(V(copy_vector(q), t), "ukdyn callable", "V(q, t)", t); },
          [&] { value = kNaN; });
      return value;
    });
  }
  if (!P.is_none()) {
    b.external_power([errs, P](const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t) {
      double value = kNaN;
      call_python(
          *errs,
          [&] {
            value = read_number(P(copy_vector(q), copy_vector(qd), t), "ukdyn callable",
                                "P(q, q_dot, t)", t);
          },
          [&] { value = kNaN; });
      return value;
    });
  }
  for (py::handle c : constraints) {
    b.add(make_constraint(c.cast<py::tuple>(), errs, "from_callables"));
  }
  // non-ideal forces: ("C", name, fn) with fn(q, q', t, Qc_ideal, lambda); ("viscous", c,
  // coordinates); ("coulomb", constraint, mu, coordinates, eps, mu_static, surface_velocity)
  for (py::handle item : nonideal) {
    py::tuple spec = item.cast<py::tuple>();
    const std::string kind = spec[0].cast<std::string>();
    auto coordinate_indices = [&](py::handle names) {
      std::vector<Index> idx;
      for (py::handle nm : names) {
        const std::string s = nm.cast<std::string>();
        const auto it = std::find(coordinates.begin(), coordinates.end(), s);
        if (it == coordinates.end())
          throw std::invalid_argument("from_callables: unknown coordinate '" + s + "'");
        idx.push_back(Index(it - coordinates.begin()));
      }
      return idx;
    };
    if (kind == "C") {
      const std::string name = spec[1].cast<std::string>();
      py::object fn = spec[2];
      const std::string what = "non-ideal force '" + name + "': C(q, q_dot, t, Qc_ideal, lambda)";
      b.add(NonIdealForce(
          name, [errs, fn, what](const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t,
                                 const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C) {
            call_python(
                *errs,
                [&] {
                  read_into(fn(copy_vector(q), copy_vector(qd), t, copy_vector(ideal.Qc_ideal()),
                               copy_vector(ideal.lambda())),
                            "ukdyn callable", what.c_str(), C);
                },
                [&] { C.setConstant(kNaN); });
          }));
    } else if (kind == "viscous") {
      b.add(viscous_friction(
          {.coefficient = spec[1].cast<double>(), .coordinates = coordinate_indices(spec[2])}));
    } else if (kind == "coulomb") {
      CoulombFriction f;
      f.constraint = spec[1].cast<std::string>();
      f.mu = spec[2].cast<double>();
      f.coordinates = coordinate_indices(spec[3]);
      if (!spec[4].is_none()) f.regularization_velocity = spec[4].cast<double>();
      if (spec.size() > 5 && !spec[5].is_none()) f.mu_static = spec[5].cast<double>();
      if (spec.size() > 6 && !spec[6].is_none()) {
        // u(q, t) and u' = du/dt along the motion, from surface_velocity(q, q_dot, t) -> (u, u')
        py::object fn = spec[6];
        const std::string what =
            "coulomb friction on '" + f.constraint + "': surface_velocity(q, q_dot, t)";
        f.surface_velocity = [errs, fn, what](const Eigen::Ref<const VectorXd>& q,
                                              const Eigen::Ref<const VectorXd>& qd, double t,
                                              Eigen::Ref<VectorXd> u, Eigen::Ref<VectorXd> u_dot) {
          call_python(
              *errs,
              [&] {
                const py::object got = fn(copy_vector(q), copy_vector(qd), t);
                if (!py::isinstance<py::tuple>(got) && !py::isinstance<py::list>(got)) {
                  throw std::invalid_argument(
                      "ukdyn callable: " + what + " must return (u, u_dot) (got " +
                      std::string(py::str(got.get_type().attr("__name__"))) + ")");
                }
                const py::sequence pair = got;
                if (pair.size() != 2) {
                  throw std::invalid_argument("ukdyn callable: " + what +
                                              " must return (u, u_dot) (got " +
                                              ukdyn::format_number(pair.size()) + " items)");
                }
                read_into(pair[0], "ukdyn callable", what.c_str(), u);
                read_into(pair[1], "ukdyn callable", what.c_str(), u_dot);
              },
              [&] {
                u.setConstant(kNaN);
                u_dot.setConstant(kNaN);
              });
        };
      }
      b.add(coulomb_friction(f));
    } else {
      throw std::invalid_argument("from_callables: unknown non-ideal force kind '" + kind + "'");
    }
  }
  return SystemHandle{b.build(), errs};
}

ControllerHandle build_controller(const SystemHandle& model, const py::list& requirements,
                                  const std::string& law, py::object N, py::object actuated,
                                  py::object S, py::object robust) {
  auto errs = model.errors ? model.errors : std::make_shared<CallbackErrors>();
  ControllerBuilder b(model.system);
  for (py::handle r : requirements) {
    b.require(make_constraint(r.cast<py::tuple>(), errs, "controller"), ErrorDynamics::none());
  }
  if (law == "gauss") {
    b.gauss();
  } else if (law == "weighted") {
    if (N.is_none()) throw std::invalid_argument("controller: law 'weighted' needs N");
    if (PyCallable_Check(N.ptr())) {
      b.weighted([errs, N](const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, double t,
                           Eigen::Ref<MatrixXd> out) {
        call_python(
            *errs,
            [&] {
              read_matrix_into(N(copy_vector(q), copy_vector(qd), t), "ukdyn callable",
                               "N(q, q_dot, t)", out);
            },
            [&] { out.setConstant(kNaN); });
      });
    } else {
      b.weighted(read_matrix(N, "controller", "N"));
    }
  } else {
    throw std::invalid_argument("controller: law '" + law + "' is not one of gauss, weighted");
  }
  if (!actuated.is_none()) b.actuated(actuated.cast<std::vector<std::string>>());
  if (!S.is_none()) b.actuation(read_matrix(S, "controller", "S"));
  if (!robust.is_none()) {
    py::dict d = robust;
    RobustControl rc;
    for (auto [k, v] : d) {
      const std::string key = py::str(k);
      if (key == "bound")
        rc.bound = v.cast<double>();
      else if (key == "relative_bound")
        rc.relative_bound = v.cast<double>();
      else if (key == "gain_uncertainty")
        rc.gain_uncertainty = v.cast<double>();
      else if (key == "boundary_layer")
        rc.boundary_layer = v.cast<double>();
      else
        throw std::invalid_argument("controller: unknown robust setting '" + key + "'");
    }
    b.robust(rc);
  }
  return ControllerHandle{std::make_shared<const Controller>(b.build()), errs};
}

// simulate() (or simulate_controlled()) of a System with the GIL released; the exception of a
// Python callable, if one was raised, replaces whatever the run reported
py::tuple simulate_system(const SystemHandle& h, py::handle q0, py::handle qd0,
                          const py::dict& settings, py::object controller, py::object stop) {
  SimulationOptions o;
  apply_simulation_options(o, settings, "simulate");
  const InterruptCheck interrupt(stop);
  interrupt.attach(o);
  VectorXd q, qd;
  read_vector(q0, h.system.coordinate_count(), "simulate", "q0", q);
  read_vector(qd0, h.system.coordinate_count(), "simulate", "qd0", qd);
  const ControllerHandle* ctrl =
      controller.is_none() ? nullptr : &controller.cast<const ControllerHandle&>();
  ModelRun run;
  try {
    ReleasedGil release;
    if (ctrl) {
      ControlledTrajectory c = simulate_controlled(*ctrl->controller, h.system, q, qd, o);
      run.extra_columns = control_csv_columns(c);
      run.trajectory = std::move(c.plant);
      run.control = std::move(c.control);
      run.controlled = true;
    } else {
      run.trajectory = simulate(h.system, q, qd, o);
    }
  } catch (...) {
    h.raise_pending();
    if (ctrl) ctrl->raise_pending();
    throw;
  }
  h.raise_pending();
  if (ctrl) ctrl->raise_pending();
  return run_tuple(std::move(run), interrupt.exception(), o, nullptr);
}

}  // namespace

void bind_callables(py::module_& m) {
  m.def("_from_callables", &from_callables, py::arg("coordinates"), py::arg("M"), py::arg("Q"),
        py::arg("V"), py::arg("constraints"), py::arg("nonideal"), py::arg("P") = py::none(),
        "A System from Python callables; use ukdyn.from_callables().");
  m.def("_build_controller", &build_controller, py::arg("model"), py::arg("requirements"),
        py::arg("law"), py::arg("N"), py::arg("actuated"), py::arg("S"), py::arg("robust"),
        "A Controller from a System and acceleration-form requirements; use ukdyn.controller().");
  m.def("_simulate_system", &simulate_system, py::arg("system"), py::arg("q0"), py::arg("qd0"),
        py::arg("settings"), py::arg("controller") = py::none(), py::arg("stop") = py::none(),
        "simulate() of a System (GIL released; stop() as in Model._run); use ukdyn.simulate().");
}

}  // namespace ukdyn::python
