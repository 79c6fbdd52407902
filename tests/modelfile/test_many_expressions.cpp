// SPDX-License-Identifier: BSD-3-Clause
// Loading linear in the number of coordinates (issue #29, item 6; bench/bench_model_load.cpp,
// ManyCoordinates and ManyForces, times it): a `forces:` list of one entry per coordinate used to
// take O(n²) (every entry compiled against all n inputs, the power's zero test adding the n
// terms one by one: 5·10⁴ entries took 70 s), and a kinetic energy depending on the coordinates
// compared the whole chain of coordinates and velocities on each of its n total derivatives.
// What loads fast must load right: the accelerations against their closed forms.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// n coordinates, T = ½ Σ m_i(q) q̇_i², forces F_i = −k_i q_i − c_i q̇_i with k_i = i mod 5,
// c_i = (i mod 3)/4; m_i = 1 + (i mod 3) (constant) or 1 + q_i² (`moving_mass`)
std::string model(int n, bool moving_mass) {
  std::string names, T, F;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    const std::string m = moving_mass ? "(1 + " + q + "^2)" : std::to_string(1 + i % 3);
    T += (i ? " + " : "") + m + "*" + q + "_dot^2";
    F += (i ? ", " : "") + ("-" + std::to_string(i % 5) + "*" + q + " - " + std::to_string(i % 3) +
                            "/4*" + q + "_dot");
  }
  return "coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T + ")\nforces: [" + F + "]\n";
}

// q̈_i at q_i = s_i, q̇_i = v_i: m q̈ + ½ m'(q) q̇² = F (Lagrange, m' = 2q for m = 1 + q²)
double expected(int i, double s, double v, bool moving_mass) {
  const double F = -double(i % 5) * s - double(i % 3) / 4.0 * v;
  return moving_mass ? (F - s * v * v) / (1.0 + s * s) : F / double(1 + i % 3);
}

void check(int n, bool moving_mass) {
  const Model model_ = parse_model(model(n, moving_mass), "many.yaml");
  ASSERT_EQ(model_.system.coordinate_count(), n);
  Workspace ws(model_.system);
  VectorXd q(n), qd(n);
  for (int i = 0; i < n; ++i) {
    q[i] = 0.5 + 0.25 * (i % 7);
    qd[i] = 1.0 - 0.5 * (i % 4);
  }
  ASSERT_EQ(forward_dynamics(model_.system, ws, q, qd, 0.0), Status::kOk);
  for (int i = 0; i < n; ++i) {
    const double e = expected(i, q[i], qd[i], moving_mass);
    ASSERT_NEAR(ws.qdd[i], e, 1e-14 * (1.0 + std::abs(e))) << "q" << i;
  }
}

TEST(ManyExpressions, FiftyThousandForcesEntriesEachActOnTheirCoordinate) { check(50000, false); }

TEST(ManyExpressions, AMassDependingOnEveryCoordinateGivesEachItsOwnCurvatureForce) {
  // (M is not constant, so the engine holds it dense: 2000 coordinates, 32 MB)
  check(2000, true);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
