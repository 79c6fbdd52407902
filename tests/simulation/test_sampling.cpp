// SPDX-License-Identifier: BSD-3-Clause
// The sample points of ensembles (simulation/sampling.hpp): grids from text, the product's
// order, seeded draws that do not depend on the platform's distributions, the normal quantile
// against tabulated values, and Latin hypercube strata.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <ukdyn/simulation/sampling.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

TEST(Sampling, GridAxisFromText) {
  const GridAxis a = parse_grid_axis("mu=0:0.5:11");
  EXPECT_EQ(a.name, "mu");
  ASSERT_EQ(a.values.size(), 11u);
  EXPECT_EQ(a.values.front(), 0.0);
  EXPECT_EQ(a.values.back(), 0.5);  // the stop exactly
  EXPECT_NEAR(a.values[4], 0.2, 1e-16);
  const GridAxis b = parse_grid_axis("omega=1,2,4");
  EXPECT_EQ(b.values, (std::vector<double>{1, 2, 4}));
  EXPECT_EQ(parse_grid_axis("k=3:7:1").values, std::vector<double>{3});
  try {
    parse_grid_axis("mu=0:0.5");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "'mu=0:0.5': the form is NAME=START:STOP:COUNT or NAME=V1,V2,...");
  }
  EXPECT_THROW(parse_grid_axis("mu=0:1:2.5"), std::invalid_argument);
  EXPECT_THROW(parse_grid_axis("mu=1,x"), std::invalid_argument);
  EXPECT_THROW(parse_grid_axis("2mu=1"), std::invalid_argument);
  // interior values are the decimals they stand for when those are short (0.1 + 2 (0.4 − 0.1)/3
  // is 0.30000000000000004 in doubles: the sweep then ran what --set mu=0.3 does not), and are
  // kept as computed when they have no short form (1/3)
  EXPECT_EQ(parse_grid_axis("mu=0.1:0.4:4").values, (std::vector<double>{0.1, 0.2, 0.3, 0.4}));
  EXPECT_EQ(parse_grid_axis("mu=0:0.5:11").values[3], 0.15);
  EXPECT_EQ(parse_grid_axis("x=-2e-7:1e-7:4").values[1], -1e-7);
  const GridAxis thirds = parse_grid_axis("k=0:1:4");
  EXPECT_EQ(thirds.values[1], 1.0 / 3.0);
  EXPECT_EQ(thirds.values[2], 2.0 / 3.0);
}

TEST(Sampling, RandomVariableFromText) {
  const RandomVariable u = parse_random_variable("theta0~uniform(0,1)");
  EXPECT_EQ(u.name, "theta0");
  EXPECT_EQ(u.distribution, Distribution::kUniform);
  EXPECT_EQ(u.a, 0.0);
  EXPECT_EQ(u.b, 1.0);
  EXPECT_EQ(parse_random_variable("k~normal(2, 0.5)").distribution, Distribution::kNormal);
  EXPECT_EQ(parse_random_variable("k~loguniform(1e-3,1)").a, 1e-3);
  try {
    parse_random_variable("k~gamma(1,2)");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "'k~gamma(1,2)': unknown law 'gamma' (the laws are uniform, normal and "
                 "loguniform)");
  }
  EXPECT_THROW(parse_random_variable("k~uniform(1)"), std::invalid_argument);
}

TEST(Sampling, NormalQuantileMatchesTables) {
  // Φ⁻¹ from tables (Abramowitz & Stegun 26.2, and values to 16 digits from mpmath)
  EXPECT_EQ(normal_quantile(0.5), 0.0);
  EXPECT_NEAR(normal_quantile(0.975), 1.959963984540054, 2e-15);
  EXPECT_NEAR(normal_quantile(0.025), -1.959963984540054, 2e-15);
  EXPECT_NEAR(normal_quantile(0.8413447460685429), 1.0, 2e-15);
  EXPECT_NEAR(normal_quantile(1e-10), -6.361340902404056, 1e-13);
  EXPECT_NEAR(normal_quantile(1 - 1e-6), 4.753424308822899, 1e-9);  // (1 - 1e-6 is rounded)
  EXPECT_EQ(normal_quantile(0.75), -normal_quantile(0.25));
  EXPECT_THROW(normal_quantile(0.0), std::invalid_argument);
  EXPECT_THROW(normal_quantile(1.0), std::invalid_argument);
}

TEST(Sampling, GridProductFirstAxisSlowest) {
  Design d;
  d.grid = {{"a", {1, 2}}, {"b", {10, 20, 30}}};
  const DesignTable t = make_design(d);
  EXPECT_EQ(t.names, (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(t.rows.size(), 6u);
  EXPECT_EQ(t.rows[0], (std::vector<double>{1, 10}));
  EXPECT_EQ(t.rows[2], (std::vector<double>{1, 30}));
  EXPECT_EQ(t.rows[3], (std::vector<double>{2, 10}));
  EXPECT_EQ(t.rows[5], (std::vector<double>{2, 30}));
}

TEST(Sampling, DrawsAreSeededAndFromTheRawStream) {
  Design d;
  d.random = {{"u", Distribution::kUniform, 2.0, 4.0}, {"n", Distribution::kNormal, 1.0, 3.0}};
  d.draws = 20000;
  d.seed = 7;
  const DesignTable t = make_design(d);
  ASSERT_EQ(t.rows.size(), 20000u);
  // the first draw, from the standard-fixed raw output of std::mt19937_64(7)
  std::mt19937_64 rng(7);
  const double u0 = (double(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u1 = (double(rng() >> 11) + 0.5) * 0x1.0p-53;
  EXPECT_EQ(t.rows[0][0], 2.0 + 2.0 * u0);
  EXPECT_EQ(t.rows[0][1], 1.0 + 3.0 * normal_quantile(u1));
  // the same seed, the same numbers; another seed, others
  EXPECT_EQ(make_design(d).rows, t.rows);
  d.seed = 8;
  EXPECT_NE(make_design(d).rows[0], t.rows[0]);
  // moments: uniform(2, 4) mean 3, variance 1/3; normal(1, 3) mean 1, sd 3 (5 sigma bounds)
  double su = 0, su2 = 0, sn = 0, sn2 = 0;
  for (const auto& r : t.rows) {
    EXPECT_GT(r[0], 2.0);
    EXPECT_LT(r[0], 4.0);
    su += r[0];
    su2 += r[0] * r[0];
    sn += r[1];
    sn2 += r[1] * r[1];
  }
  const double N = 20000;
  EXPECT_NEAR(su / N, 3.0, 5 * std::sqrt(1.0 / 3 / N));
  EXPECT_NEAR(su2 / N - (su / N) * (su / N), 1.0 / 3, 0.02);
  EXPECT_NEAR(sn / N, 1.0, 5 * 3 / std::sqrt(N));
  EXPECT_NEAR(std::sqrt(sn2 / N - (sn / N) * (sn / N)), 3.0, 0.08);
}

TEST(Sampling, LatinHypercubeHasOneDrawPerStratum) {
  Design d;
  d.random = {{"a", Distribution::kUniform, 0.0, 1.0}, {"k", Distribution::kLogUniform, 1e-3, 1e3}};
  d.draws = 50;
  d.seed = 3;
  d.latin_hypercube = true;
  const DesignTable t = make_design(d);
  std::vector<int> strata_a(50, 0), strata_k(50, 0);
  for (const auto& r : t.rows) {
    ++strata_a[std::size_t(r[0] * 50)];
    // log-uniform on [1e-3, 1e3]: log10(k) uniform on [-3, 3]
    ++strata_k[std::size_t((std::log10(r[1]) + 3.0) / 6.0 * 50)];
  }
  EXPECT_EQ(strata_a, std::vector<int>(50, 1));
  EXPECT_EQ(strata_k, std::vector<int>(50, 1));
}

TEST(Sampling, GridTimesDrawsUseCommonRandomNumbers) {
  Design d;
  d.grid = {{"mu", {0.1, 0.2, 0.3}}};
  d.random = {{"x", Distribution::kUniform, 0.0, 1.0}};
  d.draws = 4;
  const DesignTable t = make_design(d);
  ASSERT_EQ(t.rows.size(), 12u);
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_EQ(t.rows[j][1], t.rows[4 + j][1]);
    EXPECT_EQ(t.rows[j][1], t.rows[8 + j][1]);
    EXPECT_EQ(t.rows[4 + j][0], 0.2);
  }
}

TEST(Sampling, BadDesignsNameTheVariable) {
  Design d;
  d.random = {{"x", Distribution::kLogUniform, 0.0, 1.0}};
  d.draws = 3;
  try {
    make_design(d);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "ukdyn::make_design: x~loguniform(0, 1): a log-uniform law needs 0 < a <= b");
  }
  d.random = {{"x", Distribution::kUniform, 0.0, 1.0}};
  d.draws = 0;
  EXPECT_THROW(make_design(d), std::invalid_argument);
  d.draws = 2;
  d.grid = {{"x", {1}}};
  EXPECT_THROW(make_design(d), std::invalid_argument);  // x twice
  // more than 1e7 samples: refused before anything is drawn
  d.grid = {{"a", {1, 2}}};
  d.draws = 6'000'000;
  try {
    make_design(d);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1.2e+07 samples, more than 1e7"), std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
