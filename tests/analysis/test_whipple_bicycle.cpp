// SPDX-License-Identifier: BSD-3-Clause
// The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina, Schwab 2007, Proc. R. Soc. A
// 463:1955): linearize() of the nonlinear model file examples/models/whipple_bicycle.yaml (two
// knife-edge wheels rolling without slipping, 8 coordinates, 1 holonomic and 4 nonholonomic
// rows) about the upright straight run, against the paper's Table 2 eigenvalues and its weave
// and capsize speeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using cd = std::complex<double>;

const Model& bicycle() {
  static const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/whipple_bicycle.yaml");
  return m;
}

// the upright straight run at speed v: all angles 0, x' = v, the wheels rolling
OperatingPoint straight_run(double v) {
  const Model& m = bicycle();
  const System& sys = m.system;
  OperatingPoint p{VectorXd::Zero(8), VectorXd::Zero(8), 0.0};
  p.qd(sys.coordinate_index("x")) = v;
  p.qd(sys.coordinate_index("theta_R")) = v / m.parameters.at("rR");
  p.qd(sys.coordinate_index("theta_F")) = v / m.parameters.at("rF");
  return p;
}

// lean and steer with their rates, the cyclic coordinates and the speed dropped
LinearizeOptions lean_and_steer() {
  LinearizeOptions o;
  o.independent_positions = {"x", "y", "psi", "phi", "delta", "theta_R", "theta_F"};
  o.independent_velocities = {"phi", "delta", "theta_R"};
  o.states = {"phi", "delta", "phi_dot", "delta_dot"};
  return o;
}

std::vector<cd> sorted(const Eigen::VectorXcd& e) {
  std::vector<cd> v(e.data(), e.data() + e.size());
  std::sort(v.begin(), v.end(), [](cd a, cd b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
  return v;
}

std::vector<cd> eigenvalues_at(double v) {
  return sorted(linearize(bicycle().system, straight_run(v), {}, {}, lean_and_steer()).eigenvalues);
}

// Table 2 of the paper (its digits): castering, capsize and the weave pair, or at v = 0 the
// two real pairs, sorted as sorted() sorts
struct Published {
  double v;
  std::vector<cd> lambda;
};
const std::vector<Published> kTable2 = {
    {0.0,
     {{-5.53094371765393, 0},
      {-3.13164324790656, 0},
      {3.13164324790656, 0},
      {5.53094371765393, 0}}},
    {4.0,
     {{-12.15861426576447, 0},
      {-1.42944427361326, 0},
      {0.41325331521125, -3.07910818603206},
      {0.41325331521125, 3.07910818603206}}},
    {5.0,
     {{-14.07838969279822, 0},
      {-0.77534188219585, -4.46486771378823},
      {-0.77534188219585, 4.46486771378823},
      {-0.32286642900409, 0}}},
    {10.0,
     {{-24.62459635017404, 0},
      {-3.72016840437287, -10.90681139476287},
      {-3.72016840437287, 10.90681139476287},
      {0.16105338653172, 0}}},
};

TEST(WhippleBicycle, EigenvaluesMatchTable2ToElevenDigits) {
  for (const auto& row : kTable2) {
    const std::vector<cd> got = eigenvalues_at(row.v);
    ASSERT_EQ(got.size(), 4u) << "v = " << row.v;
    for (std::size_t k = 0; k < 4; ++k) {
      // the issue asks for 8 significant digits; they agree to 11 or better (measured: 1.6e-13
      // relative at worst): |got − published| <= 1e-11 |published|
      const double tol = 1e-11 * std::abs(row.lambda[k]);
      EXPECT_NEAR(got[k].real(), row.lambda[k].real(), tol) << "v = " << row.v << ", k = " << k;
      EXPECT_NEAR(got[k].imag(), row.lambda[k].imag(), tol) << "v = " << row.v << ", k = " << k;
    }
  }
}

// the largest real part of the four eigenvalues (negative: self-stable)
double spectral_abscissa(double v) {
  double s = -1e300;
  for (cd l : eigenvalues_at(v)) s = std::max(s, l.real());
  return s;
}

// the root of f in [a, b] (f(a), f(b) of opposite signs) by the Illinois variant of regula falsi
double root(const std::function<double(double)>& f, double a, double b, double tol) {
  double fa = f(a), fb = f(b);
  EXPECT_LT(fa * fb, 0.0) << "no sign change in [" << a << ", " << b << "]";
  int side = 0;
  for (int it = 0; it < 60 && b - a > tol; ++it) {
    const double c = (a * fb - b * fa) / (fb - fa), fc = f(c);
    if (fc * fb > 0) {
      b = c;
      fb = fc;
      if (side == -1) fa /= 2;
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == 1) fb /= 2;
      side = 1;
    }
    if (fc == 0) return c;
  }
  return 0.5 * (a + b);
}

TEST(WhippleBicycle, WeaveAndCapsizeSpeedsBoundTheSelfStableRange) {
  // the weave pair's real part crosses 0 at v_w, the capsize root at v_c (the paper's digits)
  const double vw = root(spectral_abscissa, 4.0, 5.0, 1e-12);
  const double vc = root(spectral_abscissa, 5.5, 7.0, 1e-12);
  // (the issue asks for 1e-8; measured 1.6e-14 and 2.0e-13 m/s)
  EXPECT_NEAR(vw, 4.29238253634111, 1e-10);
  EXPECT_NEAR(vc, 6.02426201538837, 1e-10);
  // stable inside, unstable on either side
  EXPECT_LT(spectral_abscissa(5.0), -0.3);
  EXPECT_GT(spectral_abscissa(4.0), 0.4);
  EXPECT_GT(spectral_abscissa(7.0), 0.0);
}

TEST(WhippleBicycle, TheSubsystemsEigenvaluesAreTheFullModelsBesideZeros) {
  // all ten states: x, y, psi, phi, delta, theta_R, theta_F and three rates; the cyclic ones
  // add zero eigenvalues only
  LinearizeOptions all = lean_and_steer();
  all.states.clear();
  const LinearModel full = linearize(bicycle().system, straight_run(5.0), {}, {}, all);
  ASSERT_EQ(full.A.rows(), 10);
  std::vector<cd> nonzero;
  for (Index k = 0; k < full.eigenvalues.size(); ++k)
    if (std::abs(full.eigenvalues(k)) > 1e-6) nonzero.push_back(full.eigenvalues(k));
  const std::vector<cd> want = kTable2[2].lambda;
  ASSERT_EQ(nonzero.size(), 4u);
  const auto got = sorted(Eigen::Map<Eigen::VectorXcd>(nonzero.data(), 4));
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(std::abs(got[k] - want[k]), 0.0, 1e-7) << k;
  // the operating point is a steady motion in lean and steer: f0 = 0 there; the rolling
  // coordinates move (x' = v)
  const LinearModel sub = linearize(bicycle().system, straight_run(5.0), {}, {}, lean_and_steer());
  EXPECT_NEAR(sub.f0.norm(), 0.0, 1e-12);
  EXPECT_NEAR(full.f0(0), 5.0, 1e-12);
}

TEST(WhippleBicycle, KeepingStatesThatDependOnADroppedOneIsAnError) {
  LinearizeOptions o = lean_and_steer();
  o.states = {"phi", "phi_dot"};  // the steer acts on the lean
  try {
    linearize(bicycle().system, straight_run(5.0), {}, {}, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the dropped state 'delta"), std::string::npos) << what;
    EXPECT_NE(what.find("acts on the kept state 'phi"), std::string::npos) << what;
  }
  o.states = {"phi", "lean"};
  try {
    linearize(bicycle().system, straight_run(5.0), {}, {}, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'lean' is not a state of the linear model"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
