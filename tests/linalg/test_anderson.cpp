// SPDX-License-Identifier: BSD-3-Clause
// AndersonAcceleration (linalg/anderson.hpp) on affine maps g(x) = J x + c, whose fixed point
// x* = (I − J)⁻¹ c comes from an LU solve: the extrapolation reaches it once the stored
// differences span the directions the residuals take, at any contraction rate.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "ukdyn/linalg/anderson.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

struct Affine {
  MatrixXd J;
  VectorXd c;
  VectorXd operator()(const VectorXd& x) const { return J * x + c; }
  VectorXd fixed_point() const {
    return (MatrixXd::Identity(c.size(), c.size()) - J).partialPivLu().solve(c);
  }
};

// the iterate after `rounds` images from x = 0: a plain step, then Anderson's extrapolations
VectorXd iterate(const Affine& g, AndersonAcceleration& aa, int rounds) {
  VectorXd x = VectorXd::Zero(g.c.size()), next(g.c.size());
  aa.reset();
  for (int k = 0; k < rounds; ++k) {
    aa.update(x, g(x));
    aa.extrapolate(next);
    x = next;
  }
  return x;
}

// J = Σ rates_i u_i v_iᵀ with u_i, v_i fixed vectors, c in the span of the u_i (as a friction's
// C is proportional to its normal force): the residuals stay in that span
Affine low_rank(Index d, const std::vector<double>& rates) {
  Affine g{MatrixXd::Zero(d, d), VectorXd::Zero(d)};
  for (std::size_t i = 0; i < rates.size(); ++i) {
    VectorXd u(d), v(d);
    for (Index j = 0; j < d; ++j) {
      u[j] = std::cos(0.7 * double(j + 1) * double(i + 1));
      v[j] = std::sin(1.3 * double(j + 2) + double(i));
    }
    u /= u.norm();
    v /= v.dot(u);  // vᵀu = 1: the rate along u_i alone
    g.J += rates[i] * u * v.transpose();
    g.c += double(i + 2) * u;
  }
  return g;
}

TEST(AndersonAcceleration, RankOneMapNearRateOneSettlesAfterOneDifference) {
  // the plain iteration's error shrinks by 0.9975 a round (Painlevé's rod at mu = 1.33)
  for (const double rate : {0.5, 0.9, 0.9975, 2.0}) {
    SCOPED_TRACE(rate);
    const Affine g = low_rank(7, {rate});
    const VectorXd star = g.fixed_point();
    AndersonAcceleration aa(7, AndersonAcceleration::kDefaultDepth);
    // round 1: a plain step (no difference yet); round 2: the fixed point
    EXPECT_NEAR((iterate(g, aa, 1) - g(VectorXd::Zero(7))).norm(), 0.0, 1e-15);
    EXPECT_EQ(aa.used(), 0);
    const VectorXd x = iterate(g, aa, 2);
    EXPECT_EQ(aa.stored(), 1);
    EXPECT_EQ(aa.used(), 1);
    EXPECT_NEAR((x - star).norm(), 0.0, 1e-12 * star.norm());
    // a third round: the new difference is parallel to the first, which is left out
    const VectorXd x3 = iterate(g, aa, 3);
    EXPECT_EQ(aa.stored(), 2);
    EXPECT_EQ(aa.used(), 1);
    EXPECT_NEAR((x3 - star).norm(), 0.0, 1e-12 * star.norm());
  }
}

TEST(AndersonAcceleration, RankThreeMapSettlesAfterThreeDifferences) {
  const Affine g = low_rank(9, {0.99, 0.95, -0.8});
  const VectorXd star = g.fixed_point();
  AndersonAcceleration aa(9, 5);
  const VectorXd x3 = iterate(g, aa, 3);  // two differences: not yet
  EXPECT_GT((x3 - star).norm(), 1e-6 * star.norm());
  const VectorXd x4 = iterate(g, aa, 4);
  EXPECT_EQ(aa.used(), 3);
  EXPECT_NEAR((x4 - star).norm(), 0.0, 1e-11 * star.norm());
}

TEST(AndersonAcceleration, DepthOneOnARankTwoMapStillConverges) {
  // (a secant on the last difference only: no longer exact, but far faster than 0.999^k)
  const Affine g = low_rank(5, {0.999, 0.5});
  const VectorXd star = g.fixed_point();
  AndersonAcceleration aa(5, 1);
  const VectorXd x = iterate(g, aa, 30);
  EXPECT_NEAR((x - star).norm(), 0.0, 1e-10 * star.norm());
}

TEST(AndersonAcceleration, SettingsOutOfRangeAreRefusedByName) {
  AndersonAcceleration aa;
  try {
    aa.resize(-1, 5);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "ukdyn::AndersonAcceleration::resize: expected dimension >= 0 and depth >= 1, got "
              "-1 and 5");
  }
  EXPECT_THROW(aa.resize(3, 0), std::invalid_argument);
  try {
    aa.set_drop_tolerance(1.0);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "ukdyn::AndersonAcceleration::set_drop_tolerance: expected a tolerance in [0, 1), "
              "got 1");
  }
  EXPECT_EQ(aa.set_drop_tolerance(0.0).drop_tolerance(), 0.0);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
