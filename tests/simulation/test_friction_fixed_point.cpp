// SPDX-License-Identifier: BSD-3-Clause
// The non-ideal forces' fixed point on the reactions they cause (apply_nonideal, docs/friction.md
// §1; tester u23 item 2): Painlevé's rod sliding close below the critical mu, whose plain rounds
// contract at mu / mu_c, settles on its closed-form normal force in a few rounds, in SI, mm/g/ms
// and cm/g/s; a force whose feedback through the reactions has no fixed point is counted, located
// and named in the run's notes.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// Painlevé's rod (as in test_contact_friction.cpp): a uniform rod (mass m, length L = 2) whose
// end A slides at v towards −x on a rough floor (yA >= 0, friction mu on xA), at tan th = 2.
// The friction's normal force is the fixed point of N ↦ m g / 1.6 + (mu / mu_c) N (the ideal
// share, plus what the friction mu N presses on the floor), whose plain rounds contract at the
// rate mu / mu_c (docs/friction.md §1): 50 of them stopped 0.42 % short at mu = 1.2 and 27 %
// short at mu = 1.3, with status ok. The same rod in SI, in mm/g/ms and in
// cm/g/s (lengths × ℓ, masses × M, times × τ): N = m g / (1.6 − 1.2 mu) in the model's units.
struct RodUnits {
  const char* units;  // the model file's units: (empty for SI)
  double length, mass, time;
};
constexpr RodUnits kRodUnits[] = {{"", 1.0, 1.0, 1.0},
                                  {"length: mm, mass: g, time: ms", 1e3, 1e3, 1e3},
                                  {"length: cm, mass: g, time: s", 1e2, 1e3, 1.0}};

std::string rod_in(const RodUnits& u) {
  std::ostringstream s;
  s.precision(17);
  const double L = 2.0 * u.length, m = u.mass, g = kG * u.length / (u.time * u.time);
  if (*u.units != '\0') s << "units: {" << u.units << "}\n";
  s << "parameters: {m: " << m << ", L: " << L << ", g: " << g
    << ", th0: 1.1071487177940904, mu: 0.5, v: " << u.length / u.time << "}\n"
    << "coordinates: [xA, yA, xB, yB]\n"
    << "kinetic_energy: m/6*(xA_dot^2 + yA_dot^2 + xA_dot*xB_dot + yA_dot*yB_dot + xB_dot^2 + "
       "yB_dot^2)\n"
    << "potential_energy: m*g*(yA + yB)/2\n"
    << "constraints:\n"
    << "  - {name: rod, holonomic: ((xA - xB)^2 + (yA - yB)^2 - L^2)/(2*L)}\n"
    << "  - {name: floor, holonomic: yA, unilateral: true}\n"
    << "nonideal:\n"
    << "  - {friction: coulomb, constraint: floor, mu: mu, coordinates: [xA]}\n"
    << "initial:\n"
    << "  q: {xA: 0, yA: 0, xB: L*cos(th0), yB: L*sin(th0)}\n"
    << "  q_dot: {xA: -v, xB: -v}\n"
    << "simulate: {t_end: " << 5e-5 * u.time << ", integrator: dopri5, rtol: 1e-10}\n"
    << "output: {every: " << 5e-5 * u.time << "}\n";
  return s.str();
}

TEST(FrictionFixedPoint, PainleveRodCloseBelowTheCriticalMuSettlesOnTheClosedFormInAFewRounds) {
  for (const RodUnits& u : kRodUnits) {
    for (const double mu : {1.2, 1.3, 1.33}) {
      SCOPED_TRACE(std::string("units {") + u.units + "}, mu " + std::to_string(mu));
      const Model model = parse_model(rod_in(u), "rod.yaml", {{"mu", mu}});
      const double m = u.mass, g = kG * u.length / (u.time * u.time);
      const double N = m * g / (1.6 - 1.2 * mu);
      // one evaluation at the start: N is the floor's whole multiplier (its row yA has unit
      // gradient), A stays on the floor
      Workspace ws(model.system);
      ASSERT_EQ(forward_dynamics(model.system, ws, model.q0, model.qd0, 0.0), Status::kOk);
      const Index floor = model.system.row_offset(1);
      EXPECT_NEAR(ws.lambda[floor] + ws.lambda_nonideal[floor], N, 1e-9 * N);
      EXPECT_NEAR(ws.qdd[1], 0.0, 1e-9 * g);
      // the rounds: two plain ones, then Anderson's extrapolation, exact for this affine map
      // (the plain rounds alone would need log(1e-13) / log(mu / mu_c), 284 to 12 000)
      EXPECT_EQ(ws.counters.nonideal_unsettled, 0);
      EXPECT_GE(ws.counters.nonideal_rounds, 3);
      EXPECT_LE(ws.counters.nonideal_rounds, 4);
      // a run, short of A's stop (at mu >= 1.2 the friction stops A within 6 ms, at 1.33
      // within 0.15 ms, and it sticks): the same N at its first sample, and nothing to note
      const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      EXPECT_TRUE(tr.stats.contact_events.empty());
      EXPECT_TRUE(tr.stats.notes.empty()) << tr.stats.notes.front();
      ASSERT_EQ(tr.lambda_total.size(), tr.t.size());
      EXPECT_NEAR(tr.lambda_total[0], N, 1e-9 * N);
    }
  }
}

// A force that pushes a particle into a floor (y = 0, bilateral) with twice the floor's normal
// force, C = (0, −2 N_floor), has no consistent N: N = m g + 2 N has no solution N >= 0. Every
// evaluation ends unsettled after its 51 rounds, and the run's notes say so, naming the floor.
TEST(FrictionFixedPoint, ReactionsThatDoNotSettleAreNotedNamingTheConstraint) {
  for (const RodUnits& u : kRodUnits) {
    SCOPED_TRACE(std::string("units {") + u.units + "}");
    std::ostringstream s;
    s.precision(17);
    if (*u.units != '\0') s << "units: {" << u.units << "}\n";
    s << "parameters: {m: " << u.mass << ", g: " << kG * u.length / (u.time * u.time)
      << ", v: " << u.length / u.time << "}\n"
      << "coordinates: [x, y]\n"
      << "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
      << "potential_energy: m*g*y\n"
      << "constraints:\n"
      << "  - {name: floor, holonomic: y}\n"
      << "nonideal:\n"
      << "  - {C: [0, -2*N_floor]}\n"
      << "initial: {q: {x: 0, y: 0}, q_dot: {x: v, y: 0}}\n"
      << "simulate: {t_end: " << 0.01 * u.time << ", integrator: rk4, step: " << 0.005 * u.time
      << "}\n"
      << "output: {every: " << 0.005 * u.time << "}\n";
    const Model model = parse_model(s.str(), "push.yaml");
    Workspace ws(model.system);
    const double t = 0.003 * u.time;
    ASSERT_EQ(forward_dynamics(model.system, ws, model.q0, model.qd0, t), Status::kOk);
    EXPECT_EQ(ws.counters.nonideal_unsettled, 1);
    EXPECT_EQ(ws.counters.nonideal_rounds, 51);
    EXPECT_EQ(ws.unsettled.worst_constraint, 0);
    EXPECT_EQ(ws.unsettled.first_t, t);
    EXPECT_EQ(ws.unsettled.last_t, t);
    EXPECT_EQ(ws.unsettled.worst_t, t);
    EXPECT_GT(ws.unsettled.worst_residual, 1e-13);
    // (the reaction is along the floor's normal: the motion does not depend on it)
    EXPECT_NEAR(ws.qdd.norm(), 0.0, 1e-12 * kG * u.length / (u.time * u.time));
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    ASSERT_EQ(tr.stats.notes.size(), 1u);
    const std::string& note = tr.stats.notes[0];
    const std::string time = u.time == 1.0 ? " s" : " ms";
    EXPECT_NE(note.find("t = 0 to " + std::string(u.time == 1.0 ? "0.01" : "10") + time +
                        ": the non-ideal forces did not settle on the reactions they cause in "),
              std::string::npos)
        << note;
    EXPECT_NE(note.find("still moved the reaction of 'floor' by "), std::string::npos) << note;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
