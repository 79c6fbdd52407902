// SPDX-License-Identifier: BSD-3-Clause
// Many coordinates listed in a model file (reproducers 2026-11-28, many_coordinates.sh: 10^5
// decoupled coordinates took 66 s to load; bench/bench_model_load.cpp, ManyCoordinates, times
// it). What loads fast must load right: a model written as the reproducer writes it — a kinetic
// energy listing every coordinate, one mass each, and a potential the same — against its closed
// form.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// n uncoupled oscillators of masses m_i = 1 + (i mod 3) and stiffnesses k_i = i mod 5:
// q̈_i = -k_i q_i / m_i
std::string oscillators(int n) {
  std::string names, T, V;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? " + " : "") + std::to_string(1 + i % 3) + "*" + q + "_dot^2";
    V += (i ? " + " : "") + std::to_string(i % 5) + "*" + q + "^2";
  }
  return "coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T + ")\npotential_energy: 0.5*(" +
         V + ")\nsimulate: {t_end: 0.01}\noutput: {every: 0.01}\n";
}

TEST(ManyCoordinates, FiftyThousandOscillatorsHaveTheirOwnMassesAndSprings) {
  const int n = 50000;
  const Model model = parse_model(oscillators(n), "many.yaml");
  ASSERT_EQ(model.system.coordinate_count(), n);
  EXPECT_EQ(model.system.coordinate_names()[std::size_t(n - 1)], "q" + std::to_string(n - 1));
  // M = diag(1 + i mod 3), given by its 1 × 1 blocks
  ASSERT_TRUE(model.system.mass_is_block_diagonal());
  ASSERT_EQ(model.system.mass_blocks().size(), std::size_t(n));
  Workspace ws(model.system);
  const VectorXd q = VectorXd::Ones(n), qd = VectorXd::Ones(n);
  ASSERT_EQ(forward_dynamics(model.system, ws, q, qd, 0.0), Status::kOk);
  for (int i = 0; i < n; ++i) {
    const double expected = -double(i % 5) / double(1 + i % 3);
    ASSERT_NEAR(ws.qdd[i], expected, 1e-15 * (1.0 + std::abs(expected))) << "q" << i;
  }
}

// The reproducer's model at its size, 10⁵ coordinates, with masses of their own: T = ½ Σ m_i q̇_i²,
// m_i = 1 + (i mod 7)/4 (written 1.25, 1.5, … as decimals), and no forces. M is given by its
// 1 × 1 blocks m_i; Q = 0 (T holds no coordinate); the external power is 0.
TEST(ManyCoordinates, AHundredThousandCoordinatesLoadTheirMasses) {
  const int n = 100000;
  std::string names, T;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? "+" : "") + std::to_string(1.0 + double(i % 7) / 4.0).substr(0, 4) + "*" + q +
         "_dot^2";
  }
  const Model model = parse_model("coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T +
                                      ")\nsimulate: {t_end: 0.01}\noutput: {every: 0.01}\n",
                                  "many.yaml");
  const System& sys = model.system;
  ASSERT_EQ(sys.coordinate_count(), n);
  ASSERT_TRUE(sys.mass_is_block_diagonal());
  ASSERT_EQ(sys.mass_blocks().size(), std::size_t(n));
  for (const int i : {0, 1, 6, 7, 12345, 99998, 99999}) {
    const MassBlock& b = sys.mass_blocks()[std::size_t(i)];
    EXPECT_EQ(b.offset, i);
    ASSERT_EQ(b.size, 1);
    ASSERT_FALSE(b.fn) << "constant";
    EXPECT_EQ(b.value(0, 0), 1.0 + double(i % 7) / 4.0) << "m_" << i;  // exact: quarters
  }
  VectorXd q(n), qd(n), Q(n);
  for (int i = 0; i < n; ++i) {
    q[i] = 0.001 * i;
    qd[i] = 1.0 - 0.002 * (i % 11);
  }
  sys.forces(q, qd, 0.3, Q);
  EXPECT_EQ(Q.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(sys.external_power(q, qd, 0.3), 0.0);
}

// 5·10⁴ `forces:` entries (the other reproducer of issue #29 item 6: 70 s, O(N²)), each of its own,
// F_i = −k_i q_i − c q̇_i t with k_i = i mod 5 and c = 0.5, beside T = ½ Σ q̇_i² and
// V = Σ ½ q_i²: Q_i = −q_i − k_i q_i − c q̇_i t, and the external power (what V does not account
// for) is Σ q̇_i F_i, against the closed forms.
TEST(ManyForces, FiftyThousandForceEntriesGiveQAndTheirPower) {
  const int n = 50000;
  std::string names, T, V, F;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? "+" : "") + q + "_dot^2";
    V += (i ? "+" : "") + q + "^2";
    F += (i ? ", " : "") + ("-" + std::to_string(i % 5) + "*" + q + " - 0.5*" + q + "_dot*t");
  }
  const Model model = parse_model("coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T +
                                      ")\npotential_energy: 0.5*(" + V + ")\nforces: [" + F +
                                      "]\nsimulate: {t_end: 0.01}\n",
                                  "forces.yaml");
  const System& sys = model.system;
  ASSERT_EQ(sys.coordinate_count(), n);
  VectorXd q(n), qd(n), Q(n);
  for (int i = 0; i < n; ++i) {
    q[i] = std::sin(0.001 * i);
    qd[i] = std::cos(0.003 * i);
  }
  const double t = 0.7;
  sys.forces(q, qd, t, Q);
  double power = 0.0;
  for (int i = 0; i < n; ++i) {
    const double F_i = -double(i % 5) * q[i] - 0.5 * qd[i] * t;
    power += qd[i] * F_i;
    const double expected = -q[i] + F_i;
    ASSERT_NEAR(Q[i], expected, 4e-16 * (1.0 + std::abs(expected))) << "Q_" << i;
  }
  // a sum of 5·10⁴ terms of magnitude ≤ 5: a relative error of some 1e-12 at most
  EXPECT_NEAR(sys.external_power(q, qd, t), power, 1e-11 * (1.0 + std::abs(power)));
  EXPECT_GT(std::abs(power), 100.0);  // not a sum that happens to be 0
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
