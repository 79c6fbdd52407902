// SPDX-License-Identifier: BSD-3-Clause
// Tests of linearize() (src/analysis/): textbook matrices, reduced one-DOF frequencies, the
// sleeping top's threshold, the rolling disk's stability criterion, and Ridders' error estimate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "analysis/models.hpp"
#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

OperatingPoint at_rest(const System& sys) {
  const Index n = sys.coordinate_count();
  return {VectorXd::Zero(n), VectorXd::Zero(n), 0.0};
}

// |got − want| <= tol entrywise, with the entry named on failure
void expect_matrix_near(const MatrixXd& got, const MatrixXd& want, double tol, const char* what) {
  ASSERT_EQ(got.rows(), want.rows()) << what;
  ASSERT_EQ(got.cols(), want.cols()) << what;
  for (Index i = 0; i < got.rows(); ++i)
    for (Index j = 0; j < got.cols(); ++j)
      EXPECT_NEAR(got(i, j), want(i, j), tol) << what << "(" << i << ", " << j << ")";
}

// the estimate bounds the true error: |got − exact| <= err (+ a roundoff allowance), and err is
// small (the derivatives are good to 1e-7 or better)
void expect_error_bounds(const MatrixXd& got, const MatrixXd& err, const MatrixXd& exact,
                         const char* what) {
  for (Index i = 0; i < got.rows(); ++i)
    for (Index j = 0; j < got.cols(); ++j) {
      EXPECT_NEAR(got(i, j), exact(i, j), err(i, j) + 1e-14 * (1 + std::abs(exact(i, j))))
          << what << "(" << i << ", " << j << ")";
      EXPECT_LE(err(i, j), 1e-7) << what << "(" << i << ", " << j << ")";
      EXPECT_GE(err(i, j), 0.0) << what << "(" << i << ", " << j << ")";
    }
}

// textbook A, B of the cart pendulum in (x, th, x', th')
void cart_pendulum_textbook(MatrixXd& A, MatrixXd& B) {
  const double M = 2, m = 0.5, l = 0.8, g = 9.81;
  A.setZero(4, 4);
  A(0, 2) = A(1, 3) = 1;
  A(2, 1) = -m * g / M;
  A(3, 1) = (M + m) * g / (M * l);
  B.setZero(4, 1);
  B(2, 0) = 1 / M;
  B(3, 0) = -1 / (M * l);
}

TEST(Linearize, CartPendulumMatchesTheTextbookMatrices) {
  const Model model = parse_model(test::kCartPendulum);
  const System& sys = model.system;
  const LinearModel lm = linearize(sys, at_rest(sys), {force_input(sys, "x")},
                                   {coordinate_output(sys, "th"), coordinate_output(sys, "x_dot")});
  MatrixXd A, B;
  cart_pendulum_textbook(A, B);
  EXPECT_EQ(lm.state_names, (std::vector<std::string>{"x", "th", "x_dot", "th_dot"}));
  expect_error_bounds(lm.A, lm.A_error, A, "A");
  expect_matrix_near(lm.B, B, 1e-14, "B");  // force inputs are exact
  MatrixXd C = MatrixXd::Zero(2, 4);
  C(0, 1) = C(1, 2) = 1;
  expect_error_bounds(lm.C, lm.C_error, C, "C");
  expect_matrix_near(lm.D, MatrixXd::Zero(2, 1), 0.0, "D");
  expect_matrix_near(lm.f0, VectorXd::Zero(4), 1e-15, "f0");
  // eigenvalues 0, 0, ±sqrt((M + m) g / (M l))
  std::vector<double> re;
  for (Index k = 0; k < 4; ++k) re.push_back(lm.eigenvalues(k).real());
  std::sort(re.begin(), re.end());
  const double p = std::sqrt(2.5 * 9.81 / 1.6);
  EXPECT_NEAR(re[0], -p, 1e-7);
  EXPECT_NEAR(re[3], p, 1e-7);
  EXPECT_NEAR(re[1], 0, 1e-7);
  EXPECT_NEAR(re[2], 0, 1e-7);
}

TEST(Linearize, ParameterInputAgreesWithTheExactForceColumn) {
  // F0 enters as a generalized force on x: ∂f/∂F0 by Ridders over reloaded models = 1/M, −1/(M l)
  const Model model = parse_model(test::kCartPendulum);
  const System& sys = model.system;
  const LinearModel lm =
      linearize(sys, at_rest(sys), {model_parameter_input(test::kCartPendulum, "cart", {}, "F0")});
  MatrixXd A, B;
  cart_pendulum_textbook(A, B);
  expect_error_bounds(lm.B, lm.B_error, B, "B");
  EXPECT_THROW(model_parameter_input(test::kCartPendulum, "cart", {}, "nope"),
               std::invalid_argument);
}

TEST(Linearize, ConstrainedCartesianCartPendulumIsTheTextbookModelInOtherCoordinates) {
  // (xc, xb) = T (x, th) to first order with T = [[1, 0], [1, l]]: A' = T₂ A T₂⁻¹, B' = T₂ B
  const Model model = parse_model(test::kCartPendulumCartesian);
  const System& sys = model.system;
  OperatingPoint op = at_rest(sys);
  op.q(3) = 0.8;  // the bob above the cart
  for (bool by_name : {false, true}) {
    LinearizeOptions o;
    if (by_name) o.independent_positions = {"xb", "xc"};
    const LinearModel lm = linearize(sys, op, {force_input(sys, "xc")}, {}, o);
    EXPECT_EQ(lm.state_names, (std::vector<std::string>{"xc", "xb", "xc_dot", "xb_dot"}));
    MatrixXd A, B;
    cart_pendulum_textbook(A, B);
    MatrixXd T2 = MatrixXd::Zero(4, 4);
    T2(0, 0) = T2(1, 0) = T2(2, 2) = T2(3, 2) = 1;
    T2(1, 1) = T2(3, 3) = 0.8;
    const MatrixXd A2 = T2 * A * T2.inverse(), B2 = T2 * B;
    expect_error_bounds(lm.A, lm.A_error, A2, "A");
    expect_matrix_near(lm.B, B2, 1e-13, "B");
  }
}

TEST(Linearize, RiddersErrorEstimateBoundsTheTrueErrorAwayFromEquilibrium) {
  // th'' = −(g/l) sin th − c th'³/(m l²): A = [[0, 1], [−(g/l) cos th0, −3 c th0'²/(m l²)]]
  const Model model = parse_model(test::kCubicPendulum);
  const double m = 1.5, l = 0.7, g = 9.81, c = 0.3;
  for (double th0 : {0.3, 1.1, 2.5})
    for (double w0 : {-2.0, 0.4, 3.0}) {
      OperatingPoint op{VectorXd::Constant(1, th0), VectorXd::Constant(1, w0), 0.0};
      const LinearModel lm = linearize(model.system, op);
      MatrixXd A(2, 2);
      A << 0, 1, -(g / l) * std::cos(th0), -3 * c * w0 * w0 / (m * l * l);
      expect_error_bounds(lm.A, lm.A_error, A, "A");
      EXPECT_NEAR(lm.f0(1), -(g / l) * std::sin(th0) - c * w0 * w0 * w0 / (m * l * l), 1e-12);
    }
}

TEST(Linearize, ParallelogramFourBarOscillatesAtItsReducedOneDofFrequency) {
  const Model model = parse_model(test::kParallelogram);
  const System& sys = model.system;
  const double mc = 1, mk = 2, L = 0.5, g = 9.81;
  const double w = std::sqrt(g * (mc + mk) / (L * (2 * mc / 3 + mk)));
  for (const char* independent : {"", "t1", "t3"}) {
    LinearizeOptions o;
    if (*independent) o.independent_positions = {independent};
    const LinearModel lm = linearize(sys, at_rest(sys), {}, {coordinate_output(sys, "t2")}, o);
    ASSERT_EQ(lm.state_names.size(), 2u) << independent;
    EXPECT_NEAR(std::abs(lm.eigenvalues(0).imag()), w, 1e-8 * w) << independent;
    EXPECT_NEAR(lm.eigenvalues(0).real(), 0.0, 1e-8 * w) << independent;
    EXPECT_NEAR(lm.eigenvalues(1).imag(), -lm.eigenvalues(0).imag(), 1e-12) << independent;
    // the coupler does not turn on the one-DOF motion: C = 0 for t2
    EXPECT_NEAR(lm.C(0, 0), 0.0, 1e-9);
    if (*independent) {
      EXPECT_EQ(lm.state_names[0], independent);
    }
  }
  // t2 cannot be independent here: the dependent pair (t1, t3) has a singular block
  LinearizeOptions o;
  o.independent_positions = {"t2"};
  try {
    linearize(sys, at_rest(sys), {}, {}, o);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("t1, t3 cannot be the dependent ones"), std::string::npos)
        << e.what();
  }
}

TEST(Linearize, AlongAMotionOfTheFourBarTheReducedEquationIsPendulumLike) {
  // the parallelogram's one-DOF motion has constant inertia: θ'' = −ω² sin θ exactly, so along
  // any motion t1 = t3 = θ, t2 = 0: A(t) = [[0, 1], [−ω² cos θ, 0]], f0 = (θ', −ω² sin θ)
  const Model model = parse_model(test::kParallelogram);
  const System& sys = model.system;
  const double w2 = 9.81 * 3 / (0.5 * (2.0 / 3 + 2));
  std::vector<OperatingPoint> path;
  for (double th : {0.3, 0.8, 1.2, -0.5}) {
    OperatingPoint op{VectorXd::Zero(3), VectorXd::Zero(3), 0.1 * double(path.size())};
    op.q << th, 0, th;
    op.qd << 0.5, 0, 0.5;
    path.push_back(op);
  }
  const auto models = linearize_along(sys, path, {}, {coordinate_output(sys, "t3")});
  ASSERT_EQ(models.size(), path.size());
  for (std::size_t k = 0; k < path.size(); ++k) {
    const double th = path[k].q(0);
    EXPECT_EQ(models[k].state_names, models[0].state_names) << k;  // one chart
    MatrixXd A(2, 2);
    A << 0, 1, -w2 * std::cos(th), 0;
    expect_error_bounds(models[k].A, models[k].A_error, A, "A");
    EXPECT_NEAR(models[k].f0(0), 0.5, 1e-12) << k;
    EXPECT_NEAR(models[k].f0(1), -w2 * std::sin(th), 1e-10) << k;
    // the other crank follows: C = [1, 0] whichever crank is independent
    EXPECT_NEAR(models[k].C(0, 0), 1.0, 1e-9) << k;
    EXPECT_NEAR(models[k].C(0, 1), 0.0, 1e-9) << k;
  }
  // a point off the manifold is named by its index
  path[2].q(1) = 0.2;
  try {
    linearize_along(sys, path);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 2 (t = 0.2"), std::string::npos) << e.what();
  }
}

TEST(Linearize, FourBarAtAFoldIsASingularConfigurationError) {
  // cranks straight up along the coupler's line: t1 = t3 = π/2, where loop_y's row vanishes
  // against loop_x's — the Jacobian loses rank and no silent matrix is returned
  const Model model = parse_model(test::kParallelogram);
  const System& sys = model.system;
  OperatingPoint op = at_rest(sys);
  op.q << M_PI / 2, 0, M_PI / 2;
  try {
    linearize(sys, op);
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("singular configuration"), std::string::npos) << e.what();
  }
  op.q(0) = 0.1;  // off the manifold
  EXPECT_THROW(linearize(sys, op), std::invalid_argument);
}

TEST(Linearize, AStateProjectedOntoTheManifoldLinearizes) {
  // a four-bar state off the loop: projected, it satisfies both loop rows, and linearizes
  const Model model = parse_model(test::kParallelogram);
  const System& sys = model.system;
  OperatingPoint op{VectorXd::Zero(3), VectorXd::Zero(3), 0.0};
  op.q << 0.3, 0.05, 0.2;
  op.qd << 0.1, 0.0, 0.3;
  const OperatingPoint p = project_onto_manifold(sys, op);
  const double L = 0.5, d = 1;
  EXPECT_NEAR(L * std::sin(p.q(0)) + d * std::cos(p.q(1)) - d - L * std::sin(p.q(2)), 0.0, 1e-12);
  EXPECT_NEAR(-L * std::cos(p.q(0)) + d * std::sin(p.q(1)) + L * std::cos(p.q(2)), 0.0, 1e-12);
  // the velocity rows: d/dt of both loop rows
  EXPECT_NEAR(L * std::cos(p.q(0)) * p.qd(0) - d * std::sin(p.q(1)) * p.qd(1) -
                  L * std::cos(p.q(2)) * p.qd(2),
              0.0, 1e-12);
  EXPECT_NEAR(L * std::sin(p.q(0)) * p.qd(0) + d * std::cos(p.q(1)) * p.qd(1) -
                  L * std::sin(p.q(2)) * p.qd(2),
              0.0, 1e-12);
  EXPECT_EQ(linearize(sys, p).state_names.size(), 2u);
}

// a ball on a horizontal spring (k, along x) over a floor y >= 0 (unilateral): the contact mode
// of the point decides the model
constexpr const char* kBallOverFloor = R"(
name: ball over a floor
parameters: {m: 2, g: 9.81, k: 50}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y + 0.5*k*x^2
constraints:
  - {name: floor, holonomic: y, unilateral: true, restitution: 0.5}
initial:
  q: {x: 0.1, y: 1}
)";

TEST(Linearize, AnOpenContactIsLeftOutAndAClosedOneHeld) {
  const Model model = parse_model(kBallOverFloor);
  const System& sys = model.system;
  const double m = 2, g = 9.81, k = 50;
  // open (y = 1): the free ball, x = (x, y, x', y'), f0 = (0, 0, −k x/m, −g)
  OperatingPoint op{VectorXd::Zero(2), VectorXd::Zero(2), 0.0};
  op.q << 0.1, 1.0;
  const LinearModel open = linearize(sys, op);
  ASSERT_EQ(open.state_names, (std::vector<std::string>{"x", "y", "x_dot", "y_dot"}));
  MatrixXd A_open = MatrixXd::Zero(4, 4);
  A_open(0, 2) = A_open(1, 3) = 1.0;
  A_open(2, 0) = -k / m;
  expect_matrix_near(open.A, A_open, 1e-7, "A (open)");
  EXPECT_NEAR(open.f0(2), -k * 0.1 / m, 1e-12);
  EXPECT_NEAR(open.f0(3), -g, 1e-12);
  EXPECT_EQ(open.open_contacts, std::vector<std::string>{"floor"});
  // closed (y = 0): held, the oscillator in x alone, eigenvalues ±i sqrt(k/m)
  op.q << 0.1, 0.0;
  const LinearModel held = linearize(sys, op);
  ASSERT_EQ(held.state_names, (std::vector<std::string>{"x", "x_dot"}));
  EXPECT_TRUE(held.open_contacts.empty());
  EXPECT_NEAR(std::abs(held.eigenvalues(0).imag()), std::sqrt(k / m), 1e-7);
  EXPECT_NEAR(held.eigenvalues(0).real(), 0.0, 1e-7);
  // projection: an open gap is kept (no violation), a penetrating state moved onto the floor
  op.q << 0.1, 0.3;
  op.qd << 0.0, -1.0;
  const OperatingPoint kept = project_onto_manifold(sys, op);
  EXPECT_EQ(kept.q(1), 0.3);
  EXPECT_EQ(kept.qd(1), -1.0);
  op.q << 0.1, -0.01;
  const OperatingPoint moved = project_onto_manifold(sys, op);
  EXPECT_NEAR(moved.q(1), 0.0, 1e-12);
  EXPECT_NEAR(moved.qd(1), 0.0, 1e-12);
  EXPECT_NEAR(moved.q(0), 0.1, 1e-15);
}

std::vector<std::complex<double>> sorted_eigenvalues(const LinearModel& lm) {
  std::vector<std::complex<double>> ev(lm.eigenvalues.data(),
                                       lm.eigenvalues.data() + lm.eigenvalues.size());
  std::sort(ev.begin(), ev.end(), [](auto a, auto b) {
    return a.imag() != b.imag() ? a.imag() < b.imag() : a.real() < b.real();
  });
  return ev;
}

TEST(Linearize, SleepingTopThresholdFromTheEigenvalues) {
  const Model model = parse_model(test::kCardanTop);
  const System& sys = model.system;
  const double m = 1, l = 0.5, g = 9.81, I1 = 0.05 + m * l * l, I3 = 0.08;
  const double wc = std::sqrt(4 * m * g * l * I1) / I3;
  auto at_spin = [&](double w) {
    OperatingPoint op = at_rest(sys);
    op.qd(2) = w;
    return linearize(sys, op);
  };
  // above the threshold: λ = i (±I3 ω ± √(I3²ω² − 4 I1 m g l)) / (2 I1), and 0 twice
  for (double w : {1.2 * wc, 2.0 * wc}) {
    const LinearModel lm = at_spin(w);
    EXPECT_EQ(lm.state_names, (std::vector<std::string>{"a", "b", "c", "a_dot", "b_dot", "c_dot"}));
    const double root = std::sqrt(I3 * I3 * w * w - 4 * I1 * m * g * l);
    std::vector<double> want = {-(I3 * w + root) / (2 * I1), -(I3 * w - root) / (2 * I1), 0, 0,
                                (I3 * w - root) / (2 * I1),  (I3 * w + root) / (2 * I1)};
    const auto ev = sorted_eigenvalues(lm);
    for (std::size_t k = 0; k < 6; ++k) {
      EXPECT_NEAR(ev[k].imag(), want[k], 1e-6 * wc) << k;
      EXPECT_NEAR(ev[k].real(), 0.0, 1e-5) << k;
    }
  }
  // below it a pair with real parts ±√(4 I1 m g l − I3² ω²) / (2 I1)
  {
    const double w = 0.8 * wc;
    const auto ev = sorted_eigenvalues(at_spin(w));
    double re_max = 0;
    for (const auto& z : ev) re_max = std::max(re_max, z.real());
    EXPECT_NEAR(re_max, std::sqrt(4 * I1 * m * g * l - I3 * I3 * w * w) / (2 * I1), 1e-6);
  }
  // the crossing located by bisection on "some eigenvalue has Re > 1e-3"
  double lo = 0.5 * wc, hi = 1.5 * wc;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    double re_max = 0;
    for (const auto& z : sorted_eigenvalues(at_spin(mid))) re_max = std::max(re_max, z.real());
    (re_max > 1e-3 ? lo : hi) = mid;
  }
  EXPECT_NEAR(0.5 * (lo + hi), wc, 1e-5 * wc);
}

TEST(Linearize, RollingDiskUprightStabilityMatchesTheClassicalCriterion) {
  // upright rolling at spin rate W (lean theta = 0, straight): with A = m R²/4, C = m R²/2 the
  // lean obeys (A + m R²) θ'' + [(C + m R²) C W²/A − m g R] θ = 0, so λ² = −0.8 (3 W² − g/R)
  // and it is stable iff W² > g / (3 R) (v² > g R / 3)
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/rolling_disk.yaml");
  const System& sys = model.system;
  const double R = 0.5, g = 9.81;
  for (double W : {1.5, 2.0, 4.0, 8.0}) {
    OperatingPoint op = at_rest(sys);
    op.qd(sys.coordinate_index("phi")) = W;
    op.qd(sys.coordinate_index("x")) = R * W;
    const LinearModel lm = linearize(sys, op);
    ASSERT_EQ(lm.state_names.size(), 8u);  // 5 positions, 3 velocities (2 rolling rows)
    EXPECT_EQ(lm.independent_velocities.size(), 3u);
    const double lambda2 = -0.8 * (3 * W * W - g / R);
    auto ev = sorted_eigenvalues(lm);
    std::sort(ev.begin(), ev.end(), [](auto a, auto b) { return std::abs(a) > std::abs(b); });
    const double expected = std::sqrt(std::abs(lambda2));
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(std::abs(ev[std::size_t(k)]), expected, 1e-6 * expected) << "W " << W;
      if (lambda2 < 0) {
        EXPECT_NEAR(ev[std::size_t(k)].real(), 0.0, 1e-6) << "W " << W;
      }
      if (lambda2 > 0) {
        EXPECT_NEAR(ev[std::size_t(k)].imag(), 0.0, 1e-6) << "W " << W;
      }
    }
    for (std::size_t k = 2; k < ev.size(); ++k) EXPECT_NEAR(std::abs(ev[k]), 0.0, 1e-4) << k;
  }
}

TEST(Linearize, MisuseNamesWhatIsWrong) {
  const Model model = parse_model(test::kCartPendulum);
  const System& sys = model.system;
  OperatingPoint op = at_rest(sys);
  op.q.resize(3);
  EXPECT_THROW(linearize(sys, op), std::invalid_argument);
  try {
    coordinate_output(sys, "y");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no coordinate 'y'"), std::string::npos) << e.what();
  }
  // model_inputs: a coordinate is a force, a parameter a parameter, anything else an error
  const auto inputs = model_inputs(model, test::kCartPendulum, {"x", "F0"}, "--inputs");
  ASSERT_EQ(inputs.size(), 2u);
  EXPECT_EQ(inputs[0].kind, InputKind::kForce);
  EXPECT_EQ(inputs[0].coordinate, 0);
  EXPECT_EQ(inputs[1].kind, InputKind::kParameter);
  EXPECT_EQ(inputs[1].nominal, 0.0);
  try {
    model_inputs(model, test::kCartPendulum, {"nosuch"}, "--inputs");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--inputs nosuch: neither a coordinate"),
              std::string::npos)
        << e.what();
  }
  LinearizeOptions o;
  o.table_size = 1;
  EXPECT_THROW(linearize(sys, at_rest(sys), {}, {}, o), std::invalid_argument);
}

// A pendulum in its angle, l as an input: th'' = −(g/l) sin th, so A₂₁ = −(g/l) cos th and B (the
// column of l) = g sin th / l², in any units. Ridders' first step on l is 0.1 |l| (it was 0.1 ·
// max(1, |l|): for l = 1 mm, a step of 100 l that crossed l = 0 and gave B = −858 for 2.9e6,
// B_error 568, as the answer; u18 02)
constexpr const char* kAnglePendulum = R"(name: gp
parameters: {m: 1, l: 1, g: 9.81}
coordinates: [th]
kinetic_energy: 0.5*m*l^2*th_dot^2
potential_energy: -m*g*l*cos(th)
)";

TEST(LinearizeUnits, ParameterColumnIsRightForAnyLengthAndInKilometresAndHours) {
  const double th = 0.3;
  // (l in m with g in m/s², and the same pendulums in km and h: g = 9.81 · 3600² / 1000)
  for (const double g : {9.81, 127137.6}) {
    const double metre = g == 9.81 ? 1.0 : 1e-3;
    for (const double l : {1e-3, 1.0, 1e3}) {
      const std::map<std::string, double> p{{"l", l * metre}, {"g", g}};
      const Model model = parse_model(kAnglePendulum, "gp", p);
      const OperatingPoint at{VectorXd::Constant(1, th), VectorXd::Zero(1), 0.0};
      const LinearModel lm =
          linearize(model.system, at, {model_parameter_input(kAnglePendulum, "gp", p, "l")});
      const double L = l * metre, A21 = -g / L * std::cos(th), B = g * std::sin(th) / (L * L);
      EXPECT_NEAR(lm.A(1, 0), A21, 1e-9 * std::abs(A21)) << "g " << g << ", l " << L;
      EXPECT_NEAR(lm.B(1, 0), B, 1e-9 * B) << "g " << g << ", l " << L;
      // the estimate bounds the error and is small
      EXPECT_LE(lm.B_error(1, 0), 1e-9 * B) << "g " << g << ", l " << L;
      EXPECT_GE(lm.B_error(1, 0), std::abs(lm.B(1, 0) - B) - 1e-14 * B);
    }
  }
}

// A Cartesian pendulum (x, y; the row (x² + y² − L²) / (2L)): A₂₁ = ∂x''/∂x = −g cos 2θ /
// (L cos θ) at rest at angle θ from the vertical (−g/L hanging), and ∂x''/∂x' = 0, in any units.
// The first steps are relative to each state's scale (0.1 |x|, 0.1 ℓ for x = 0): 0.1 · max(1,
// |x|) left Newton's basin for L <= 1.5 mm in SI units and for L = 1 m in km ("Newton on the
// holonomic constraints did not converge"), and in nm its step of 0.1 nm/s on x' hit the roundoff
// floor (A_error 3.4e-5 /s; u18 05)
TEST(LinearizeUnits, CartesianPendulumIsRightForAnyLengthAndInOtherUnits) {
  const std::string text = R"(name: pend
parameters: {m: 1, L: 1, g: 9.81}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: rod, holonomic: (x^2 + y^2 - L^2)/(2*L)}
)";
  struct Units {
    double L, g, m;
  };
  // SI with L = 1 mm, 1 m, 1 km; L = 1 m in km and h; in nm, mg and s
  const std::vector<Units> cases{
      {1e-3, 9.81, 1}, {1.0, 9.81, 1}, {1e3, 9.81, 1}, {1e-3, 127137.6, 1}, {1e9, 9.81e9, 1e6}};
  for (const Units& u : cases) {
    const Model model = parse_model(text, "pend", {{"L", u.L}, {"g", u.g}, {"m", u.m}});
    for (const double th : {0.0, 0.3}) {
      const OperatingPoint at{Eigen::Vector2d(u.L * std::sin(th), -u.L * std::cos(th)),
                              VectorXd::Zero(2), 0.0};
      const LinearModel lm = linearize(model.system, at);
      ASSERT_EQ(lm.state_names.front(), "x");
      const double A21 = -u.g * std::cos(2 * th) / (u.L * std::cos(th));
      const double rate = std::sqrt(u.g / u.L);
      EXPECT_NEAR(lm.A(1, 0), A21, 1e-9 * std::abs(A21)) << "L " << u.L << ", th " << th;
      EXPECT_LE(lm.A_error(1, 0), 1e-8 * std::abs(A21)) << "L " << u.L << ", th " << th;
      EXPECT_NEAR(lm.A(1, 1), 0.0, 1e-8 * rate) << "L " << u.L << ", th " << th;
      EXPECT_LE(lm.A_error(1, 1), 1e-8 * rate) << "L " << u.L << ", th " << th;
      EXPECT_NEAR(lm.eigenvalues[0].imag() * lm.eigenvalues[0].imag(), -A21, 1e-9 * -A21);
    }
  }
}

// A parameter at 0 has no scale but its unit's: the first step is 0.1 (a force's magnitude,
// where any step is exact: ParameterInputAgreesWithTheExactForceColumn). When that step leaves
// the function's smooth part — here a pole at l = −1 mm, which 0.1 crosses — the table does not
// settle, and linearize says so rather than return it (u18 02's mechanism)
TEST(LinearizeUnits, ATableThatDoesNotSettleIsAnErrorNamingTheInput) {
  const std::string text = R"(name: gp
parameters: {m: 1, l: 0, g: 9.81}
coordinates: [th]
kinetic_energy: 0.5*m*(l + 0.001)^2*th_dot^2
potential_energy: -m*g*(l + 0.001)*cos(th)
)";
  const Model model = parse_model(text, "gp");
  const OperatingPoint at{VectorXd::Constant(1, 0.3), VectorXd::Zero(1), 0.0};
  try {
    linearize(model.system, at, {model_parameter_input(text, "gp", {}, "l")});
    ADD_FAILURE() << "no error";
  } catch (const SolveError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the derivative of th_dot' along parameter 'l' did not settle"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("not smooth over steps of 0.1"), std::string::npos) << what;
  }
  // a parameter whose family cannot be evaluated on either side (sqrt of l < 0) is an error too
  const std::string root = R"(name: gp
parameters: {m: 1, l: 0, g: 9.81}
coordinates: [th]
kinetic_energy: 0.5*m*th_dot^2
potential_energy: -m*g*sqrt(l)*cos(th)
)";
  const Model rooted = parse_model(root, "gp");
  EXPECT_THROW(linearize(rooted.system, at, {model_parameter_input(root, "gp", {}, "l")}),
               SolveError);
}

// The parallelogram four-bar of u20 05 in angles (cranks th1, th2 of L, mc uniform; coupler ph
// of d, mk): hanging at rest its one-DOF motion is θ'' = −ω² θ with ω² = g (mc + mk) / (L (2 mc/3
// + mk)) = 24.852 /s², in SI units and in mm, g and ms (ω 1000 times smaller)
const char* kFourBarAngles = R"(name: parallelogram in angles
parameters: {L: 0.5, d: 0.8, mc: 1.2, mk: 0.7, g: 9.81}
coordinates: [th1, th2, ph]
kinetic_energy: >-
  0.5*(mc*L^2/3)*(th1_dot^2 + th2_dot^2)
  + 0.5*mk*((L*cos(th1)*th1_dot - d/2*sin(ph)*ph_dot)^2 + (L*sin(th1)*th1_dot + d/2*cos(ph)*ph_dot)^2)
  + 0.5*(mk*d^2/12)*ph_dot^2
potential_energy: g*(-mc*L/2*cos(th1) - mc*L/2*cos(th2) + mk*(-L*cos(th1) + d/2*sin(ph)))
constraints:
  - {name: lx, holonomic: L*sin(th1) + d*cos(ph) - d - L*sin(th2)}
  - {name: lz, holonomic: -L*cos(th1) + d*sin(ph) + L*cos(th2)}
)";

struct FourBarUnits {
  const char* name;
  std::map<std::string, double> parameters;
  double second;  // the model's time unit in s
};
const std::vector<FourBarUnits> kFourBarUnits{
    {"SI", {}, 1.0},
    {"mm g ms", {{"L", 500}, {"d", 800}, {"mc", 1200}, {"mk", 700}, {"g", 9.81e-3}}, 1e-3}};

// A of a hanging four-bar: [[0, 1], [−ω², 0]] in the state (crank, crank'), to its estimate
void expect_hanging_four_bar(const LinearModel& lm, double second, const std::string& what) {
  const double w = std::sqrt(9.81 * 1.9 / (0.5 * (0.8 + 0.7))) * second;  // 4.98517803092327 /s
  ASSERT_EQ(lm.A.rows(), 2) << what;
  MatrixXd A(2, 2);
  A << 0, 1, -w * w, 0;
  for (Index i = 0; i < 2; ++i)
    for (Index j = 0; j < 2; ++j) {
      EXPECT_NEAR(lm.A(i, j), A(i, j), 1e-9 * w * w + lm.A_error(i, j)) << what << i << j;
      EXPECT_LE(lm.A_error(i, j), 1e-8 * w * w) << what << i << j;
      EXPECT_GE(lm.A_error(i, j), 0.0) << what << i << j;
    }
  EXPECT_NEAR(std::abs(lm.eigenvalues(0).imag()), w, 1e-9 * w) << what;
  EXPECT_NEAR(lm.eigenvalues(0).real(), 0.0, 1e-9 * w) << what;
}

// At q = 0 to roundoff (what an equilibrium search returns, 1e-14 rad) the steps are those of q
// = 0, 0.1 of the loop's natural scale, not 0.1 ‖q‖∞ = 1e-15 rad, where the loop's Newton
// roundoff gave ω = 4.43 or 4.61 for 4.985, or an unstable four-bar with --independent (u20 05)
TEST(LinearizeRoundoff, AClosedChainAtTheRoundoffOfZeroIsLinearizedAsAtZero) {
  for (const auto& u : kFourBarUnits) {
    const Model model = parse_model(kFourBarAngles, "fb", u.parameters);
    const System& sys = model.system;
    OperatingPoint guess{Eigen::Vector3d(0.3, 0.3, 0.0), VectorXd::Zero(3), 0.0};
    const OperatingPoint found = find_equilibrium(sys, guess).point;
    EXPECT_LE(found.q.lpNorm<Eigen::Infinity>(), 1e-10) << u.name;
    std::vector<std::pair<std::string, OperatingPoint>> points{
        {"at 0", {VectorXd::Zero(3), VectorXd::Zero(3), 0.0}},
        {"at 1e-14", {Eigen::Vector3d(1e-14, 1e-14, 1e-14), VectorXd::Zero(3), 0.0}},
        {"at 1e-14, -1e-14", {Eigen::Vector3d(1e-14, -1e-14, 1e-14), VectorXd::Zero(3), 0.0}},
        {"at the equilibrium found", found}};
    for (const auto& [where, at] : points)
      for (const char* independent : {"", "th1", "th2"}) {
        LinearizeOptions o;
        if (*independent) o.independent_positions = {independent};
        const std::string what = std::string(u.name) + " " + where + " " + independent + ": ";
        try {
          expect_hanging_four_bar(linearize(sys, at, {}, {}, o), u.second, what);
        } catch (const std::exception& e) {
          ADD_FAILURE() << what << e.what();
        }
      }
    // at rest after a run (q and q' at roundoff, or in a damped run's tail: 2.6e-9 rad stepped by
    // 2.6e-10 had an error of 3e-6 that its estimate did not bound), along a path: the same A
    std::vector<OperatingPoint> path;
    for (double r : {1e-13, -3e-14, 1e-14, 0.0, -2.6e-9, 4e-7}) {
      path.push_back({Eigen::Vector3d(r, r, 0.0), Eigen::Vector3d(r, r, 0.0) / u.second, 0.0});
    }
    const auto models = linearize_along(sys, path);
    for (std::size_t k = 0; k < models.size(); ++k)
      expect_hanging_four_bar(models[k], u.second,
                              std::string(u.name) + " along, point " + std::to_string(k) + ": ");
  }
}

// A cart pole (cart x, pole th from the upright; M = 1 kg, m = 0.1 kg, l = 0.5 m) in mm, g and ms:
// x is cyclic, so A at x = 500 mm is A at x = 0 — the angle at 0 steps in its own scale (about
// 1 rad), not by 0.1 ‖q‖∞ = 50 rad ("did not settle ... steps of 50"; u20 06)
TEST(LinearizeRoundoff, AnAngleAtZeroBesideALengthStepsInItsOwnScale) {
  const std::string text = R"(name: cart pole
parameters: {M: 1000, m: 100, l: 500, g: 9.81e-3}
coordinates: [x, th]
kinetic_energy: 0.5*(M + m)*x_dot^2 + m*l*x_dot*th_dot*cos(th) + 0.5*m*l^2*th_dot^2
potential_energy: m*g*l*cos(th)
)";
  const Model model = parse_model(text, "cp");
  const double M = 1000, m = 100, l = 500, g = 9.81e-3;
  MatrixXd A = MatrixXd::Zero(4, 4);
  A(0, 2) = A(1, 3) = 1;
  A(2, 1) = -m * g / M;
  A(3, 1) = (M + m) * g / (M * l);
  for (const double x : {0.0, 500.0, -2e4}) {
    const OperatingPoint at{Eigen::Vector2d(x, 0.0), VectorXd::Zero(2), 0.0};
    const LinearModel lm = linearize(model.system, at);
    for (Index i = 0; i < 4; ++i)
      for (Index j = 0; j < 4; ++j)
        EXPECT_NEAR(lm.A(i, j), A(i, j), 1e-9 * A(3, 1) + lm.A_error(i, j))
            << "x " << x << ": " << i << j;
    EXPECT_LE(lm.A_error.maxCoeff(), 1e-9 * A(3, 1)) << "x " << x;
    // a program can still choose its first step (`--initial-step`, initial_step=)
    LinearizeOptions o;
    o.initial_step = 0.01;
    EXPECT_NEAR(linearize(model.system, at, {}, {}, o).A(3, 1), A(3, 1), 1e-9 * A(3, 1));
  }
}

// Joint friction that reads no reaction (C(q')) on an unconstrained pendulum: a force input's
// column of B is exact (1 / (m l²)), as without the friction (u20 06 a: every joint torque of a
// URDF robot with <dynamics friction> was refused); at rest the friction's kink has no linear
// model, and the error says so (06 b), not only that the table did not settle
TEST(LinearizeRoundoff, JointFrictionWithoutReactionsKeepsExactForceInputs) {
  const std::string text = R"(name: pendulum with joint friction
parameters: {m: 2, l: 0.5, g: 9.81, mu: 0.2, c: 0.1}
coordinates: [th]
kinetic_energy: 0.5*m*l^2*th_dot^2
potential_energy: -m*g*l*cos(th)
nonideal:
  - {C: [-mu*th_dot/sqrt(th_dot^2 + 1e-12) - c*th_dot]}
)";
  const Model model = parse_model(text, "pf");
  const System& sys = model.system;
  const double I = 2 * 0.25;
  const OperatingPoint moving{VectorXd::Constant(1, 0.3), VectorXd::Constant(1, 1.0), 0.0};
  const LinearModel lm = linearize(sys, moving, {force_input(sys, "th")});
  EXPECT_EQ(lm.B_error(1, 0), 0.0);
  EXPECT_NEAR(lm.B(1, 0), 1 / I, 1e-15 / I);
  EXPECT_NEAR(lm.B(0, 0), 0.0, 1e-300);
  const double A21 = -9.81 / 0.5 * std::cos(0.3), A22 = -0.1 / I;  // (μ ε² / |ω|³ ≈ 2e-13)
  EXPECT_NEAR(lm.A(1, 0), A21, 1e-9 * std::abs(A21));
  EXPECT_NEAR(lm.A(1, 1), A22, 1e-9);
  try {
    linearize(sys, {VectorXd::Constant(1, 0.3), VectorXd::Zero(1), 0.0}, {force_input(sys, "th")});
    ADD_FAILURE() << "no error at rest";
  } catch (const SolveError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("at th_dot = 0 the system's non-ideal forces"), std::string::npos) << what;
    EXPECT_NE(what.find("not differentiable"), std::string::npos) << what;
    EXPECT_NE(what.find("no linear model exists there"), std::string::npos) << what;
  }
}

// ---- a contact switching at the point (u22 03) ------------------------------------------------

// a smooth ball (radius r) on a box of half-extents 0.5 whose top face is z = 1 and whose edge
// along y is at x = 0.5: on the face (|x| < 0.5) its centre slides freely, x'' = 0; beyond the
// edge it pivots about the edge as an inverted pendulum of length r, θ'' = (g/r) sin θ with
// x = 0.5 + r sin θ, so that at rest x'' = g sin θ cos θ and ∂x''/∂x = (g/r) cos 2θ / cos θ
// (g/r at θ = 0). Straight above the edge the gap is C¹, not C²: no linear model exists there.
constexpr const char* kBallOnBox = R"(
name: ball on a box
parameters: {m: 1, r: 0.1, bx: 0.5, bz: 1.1}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [bx, 0, bz]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: edge, body: ball, shape: sphere, radius: r,
     box: {body: ground, point: [0, 0, 0.5], size: [0.5, 0.5, 0.5]}}
)";

// A[x_dot', x] of the ball at (x, z), at rest
double ball_on_box_slope(double x, double z, LinearModel* out = nullptr) {
  const Model model = parse_model(kBallOnBox, "ball", {{"bx", x}, {"bz", z}});
  const LinearModel lm = linearize(model.system, {model.q0, model.qd0, 0.0});
  const auto& names = lm.state_names;
  const auto row = std::find(names.begin(), names.end(), "ball.x_dot") - names.begin();
  const auto col = std::find(names.begin(), names.end(), "ball.x") - names.begin();
  EXPECT_LT(row, Index(names.size()));
  EXPECT_LT(col, Index(names.size()));
  EXPECT_EQ(std::find(names.begin(), names.end(), "ball.z"), names.end());  // (held: dependent)
  if (out) *out = lm;
  return lm.A(row, col);
}

TEST(LinearizeContactSwitch, ABallOnABoxEdgeIsRefusedNamingTheContact) {
  // straight above the edge, and 1e-9 beside it (within the smallest step): refused, the contact
  // named with both one-sided slopes, 0 and g/r = 98.1
  for (const double dx : {0.0, 1e-9, -1e-9}) {
    try {
      ball_on_box_slope(0.5 + dx, 1.1);
      ADD_FAILURE() << "linearized at the edge, dx = " << dx;
    } catch (const SolveError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the contact 'edge' switches there between two regions of its gap"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("the derivative of ball.x_dot' along ball.x is "), std::string::npos)
          << what;
      EXPECT_NE(what.find(" and 98.1 on ball.x > 0.5"), std::string::npos) << what;
      if (dx == 0.0) {
        EXPECT_NE(what.find("is 0 on the side ball.x < 0.5 and 98.1 on ball.x > 0.5 (a central "
                            "difference returns their mean, 49.05)"),
                  std::string::npos)
            << what;
      }
      EXPECT_NE(what.find("move the operating point off it"), std::string::npos) << what;
    }
  }
}

TEST(LinearizeContactSwitch, OnEitherSideOfTheEdgeTheBallLinearizesToItsClosedForm) {
  const double g = 9.81, r = 0.1;
  // on the face: x'' = 0 whatever x
  LinearModel face;
  EXPECT_NEAR(ball_on_box_slope(-0.1, 1.1, &face), 0.0, 1e-9);
  EXPECT_NEAR(face.f0.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // beyond the edge, pivoting: (g/r) cos 2θ / cos θ (measured: 4.5e-13 relative or better)
  for (const double th : {0.05, 0.2, 0.5}) {
    const double want = g / r * std::cos(2 * th) / std::cos(th);
    EXPECT_NEAR(ball_on_box_slope(0.5 + r * std::sin(th), 1.0 + r * std::cos(th)), want,
                1e-10 * want)
        << "theta = " << th;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
