// SPDX-License-Identifier: BSD-3-Clause
// tables: of a model file (modelfile/reader_tables.cpp) and the table columns of the expression
// language (modelfile/table.hpp): interpolation exact on data it reproduces, the spline's
// measured order, derivatives through the expression engine, a drive tracking a recorded
// trajectory, an oscillator shaken by a recorded ground acceleration against its closed form,
// the range error, and every load error at file:line:column.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/expression.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/modelfile/table.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using expr::Extrapolation;
using expr::Interpolation;
using expr::TableColumn;

::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

// n + 1 abscissae from a to b, spaced unevenly (x_i = a + (b − a) s_i with s_i = i/n + a wobble
// that keeps them increasing)
std::vector<double> uneven(double a, double b, int n) {
  std::vector<double> x;
  for (int i = 0; i <= n; ++i) {
    const double s = double(i) / n + (i > 0 && i < n ? 0.3 / n * std::sin(7.0 * i) : 0.0);
    x.push_back(a + (b - a) * s);
  }
  return x;
}

std::vector<double> map(const std::vector<double>& x, const std::function<double(double)>& f) {
  std::vector<double> y;
  for (const double v : x) y.push_back(f(v));
  return y;
}

// a directory of this process's own for the tables' files
std::filesystem::path scratch_dir() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("ukdyn_test_tables_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

std::string write(const std::string& name, const std::string& text) {
  const auto path = scratch_dir() / name;
  std::ofstream(path) << text;
  return path.string();
}

// a CSV of the columns `names`, rows f(x) for each x
std::string csv(const std::vector<std::string>& names, const std::vector<double>& x,
                const std::vector<std::function<double(double)>>& f) {
  std::ostringstream os;
  os.precision(17);
  for (std::size_t k = 0; k < names.size(); ++k) os << (k ? "," : "") << names[k];
  os << "\n";
  for (const double v : x) {
    os << v;
    for (const auto& g : f) os << "," << g(v);
    os << "\n";
  }
  return os.str();
}

std::vector<double> grid(double a, double b, double h) {
  std::vector<double> x;
  const int n = int(std::lround((b - a) / h));
  for (int i = 0; i <= n; ++i) x.push_back(a + i * h);
  return x;
}

// ---- the interpolants -----------------------------------------------------------------------

TEST(TableColumn, LinearIsExactOnLinearData) {
  const auto x = uneven(-1.0, 3.0, 9);
  const TableColumn c("d.y", x, map(x, [](double v) { return 2.0 * v + 1.0; }));
  for (const double v : {-1.0, -0.37, 0.0, 1.234, 2.999, 3.0}) {
    EXPECT_NEAR(c.evaluate(v), 2.0 * v + 1.0, 1e-14) << v;
    EXPECT_NEAR(c.evaluate(v, 1), 2.0, 1e-13) << v;
    EXPECT_EQ(c.evaluate(v, 2), 0.0);
  }
  EXPECT_EQ(c.degree(), 1);
}

TEST(TableColumn, NotAKnotCubicIsExactOnACubic) {
  // the not-a-knot spline reproduces any cubic (its ends are not forced to S'' = 0), on uneven
  // rows and on the fewest rows it takes (4)
  const auto p = [](double v) { return v * v * v - 2.0 * v * v + 0.5 * v + 1.0; };
  const auto dp = [](double v) { return 3.0 * v * v - 4.0 * v + 0.5; };
  const auto ddp = [](double v) { return 6.0 * v - 4.0; };
  for (const int n : {3, 12}) {
    const auto x = uneven(-1.0, 2.0, n);
    const TableColumn c("d.y", x, map(x, p), Interpolation::kCubic);
    for (const double v : {-1.0, -0.61, 0.0, 0.77, 1.5, 2.0}) {
      EXPECT_NEAR(c.evaluate(v), p(v), 1e-12) << n << " rows, x = " << v;
      EXPECT_NEAR(c.evaluate(v, 1), dp(v), 1e-11) << n << " rows, x = " << v;
      EXPECT_NEAR(c.evaluate(v, 2), ddp(v), 1e-10) << n << " rows, x = " << v;
      EXPECT_NEAR(c.evaluate(v, 3), 6.0, 1e-9) << n << " rows, x = " << v;
      EXPECT_EQ(c.evaluate(v, 4), 0.0);
    }
  }
}

// the largest error of the spline of sin sampled every h over [0, 4], and of its first and
// second derivatives, at 1000 points
std::array<double, 3> spline_errors(double h) {
  const auto x = grid(0.0, 4.0, h);
  const TableColumn c("d.s", x, map(x, [](double v) { return std::sin(v); }),
                      Interpolation::kCubic);
  std::array<double, 3> e{0.0, 0.0, 0.0};
  for (int k = 0; k <= 1000; ++k) {
    const double v = 4.0 * k / 1000.0;
    e[0] = std::max(e[0], std::fabs(c.evaluate(v) - std::sin(v)));
    e[1] = std::max(e[1], std::fabs(c.evaluate(v, 1) - std::cos(v)));
    e[2] = std::max(e[2], std::fabs(c.evaluate(v, 2) + std::sin(v)));
  }
  return e;
}

TEST(TableColumn, CubicSplineConvergesAtOrderFour) {
  // the spline's error is O(h⁴), its derivatives' O(h³) and O(h²): halving h divides them by
  // about 16, 8 and 4 (measured orders log2 of the ratios)
  const auto coarse = spline_errors(0.2), fine = spline_errors(0.1);
  const double order0 = std::log2(coarse[0] / fine[0]), order1 = std::log2(coarse[1] / fine[1]),
               order2 = std::log2(coarse[2] / fine[2]);
  EXPECT_GT(order0, 3.7);
  EXPECT_LT(order0, 4.4);
  EXPECT_GT(order1, 2.7);
  EXPECT_LT(order1, 3.4);
  EXPECT_GT(order2, 1.7);
  EXPECT_LT(order2, 2.4);
  // and the bound 5/384 h⁴ max|f⁗| of the interior, within a factor 4 at the ends
  EXPECT_LT(fine[0], 4.0 * 5.0 / 384.0 * std::pow(0.1, 4));
}

TEST(TableColumn, StepHoldsEachRowUntilTheNext) {
  const std::vector<double> x{0.0, 1.0, 2.5, 4.0}, y{3.0, -1.0, 2.0, 7.0};
  const TableColumn c("d.u", x, y, Interpolation::kStep);
  EXPECT_EQ(c.evaluate(0.0), 3.0);
  EXPECT_EQ(c.evaluate(0.999), 3.0);
  EXPECT_EQ(c.evaluate(1.0), -1.0);
  EXPECT_EQ(c.evaluate(2.49), -1.0);
  EXPECT_EQ(c.evaluate(3.9), 2.0);
  EXPECT_EQ(c.evaluate(4.0), 7.0);
  EXPECT_EQ(c.evaluate(1.5, 1), 0.0);
  EXPECT_EQ(c.degree(), 0);
}

TEST(TableColumn, OutsideTheRangeAnErrorOrTheExtrapolationAsked) {
  const std::vector<double> x{0.0, 1.0, 2.0}, y{0.0, 2.0, 3.0};
  const TableColumn error("ground.acc", x, y, Interpolation::kLinear, Extrapolation::kError,
                          "ground.csv");
  try {
    error.evaluate(2.5);
    ADD_FAILURE() << "no error outside the range";
  } catch (const expr::TableRangeError& e) {
    EXPECT_TRUE(contains(e.what(),
                         "table column 'ground.acc' (from ground.csv) evaluated at 2.5, "
                         "outside its rows' range [0, 2]"));
    EXPECT_TRUE(contains(e.what(), "extrapolation: hold or linear"));
  }
  EXPECT_THROW(error.evaluate(-1e-3), expr::TableRangeError);
  // an end within roundoff: at the end
  EXPECT_EQ(error.evaluate(2.0 * (1.0 + 2e-16)), 3.0);
  const TableColumn hold("d.y", x, y, Interpolation::kLinear, Extrapolation::kHold);
  EXPECT_EQ(hold.evaluate(5.0), 3.0);
  EXPECT_EQ(hold.evaluate(-5.0), 0.0);
  EXPECT_EQ(hold.evaluate(5.0, 1), 0.0);
  const TableColumn line("d.y", x, y, Interpolation::kLinear, Extrapolation::kLinear);
  EXPECT_DOUBLE_EQ(line.evaluate(4.0), 3.0 + 1.0 * 2.0);
  EXPECT_DOUBLE_EQ(line.evaluate(-1.0), -2.0);
  EXPECT_DOUBLE_EQ(line.evaluate(4.0, 1), 1.0);
}

TEST(TableColumn, RefusesDataItCannotInterpolate) {
  const auto refused = [](std::vector<double> x, std::vector<double> y, Interpolation i) {
    try {
      TableColumn("d.y", std::move(x), std::move(y), i);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_TRUE(contains(refused({0, 1, 2}, {0, 1, 2}, Interpolation::kCubic),
                       "3 rows; cubic interpolation needs at least 4"));
  EXPECT_TRUE(contains(refused({0}, {0}, Interpolation::kLinear),
                       "1 rows; linear interpolation needs at least 2"));
  EXPECT_TRUE(contains(refused({0, 1, 1}, {0, 1, 2}, Interpolation::kLinear),
                       "not strictly increasing at row 2 (1 after 1)"));
  EXPECT_TRUE(contains(refused({0, 1}, {0, NAN}, Interpolation::kLinear), "finite"));
  EXPECT_TRUE(contains(refused({0, 1}, {0}, Interpolation::kLinear), "2 abscissae but 1 values"));
}

// ---- in the expression language -------------------------------------------------------------

TEST(TableExpressions, DerivativesAreTheInterpolantsAndVanishBeyondItsDegree) {
  const auto x = grid(0.0, 2.0, 0.25);
  auto cubic = std::make_shared<const TableColumn>(
      "rec.s", x, map(x, [](double v) { return std::sin(v); }), Interpolation::kCubic);
  auto linear = std::make_shared<const TableColumn>(
      "rec.l", x, map(x, [](double v) { return v * v; }), Interpolation::kLinear);
  expr::ExpressionSet set({"q", "t"});
  set.add_table_column("rec.s", cubic);
  set.add_table_column("rec.l", linear);
  const expr::Expr e = set.parse("q*rec.s(2*t) + rec.l(t)");
  const expr::Expr d1 = set.diff(e, "t"), d2 = set.diff(d1, "t");
  const expr::Program p = set.compile({e, d1, d2, set.diff(e, "q")});
  std::vector<double> scratch(std::size_t(p.scratch_size())), out(4);
  const double in[2] = {1.5, 0.6};
  p.evaluate(in, out.data(), scratch.data());
  EXPECT_DOUBLE_EQ(out[0], 1.5 * cubic->evaluate(1.2) + linear->evaluate(0.6));
  EXPECT_DOUBLE_EQ(out[1], 1.5 * 2.0 * cubic->evaluate(1.2, 1) + linear->evaluate(0.6, 1));
  // (the linear column's second derivative is 0: impulses are not seen)
  EXPECT_DOUBLE_EQ(out[2], 1.5 * 4.0 * cubic->evaluate(1.2, 2));
  EXPECT_DOUBLE_EQ(out[3], cubic->evaluate(1.2));
  EXPECT_EQ(set.to_string(d2).find("rec.l"), std::string::npos) << set.to_string(d2);
  EXPECT_TRUE(contains(set.to_string(d2), "rec.s''(2*t)"));
  // beyond the cubic's degree: exactly 0
  const expr::Expr s = set.parse("rec.s(t)");
  expr::Expr d = s;
  for (int k = 0; k < 4; ++k) d = set.diff(d, "t");
  EXPECT_TRUE(set.is_literal_zero(d));
  // a constant argument is folded when compiling
  EXPECT_EQ(set.compile({set.parse("rec.s(1)")}).operations(), 0);
}

TEST(TableExpressions, ProgramsGiveNaNOutsideTheRangeAndRecordWhy) {
  const std::vector<double> x{0.0, 1.0}, y{0.0, 1.0};
  expr::ExpressionSet set({"t"});
  set.add_table_column("g.a", std::make_shared<const TableColumn>("g.a", x, y));
  const expr::Program p = set.compile({set.parse("g.a(t)")});
  ASSERT_LE(p.scratch_size(), 8);
  double scratch[8], out = 0.0, t = 0.25;
  p.evaluate(&t, &out, scratch);
  EXPECT_EQ(out, 0.25);
  // outside: NaN, and the message recorded for this thread (the first since it was cleared)
  expr::clear_table_range_error();
  t = 1.5;
  p.evaluate(&t, &out, scratch);
  EXPECT_TRUE(std::isnan(out));
  t = 2.5;
  p.evaluate(&t, &out, scratch);
  EXPECT_EQ(expr::table_range_error(),
            "table column 'g.a' evaluated at 1.5, outside its rows' range [0, 1] (extrapolation: "
            "error; give the table extrapolation: hold or linear to extend it)");
  expr::clear_table_range_error();
  EXPECT_EQ(expr::table_range_error(), "");
  // a constant argument outside the range: an error when compiling
  EXPECT_THROW(set.compile({set.parse("g.a(2)")}), std::invalid_argument);
}

TEST(TableExpressions, NamesErrorsAndSuggestions) {
  const std::vector<double> x{0.0, 1.0}, y{0.0, 1.0};
  expr::ExpressionSet set({"crank_x", "t"});
  set.add_table_column("ground.acc", std::make_shared<const TableColumn>("ground.acc", x, y));
  const auto error = [&](const std::string& text) {
    try {
      set.parse(text);
    } catch (const expr::ParseError& e) {
      return std::string(e.what()) + " @" + std::to_string(e.position());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("1 + ground.acc"),
            "'ground.acc' is a table column: write ground.acc(x), x its "
            "argument (t, …) @4");
  EXPECT_EQ(error("ground.ac(t)"),
            "unknown table column 'ground.ac' (did you mean "
            "'ground.acc'?) @0");
  EXPECT_EQ(error("ground.acc(t, 1)"), "ground.acc takes 1 argument, got more @12");
  EXPECT_EQ(error("ground.acc()"), "ground.acc takes 1 argument, got 0 @0");
  EXPECT_TRUE(contains(error("2*crank.x"), "did you mean 'crank_x'?"));
  EXPECT_THROW(set.add_table_column("ground.acc", std::make_shared<const TableColumn>("a.b", x, y)),
               std::invalid_argument);
  EXPECT_THROW(set.add_table_column("groundacc", std::make_shared<const TableColumn>("a.b", x, y)),
               std::invalid_argument);
}

// ---- model files ----------------------------------------------------------------------------

// the ModelError of loading a model whose table g is `table_entry`
struct Failure {
  int line = 0, column = 0;
  std::string what;
};
Failure failure_of(const std::string& name, const std::string& table_entry) {
  const std::string path = write(name,
                                 "coordinates: [u]\nkinetic_energy: 0.5*u_dot^2\n"
                                 "forces: [g.a(t)]\ntables:\n  g: " +
                                     table_entry + "\n");
  try {
    load_model(path);
  } catch (const ModelError& e) {
    return {e.line(), e.column(), e.what()};
  }
  ADD_FAILURE() << "no error for " << table_entry;
  return {};
}

TEST(ModelTables, ADriveTracksARecordedTrajectory) {
  // x is driven along a recording of sin(t) sampled every 0.05 s (cubic): the run follows sin
  // within the spline's error (5/384 h⁴ ≈ 8e-8 inside, a few times that at the ends), and the
  // drive's force is m x'' = −m sin t within the second derivative's O(h²) error
  write("recorded_sin.csv",
        csv({"t", "x"}, grid(0.0, 4.0, 0.05), {[](double v) { return std::sin(v); }}));
  const std::string model = write("tracking.yaml", R"(
parameters: {m: 2}
coordinates: [x]
kinetic_energy: 0.5*m*x_dot^2
tables:
  rec: {file: recorded_sin.csv, x: t, interpolation: cubic}
constraints:
  - {name: drive, holonomic: x - rec.x(t)}
initial: {q: {x: 0}, q_dot: {x: 1}, project: true}
simulate: {t_end: 4, rtol: 1e-11, atol: 1e-12}
output: {every: 0.1}
)");
  const Model m = load_model(model);
  const ModelRun run = run_model(m);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.t.size(), 41u);
  double worst = 0.0, worst_force = 0.0;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    worst = std::max(worst, std::fabs(tr.q[k] - std::sin(tr.t[k])));
    worst_force = std::max(worst_force, std::fabs(tr.Qc_ideal[k] + 2.0 * std::sin(tr.t[k])));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_force, 2.0 * 0.05 * 0.05);
}

// u'' + ω² u = −a_g(t), a_g = A sin(Ω t), from rest: the relative displacement of a mass on a
// spring whose base is shaken
double shaken(double t, double A, double omega, double Omega) {
  return -A / (omega * omega - Omega * Omega) *
         (std::sin(Omega * t) - Omega / omega * std::sin(omega * t));
}

std::string oscillator(const std::string& table, double t_end) {
  return R"(
parameters: {m: 3, k: 3*(2*pi)^2}
coordinates: [u]
kinetic_energy: 0.5*m*u_dot^2
potential_energy: 0.5*k*u^2
forces: [-m*ground.acc(t)]
tables:
  ground: )" +
         table + R"(
simulate: {t_end: )" +
         std::to_string(t_end) +
         R"(, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
)";
}

TEST(ModelTables, AControlRequirementAndAJointDriveFollowATable) {
  // data on a cubic, p(t) = t − t³/10, which the spline reproduces exactly: a control
  // requirement x − rec.p(t) from a consistent start keeps x = p, and a multibody joint's drive
  // th0 + rec.p(t) turns the crank by p (the slider-crank example's drive replaced)
  const auto x = grid(0.0, 2.0, 0.25);
  std::ostringstream data;
  data.precision(17);
  data << "{interpolation: cubic, data: {t: [";
  for (std::size_t k = 0; k < x.size(); ++k) data << (k ? ", " : "") << x[k];
  data << "], p: [";
  for (std::size_t k = 0; k < x.size(); ++k)
    data << (k ? ", " : "") << x[k] - x[k] * x[k] * x[k] / 10.0;
  data << "]}}";
  const auto p = [](double t) { return t - t * t * t / 10.0; };
  const Trajectory controlled = run_model(parse_model(R"(
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
tables: {rec: )" + data.str() + R"(}
control:
  requirements:
    - {name: track, holonomic: x - rec.p(t), dynamics: {omega: 5}}
initial: {q_dot: {x: 1}}
simulate: {t_end: 2, rtol: 1e-11, atol: 1e-12}
output: {every: 0.1}
)"))
                                    .trajectory;
  ASSERT_EQ(controlled.stats.status, Status::kOk) << controlled.stats.message;
  ASSERT_EQ(controlled.t.size(), 21u);
  for (std::size_t k = 0; k < controlled.t.size(); ++k)
    EXPECT_NEAR(controlled.q[k], p(controlled.t[k]), 1e-8) << controlled.t[k];

  std::ifstream in(std::string(UKDYN_EXAMPLES_DIR) + "/slider_crank.yaml");
  std::string crank((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string drive = "drive: th0 + w*t}";
  ASSERT_NE(crank.find(drive), std::string::npos);
  crank.replace(crank.find(drive), drive.size(), "drive: th0 + rec.p(t)}");
  crank += "tables: {rec: " + data.str() + "}\n";
  const Trajectory driven = run_model(parse_model(crank, "crank.yaml")).trajectory;
  ASSERT_EQ(driven.stats.status, Status::kOk) << driven.stats.message;
  const auto& names = driven.coordinate_names;
  const std::size_t theta =
      std::size_t(std::find(names.begin(), names.end(), "crank.theta") - names.begin());
  ASSERT_LT(theta, names.size());
  for (std::size_t k = 0; k < driven.t.size(); ++k) {
    EXPECT_NEAR(driven.q[k * names.size() + theta], 0.3 + p(driven.t[k]), 1e-9) << driven.t[k];
  }
}

TEST(ModelTables, AnOscillatorShakenByARecordedGroundAcceleration) {
  // the recording: a_g = 1.5 sin(2 t) every 0.01 s over [0, 5]; the closed form of the forced
  // oscillator (ω = 2π) within the interpolation's error over ω² (cubic ≈ 5/384 h⁴ A Ω⁴/ω²
  // ≈ 1e-10, under the integrator's error; linear ≈ h²/8 A Ω²/ω² ≈ 2e-6)
  write("ground.csv", csv({"time", "acc"}, grid(0.0, 5.0, 0.01),
                          {[](double v) { return 1.5 * std::sin(2.0 * v); }}));
  const double omega = 2.0 * std::numbers::pi;
  for (const auto& [interp, tol] : {std::pair{"cubic", 1e-8}, std::pair{"linear", 1e-5}}) {
    const std::string model = write(
        "shaken.yaml",
        oscillator(std::string("{file: ground.csv, x: time, interpolation: ") + interp + "}", 5.0));
    const ModelRun run = run_model(load_model(model));
    const Trajectory& tr = run.trajectory;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    ASSERT_EQ(tr.t.size(), 101u);
    double worst = 0.0;
    for (std::size_t k = 0; k < tr.t.size(); ++k)
      worst = std::max(worst, std::fabs(tr.q[k] - shaken(tr.t[k], 1.5, omega, 2.0)));
    EXPECT_LT(worst, tol) << interp;
    EXPECT_GT(std::fabs(tr.q.back()), 0.01);  // (it moved)
  }
}

TEST(ModelTables, AnHdf5Recording) {
  // the datasets of an HDF5 file (here written by ukdyn's own write_table_hdf5): named by x:
  // and columns:, or every column of a table ukdyn wrote
  const auto x = grid(0.0, 5.0, 0.01);
  const std::string h5 = (scratch_dir() / "ground.h5").string();
  write_table_hdf5(h5, {{"t", x},
                        {"acc", map(x, [](double v) { return 1.5 * std::sin(2.0 * v); })},
                        {"lambda.rod", x}});
  const double omega = 2.0 * std::numbers::pi;
  for (const std::string table : {"{file: ground.h5, x: t, columns: [acc], interpolation: cubic}",
                                  "{file: ground.h5, interpolation: cubic}"}) {
    const ModelRun run = run_model(load_model(write("shaken_h5.yaml", oscillator(table, 5.0))));
    const Trajectory& tr = run.trajectory;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    double worst = 0.0;
    for (std::size_t k = 0; k < tr.t.size(); ++k)
      worst = std::max(worst, std::fabs(tr.q[k] - shaken(tr.t[k], 1.5, omega, 2.0)));
    EXPECT_LT(worst, 1e-8) << table;
  }
  const Failure f = failure_of("h5.yaml", "{file: ground.h5, columns: [accel]}");
  EXPECT_EQ(f.line, 5);
  EXPECT_TRUE(contains(f.what, "in table 'g': ukdyn::read_hdf5_field: no dataset 'accel' in "));
}

TEST(ModelTables, ARunPastTheRecordingStopsNamingTheTableOrHoldsItsEnd) {
  write("ground_short.csv",
        csv({"t", "acc"}, grid(0.0, 1.0, 0.1), {[](double v) { return std::sin(v); }}));
  const Model m = load_model(write("past.yaml", oscillator("{file: ground_short.csv}", 2.0)));
  const Trajectory tr = run_model(m).trajectory;
  EXPECT_NE(tr.stats.status, Status::kOk);
  EXPECT_TRUE(contains(tr.stats.message,
                       "table column 'ground.acc' (from ground_short.csv) evaluated at 1."));
  EXPECT_TRUE(contains(tr.stats.message, "outside its rows' range [0, 1] (extrapolation: error"));
  // what was computed is kept: the samples up to the table's end
  ASSERT_GE(tr.t.size(), 21u);
  EXPECT_EQ(tr.t[20], 1.0);
  EXPECT_LE(tr.t.back(), 1.05);
  // the streamed run (ukdyn run) says the same
  std::size_t streamed = 0;
  const ModelRun s = run_model(
      m, m.options, [&](const ModelRun& chunk) { streamed += chunk.trajectory.t.size(); });
  EXPECT_EQ(s.trajectory.stats.message, tr.stats.message);
  EXPECT_EQ(streamed, tr.t.size());
  // extrapolation: hold — after t = 1 the base is at rest: a free oscillation
  const Model held = load_model(
      write("held.yaml", oscillator("{file: ground_short.csv, extrapolation: hold}", 2.0)));
  const ModelRun run = run_model(held);
  EXPECT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  EXPECT_EQ(run.trajectory.t.back(), 2.0);
}

// the oscillator's response to a = 2 t (exact for linear interpolation), ω = 2π:
// u = −2 (t − sin(ω t)/ω)/ω²
void expect_ramp_response(const Trajectory& tr) {
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.t.size(), 21u);
  const double w = 2.0 * std::numbers::pi;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    const double t = tr.t[k];
    EXPECT_NEAR(tr.q[k], -2.0 * (t - std::sin(w * t) / w) / (w * w), 1e-9) << t;
  }
}

TEST(ModelTables, DataWrittenInTheModelFile) {
  expect_ramp_response(
      run_model(parse_model(oscillator("{data: {t: [0, 0.5, 1], acc: [0, 1, 2]}}", 1.0)))
          .trajectory);
}

TEST(ModelTables, TablesGivenByTheProgramThatLoadsTheModel) {
  // the file declares the table (its abscissa, interpolation); the caller gives the data, which
  // replace any the file has (as overrides replace parameters)
  const std::string text = oscillator("{x: time, data: {time: [0, 1], acc: [5, 5]}}", 1.0);
  const GivenTables given{{"ground", {{"acc", {0.0, 1.0, 2.0}}, {"time", {0.0, 0.5, 1.0}}}}};
  expect_ramp_response(run_model(parse_model(text, "given.yaml", {}, given)).trajectory);
  // a table the file does not declare, and given data it cannot interpolate
  try {
    parse_model(text, "given.yaml", {}, {{"groun", {{"t", {0.0, 1.0}}, {"acc", {0.0, 1.0}}}}});
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_TRUE(contains(e.what(),
                         "the table 'groun' given is not declared in tables: (hint: "
                         "the model's tables are ground)"));
  }
  try {
    parse_model(text, "given.yaml", {},
                {{"ground", {{"time", {0.0, 2.0, 1.0}}, {"acc", {0, 1, 2}}}}});
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 8);
    EXPECT_TRUE(contains(e.what(),
                         "in table 'ground': row 3: the abscissa 'time' is not strictly "
                         "increasing (1 after 2)"));
  }
}

// ---- load errors ----------------------------------------------------------------------------

TEST(ModelTables, LoadErrorsNameTheFileTheLineAndTheCell) {
  write("bad_cell.csv", "t, a\n0, 1\n1, x2\n");
  write("not_increasing.csv", "t,a\n# a comment\n0,1\n1,2\n1,3\n");
  write("one_row.csv", "t,a\n0,1\n");
  write("three_rows.csv", "t,a\n0,1\n1,2\n2,3\n");
  write("ragged.csv", "t,a\n0,1\n1\n");
  write("good.csv", "t,a\n0,1\n1,2\n");

  Failure f = failure_of("e1.yaml", "{file: missing.csv}");
  EXPECT_EQ(f.line, 5);
  EXPECT_EQ(f.column, 13);
  EXPECT_TRUE(contains(f.what, "cannot read "));
  EXPECT_TRUE(contains(f.what, "missing.csv, the file of table 'g'"));

  f = failure_of("e2.yaml", "{file: good.csv, x: time}");
  EXPECT_EQ(f.line, 5);
  EXPECT_EQ(f.column, 26);
  EXPECT_TRUE(contains(f.what, "table 'g' has no column 'time' (hint: its columns are t, a)"));

  f = failure_of("e3.yaml", "{file: good.csv, columns: [acc]}");
  EXPECT_EQ(f.column, 33);
  EXPECT_TRUE(contains(f.what, "table 'g' has no column 'acc'"));

  f = failure_of("e4.yaml", "{file: bad_cell.csv}");
  EXPECT_EQ(f.line, 5);
  EXPECT_TRUE(
      contains(f.what, "in table 'g': bad_cell.csv:3:4: 'x2' is not a number (column 'a')"));

  f = failure_of("e5.yaml", "{file: not_increasing.csv}");
  EXPECT_TRUE(contains(f.what,
                       "in table 'g': not_increasing.csv:5: the abscissa 't' is not "
                       "strictly increasing (1 after 1)"));

  f = failure_of("e6.yaml", "{file: one_row.csv}");
  EXPECT_TRUE(contains(f.what, "table 'g' has 1 row; linear interpolation needs at least 2"));

  f = failure_of("e7.yaml", "{file: three_rows.csv, interpolation: cubic}");
  EXPECT_TRUE(contains(f.what, "table 'g' has 3 rows; cubic interpolation needs at least 4"));

  f = failure_of("e8.yaml", "{file: ragged.csv}");
  EXPECT_TRUE(contains(f.what, "ragged.csv:3:1: 1 cells, but the header names 2 columns"));

  f = failure_of("e9.yaml", "{file: good.csv, interpolation: spline}");
  EXPECT_EQ(f.column, 38);
  EXPECT_TRUE(contains(f.what,
                       "interpolation: of table 'g' is 'spline' (hint: one of step, "
                       "linear, cubic)"));

  f = failure_of("e10.yaml", "{data: {t: [0, 1], a: [1, two]}}");
  EXPECT_EQ(f.column, 32);
  EXPECT_TRUE(contains(f.what, "'two' is not a finite number"));

  f = failure_of("e11.yaml", "{file: good.csv, data: {t: [0, 1]}}");
  EXPECT_TRUE(contains(f.what, "table 'g' has both file: and data:"));

  f = failure_of("e13.yaml", "{x: t}");
  EXPECT_TRUE(contains(f.what, "table 'g' has no data: give file: (a CSV file) or data:"));

  // an unknown column where it is called: at the expression
  const std::string path = write("e12.yaml",
                                 "coordinates: [u]\nkinetic_energy: 0.5*u_dot^2\n"
                                 "forces: [g.acc(t)]\ntables:\n  g: {file: good.csv}\n");
  try {
    load_model(path);
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.column(), 10);
    EXPECT_TRUE(contains(e.what(), "unknown table column 'g.acc' (did you mean 'g.a'?)"));
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
