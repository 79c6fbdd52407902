// SPDX-License-Identifier: BSD-3-Clause
// Large models (issue #14, item 7): what loads fast must load the same. The expression engine's
// shortcuts (inputs_of, sums built at once, derivatives skipped where they are 0) against the
// term-by-term results, and big generated models against their closed-form dynamics.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/expression.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using expr::Expr;
using expr::ExpressionSet;

// the values of a program at `in`
std::vector<double> values(const expr::Program& p, const std::vector<double>& in) {
  std::vector<double> out(std::size_t(p.outputs())), scratch(std::size_t(p.scratch_size()));
  p.evaluate(in.data(), out.data(), scratch.data());
  return out;
}

TEST(ModelLoad, InputsOfListsTheInputsAnExpressionHoldsInOrder) {
  ExpressionSet set({"x", "y", "x_dot", "t"});
  set.set_constant("m", 2.0);
  EXPECT_EQ(set.inputs_of(set.parse("m*x_dot^2 + sin(t)*y")), (std::vector<Index>{1, 2, 3}));
  EXPECT_EQ(set.inputs_of(set.parse("m*3")), std::vector<Index>());
  EXPECT_EQ(set.inputs_of(set.parse("atan2(y, x)*x")), (std::vector<Index>{0, 1}));
  // x − x is 0 as GiNaC builds it; sin(x)^2 + cos(x)^2 − 1 holds x until normalized
  EXPECT_EQ(set.inputs_of(set.parse("x - x")), std::vector<Index>());
  EXPECT_EQ(set.inputs_of(set.parse("sin(x)^2 + cos(x)^2 - 1")), (std::vector<Index>{0}));
  EXPECT_THROW(set.inputs_of(1000), std::invalid_argument);
}

TEST(ModelLoad, LiteralZeroIsWhatDiffGivesForAnInputNotHeld) {
  ExpressionSet set({"x", "y"});
  const Expr e = set.parse("x^2 + 3*x");
  EXPECT_TRUE(set.is_literal_zero(set.diff(e, "y")));
  EXPECT_TRUE(set.is_literal_zero(set.constant(0.0)));
  EXPECT_FALSE(set.is_literal_zero(set.diff(e, "x")));
  // 0 only once expanded
  EXPECT_FALSE(set.is_literal_zero(set.parse("(x + 1)^2 - x^2 - 2*x - 1")));
  EXPECT_TRUE(set.is_zero(set.parse("(x + 1)^2 - x^2 - 2*x - 1")));
}

TEST(ModelLoad, SumAtOnceIsTheTermByTermSum) {
  ExpressionSet set({"x", "y", "t"});
  std::vector<Expr> terms;
  Expr by_terms = set.constant(0.0);
  for (int i = 1; i <= 300; ++i) {
    const std::string s = "sin(x + " + std::to_string(i % 37) + ")*y^" + std::to_string(i % 5) +
                          " - " + std::to_string(i) + "/7*x*t";
    terms.push_back(set.parse(s));
    by_terms = set.add(by_terms, terms.back());
  }
  const Expr at_once = set.sum(terms);
  EXPECT_EQ(set.to_string(at_once), set.to_string(by_terms));
  EXPECT_EQ(set.to_string(set.sum({})), "0");
  const std::vector<double> in{0.3, -1.7, 2.5};
  EXPECT_EQ(values(set.compile({at_once}), in), values(set.compile({by_terms}), in));
}

TEST(ModelLoad, ParsedLongSumIsTheTermByTermSum) {
  // the parser sums a + b − c … at once; built pairwise with add and subtract, the same
  ExpressionSet set({"x", "x_dot"});
  std::string text;
  Expr by_terms = 0;
  for (int i = 1; i <= 2000; ++i) {
    const std::string term = "sin(x + " + std::to_string(i) + ")/" + std::to_string(2000 + i % 3);
    const bool minus = i % 4 == 3;
    text += (i == 1 ? "" : minus ? " - " : " + ") + term;
    const Expr t = set.parse(term);
    by_terms = i == 1 ? t : minus ? set.subtract(by_terms, t) : set.add(by_terms, t);
  }
  const Expr parsed = set.parse(text);
  EXPECT_EQ(set.to_string(parsed), set.to_string(by_terms));
  const std::vector<double> in{0.41, 0.0};
  EXPECT_EQ(values(set.compile({parsed}), in), values(set.compile({by_terms}), in));
}

TEST(ModelLoad, LongSumsDifferentiateAsGiNaCDoes) {
  // diff() of a sum of ≥ 16 terms goes through the terms holding the input only; inside y·(…)
  // GiNaC differentiates the whole sum itself: the two must be the same expression
  ExpressionSet set({"x", "z", "y", "x_dot", "z_dot", "y_dot", "t"});
  std::string sum;
  for (int i = 1; i <= 60; ++i) {
    sum += (i > 1 ? " + " : "") + std::to_string(i) + "/7*" +
           (i % 3 == 0   ? "x^2*sin(z + " + std::to_string(i) + ")"
            : i % 3 == 1 ? "z^" + std::to_string(i % 5 + 1) + "*t"
                         : "x*cos(x)^" + std::to_string(i % 4));
  }
  sum += " + x + 3";
  const Expr s = set.parse(sum), ys = set.parse("y*(" + sum + ")"), y = set.parse("y");
  for (const char* name : {"x", "z", "t", "x_dot"}) {
    const Expr mine = set.multiply(y, set.diff(s, name)), ginac = set.diff(ys, name);
    EXPECT_EQ(set.to_string(mine), set.to_string(ginac)) << name;
  }
  const Expr d = set.total_derivative(s, "t", {{"x", "x_dot"}, {"z", "z_dot"}});
  const Expr dy = set.total_derivative(ys, "t", {{"x", "x_dot"}, {"z", "z_dot"}});
  EXPECT_TRUE(set.is_zero(set.subtract(set.multiply(y, d), dy)));
}

TEST(ModelLoad, TotalDerivativeSkipsOnlyTheCoordinatesNotHeld) {
  ExpressionSet set({"x", "y", "z", "x_dot", "y_dot", "z_dot", "t"});
  const Expr e = set.parse("x^2*sin(t) + y*z_dot");
  const Expr d = set.total_derivative(e, "t", {{"x", "x_dot"}, {"y", "y_dot"}, {"z", "z_dot"}});
  // by hand: ∂e/∂t + ∂e/∂x ẋ + ∂e/∂y ẏ (no z: e holds ż only)
  const Expr by_hand =
      set.add(set.diff(e, "t"), set.add(set.multiply(set.diff(e, "x"), set.parse("x_dot")),
                                        set.multiply(set.diff(e, "y"), set.parse("y_dot"))));
  EXPECT_TRUE(set.is_zero(set.subtract(d, by_hand)));
  const std::vector<double> in{0.3, -0.2, 0.9, 1.1, -0.4, 0.6, 0.7};
  const double expected = 2 * 0.3 * std::sin(0.7) * 1.1 + 0.3 * 0.3 * std::cos(0.7) + 0.6 * -0.4;
  const double got = values(set.compile({d}), in)[0];
  EXPECT_NEAR(got, expected, 1e-15);
  EXPECT_THROW(set.total_derivative(e, "t", {{"w", "x_dot"}}), std::invalid_argument);
  EXPECT_THROW(set.total_derivative(e, "t", {{"x", "w_dot"}}), std::invalid_argument);
}

// n oscillators q_i with masses m_i and stiffnesses k_i written as kinetic and potential
// energy, optionally with holonomic constraints q_{2c} = q_{2c+1} for c < pairs
std::string oscillators(int n, int pairs, const std::vector<double>& m,
                        const std::vector<double>& k) {
  std::string names, T, V, C;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? " + " : "") + std::to_string(m[std::size_t(i)]) + "*" + q + "_dot^2";
    V += (i ? " + " : "") + std::to_string(k[std::size_t(i)]) + "*" + q + "^2";
  }
  for (int c = 0; c < pairs; ++c) {
    C += "  - {name: c" + std::to_string(c) + ", holonomic: q" + std::to_string(2 * c) + " - q" +
         std::to_string(2 * c + 1) + "}\n";
  }
  return "coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T + ")\npotential_energy: 0.5*(" +
         V + ")\n" + (pairs ? "constraints:\n" + C : "");
}

// m_i, k_i with 6 decimals (as written into the model)
std::vector<double> decimals(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(std::stod(std::to_string(u(rng))));
  return v;
}

TEST(ModelLoad, TwoThousandUncoupledOscillatorsMoveAsOne) {
  const int n = 2000;
  std::mt19937 rng(14);
  const auto m = decimals(rng, n, 0.5, 3.0), k = decimals(rng, n, 1.0, 20.0);
  const Model model = parse_model(oscillators(n, 0, m, k), "big.yaml");
  ASSERT_EQ(model.system.coordinate_count(), n);
  // M = diag(m) is given by its 1 × 1 blocks
  EXPECT_TRUE(model.system.mass_is_block_diagonal());
  EXPECT_EQ(model.system.mass_blocks().size(), std::size_t(n));
  std::normal_distribution<double> g;
  VectorXd q(n), qd(n);
  for (int i = 0; i < n; ++i) q[i] = g(rng), qd[i] = g(rng);
  Workspace ws(model.system);
  ASSERT_EQ(forward_dynamics(model.system, ws, q, qd, 0.3), Status::kOk);
  for (int i = 0; i < n; ++i) {
    const double expected = -k[std::size_t(i)] / m[std::size_t(i)] * q[i];
    ASSERT_NEAR(ws.qdd[i], expected, 1e-13 * (1.0 + std::abs(expected))) << "q" << i;
  }
  // the same as one of them alone, a small model on the dense engine
  const int i = 1234;
  const Model one = parse_model(oscillators(1, 0, {m[i]}, {k[i]}), "one.yaml");
  Workspace w1(one.system);
  ASSERT_EQ(forward_dynamics(one.system, w1, q.segment(i, 1), qd.segment(i, 1), 0.3), Status::kOk);
  EXPECT_NEAR(ws.qdd[i], w1.qdd[0], 1e-14 * std::abs(w1.qdd[0]));
  // and check_model reports it whole
  const CheckReport r = check_model(model);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.degrees_of_freedom, n);
  EXPECT_TRUE(r.mass_positive_definite);
}

TEST(ModelLoad, ThreeHundredOscillatorsTiedInPairsMoveAsPairs) {
  // q_{2c} = q_{2c+1}: the pair moves as one mass m_a + m_b on a spring k_a + k_b
  const int n = 300, pairs = 150;
  std::mt19937 rng(7);
  const auto m = decimals(rng, n, 0.5, 3.0), k = decimals(rng, n, 1.0, 20.0);
  const Model model = parse_model(oscillators(n, pairs, m, k), "pairs.yaml");
  ASSERT_EQ(model.system.constraint_count(), pairs);
  std::normal_distribution<double> g;
  VectorXd q(n), qd(n);
  for (int c = 0; c < pairs; ++c) {
    q[2 * c] = q[2 * c + 1] = g(rng);
    qd[2 * c] = qd[2 * c + 1] = g(rng);
  }
  Workspace ws(model.system);
  ASSERT_EQ(forward_dynamics(model.system, ws, q, qd, 0.0), Status::kOk);
  for (int c = 0; c < pairs; ++c) {
    const std::size_t a = std::size_t(2 * c), b = a + 1;
    const double expected = -(k[a] + k[b]) / (m[a] + m[b]) * q[2 * c];
    ASSERT_NEAR(ws.qdd[2 * c], expected, 1e-11 * (1.0 + std::abs(expected))) << "pair " << c;
    ASSERT_NEAR(ws.qdd[2 * c + 1], expected, 1e-11 * (1.0 + std::abs(expected))) << "pair " << c;
  }
  const CheckReport r = check_model(model);
  EXPECT_EQ(r.rank, pairs);
  EXPECT_EQ(r.degrees_of_freedom, n - pairs);
  EXPECT_TRUE(r.redundant.empty());
  // each constraint is local to its pair: the sparse engine runs it, and the dense engine (an
  // independent factorization of the whole M and A) agrees
  for (int c = 0; c < pairs; ++c) {
    ASSERT_EQ(model.system.constraint(c).model().columns(), (std::vector<Index>{2 * c, 2 * c + 1}));
  }
  EXPECT_TRUE(ws.is_sparse());
  SolverOptions dense;
  dense.engine = Engine::kDense;
  Workspace wd(model.system, dense);
  ASSERT_EQ(forward_dynamics(model.system, wd, q, qd, 0.0), Status::kOk);
  for (int i = 0; i < n; ++i)
    ASSERT_NEAR(ws.qdd[i], wd.qdd[i], 1e-12 * (1.0 + std::abs(wd.qdd[i])));
}

TEST(ModelLoad, LocalConstraintsOfEveryKindWriteTheirColumnsOnly) {
  // 30 unit masses on springs k_i = 1 + i; three constraints, each over two coordinates:
  //   holonomic q0 − q1 = 0, nonholonomic q2' − t q3' = 0, acceleration form q4'' − q5'' = 0.1,
  //   and one over no coordinate written in full (q29 − q29 + t − 1/2, kept dense)
  const int n = 30;
  std::string names, T, V, A = "[";
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? " + " : "") + q + "_dot^2";
    V += (i ? " + " : "") + std::to_string(1 + i) + "*" + q + "^2";
    A += std::string(i ? ", " : "") + (i == 4 ? "1" : i == 5 ? "-1" : "0");
  }
  A += "]";
  const Model model = parse_model("coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T +
                                      ")\npotential_energy: 0.5*(" + V +
                                      ")\nconstraints:\n  - {name: h, holonomic: q0 - q1}\n"
                                      "  - {name: nh, nonholonomic: q2_dot - t*q3_dot}\n"
                                      "  - {name: acc, A: [" +
                                      A + "], b: [0.1]}\n",
                                  "local.yaml");
  EXPECT_EQ(model.system.constraint(0).model().columns(), (std::vector<Index>{0, 1}));
  EXPECT_EQ(model.system.constraint(1).model().columns(), (std::vector<Index>{2, 3}));
  EXPECT_EQ(model.system.constraint(2).model().columns(), (std::vector<Index>{4, 5}));
  // the dense form: rows of A over all n columns, zero outside the pair
  const Constraint& nh = model.system.constraint(1);
  auto scratch = nh.model().make_scratch(n);
  VectorXd q = VectorXd::LinSpaced(n, -1.0, 1.0), qd = VectorXd::LinSpaced(n, 0.5, -0.7);
  MatrixXd Arow = MatrixXd::Constant(1, n, 7.0);
  VectorXd b(1);
  nh.model().acceleration_form(q, qd, 2.0, scratch.get(), Arow, b);
  MatrixXd expected = MatrixXd::Zero(1, n);
  expected(0, 2) = 1.0;
  expected(0, 3) = -2.0;
  EXPECT_EQ(Arow, expected);
  EXPECT_DOUBLE_EQ(b[0], qd[3]);  // b = −∂ψ/∂t = q3'
  // the motion at a consistent state: q0 = q1, q2' = t q3'
  q[1] = q[0];
  qd[1] = qd[0];
  const double t = 2.0;
  qd[2] = t * qd[3];
  Workspace ws(model.system);
  ASSERT_TRUE(ws.is_sparse());
  ASSERT_EQ(forward_dynamics(model.system, ws, q, qd, t), Status::kOk);
  // pair 0: one mass 2 on spring 1 + 2; pair 4, 5: q4'' − q5'' = 0.1 with the force split evenly
  EXPECT_NEAR(ws.qdd[0], -3.0 / 2.0 * q[0], 1e-13);
  EXPECT_NEAR(ws.qdd[1], ws.qdd[0], 1e-13);
  const double f4 = -5.0 * q[4], f5 = -6.0 * q[5], lam = (0.1 - (f4 - f5)) / 2.0;
  EXPECT_NEAR(ws.qdd[4], f4 + lam, 1e-13);
  EXPECT_NEAR(ws.qdd[5], f5 - lam, 1e-13);
  // nonholonomic: q2'' − t q3'' = q3', the reaction along (1, −t) for unit masses
  const double f2 = -3.0 * q[2], f3 = -4.0 * q[3];
  const double mu = (qd[3] - (f2 - t * f3)) / (1.0 + t * t);
  EXPECT_NEAR(ws.qdd[2], f2 + mu, 1e-13);
  EXPECT_NEAR(ws.qdd[3], f3 - t * mu, 1e-13);
  for (int i = 6; i < n; ++i) EXPECT_NEAR(ws.qdd[i], -(1.0 + i) * q[i], 1e-13);
}

TEST(ModelLoad, CoupledBlocksOfTheMassMatrixKeepTheirCoupling) {
  // T = ½ Σ_c (2 ẋ_c² + 2 ẋ_c ẏ_c + ẏ_c²): 40 blocks [[2, 1], [1, 1]], V = ½ Σ (x_c² + y_c²);
  // M⁻¹ = [[1, −1], [−1, 2]], so ẍ = −x + y, ÿ = x − 2y
  const int blocks = 40;
  std::string names, T, V;
  for (int c = 0; c < blocks; ++c) {
    const std::string x = "x" + std::to_string(c), y = "y" + std::to_string(c);
    names += (c ? ", " : "") + x + ", " + y;
    T += (c ? " + " : "") + ("2*" + x + "_dot^2 + 2*" + x + "_dot*" + y + "_dot + " + y + "_dot^2");
    V += (c ? " + " : "") + (x + "^2 + " + y + "^2");
  }
  const Model model = parse_model("coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T +
                                      ")\npotential_energy: 0.5*(" + V + ")\n",
                                  "blocks.yaml");
  ASSERT_TRUE(model.system.mass_is_block_diagonal());
  ASSERT_EQ(model.system.mass_blocks().size(), std::size_t(blocks));
  EXPECT_EQ(model.system.mass_blocks()[3].value, (MatrixXd(2, 2) << 2, 1, 1, 1).finished());
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  VectorXd q(2 * blocks), qd(2 * blocks);
  for (int i = 0; i < 2 * blocks; ++i) q[i] = g(rng), qd[i] = g(rng);
  Workspace ws(model.system);
  ASSERT_EQ(forward_dynamics(model.system, ws, q, qd, 0.0), Status::kOk);
  for (int c = 0; c < blocks; ++c) {
    const double x = q[2 * c], y = q[2 * c + 1];
    EXPECT_NEAR(ws.qdd[2 * c], -x + y, 1e-12);
    EXPECT_NEAR(ws.qdd[2 * c + 1], x - 2 * y, 1e-12);
  }
}

TEST(ModelLoad, APotentialOfTwentyThousandDistinctTermsHasItsExactForce) {
  // V = Σ_{i=1}^{N} sin(x + i)/N: Q = −Σ cos(x + i)/N
  const int N = 20000;
  std::string V;
  for (int i = 1; i <= N; ++i)
    V += (i > 1 ? "+" : "") + ("sin(x+" + std::to_string(i) + ")/" + std::to_string(N));
  const Model model =
      parse_model("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\npotential_energy: " + V + "\n",
                  "distinct.yaml");
  const double x = 0.37;
  double expected = 0.0;
  for (int i = 1; i <= N; ++i) expected -= std::cos(x + i) / N;
  Workspace ws(model.system);
  ASSERT_EQ(forward_dynamics(model.system, ws, VectorXd::Constant(1, x), VectorXd::Zero(1), 0.0),
            Status::kOk);
  EXPECT_NEAR(ws.qdd[0], expected, 1e-13);
  double v = 0.0;
  for (int i = 1; i <= N; ++i) v += std::sin(x + i) / N;
  EXPECT_NEAR(model.system.potential_energy(VectorXd::Constant(1, x), 0.0), v, 1e-13);
}

TEST(ModelLoad, ErrorsOfLargeModelsNameTheVelocityAndTheInput) {
  // the first entry of M (row by row) that depends on a velocity, and its first velocity, as
  // before: ∂²T/∂q̇3∂q̇7 = 3 q̇7²
  std::string names, T;
  for (int i = 0; i < 30; ++i) {
    names += (i ? ", " : "") + ("q" + std::to_string(i));
    T += (i ? " + " : "") + ("q" + std::to_string(i) + "_dot^2");
  }
  try {
    parse_model("coordinates: [" + names + "]\nkinetic_energy: " + T + " + q7_dot^3*q3_dot\n",
                "cubic.yaml");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("its mass matrix depends on 'q7_dot'"), std::string::npos)
        << e.what();
    EXPECT_EQ(e.line(), 2);
  }
  try {
    parse_model(
        "coordinates: [" + names + "]\nkinetic_energy: " + T + "\nsimulate: {t_end: q2 + q1_dot}\n",
        "constant.yaml");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("t_end must be a constant, but depends on 'q2'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
