// SPDX-License-Identifier: BSD-3-Clause
// Rough contacts of one body that stop together where only part of the group can hold
// (docs/friction.md, "Several contacts"), against closed forms: a rod on two ends of different
// mu_s stopping together where only one end can hold alone turns about it (RK4 of the pivot, its
// slip time bisected), where none can slides on; the held end's reported holding force
// (lambda.stick, the viewer's) is the whole one, with the part of the other end's sliding
// friction it carries (the rod; a ladder's floor, statics). The group stopping and holding as a
// whole: test_stick_several_contacts.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81, kMass = 3.0, kMu = 0.3;

// column `name` of field f (width n) at sample i
constexpr auto* at = &testing::coordinate_at;
constexpr auto* multipliers = &testing::constraint_multipliers;
constexpr auto* norm = &testing::vector_norm;
constexpr auto* run_at = &testing::run_sampled_at;

// ---- a group that stops together where only part of it can hold ------------------------------

// A rod (m = 3, length L = 0.4 along its y, Iz = m (L² + w²)/12, w = 0.04) lying on the floor on
// its ends A (y = −L/2) and B (y = +L/2), its centre of mass at their height (every force then
// passes through the line AB: no tipping about it, N_A = N_B = m g / 2 whatever the horizontal
// forces), mu = 0.3 at both, mu_s = 0.8 at A and 0.4 at B, launched at x' = −1 against a push
// F x̂ at its centre, up to t_end
std::string rod(double F, double t_end) {
  return "parameters: {m: 3, L: 0.4, w: 0.04, g: 9.81, F: " + std::to_string(F) +
         ", mu: 0.3, musA: 0.8, musB: 0.4}\n"
         "bodies:\n"
         "  - {name: rod, type: rigid, mass: m, inertia: [m*(L^2+w^2)/12, m*w^2/6,"
         " m*(L^2+w^2)/12], position: [0, 0, 0], velocity: [-1, 0, 0]}\n"
         "forces:\n"
         "  - {type: gravity, g: [0, 0, -g]}\n"
         "  - {name: push, type: applied, body: rod, point: [0, 0, 0], force: [F, 0, 0],"
         " torque: [0, 0, 0]}\n"
         "contacts:\n"
         "  - {name: A, body: rod, point: [0, -L/2, 0]}\n"
         "  - {name: B, body: rod, point: [0, L/2, 0]}\n"
         "nonideal:\n"
         "  - {friction: coulomb, constraint: A, mu: mu, mu_static: musA}\n"
         "  - {friction: coulomb, constraint: B, mu: mu, mu_static: musB}\n"
         "simulate: {t_end: " +
         std::to_string(t_end) + ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
}

// The rod turning about A held (B sliding), by RK4 (step <= 1e-5) from φ = φ' = 0 at the stop:
// I_A φ'' = (L/2)(F cos φ − mu m g), I_A = Iz + m L²/4 (yaw −φ; B's friction mu m g / 2 against
// its velocity L φ' (cos φ, −sin φ)); A's holding force f_A = m a_G − F x̂ − f_B, a_G the
// centre's acceleration on its circle of radius L/2 about A
struct Pivot {
  double phi = 0.0, rate = 0.0;
  double fA[2] = {0.0, 0.0}, fB[2] = {0.0, 0.0};
};
Pivot pivot_about_A(double F, double tau) {
  constexpr double L = 0.4, w = 0.04;
  const double I_A = kMass * (L * L + w * w) / 12.0 + kMass * L * L / 4.0;
  auto accel = [&](double phi) { return 0.5 * L * (F * std::cos(phi) - kMu * kMass * kG) / I_A; };
  Pivot p;
  const int steps = std::max(1, int(std::ceil(tau / 1e-5)));
  const double h = tau / steps;
  for (int i = 0; i < steps; ++i) {
    const double k1p = p.rate, k1w = accel(p.phi);
    const double k2p = p.rate + 0.5 * h * k1w, k2w = accel(p.phi + 0.5 * h * k1p);
    const double k3p = p.rate + 0.5 * h * k2w, k3w = accel(p.phi + 0.5 * h * k2p);
    const double k4p = p.rate + h * k3w, k4w = accel(p.phi + h * k3p);
    p.phi += h / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
    p.rate += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
  }
  const double c = std::cos(p.phi), s = std::sin(p.phi), a = accel(p.phi), r2 = p.rate * p.rate;
  const double slide = kMu * kMass * kG / 2.0;
  p.fB[0] = -slide * c;
  p.fB[1] = slide * s;
  p.fA[0] = kMass * 0.5 * L * (a * c - r2 * s) - F - p.fB[0];
  p.fA[1] = kMass * 0.5 * L * (-a * s - r2 * c) - p.fB[1];
  return p;
}

// the friction events of the run at contact `name`
std::vector<ContactEvent> friction_events(const Trajectory& tr, const std::string& name) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.friction == "coulomb." + name) out.push_back(e);
  }
  return out;
}

// the normal force of unilateral contact `name` at sample i (lambda_total: ideal + non-ideal)
double normal_force(const Trajectory& tr, const std::string& name, std::size_t i) {
  for (std::size_t j = 0; j < tr.unilateral.size(); ++j) {
    if (tr.constraint_names[std::size_t(tr.unilateral[j])] == name)
      return tr.lambda_total[i * tr.unilateral.size() + j];
  }
  ADD_FAILURE() << "no unilateral contact " << name;
  return 0.0;
}

// yaw of the rod at sample i (a turn about z: 2 atan2(u3, u0))
double yaw(const Trajectory& tr, std::size_t i) {
  return 2.0 * std::atan2(at(tr, tr.q, "rod.u3", i), at(tr, tr.q, "rod.u0", i));
}

// The rod's ends stop together at t_s = m / (F + mu m g) (same mu, same N: no yaw before). Both
// hold iff F <= mu_sB m g = 11.77 N (the moment about the centre fixes f_Ax = f_Bx = −F/2; only
// the squeeze along AB is free). A alone holds at the stop iff |f_A(0)| <= mu_sA m g / 2, i.e.
// F <= 38.0 N, B alone iff F <= 14.67 N. At F = 18 only A can: the group's joint stick fails,
// B (the least held) slips, A holds, and the rod turns about A until |f_A| reaches mu_sA m g / 2
// at t_s + tau_A (tau_A = 0.23621 s; the independent RK4 above, bisected); at F = 45 no subset
// holds and both ends slide on through the stop, x'' = (F − mu m g) / m, straight; at F = 10
// both hold. (Both sliding is consistent at F = 18 too — a translation, the friction of each
// end against x' — but A, at rest and able to hold, sticks: the largest set that holds.)
TEST(StickSeveralContacts, RodWhoseEndsStopTogetherTurnsAboutTheEndThatAloneCanHold) {
  const double F = 18.0, a = (F + kMu * kMass * kG) / kMass, t_s = 1.0 / a;
  // tau_A: the root of mu_sA m g / 2 − |f_A| (bisection on [0.2, 0.3], 1e-13)
  auto margin_A = [&](double tau) {
    const Pivot p = pivot_about_A(F, tau);
    return 0.8 * kMass * kG / 2.0 - std::hypot(p.fA[0], p.fA[1]);
  };
  double lo = 0.2, hi = 0.3;
  ASSERT_GT(margin_A(lo), 0.0);
  ASSERT_LT(margin_A(hi), 0.0);
  while (hi - lo > 1e-13) (margin_A(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  const double tau_A = 0.5 * (lo + hi);
  EXPECT_NEAR(tau_A, 0.23621, 1e-5);
  const Trajectory tr = run_at(rod(F, t_s + tau_A + 0.02),
                               {0.05, t_s - 1e-4, t_s + 1e-4, t_s + 0.05, t_s + 0.1, t_s + 0.15,
                                t_s + 0.2, t_s + tau_A - 1e-4, t_s + tau_A + 0.01});
  // A sticks at t_s (the stop early by v_stop / a = 1.1e-8 s) and slips at t_s + tau_A, its
  // holding force then mu_sA N_A; B is never listed: released at the stop, as it stopped
  const std::vector<ContactEvent> A = friction_events(tr, "A"), B = friction_events(tr, "B");
  ASSERT_EQ(A.size(), 2u);
  EXPECT_TRUE(B.empty());
  EXPECT_EQ(A[0].kind, ContactEvent::Kind::kStick);
  EXPECT_NEAR(A[0].t, t_s, 1e-7);
  const double t_stop = A[0].t;
  EXPECT_EQ(A[1].kind, ContactEvent::Kind::kSlip);
  EXPECT_NEAR(A[1].t - t_stop, tau_A, 1e-8);
  EXPECT_NEAR(A[1].holding_force, 0.8 * kMass * kG / 2.0, 1e-6);
  EXPECT_NEAR(A[1].friction_limit, 0.8 * kMass * kG / 2.0, 1e-9);
  const double x_s = -t_s + 0.5 * a * t_s * t_s;
  // the viewer's contact forces visual.contact.<A, B>.fx, .fy (run_model) at the same samples
  Model viewed = parse_model(rod(F, t_s + tau_A + 0.02));
  viewed.options.output_at.assign(tr.t.begin(), tr.t.end());
  const ModelRun run = run_model(viewed);
  ASSERT_EQ(run.trajectory.t, tr.t);
  auto viewer = [&](const std::string& name) -> const std::vector<double>& {
    for (const CsvColumn& col : run.extra_columns)
      if (col.name == "visual.contact." + name) return col.values;
    ADD_FAILURE() << "no column visual.contact." << name;
    static const std::vector<double> none(tr.t.size(), 0.0);
    return none;
  };
  const std::vector<double>&Ax = viewer("A.fx"), &Ay = viewer("A.fy"), &Bx = viewer("B.fx"),
        &By = viewer("B.fy");
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    SCOPED_TRACE("t = " + std::to_string(t));
    // N = m g / 2 at each end throughout
    EXPECT_NEAR(normal_force(tr, "A", i), kMass * kG / 2.0, 1e-7);
    EXPECT_NEAR(normal_force(tr, "B", i), kMass * kG / 2.0, 1e-7);
    if (t < t_s) {
      EXPECT_NEAR(at(tr, tr.qd, "rod.x", i), -1.0 + a * t, 1e-7);
      EXPECT_NEAR(yaw(tr, i), 0.0, 1e-12);
      EXPECT_NEAR(at(tr, tr.q, "rod.y", i), 0.0, 1e-12);
      continue;
    }
    if (t > t_s + tau_A) {
      // A slides too: its point has left (x_s, −L/2)
      const double psi = yaw(tr, i);
      const double xA = at(tr, tr.q, "rod.x", i) + 0.2 * std::sin(psi);
      const double yA = at(tr, tr.q, "rod.y", i) - 0.2 * std::cos(psi);
      EXPECT_GT(std::hypot(xA - x_s, yA + 0.2), 1e-6);
      continue;
    }
    const Pivot p = pivot_about_A(F, t - t_stop);
    // turning about A: yaw −φ, A's point at (x_s, −L/2), the centre at x_s + (L/2) sin φ
    const double psi = yaw(tr, i);
    EXPECT_NEAR(psi, -p.phi, 1e-8);
    EXPECT_NEAR(at(tr, tr.q, "rod.x", i), x_s + 0.2 * std::sin(p.phi), 1e-8);
    EXPECT_NEAR(at(tr, tr.q, "rod.y", i), -0.2 + 0.2 * std::cos(p.phi), 1e-8);
    // the centre's velocity (L/2) φ' (cos φ, −sin φ)
    EXPECT_NEAR(at(tr, tr.qd, "rod.x", i), 0.2 * p.rate * std::cos(p.phi), 1e-7);
    EXPECT_NEAR(at(tr, tr.qd, "rod.y", i), -0.2 * p.rate * std::sin(p.phi), 1e-7);
    // the contacts' horizontal force (Qc, ideal + non-ideal: the normals are vertical) is
    // f_A + f_B, A's inside its cone
    const double Qx = at(tr, tr.Qc_ideal, "rod.x", i) + at(tr, tr.Qc_nonideal, "rod.x", i);
    const double Qy = at(tr, tr.Qc_ideal, "rod.y", i) + at(tr, tr.Qc_nonideal, "rod.y", i);
    EXPECT_NEAR(Qx, p.fA[0] + p.fB[0], 1e-6);
    EXPECT_NEAR(Qy, p.fA[1] + p.fB[1], 1e-6);
    EXPECT_LE(std::hypot(p.fA[0], p.fA[1]), 0.8 * kMass * kG / 2.0);
    // A's reported holding force lambda.stick.coulomb.A (κ = 1: the gap's gradient is ẑ; the
    // tangents x̂, ŷ) is the whole f_A the slip decision reads, including the part of B's
    // friction that A carries (the ideal multipliers alone gave −4.54 N for −6.73 N at
    // t_s + 0.15); B slides: no holding force
    const std::vector<double> hA = multipliers(tr, "stick.coulomb.A", i);
    ASSERT_EQ(hA.size(), 2u);
    EXPECT_NEAR(hA[0], p.fA[0], 1e-8);
    EXPECT_NEAR(hA[1], p.fA[1], 1e-8);
    EXPECT_EQ(norm(multipliers(tr, "stick.coulomb.B", i)), 0.0);
    // the viewer draws the same forces (−4.54 N for A's x too, before): A's holding force, B's
    // sliding friction mu m g / 2 against its velocity
    EXPECT_NEAR(Ax[i], p.fA[0], 1e-8);
    EXPECT_NEAR(Ay[i], p.fA[1], 1e-8);
    EXPECT_NEAR(Bx[i], p.fB[0], 1e-6);
    EXPECT_NEAR(By[i], p.fB[1], 1e-6);
  }
}

TEST(StickSeveralContacts, RodWhoseEndsStopTogetherSlidesOnWhereNoSubsetHoldsAndStopsWhereBothDo) {
  // F = 45: no subset holds (A alone needs F <= 38.0): both slide on, straight
  {
    const double F = 45.0, t_s = kMass / (F + kMu * kMass * kG);
    const Trajectory tr = run_at(rod(F, 0.4), {0.02, t_s - 1e-4, t_s + 1e-4, 0.2, 0.4});
    EXPECT_TRUE(tr.stats.contact_events.empty());
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i];
      const double v = t < t_s ? -1.0 + (F + kMu * kMass * kG) * t / kMass
                               : (F - kMu * kMass * kG) * (t - t_s) / kMass;
      EXPECT_NEAR(at(tr, tr.qd, "rod.x", i), v, 1e-6) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "rod.y", i), 0.0, 1e-12) << "t = " << t;
      EXPECT_NEAR(yaw(tr, i), 0.0, 1e-12) << "t = " << t;
    }
  }
  // F = 10 < mu_sB m g = 11.77: both stick at t_s and hold, f_Ax = f_Bx = −F/2
  {
    const double F = 10.0, t_s = kMass / (F + kMu * kMass * kG);
    const Trajectory tr = run_at(rod(F, 0.5), {0.02, t_s - 1e-4, t_s + 1e-4, 0.3, 0.5});
    for (const char* c : {"A", "B"}) {
      const std::vector<ContactEvent> ev = friction_events(tr, c);
      ASSERT_EQ(ev.size(), 1u) << c;
      EXPECT_EQ(ev[0].kind, ContactEvent::Kind::kStick) << c;
      EXPECT_NEAR(ev[0].t, t_s, 1e-7) << c;
    }
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i];
      const double v = t < t_s ? -1.0 + (F + kMu * kMass * kG) * t / kMass : 0.0;
      EXPECT_NEAR(at(tr, tr.qd, "rod.x", i), v, 1e-7) << "t = " << t;
      EXPECT_NEAR(yaw(tr, i), 0.0, 1e-12) << "t = " << t;
      if (t < t_s) continue;
      EXPECT_NEAR(multipliers(tr, "stick.coulomb.A", i)[0], -F / 2.0, 1e-7) << "t = " << t;
      EXPECT_NEAR(multipliers(tr, "stick.coulomb.B", i)[0], -F / 2.0, 1e-7) << "t = " << t;
    }
  }
}

// The ladder of examples/models/ladder_coulomb.yaml (coordinate path: floor friction on xA,
// wall friction on yB; m = 1, L = 2, mu_f = 0.2, mu_w = 0.3) at rest at θ0 = 1.169082, 6e-4 rad
// above the angle where both frictions together just hold: the wall slides at its limit (its
// friction mu_w N_w up, the force it holds with), the floor holds. Statics: N_w (sin θ +
// mu_w cos θ) L = m g (L/2) cos θ, and the floor's holding force is −N_w along x. The ideal
// stick multiplier alone is the floor's share without the wall's friction (−2.0837 for −1.8482):
// lambda.stick.coulomb.floor is the whole one, and so is the viewer's friction on xA
// (visual.contact.floor.Qf.xA, not Qc_nonideal.xA + the multiplier, which counted the wall's
// friction carried twice)
TEST(StickSeveralContacts, LadderFloorHoldsTheWholeForceWhileTheWallSlidesAtItsLimit) {
  const double th0 = 1.169082, m = 1.0, mu_w = 0.3;
  const double N_w = m * kG * std::cos(th0) / (2.0 * (std::sin(th0) + mu_w * std::cos(th0)));
  const std::string text =
      "parameters: {m: 1, L: 2, g: 9.81, mu_f: 0.2, mu_w: 0.3, th0: 1.169082}\n" +
      testing::ladder_in_coordinates(false) +
      "simulate: {t_end: 0.4}\n"
      "output: {every: 0.05}\n"
      "visual: {contacts: {floor: {at: [xA, yA], normal: [0, 1]}}}\n";
  const Model model = parse_model(text);
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const ModelRun run = run_model(model);
  ASSERT_EQ(run.trajectory.t, tr.t);
  const std::vector<double>* viewed = nullptr;
  for (const CsvColumn& col : run.extra_columns)
    if (col.name == "visual.contact.floor.Qf.xA") viewed = &col.values;
  EXPECT_NE(viewed, nullptr);
  ASSERT_GE(tr.t.size(), 8u);
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    SCOPED_TRACE("t = " + std::to_string(tr.t[i]));
    // at rest
    EXPECT_NEAR(at(tr, tr.q, "xA", i), 2.0 * std::cos(th0), 1e-12);
    EXPECT_NEAR(at(tr, tr.qd, "xA", i), 0.0, 1e-12);
    // the floor holds −N_w, the wall (sliding) holds nothing through its stick rows
    EXPECT_NEAR(multipliers(tr, "stick.coulomb.floor", i)[0], -N_w, 1e-9);
    EXPECT_EQ(multipliers(tr, "stick.coulomb.wall", i)[0], 0.0);
    if (viewed) EXPECT_NEAR((*viewed)[i], -N_w, 1e-9);
  }
  // the scene draws the floor's friction from that column alone
  const std::string scene = viewer_scene_json(model);
  EXPECT_NE(scene.find("\"visual.contact.floor.Qf.xA\""), std::string::npos);
  EXPECT_EQ(scene.find("\"Qc_nonideal.xA\""), std::string::npos);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
