// SPDX-License-Identifier: BSD-3-Clause
// Writers of trajectories: CSV, JSON summary and HDF5 read back against the trajectory written.
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <nlohmann/json.hpp>

#include <ukdyn/control/control.hpp>
#include <ukdyn/io/provenance.hpp>
#include <ukdyn/io/trajectory_files.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Same double, bit for bit (so -0.0 differs from 0.0; NaN payloads must match too).
std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

std::string temp_path(const std::string& name) { return ::testing::TempDir() + "ukdyn_" + name; }

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = line.find(sep, start);
    out.push_back(line.substr(start, end - start));
    if (end == std::string::npos) return out;
    start = end + 1;
  }
}

// Values that a fixed number of decimal digits or a locale would spoil.
const std::vector<double> kHardValues = {
    0.1,
    1.0 / 3.0,
    1e-300,
    -2.5e17,
    2.0 / 3.0,
    5e-324 /* smallest subnormal */,
    -0.0,
    std::numbers::pi,
    1e22,
    -1.7976931348623157e308,
    123456789.123456789,
    std::nextafter(1.0, 2.0),
    0.30000000000000004,
    -7.0,
    4.9406564584124654e-320,
};

// Two coordinates x, y; a holonomic "rod" (1 row) and a nonholonomic "knife" (2 rows), m = 3;
// five samples. The fields take kHardValues first, then ±(k + 0.1) 2⁻ᵏ (all different, so a
// value in the wrong column is caught); one NaN and both infinities among them.
Trajectory hand_made_trajectory() {
  Trajectory tr;
  tr.coordinate_names = {"x", "y"};
  tr.constraint_names = {"rod", "knife"};
  tr.constraint_rows = {1, 2};
  tr.constraint_kinds = {ConstraintKind::kHolonomic, ConstraintKind::kNonholonomic};
  tr.n = 2;
  tr.m = 3;
  const std::size_t N = 5;

  std::size_t k = 0;
  auto fill = [&](std::vector<double>& f, std::size_t width) {
    f.resize(N * width);
    for (double& v : f) {
      v = k < kHardValues.size() ? kHardValues[k]
                                 : (k % 2 ? -1.0 : 1.0) * std::ldexp(double(k) + 0.1, -int(k));
      ++k;
    }
  };
  tr.t = {0.0, 0.05, 0.15, 0.25, 0.35};
  fill(tr.q, 2);
  fill(tr.qd, 2);
  fill(tr.qdd, 2);
  fill(tr.Qc_ideal, 2);
  fill(tr.Qc_nonideal, 2);
  fill(tr.lambda, 3);
  fill(tr.position_violation, 2);
  fill(tr.velocity_violation, 2);
  fill(tr.kinetic_energy, 1);
  fill(tr.potential_energy, 1);
  fill(tr.energy, 1);
  fill(tr.work_nonideal, 1);
  fill(tr.work_ideal, 1);
  fill(tr.work_drive, 1);
  fill(tr.work_external, 1);
  fill(tr.work_control, 1);
  fill(tr.energy_balance_residual, 1);
  tr.energy[2] = kNaN;
  tr.lambda[1 * 3 + 2] = kInf;
  tr.Qc_nonideal[3 * 2 + 0] = -kInf;

  tr.stats.steps = 1234;
  tr.stats.rejected_steps = 56;
  tr.stats.evaluations = 7890;
  tr.stats.projections = 12;
  tr.stats.wall_time = 0.125;
  tr.stats.max_position_violation = 1.0 / 3.0 * 1e-12;
  tr.stats.max_velocity_violation = 2.5e-11;
  tr.stats.energy_drift = 0.1 * 1e-9;
  tr.stats.energy_balance = 0.3 * 1e-9;
  tr.stats.energy_exchanged = 12.75;
  tr.stats.t_reached = 0.35;
  tr.stats.status = Status::kMassNotPositiveDefinite;
  tr.stats.message = "mass matrix not positive definite at t = 0.3";
  return tr;
}

// The value in column `name` of sample i, straight from the documented meaning of each column.
double expected_value(const Trajectory& tr, const std::string& name, std::size_t i) {
  const std::map<std::string, std::function<double(std::size_t)>> by_name = {
      {"t", [&](std::size_t s) { return tr.t[s]; }},
      {"x", [&](std::size_t s) { return tr.q[s * 2 + 0]; }},
      {"y", [&](std::size_t s) { return tr.q[s * 2 + 1]; }},
      {"x_dot", [&](std::size_t s) { return tr.qd[s * 2 + 0]; }},
      {"y_dot", [&](std::size_t s) { return tr.qd[s * 2 + 1]; }},
      {"x_ddot", [&](std::size_t s) { return tr.qdd[s * 2 + 0]; }},
      {"y_ddot", [&](std::size_t s) { return tr.qdd[s * 2 + 1]; }},
      {"Qc_ideal.x", [&](std::size_t s) { return tr.Qc_ideal[s * 2 + 0]; }},
      {"Qc_ideal.y", [&](std::size_t s) { return tr.Qc_ideal[s * 2 + 1]; }},
      {"Qc_nonideal.x", [&](std::size_t s) { return tr.Qc_nonideal[s * 2 + 0]; }},
      {"Qc_nonideal.y", [&](std::size_t s) { return tr.Qc_nonideal[s * 2 + 1]; }},
      {"lambda.rod", [&](std::size_t s) { return tr.lambda[s * 3 + 0]; }},
      {"lambda.knife.0", [&](std::size_t s) { return tr.lambda[s * 3 + 1]; }},
      {"lambda.knife.1", [&](std::size_t s) { return tr.lambda[s * 3 + 2]; }},
      // holonomic: position level; nonholonomic: velocity level
      {"violation.rod", [&](std::size_t s) { return tr.position_violation[s * 2 + 0]; }},
      {"violation.knife", [&](std::size_t s) { return tr.velocity_violation[s * 2 + 1]; }},
      {"violation_velocity.rod", [&](std::size_t s) { return tr.velocity_violation[s * 2 + 0]; }},
      {"kinetic_energy", [&](std::size_t s) { return tr.kinetic_energy[s]; }},
      {"potential_energy", [&](std::size_t s) { return tr.potential_energy[s]; }},
      {"energy", [&](std::size_t s) { return tr.energy[s]; }},
      {"work_nonideal", [&](std::size_t s) { return tr.work_nonideal[s]; }},
      {"work_ideal", [&](std::size_t s) { return tr.work_ideal[s]; }},
      {"work_drive", [&](std::size_t s) { return tr.work_drive[s]; }},
      {"work_external", [&](std::size_t s) { return tr.work_external[s]; }},
      {"work_control", [&](std::size_t s) { return tr.work_control[s]; }},
      {"energy_balance_residual", [&](std::size_t s) { return tr.energy_balance_residual[s]; }},
  };
  return by_name.at(name)(i);
}

const std::vector<std::string> kDocumentedColumns = {
    "t",
    "x",
    "y",
    "x_dot",
    "y_dot",
    "x_ddot",
    "y_ddot",
    "Qc_ideal.x",
    "Qc_ideal.y",
    "Qc_nonideal.x",
    "Qc_nonideal.y",
    "lambda.rod",
    "lambda.knife.0",
    "lambda.knife.1",
    "violation.rod",
    "violation.knife",
    "violation_velocity.rod",
    "kinetic_energy",
    "potential_energy",
    "energy",
    "work_nonideal",
    "work_ideal",
    "work_drive",
    "work_external",
    "work_control",
    "energy_balance_residual",
};

// ---------------------------------------------------------------------------------------------
// CSV

TEST(IoCsv, ColumnsAreTheDocumentedList) {
  EXPECT_EQ(csv_columns(hand_made_trajectory()), kDocumentedColumns);
}

TEST(IoCsv, HeaderLineIsTheColumnList) {
  const std::string path = temp_path("header.csv");
  write_csv(hand_made_trajectory(), path);
  const std::string text = read_text(path);
  const std::string header = text.substr(0, text.find('\n'));
  EXPECT_EQ(split(header, ','), kDocumentedColumns);
}

TEST(IoCsv, ValuesReadBackBitForBitInTheirColumns) {
  const Trajectory tr = hand_made_trajectory();
  std::set<std::uint64_t> distinct;
  std::size_t count = 0;
  for (const auto* f :
       {&tr.q, &tr.qd, &tr.qdd, &tr.Qc_ideal, &tr.Qc_nonideal, &tr.lambda, &tr.position_violation,
        &tr.velocity_violation, &tr.kinetic_energy, &tr.potential_energy, &tr.energy,
        &tr.work_nonideal, &tr.work_ideal, &tr.work_drive, &tr.work_external, &tr.work_control,
        &tr.energy_balance_residual}) {
    for (double v : *f) {
      distinct.insert(bits(v));
      ++count;
    }
  }
  ASSERT_EQ(distinct.size(), count) << "the test needs a different value in every cell";
  const std::string path = temp_path("values.csv");
  write_csv(tr, path);

  std::istringstream in(read_text(path));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = split(line, ',');
  std::size_t sample = 0;
  while (std::getline(in, line)) {
    ASSERT_LT(sample, tr.t.size()) << "more rows than samples";
    const std::vector<std::string> cells = split(line, ',');
    ASSERT_EQ(cells.size(), header.size()) << "row " << sample;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      double read = 0.0;
      const char* first = cells[c].data();
      const char* last = first + cells[c].size();
      const auto [end, ec] = std::from_chars(first, last, read);
      ASSERT_EQ(ec, std::errc()) << "'" << cells[c] << "' in column " << header[c];
      ASSERT_EQ(end, last) << "'" << cells[c] << "' in column " << header[c];
      const double expected = expected_value(tr, header[c], sample);
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(read)) << header[c] << " of sample " << sample;
      } else {
        EXPECT_EQ(bits(read), bits(expected)) << header[c] << " of sample " << sample << ": wrote "
                                              << cells[c] << ", expected " << expected;
      }
    }
    ++sample;
  }
  EXPECT_EQ(sample, tr.t.size());
}

TEST(IoCsv, NanAndInfinitiesAreSpelledOut) {
  Trajectory tr = hand_made_trajectory();
  tr.energy[0] = -kNaN;  // the sign of a NaN is not written
  const std::string path = temp_path("special.csv");
  write_csv(tr, path);
  std::istringstream in(read_text(path));
  std::string line;
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(split(line, ','));
  ASSERT_EQ(rows.size(), 6u);
  const std::size_t energy = 19, lambda_knife_1 = 13, Qc_nonideal_x = 9;
  ASSERT_EQ(rows[0][energy], "energy");
  EXPECT_EQ(rows[1 + 0][energy], "nan");
  EXPECT_EQ(rows[1 + 2][energy], "nan");
  EXPECT_EQ(rows[1 + 1][lambda_knife_1], "inf");
  EXPECT_EQ(rows[1 + 3][Qc_nonideal_x], "-inf");
}

TEST(IoCsv, ShortestFormAndNoLocaleSeparators) {
  Trajectory tr = hand_made_trajectory();
  tr.t = {0.1, 1e-300, -2.5e17, 1234567.0, 0.5};
  const std::string path = temp_path("shortest.csv");
  write_csv(tr, path);
  std::istringstream in(read_text(path));
  std::string line;
  std::vector<std::string> t_column;
  std::getline(in, line);
  while (std::getline(in, line)) t_column.push_back(split(line, ',')[0]);
  EXPECT_EQ(t_column, (std::vector<std::string>{"0.1", "1e-300", "-2.5e+17", "1234567", "0.5"}));
}

TEST(IoCsv, EmptyTrajectoryWritesTheHeaderOnly) {
  Trajectory tr;
  tr.coordinate_names = {"x"};
  tr.n = 1;
  const std::string path = temp_path("empty.csv");
  write_csv(tr, path);
  EXPECT_EQ(read_text(path),
            "t,x,x_dot,x_ddot,Qc_ideal.x,Qc_nonideal.x,kinetic_energy,potential_energy,energy,"
            "work_nonideal,work_ideal,work_drive,work_external,work_control,"
            "energy_balance_residual\n");
}

TEST(IoCsv, NamesWithCommasAreQuoted) {
  Trajectory tr;
  tr.coordinate_names = {"a,b"};
  tr.n = 1;
  const std::string path = temp_path("quoted.csv");
  write_csv(tr, path);
  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "t,\"a,b\",\"a,b_dot\",\"a,b_ddot\",\"Qc_ideal.a,b\",\"Qc_nonideal.a,b\","
            "kinetic_energy,potential_energy,energy,work_nonideal,work_ideal,work_drive,"
            "work_external,work_control,energy_balance_residual");
}

TEST(IoCsv, UnwritablePathThrowsNamingPathAndReason) {
  const std::string path = "/nonexistent/dir/x.csv";
  try {
    write_csv(hand_made_trajectory(), path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
}

TEST(IoCsv, InconsistentTrajectoryThrowsInvalidArgument) {
  Trajectory tr = hand_made_trajectory();
  tr.qd.pop_back();
  try {
    write_csv(tr, temp_path("bad.csv"));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ukdyn::write_csv"), std::string::npos) << what;
    EXPECT_NE(what.find("'qd' has 9 values, expected N × n = 5 × 2"), std::string::npos) << what;
  }
  tr = hand_made_trajectory();
  tr.constraint_rows = {1, 1};
  EXPECT_THROW(csv_columns(tr), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// JSON

TEST(IoJson, SummaryReadsBack) {
  const Trajectory tr = hand_made_trajectory();
  SimulationOptions options;
  options.integrator = Integrator::kBDF;
  options.drift = DriftControl::kBaumgarte;
  options.rtol = 1e-9;
  options.atol = 1.0 / 3.0 * 1e-12;
  options.step = 0.1;
  options.max_step = 0.25;
  options.output_every = 0.1;
  options.t_start = 0.0;
  options.t_end = 0.30000000000000004;
  options.projection.tolerance = 1e-13;
  const std::string path = temp_path("summary.json");
  write_summary_json(tr, options, path);

  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, 5), "{\n  \"") << "pretty-printed with 2 spaces";
  const nlohmann::json j = nlohmann::json::parse(text);

  EXPECT_EQ(j.at("status"), to_string(Status::kMassNotPositiveDefinite));
  EXPECT_EQ(j.at("message"), "mass matrix not positive definite at t = 0.3");
  EXPECT_EQ(j.at("steps"), 1234);
  EXPECT_EQ(j.at("rejected_steps"), 56);
  EXPECT_EQ(j.at("evaluations"), 7890);
  EXPECT_EQ(j.at("projections"), 12);
  EXPECT_EQ(j.at("wall_time").get<double>(), 0.125);
  EXPECT_EQ(bits(j.at("max_position_violation").get<double>()),
            bits(tr.stats.max_position_violation));
  EXPECT_EQ(j.at("max_velocity_violation").get<double>(), 2.5e-11);
  EXPECT_EQ(bits(j.at("energy_drift").get<double>()), bits(tr.stats.energy_drift));
  EXPECT_EQ(bits(j.at("energy_balance").get<double>()), bits(tr.stats.energy_balance));
  EXPECT_EQ(j.at("energy_exchanged").get<double>(), 12.75);
  EXPECT_EQ(j.at("energy_balance_tolerance").get<double>(), options.energy_balance_tolerance);
  EXPECT_EQ(j.at("t_start").get<double>(), 0.0);
  EXPECT_EQ(j.at("t_reached").get<double>(), 0.35);
  EXPECT_EQ(j.at("samples"), 5);

  // the last sample, by coordinate name
  const auto& fs = j.at("final_state");
  EXPECT_EQ(bits(fs.at("q").at("x").get<double>()), bits(tr.q[4 * 2 + 0]));
  EXPECT_EQ(bits(fs.at("q").at("y").get<double>()), bits(tr.q[4 * 2 + 1]));
  EXPECT_EQ(bits(fs.at("q_dot").at("x").get<double>()), bits(tr.qd[4 * 2 + 0]));
  EXPECT_EQ(bits(fs.at("q_dot").at("y").get<double>()), bits(tr.qd[4 * 2 + 1]));
  EXPECT_EQ(j.at("constraints"), (std::vector<std::string>{"rod", "knife"}));

  const auto& o = j.at("options");
  EXPECT_EQ(o.at("integrator"), "bdf");
  EXPECT_EQ(o.at("drift"), "baumgarte");
  EXPECT_EQ(o.at("rtol").get<double>(), 1e-9);
  EXPECT_EQ(bits(o.at("atol").get<double>()), bits(options.atol));
  EXPECT_EQ(o.at("step").get<double>(), 0.1);
  EXPECT_EQ(o.at("max_step").get<double>(), 0.25);
  EXPECT_EQ(o.at("output_every").get<double>(), 0.1);
  EXPECT_EQ(o.at("t_start").get<double>(), 0.0);
  EXPECT_EQ(o.at("t_end").get<double>(), 0.30000000000000004);
  EXPECT_EQ(o.at("projection_tolerance").get<double>(), 1e-13);
}

TEST(IoJson, NonFiniteStatisticsAreNull) {
  Trajectory tr = hand_made_trajectory();
  tr.stats.energy_drift = kNaN;
  tr.stats.max_velocity_violation = kInf;
  const std::string path = temp_path("nan.json");
  write_summary_json(tr, {}, path);
  const nlohmann::json j = nlohmann::json::parse(read_text(path));
  EXPECT_TRUE(j.at("energy_drift").is_null());
  EXPECT_TRUE(j.at("max_velocity_violation").is_null());
  EXPECT_EQ(j.at("options").at("integrator"), "dopri5");
  EXPECT_EQ(j.at("options").at("drift"), "projection");
}

TEST(IoJson, NoSamplesGivesNullStartAndState) {
  Trajectory tr;
  tr.coordinate_names = {"x"};
  tr.n = 1;
  const std::string path = temp_path("nosamples.json");
  write_summary_json(tr, {}, path);
  const nlohmann::json j = nlohmann::json::parse(read_text(path));
  EXPECT_EQ(j.at("samples"), 0);
  EXPECT_TRUE(j.at("t_start").is_null());
  EXPECT_TRUE(j.at("final_state").is_null());
}

TEST(IoJson, UnwritablePathThrowsNamingPathAndReason) {
  const std::string path = "/nonexistent/dir/x.json";
  try {
    write_summary_json(hand_made_trajectory(), {}, path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
}

// ---------------------------------------------------------------------------------------------
// HDF5

void expect_same_bits(const std::vector<double>& read, const std::vector<double>& written,
                      const char* name) {
  ASSERT_EQ(read.size(), written.size()) << name;
  for (std::size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(bits(read[i]), bits(written[i])) << name << "[" << i << "]";
  }
}

TEST(IoHdf5, FieldsReadBackBitForBit) {
  const Trajectory tr = hand_made_trajectory();
  const std::string path = temp_path("traj.h5");
  write_hdf5(tr, path);
  expect_same_bits(read_hdf5_field(path, "t"), tr.t, "t");
  expect_same_bits(read_hdf5_field(path, "q"), tr.q, "q");
  expect_same_bits(read_hdf5_field(path, "q_dot"), tr.qd, "q_dot");
  expect_same_bits(read_hdf5_field(path, "q_ddot"), tr.qdd, "q_ddot");
  expect_same_bits(read_hdf5_field(path, "Qc_ideal"), tr.Qc_ideal, "Qc_ideal");
  expect_same_bits(read_hdf5_field(path, "Qc_nonideal"), tr.Qc_nonideal, "Qc_nonideal");
  expect_same_bits(read_hdf5_field(path, "lambda"), tr.lambda, "lambda");
  expect_same_bits(read_hdf5_field(path, "position_violation"), tr.position_violation,
                   "position_violation");
  expect_same_bits(read_hdf5_field(path, "velocity_violation"), tr.velocity_violation,
                   "velocity_violation");
  expect_same_bits(read_hdf5_field(path, "kinetic_energy"), tr.kinetic_energy, "kinetic_energy");
  expect_same_bits(read_hdf5_field(path, "potential_energy"), tr.potential_energy,
                   "potential_energy");
  expect_same_bits(read_hdf5_field(path, "energy"), tr.energy, "energy");  // holds the NaN
  expect_same_bits(read_hdf5_field(path, "work_nonideal"), tr.work_nonideal, "work_nonideal");
  expect_same_bits(read_hdf5_field(path, "work_drive"), tr.work_drive, "work_drive");
  expect_same_bits(read_hdf5_field(path, "energy_balance_residual"), tr.energy_balance_residual,
                   "energy_balance_residual");
}

TEST(IoHdf5, LongRunSpansSeveralChunks) {
  // 2500 samples: more than two chunks of 1024
  Trajectory tr;
  tr.coordinate_names = {"x", "y"};
  tr.constraint_names = {"rod"};
  tr.constraint_rows = {1};
  tr.constraint_kinds = {ConstraintKind::kHolonomic};
  tr.n = 2;
  tr.m = 1;
  const std::size_t N = 2500;
  for (std::size_t i = 0; i < N; ++i) tr.t.push_back(double(i) / 3.0);
  for (std::size_t i = 0; i < 2 * N; ++i) tr.q.push_back(std::sin(double(i)) * 1e-3);
  tr.qd = tr.qdd = tr.Qc_ideal = tr.Qc_nonideal = tr.q;
  tr.lambda = tr.position_violation = tr.velocity_violation = tr.t;
  tr.kinetic_energy = tr.potential_energy = tr.energy = tr.work_nonideal = tr.t;
  tr.work_ideal = tr.work_drive = tr.work_external = tr.work_control = tr.t;
  tr.energy_balance_residual = tr.t;
  const std::string path = temp_path("long.h5");
  write_hdf5(tr, path);
  expect_same_bits(read_hdf5_field(path, "t"), tr.t, "t");
  expect_same_bits(read_hdf5_field(path, "q"), tr.q, "q");
}

TEST(IoHdf5, EmptyFieldsReadBackEmpty) {
  Trajectory tr;
  tr.coordinate_names = {"x"};
  tr.n = 1;
  const std::string path = temp_path("empty.h5");
  write_hdf5(tr, path);
  EXPECT_TRUE(read_hdf5_field(path, "t").empty());
  EXPECT_TRUE(read_hdf5_field(path, "q").empty());
  EXPECT_TRUE(read_hdf5_field(path, "lambda").empty());
}

TEST(IoHdf5, UnwritablePathThrowsNamingPath) {
  const std::string path = "/nonexistent/dir/x.h5";
  try {
    write_hdf5(hand_made_trajectory(), path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(IoHdf5, MissingFileOrDatasetThrowsNamingThem) {
  const std::string missing = temp_path("does_not_exist.h5");
  try {
    read_hdf5_field(missing, "t");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }

  const std::string path = temp_path("for_missing_dataset.h5");
  write_hdf5(hand_made_trajectory(), path);
  try {
    read_hdf5_field(path, "no_such_field");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("'no_such_field'"), std::string::npos) << what;
  }
}

// ---- provenance (issue #16 item 4): SHA-256, version, summary.json's provenance -----------

TEST(Provenance, Sha256MatchesTheStandardVectors) {
  // FIPS 180-4's examples, and lengths around the padding's block boundary (55, 56, 64, 119
  // bytes), checked against Python's hashlib
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(55, 'a')),
            "9f4390f8d30c2dd92ec9f095b65e2b9ae9b0a925a5258e241c9f1e910f734318");
  EXPECT_EQ(sha256_hex(std::string(56, 'a')),
            "b35439a4ac6f0948b6d6f9e3c6af0f5f590ce20f1bde7090ef7970686ec6738a");
  EXPECT_EQ(sha256_hex(std::string(64, 'a')),
            "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb");
  EXPECT_EQ(sha256_hex(std::string(119, 'a')),
            "31eba51c313a5c08226adf18d4a359cfdfd8d2e816b13f4af952f7ea6584dcfb");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Provenance, SummaryRecordsTheModelItsParametersAndTheBuild) {
  const Trajectory tr = hand_made_trajectory();
  RunProvenance p;
  p.model_name = "two masses";
  p.model_file = "/models/two.yaml";
  p.model_sha256 = sha256_hex("text");
  p.parameters = {{"k", 100.0, false}, {"m", 0.1, true}};
  p.arguments = {"ukdyn", "run", "/models/two.yaml", "--set", "m=0.1"};
  ControlStatistics c;
  c.evaluations = 40;
  c.not_met = 2;
  c.first_not_met = 0.25;
  c.max_kappa = 3.5;
  const auto j = nlohmann::json::parse(summary_json(tr, SimulationOptions{}, &p, &c));
  const auto& made = j.at("provenance");
  EXPECT_EQ(made.at("ukdyn_version"), std::string(version()));
  EXPECT_EQ(std::string(version()), "0.1.0");
  EXPECT_FALSE(std::string(commit()).empty());
  EXPECT_EQ(made.at("model_name"), "two masses");
  EXPECT_EQ(made.at("model_file"), "/models/two.yaml");
  EXPECT_TRUE(made.at("example").is_null());
  EXPECT_EQ(made.at("model_sha256"), sha256_hex("text"));
  EXPECT_EQ(made.at("parameters").at("k"), 100.0);
  EXPECT_EQ(made.at("parameters").at("m"), 0.1);
  EXPECT_EQ(made.at("overridden"), nlohmann::json::array({"m"}));
  EXPECT_EQ(made.at("arguments").size(), 5u);
  EXPECT_EQ(j.at("control").at("evaluations"), 40);
  EXPECT_EQ(j.at("control").at("not_met"), 2);
  EXPECT_EQ(j.at("control").at("first_not_met"), 0.25);
  EXPECT_EQ(j.at("control").at("max_kappa"), 3.5);
  // without provenance: the build only, and no control
  const auto plain = nlohmann::json::parse(summary_json(tr, SimulationOptions{}));
  EXPECT_EQ(plain.at("provenance").size(), 2u);
  EXPECT_FALSE(plain.contains("control"));
}

TEST(IoHdf5, TableRoundTripsBitwiseWithTheSummaryAsAttributes) {
  const Trajectory tr = hand_made_trajectory();
  std::vector<CsvColumn> columns = csv_table(tr);
  const std::size_t N = tr.t.size();
  // further columns as a run adds them: hard values, a '/' in a name, a name met twice
  CsvColumn hard{"out.hard", {}}, slash{"a/b", {}}, twice{"t", {}};
  for (std::size_t i = 0; i < N; ++i) {
    hard.values.push_back(kHardValues[i % kHardValues.size()]);
    slash.values.push_back(-0.0);
    twice.values.push_back(kNaN);
  }
  columns.push_back(hard);
  columns.push_back(slash);
  columns.push_back(twice);
  const std::string summary = summary_json(tr, SimulationOptions{});
  const std::string path = temp_path("table.h5");
  write_table_hdf5(path, columns, summary);

  const std::vector<CsvColumn> back = read_table_hdf5(path);
  ASSERT_EQ(back.size(), columns.size());
  for (std::size_t c = 0; c < columns.size(); ++c) {
    ASSERT_EQ(back[c].values.size(), N) << columns[c].name;
    for (std::size_t i = 0; i < N; ++i) {
      EXPECT_EQ(bits(back[c].values[i]), bits(columns[c].values[i]))
          << columns[c].name << " sample " << i;
    }
  }
  EXPECT_EQ(back[columns.size() - 2].name, "a|b");
  EXPECT_EQ(back.back().name, "t#2");
  EXPECT_EQ(read_hdf5_string_attribute(path, "summary"), summary);
  EXPECT_EQ(read_hdf5_string_attribute(path, "status"), "mass matrix not positive definite");
  EXPECT_EQ(read_hdf5_field(path, "t").size(), N);

  // columns of different lengths, and a summary that is not a JSON object, are refused
  columns.back().values.pop_back();
  EXPECT_THROW(write_table_hdf5(temp_path("bad.h5"), columns, summary), std::invalid_argument);
  columns.back().values.push_back(0.0);
  EXPECT_THROW(write_table_hdf5(temp_path("bad.h5"), columns, "[1, 2]"), std::invalid_argument);
  EXPECT_THROW(read_table_hdf5(temp_path("no_such.h5")), std::runtime_error);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
