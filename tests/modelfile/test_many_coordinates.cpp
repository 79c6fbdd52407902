// Many coordinates listed in a model file (reproducers 2026-11-28, many_coordinates.sh: 10^5
// decoupled coordinates took 66 s to load; bench/bench_model_load.cpp, ManyCoordinates, times
// it). What loads fast must load right: a model written as the reproducer writes it — a kinetic
// energy listing every coordinate, one mass each, and a potential the same — against its closed
// form.
#include <cmath>
#include <string>

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

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
