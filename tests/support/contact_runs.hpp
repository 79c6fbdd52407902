// SPDX-License-Identifier: BSD-3-Clause
// Test support: reading a run with unilateral contacts — its contact events of one kind at one
// constraint, and the sample at a time the run was asked to output; the ladder in natural
// coordinates; a pendulum's time to an
// angle by RK4; a gap row's g, g', A and b,
// and A and b checked by finite differences of g; a model file's error with its place.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::testing {

// column `name` of a per-coordinate field f of tr (width n: q, q', Qc_ideal, a controlled run's
// Qc_control, …) at sample i
inline double coordinate_at(const Trajectory& tr, const std::vector<double>& f,
                            const std::string& name, std::size_t i) {
  const auto& names = tr.coordinate_names;
  const auto c = std::size_t(std::find(names.begin(), names.end(), name) - names.begin());
  EXPECT_LT(c, names.size()) << name;
  return f[i * std::size_t(tr.n) + c];
}

// the multiplier of constraint `name`'s first row at sample i (failing when there is none)
inline double first_multiplier(const Trajectory& tr, const std::string& name, std::size_t i) {
  Index row = 0;
  for (std::size_t k = 0; k < tr.constraint_names.size(); ++k) {
    if (tr.constraint_names[k] == name) return tr.lambda[i * std::size_t(tr.m) + std::size_t(row)];
    row += tr.constraint_rows[k];
  }
  ADD_FAILURE() << "no constraint " << name;
  return 0.0;
}

// the multipliers of constraint `name` at sample i, one per row (failing when there is none)
inline std::vector<double> constraint_multipliers(const Trajectory& tr, const std::string& name,
                                                  std::size_t i) {
  Index row = 0;
  for (std::size_t k = 0; k < tr.constraint_names.size(); ++k) {
    if (tr.constraint_names[k] == name) {
      const auto* first = tr.lambda.data() + i * std::size_t(tr.m) + std::size_t(row);
      return {first, first + tr.constraint_rows[k]};
    }
    row += tr.constraint_rows[k];
  }
  ADD_FAILURE() << "no constraint " << name;
  return {};
}

// the Euclidean norm of v
inline double vector_norm(const std::vector<double>& v) {
  double s = 0.0;
  for (double e : v) s += e * e;
  return std::sqrt(s);
}

// the run of the model text `text` sampled at `times`; it must end ok
inline Trajectory run_sampled_at(const std::string& text, std::vector<double> times) {
  Model m = parse_model(text);
  m.options.output_at = std::move(times);
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  return tr;
}

// The ladder of examples/models/ladder_coulomb.yaml in natural coordinates: its ends A (foot, on
// the floor yA = 0) and B (top, at the wall xB = 0) joined by a rod of length L, mass m uniform;
// Coulomb friction mu_f on xA at the floor and mu_w on yB at the wall; at rest at angle th0 to
// the floor. The model text from `coordinates:` to `initial: q:` (the caller declares m, L, g,
// mu_f, mu_w and th0 under parameters:, and adds simulate: and output:); the floor is unilateral,
// and so is the wall when `unilateral_wall`.
inline std::string ladder_in_coordinates(bool unilateral_wall) {
  return std::string(
             "coordinates: [xA, yA, xB, yB]\n"
             "kinetic_energy: m/6*(xA_dot^2 + yA_dot^2 + xA_dot*xB_dot + yA_dot*yB_dot + xB_dot^2 +"
             " yB_dot^2)\n"
             "potential_energy: m*g*(yA + yB)/2\n"
             "constraints:\n"
             "  - {name: rod, holonomic: ((xA - xB)^2 + (yA - yB)^2 - L^2)/(2*L)}\n"
             "  - {name: floor, holonomic: yA, unilateral: true}\n") +
         (unilateral_wall ? "  - {name: wall, holonomic: xB, unilateral: true}\n"
                          : "  - {name: wall, holonomic: xB}\n") +
         "nonideal:\n"
         "  - {friction: coulomb, constraint: floor, mu: mu_f, coordinates: [xA]}\n"
         "  - {friction: coulomb, constraint: wall, mu: mu_w, coordinates: [yB]}\n"
         "initial:\n"
         "  q: {xA: L*cos(th0), yA: 0, xB: 0, yB: L*sin(th0)}\n";
}

// Housner's rocking block (examples/models/rocking_block.yaml: width 2b, height 2h, mass m = 1,
// μ = 1 at both corners) in natural coordinates — its bottom corners L = (x1, y1), R = (x2, y2),
// contacts `left` and `right` with Coulomb friction along x1, x2 — lengths in `unit` (b, h and g
// given in it), tilted by th0 = 0.2 on R and released. The model text up to `initial:` (the
// caller adds simulate: and output:).
inline std::string rocking_block_in_coordinates(const std::string& unit, double b, double h,
                                                double g) {
  return "parameters: {m: 1, b: " + std::to_string(b) + ", h: " + std::to_string(h) +
         ", g: " + std::to_string(g) +
         ", th0: 0.2, mu: 1}\n"
         "coordinates: [x1, y1, x2, y2]\n"
         "units: {x1: " +
         unit + ", y1: " + unit + ", x2: " + unit + ", y2: " + unit + "}\n" +
         R"(kinetic_energy: >-
  0.5*m*(((x1_dot + x2_dot)/2 - h/(2*b)*(y2_dot - y1_dot))^2
         + ((y1_dot + y2_dot)/2 + h/(2*b)*(x2_dot - x1_dot))^2)
  + 0.5*m*(b^2 + h^2)/3*((x2_dot - x1_dot)^2 + (y2_dot - y1_dot)^2)/(4*b^2)
potential_energy: m*g*((y1 + y2)/2 + h/(2*b)*(x2 - x1))
constraints:
  - {name: body, holonomic: ((x2 - x1)^2 + (y2 - y1)^2 - 4*b^2)/(4*b)}
  - {name: left, holonomic: y1, unilateral: true}
  - {name: right, holonomic: y2, unilateral: true}
nonideal:
  - {friction: coulomb, constraint: left, mu: mu, coordinates: [x1]}
  - {friction: coulomb, constraint: right, mu: mu, coordinates: [x2]}
initial:
  q: {x1: -2*b*cos(th0), y1: 2*b*sin(th0), x2: 0, y2: 0}
)";
}

// the events of kind `kind` at constraint k
inline std::vector<ContactEvent> events_of(const Trajectory& tr, Index k, ContactEvent::Kind kind) {
  std::vector<ContactEvent> out;
  for (const auto& e : tr.stats.contact_events) {
    if (e.constraint == k && e.kind == kind) out.push_back(e);
  }
  return out;
}

// the sample of tr at time t (failing when there is none)
inline std::size_t sample_at(const Trajectory& tr, double t) {
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (std::abs(tr.t[i] - t) <= 1e-12 * std::max(1.0, std::abs(t))) return i;
  }
  ADD_FAILURE() << "no sample at t = " << t;
  return 0;
}

// A ball (mass m) dropped from rest onto a floor with restitution e, reaching it at t0 with speed
// v0 = g t0: the times of the first `count` apexes, t_k + e^(k+1) v0 / g, t_k the k-th impact
inline std::vector<double> bounce_apex_times(double e, double t0, double g, int count) {
  const double v0 = g * t0;
  double tk = t0;
  std::vector<double> apex_t;
  for (int k = 0; k < count; ++k) {
    apex_t.push_back(tk + std::pow(e, k + 1) * v0 / g);
    tk += 2.0 * std::pow(e, k + 1) * v0 / g;
  }
  return apex_t;
}

// The first `count` impacts of that ball against their closed forms: the k-th at
// t_k = t0 + (2 v0 / g) Σ_{j=1..k} e^j with speed e^k v0 before and e^(k+1) v0 after, the impulse
// m (1 + e) e^k v0 and the energy lost ½ m (1 − e²) (e^k v0)²
inline void expect_bounces(const std::vector<ContactEvent>& impacts, double e, double t0, double g,
                           double m, std::size_t count) {
  ASSERT_GE(impacts.size(), count);
  const double v0 = g * t0;
  double tk = t0;
  for (std::size_t k = 0; k < count; ++k) {
    const double ek = std::pow(e, double(k));
    EXPECT_NEAR(impacts[k].t, tk, 1e-9) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_before, -ek * v0, 1e-8 * v0) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_after, e * ek * v0, 1e-8 * v0) << "impact " << k;
    EXPECT_NEAR(impacts[k].impulse, m * (1 + e) * ek * v0, 1e-8) << "impact " << k;
    EXPECT_NEAR(impacts[k].energy_change, -0.5 * m * (1 - e * e) * ek * ek * v0 * v0, 1e-8)
        << "impact " << k;
    tk += 2.0 * e * ek * v0 / g;
  }
}

// The time at which θ'' = k sin θ, from rest at θ₀, brings cos θ down to c: the test's own RK4
// (step h), the crossing interpolated linearly within the step; −1 when not before t_max
inline double pendulum_time_to_cos(double k, double th0, double c, double t_max, double h) {
  double th = th0, w = 0.0, t = 0.0;
  const auto f = [k](double x) { return k * std::sin(x); };
  while (t < t_max) {
    const double k1 = f(th), l1 = w;
    const double k2 = f(th + 0.5 * h * l1), l2 = w + 0.5 * h * k1;
    const double k3 = f(th + 0.5 * h * l2), l3 = w + 0.5 * h * k2;
    const double k4 = f(th + h * l3), l4 = w + h * k3;
    const double th1 = th + h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
    const double w1 = w + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    const double s0 = std::cos(th) - c, s1 = std::cos(th1) - c;
    if (s0 > 0 && s1 <= 0) return t + h * s0 / (s0 - s1);
    th = th1;
    w = w1;
    t += h;
  }
  return -1.0;
}

// A frictionless ball (a particle of `mass`, radius r, its x, y, z at coordinates at..at+2 of
// model m's run) released from rest at θ₀ from the vertical about the straight edge through
// `edge` along y (its centre at edge + r (sin θ, 0, cos θ)) on contact `name`: it pivots about
// the edge, θ'' = (g/r) sin θ, and leaves where the normal force m g (3 cos θ − 2 cos θ₀)
// vanishes, cos θ* = (2/3) cos θ₀, at the time pendulum_time_to_cos gives (1e-8), then flies the
// parabola to t_end (1e-7); the contact carries m g cos θ₀ at the start and nothing at the end;
// energy is kept; the viewer's contact (visual.contact.<name>.*) is the edge point, its normal
// `normal_sign` (sin θ, 0, cos θ) (+1: from the edge to the ball), while it touches.
inline void expect_tips_off_edge(const Model& m, const std::string& name, std::size_t at,
                                 const Eigen::Vector3d& edge, double r, double th0, double mass,
                                 double g, double t_end, double normal_sign) {
  const Index k = m.system.constraint_index(name);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto releases = events_of(tr, k, ContactEvent::Kind::kRelease);
  ASSERT_EQ(releases.size(), 1u);
  EXPECT_TRUE(events_of(tr, k, ContactEvent::Kind::kImpact).empty());
  const double c_star = 2.0 / 3.0 * std::cos(th0);
  const double t_star = pendulum_time_to_cos(g / r, th0, c_star, t_end, 1e-6);
  ASSERT_GT(t_star, 0.0);
  EXPECT_NEAR(releases[0].t, t_star, 1e-8);
  // free flight from the release point with the release velocity
  const double th_s = std::acos(c_star), v_s = std::sqrt(g * r * c_star);
  const Eigen::Vector3d p_s = edge + r * Eigen::Vector3d(std::sin(th_s), 0, std::cos(th_s));
  const Eigen::Vector3d v_s3 = v_s * Eigen::Vector3d(std::cos(th_s), 0, -std::sin(th_s));
  const double dt = t_end - releases[0].t;
  const Eigen::Vector3d p_end = p_s + v_s3 * dt - 0.5 * g * dt * dt * Eigen::Vector3d::UnitZ();
  const std::size_t last = tr.t.size() - 1, nq = std::size_t(m.system.coordinate_count());
  ASSERT_NEAR(tr.t[last], t_end, 1e-12);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(tr.q[nq * last + at + i], p_end[Index(i)], 1e-7);
  const std::size_t m_rows = std::size_t(tr.m), row = std::size_t(m.system.row_offset(k));
  EXPECT_NEAR(tr.lambda[row], mass * g * std::cos(th0), 1e-9);
  EXPECT_NEAR(tr.lambda[m_rows * last + row], 0.0, 1e-12);
  EXPECT_NEAR(tr.energy.back(), tr.energy.front(), 1e-8);
  // the viewer's contact, sampled 20 times before the release
  Model sampled = m;
  for (int i = 1; i < 20; ++i) sampled.options.output_at.push_back(releases[0].t * i / 20.0);
  const ModelRun run = run_model(sampled);
  const auto column = [&](const std::string& c) -> const std::vector<double>& {
    for (const CsvColumn& col : run.extra_columns)
      if (col.name == "visual.contact." + name + "." + c) return col.values;
    throw std::runtime_error("no column visual.contact." + name + "." + c);
  };
  int touching = 0;
  for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
    if (run.trajectory.t[i] >= releases[0].t) break;
    ++touching;
    const double* b = &run.trajectory.q[nq * i + at];
    const double sn = (b[0] - edge.x()) / r, cs = (b[2] - edge.z()) / r;
    EXPECT_NEAR(column("x")[i], edge.x(), 1e-12);
    EXPECT_NEAR(column("y")[i], edge.y(), 1e-12);
    EXPECT_NEAR(column("z")[i], edge.z(), 1e-12);
    EXPECT_NEAR(column("nx")[i], normal_sign * sn, 1e-9);
    EXPECT_NEAR(column("nz")[i], normal_sign * cs, 1e-9);
  }
  EXPECT_GE(touching, 20);
}

// A ball (a rigid body of `mass`, radius r, its coordinates x, y, z, u0..u3 from `at` of model
// m's run, I = 2/5 m r²) resting on a rough face (contact `name`, Coulomb μ) and launched along x
// at v0 without spin: it slides with v = v0 − μ g t while ω_y = 5 μ g t/(2 r) grows, and rolls
// from t* = 2 v0/(7 μ g) at 5/7 v0 (v 1e-8, ω 1e-7 at 0.05 s, t* ± 1e-4 s and 0.4 s; its height r
// 1e-9, the face's multiplier m g 1e-7); the friction's work is −m v0²/7 (1e-7) and balances the
// energy (1e-8).
inline void expect_rolls_from_closed_form(Model m, const std::string& name, std::size_t at,
                                          double mass, double r, double v0, double mu, double g) {
  const double t_star = 2.0 * v0 / (7.0 * mu * g), v_star = 5.0 / 7.0 * v0;
  m.options.output_at = {0.05, t_star - 1e-4, t_star + 1e-4, 0.4};
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.stick_refusals, 0);
  const std::size_t nq = std::size_t(m.system.coordinate_count());
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    const bool sliding = t < t_star;
    const double v = sliding ? v0 - mu * g * t : v_star;
    const double w = sliding ? 5.0 * mu * g * t / (2.0 * r) : v_star / r;
    const double* u = &tr.q[nq * i + at + 3];
    const double* ud = &tr.qd[nq * i + at + 3];
    const double wy = 2.0 * (u[0] * ud[2] - ud[0] * u[2] + u[3] * ud[1] - u[1] * ud[3]);
    EXPECT_NEAR(tr.qd[nq * i + at], v, 1e-8) << "t = " << t;
    EXPECT_NEAR(wy, w, 1e-7) << "t = " << t;
    EXPECT_NEAR(tr.q[nq * i + at + 2], r, 1e-9) << "t = " << t;
    EXPECT_NEAR(first_multiplier(tr, name, i), mass * g, 1e-7) << "t = " << t;
  }
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  EXPECT_NEAR(tr.work_nonideal.back(), -mass * v0 * v0 / 7.0, 1e-7);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_nonideal.back(), 1e-8);
}

// g and g' of constraint k at (q, q')
inline Eigen::Vector2d gap_of(const System& sys, Index k, const VectorXd& q, const VectorXd& qd) {
  const ConstraintModel& cm = sys.constraint(k).model();
  auto scratch = cm.make_scratch(sys.coordinate_count());
  VectorXd p(1), v(1);
  cm.violation(q, qd, 0.0, scratch.get(), p, v);
  return {p[0], v[0]};
}

// A and b of constraint k at (q, q')
inline std::pair<Eigen::RowVectorXd, double> form_of(const System& sys, Index k, const VectorXd& q,
                                                     const VectorXd& qd) {
  const ConstraintModel& cm = sys.constraint(k).model();
  auto scratch = cm.make_scratch(sys.coordinate_count());
  MatrixXd A(1, sys.coordinate_count());
  VectorXd b(1);
  cm.acceleration_form(q, qd, 0.0, scratch.get(), A, b);
  return {A.row(0), b[0]};
}

// Checks A = dg/dq along directions tangent to |u| = 1 (where the row's quaternion form and the
// normalized rotation agree) and b by g'' = A q'' − b, g'' the central difference of g' along
// q(t) = q + t q' + ½ t² q'', q'(t) = q' + t q'' with u·u'' = −|u'|² (|u(t)| = 1 + O(t³)).
inline void check_form_by_differences(const System& sys, Index k, const VectorXd& q,
                                      const VectorXd& qd, const std::vector<Index>& quaternions,
                                      double tol_A, double tol_b) {
  const Index n = sys.coordinate_count();
  const auto [A, b] = form_of(sys, k, q, qd);
  const double h = 1e-6;
  for (Index trial = 0; trial < 4; ++trial) {
    VectorXd dq = VectorXd::Random(n);
    for (Index o : quaternions) {
      const Eigen::Vector4d u = q.segment<4>(o);
      dq.segment<4>(o) -= u.dot(dq.segment<4>(o)) * u;
    }
    const double fd =
        (gap_of(sys, k, q + h * dq, qd)[0] - gap_of(sys, k, q - h * dq, qd)[0]) / (2 * h);
    EXPECT_NEAR(A.dot(dq), fd, tol_A) << "trial " << trial;
  }
  VectorXd qdd = VectorXd::Random(n);
  for (Index o : quaternions) {
    const Eigen::Vector4d u = q.segment<4>(o), ud = qd.segment<4>(o);
    qdd.segment<4>(o) += (-ud.squaredNorm() - u.dot(qdd.segment<4>(o))) * u;
  }
  const double ht = 1e-5;
  const auto gd = [&](double t) {
    return gap_of(sys, k, q + t * qd + 0.5 * t * t * qdd, qd + t * qdd)[1];
  };
  const double gdd = (gd(ht) - gd(-ht)) / (2 * ht);
  EXPECT_NEAR(A.dot(qdd) - b, gdd, tol_b);
}

// "line:column message | hint" of the ModelError that reading `text` raises, or "no error"
inline std::string model_error_text(const std::string& text) {
  try {
    parse_model(text);
  } catch (const ModelError& e) {
    return std::to_string(e.line()) + ":" + std::to_string(e.column()) + " " + e.message() + " | " +
           e.hint();
  } catch (const std::exception& e) {
    return std::string("not a ModelError: ") + e.what();
  }
  return "no error";
}

// expects reading `text` to fail at `where` ("line:column") with a message containing `what`
inline void expect_model_error(const std::string& text, const std::string& where,
                               const std::string& what) {
  const std::string got = model_error_text(text);
  EXPECT_EQ(got.rfind(where + " ", 0), 0u) << got;
  EXPECT_NE(got.find(what), std::string::npos) << got;
}

// A model (text) whose initial state penetrates a contact: simulate throws
// InconsistentInitialState, and its message holds `what`
inline void expect_penetrated(const std::string& text, const std::string& what) {
  const Model m = parse_model(text);
  try {
    simulate(m.system, m.q0, m.qd0, m.options);
    ADD_FAILURE() << "no error";
  } catch (const InconsistentInitialState& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

}  // namespace ukdyn::testing
