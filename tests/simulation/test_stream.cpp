// SPDX-License-Identifier: BSD-3-Clause
// Bounded memory and streamed output (issue #14, item 3; docs/simulation.md, "Sample grid and
// streaming"):
//  1. SimulationOptions::sample_sink receives every sample, bit for bit the sample that the
//     in-memory Trajectory holds, with the same statistics (energy balance, violations) computed
//     as the samples go, while the returned Trajectory stays empty;
//  2. the sample grid, computed on demand, has exactly the times of the former sorted vector;
//  3. a grid above the documented bounds is refused before anything is integrated, naming
//     output_every, t_end, the count and the bound;
//  4. `ukdyn run` streams trajectory.csv while it runs, and refuses a huge grid at once.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include <ukdyn/control/control.hpp>
#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "../src/simulation/sample_grid.hpp"
#include "support/cli_process.hpp"

extern char** environ;

namespace ukdyn {
namespace UKDYN_TEST_FILE {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// the sample fields of a trajectory, in one list
std::vector<const std::vector<double>*> fields(const Trajectory& t) {
  return {&t.t,
          &t.q,
          &t.qd,
          &t.qdd,
          &t.Qc_ideal,
          &t.Qc_nonideal,
          &t.lambda,
          &t.position_violation,
          &t.velocity_violation,
          &t.kinetic_energy,
          &t.potential_energy,
          &t.energy,
          &t.work_nonideal,
          &t.work_ideal,
          &t.work_drive,
          &t.work_external,
          &t.work_control,
          &t.energy_balance_residual};
}

// appends the samples of `from` to `to` (a sink that keeps them)
void append(Trajectory& to, const Trajectory& from) {
  auto dst = fields(to), src = fields(from);
  for (std::size_t f = 0; f < dst.size(); ++f) {
    auto* d = const_cast<std::vector<double>*>(dst[f]);
    d->insert(d->end(), src[f]->begin(), src[f]->end());
  }
}

// a sink's sample kept: the names with the first, then the values appended
void keep(Trajectory& received, const Trajectory& one) {
  if (received.coordinate_names.empty()) {
    received.coordinate_names = one.coordinate_names;
    received.constraint_names = one.constraint_names;
    received.constraint_rows = one.constraint_rows;
    received.constraint_kinds = one.constraint_kinds;
    received.n = one.n;
    received.m = one.m;
  }
  append(received, one);
}

// bit for bit (NaN equal to NaN)
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_samples(const Trajectory& a, const Trajectory& b) {
  auto fa = fields(a), fb = fields(b);
  for (std::size_t f = 0; f < fa.size(); ++f) {
    ASSERT_EQ(fa[f]->size(), fb[f]->size()) << "field " << f;
    for (std::size_t i = 0; i < fa[f]->size(); ++i) {
      ASSERT_TRUE(same_bits((*fa[f])[i], (*fb[f])[i]))
          << "field " << f << " value " << i << ": " << (*fa[f])[i] << " vs " << (*fb[f])[i];
    }
  }
}

struct SinkCase {
  const char* example;
  Integrator integrator;
  double t_end;
};
void PrintTo(const SinkCase& c, std::ostream* os) {
  *os << c.example << "_" << to_string(c.integrator);
}

class SampleSink : public ::testing::TestWithParam<SinkCase> {};

TEST_P(SampleSink, ReceivesTheInMemorySamplesBitForBitAndTheRunKeepsNone) {
  const SinkCase c = GetParam();
  const gallery::Example ex = gallery::make(c.example);
  SimulationOptions o;
  o.t_end = c.t_end;
  o.integrator = c.integrator;
  o.output_at = {0.123456, 0.5 + 1e-13};  // irregular times, one within rounding of the grid
  const Trajectory memory = simulate(ex.system, ex.q0, ex.qd0, o);
  ASSERT_GT(memory.samples(), 10);

  Trajectory received;
  long calls = 0;
  o.sample_sink = [&](const Trajectory& one) {
    ++calls;
    EXPECT_EQ(one.samples(), 1);
    one.check_consistent("sink");
    keep(received, one);
  };
  const Trajectory streamed = simulate(ex.system, ex.q0, ex.qd0, o);

  // nothing kept: the memory of the run does not depend on its samples
  EXPECT_EQ(streamed.samples(), 0);
  for (const auto* f : fields(streamed)) EXPECT_TRUE(f->empty());
  EXPECT_EQ(streamed.coordinate_names, memory.coordinate_names);
  // every sample received, as the in-memory run has it
  EXPECT_EQ(calls, memory.samples());
  EXPECT_EQ(streamed.stats.samples, memory.samples());
  EXPECT_EQ(memory.stats.samples, memory.samples());
  expect_same_samples(received, memory);
  // the statistics computed as the samples went: the same numbers
  const RunStatistics &s = streamed.stats, &m = memory.stats;
  EXPECT_EQ(s.status, m.status);
  EXPECT_EQ(s.steps, m.steps);
  EXPECT_TRUE(same_bits(s.t_reached, m.t_reached));
  EXPECT_TRUE(same_bits(s.energy_balance, m.energy_balance));
  EXPECT_TRUE(same_bits(s.energy_exchanged, m.energy_exchanged));
  EXPECT_TRUE(same_bits(s.energy_drift, m.energy_drift));
  EXPECT_EQ(s.energy_balance_checked, m.energy_balance_checked);
  EXPECT_TRUE(same_bits(s.max_position_violation, m.max_position_violation));
  EXPECT_TRUE(same_bits(s.max_velocity_violation, m.max_velocity_violation));
}

INSTANTIATE_TEST_SUITE_P(Stream, SampleSink,
                         ::testing::Values(SinkCase{"pendulum", Integrator::kDopri5, 3.0},
                                           SinkCase{"pendulum", Integrator::kRK4, 2.0},
                                           SinkCase{"pendulum", Integrator::kBDF, 2.0},
                                           SinkCase{"bead_on_rotating_wire", Integrator::kRKF78,
                                                    1.0},
                                           SinkCase{"block_on_incline", Integrator::kDopri5, 2.0}),
                         [](const auto& p) {
                           return std::string(p.param.example) + "_" +
                                  to_string(p.param.integrator);
                         });

TEST(SampleSink, AnInterruptedStreamedRunEndsWithTheSampleAtTReached) {
  const gallery::Example ex = gallery::pendulum();
  SimulationOptions o;
  o.t_end = 100.0;
  long asked = 0;
  o.should_stop = [&] { return ++asked >= 200; };
  std::vector<double> times;
  o.sample_sink = [&](const Trajectory& one) { times.push_back(one.t[0]); };
  const Trajectory tr = simulate(ex.system, ex.q0, ex.qd0, o);
  EXPECT_EQ(tr.stats.status, Status::kInterrupted);
  ASSERT_GE(times.size(), 2u);
  EXPECT_EQ(long(times.size()), tr.stats.samples);
  EXPECT_DOUBLE_EQ(times.back(), tr.stats.t_reached);
  EXPECT_LT(tr.stats.t_reached, 100.0);
  for (std::size_t i = 1; i < times.size(); ++i) ASSERT_LT(times[i - 1], times[i]);
}

TEST(SampleSink, AnExceptionFromTheSinkStopsTheRunAndPropagates) {
  const gallery::Example ex = gallery::pendulum();
  SimulationOptions o;
  o.t_end = 100.0;
  long calls = 0;
  o.sample_sink = [&](const Trajectory&) {
    if (++calls == 50) throw std::runtime_error("disk full (test)");
  };
  EXPECT_THROW(
      {
        try {
          simulate(ex.system, ex.q0, ex.qd0, o);
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "disk full (test)");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_EQ(calls, 50);  // not called again after it threw
}

// ---- controlled runs: streamed as the plant's and the control's values ------------------------

// every column of a run, by name (the standard ones and the extra ones)
std::vector<CsvColumn> all_columns(const ModelRun& run) { return run.columns(); }

class ControlledStream : public ::testing::TestWithParam<const char*> {};

TEST_P(ControlledStream, ChunksHoldTheInMemoryColumnsBitForBitAndTheRunKeepsOneSample) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + GetParam() + ".yaml");
  ASSERT_TRUE(model.controller);
  SimulationOptions o = model.options;
  o.t_end = std::min(o.t_end, o.t_start + 2.0);
  o.output_at = {o.t_start + 0.123456};
  const ModelRun memory = run_model(model, o);
  ASSERT_TRUE(memory.controlled);
  const auto expected = all_columns(memory);
  ASSERT_GT(memory.trajectory.samples(), 20);

  // in chunks of 7 samples: the same columns, in the same order, bit for bit
  std::vector<CsvColumn> got;
  long chunks = 0;
  const ModelRun streamed = run_model(
      model, o,
      [&](const ModelRun& chunk) {
        ++chunks;
        EXPECT_LE(chunk.trajectory.samples(), 7);
        chunk.trajectory.check_consistent("chunk");
        const auto cols = chunk.columns();
        if (got.empty()) {
          got = cols;
          return;
        }
        ASSERT_EQ(cols.size(), got.size());
        for (std::size_t c = 0; c < cols.size(); ++c) {
          ASSERT_EQ(cols[c].name, got[c].name);
          ASSERT_EQ(cols[c].values.size(), std::size_t(chunk.trajectory.samples()));
          got[c].values.insert(got[c].values.end(), cols[c].values.begin(), cols[c].values.end());
        }
      },
      7);
  EXPECT_EQ(chunks, (memory.trajectory.samples() + 6) / 7);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t c = 0; c < got.size(); ++c) {
    EXPECT_EQ(got[c].name, expected[c].name);
    ASSERT_EQ(got[c].values.size(), expected[c].values.size()) << got[c].name;
    for (std::size_t i = 0; i < got[c].values.size(); ++i) {
      ASSERT_TRUE(same_bits(got[c].values[i], expected[c].values[i]))
          << got[c].name << " sample " << i;
    }
  }
  // the result: the statistics of the whole run, the last sample with its columns
  EXPECT_TRUE(streamed.controlled);
  EXPECT_EQ(streamed.trajectory.samples(), 1);
  EXPECT_EQ(streamed.trajectory.stats.samples, memory.trajectory.samples());
  EXPECT_EQ(streamed.trajectory.stats.status, memory.trajectory.stats.status);
  EXPECT_TRUE(
      same_bits(streamed.trajectory.stats.energy_drift, memory.trajectory.stats.energy_drift));
  EXPECT_EQ(streamed.control.not_met, memory.control.not_met);
  const auto last = all_columns(streamed);
  ASSERT_EQ(last.size(), expected.size());
  for (std::size_t c = 0; c < last.size(); ++c) {
    ASSERT_EQ(last[c].values.size(), 1u) << last[c].name;
    EXPECT_TRUE(same_bits(last[c].values[0], expected[c].values.back())) << last[c].name;
  }
}

INSTANTIATE_TEST_SUITE_P(Stream, ControlledStream,
                         ::testing::Values("control_uncertain_duffing", "control_triple_pendulum",
                                           "control_spacecraft"),
                         [](const auto& p) { return std::string(p.param); });

TEST(ControlledStream, TheSinkOfTheOptionsReceivesThePlantAndTheRunKeepsNone) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
  SimulationOptions o = model.options;
  o.t_end = o.t_start + 3.0;
  const ControlledTrajectory memory =
      simulate_controlled(*model.controller, model.system, model.q0, model.qd0, o);
  Trajectory received;
  o.sample_sink = [&](const Trajectory& one) {
    EXPECT_EQ(one.samples(), 1);
    one.check_consistent("sink");
    keep(received, one);
  };
  const ControlledTrajectory streamed =
      simulate_controlled(*model.controller, model.system, model.q0, model.qd0, o);
  EXPECT_EQ(streamed.samples(), 0);
  EXPECT_TRUE(streamed.error.empty());
  EXPECT_EQ(streamed.plant.stats.samples, memory.samples());
  expect_same_samples(received, memory.plant);
  EXPECT_TRUE(same_bits(streamed.plant.stats.energy_balance, memory.plant.stats.energy_balance));
  // and the control's work is in the balance: the residual stays at the integration's error
  // (the control does work: without it the residual would be of the size of the work)
  double work = 0.0, residual = 0.0;
  for (std::size_t i = 0; i < received.t.size(); ++i) {
    work = std::max(work, std::abs(received.work_control[i]));
    residual = std::max(residual, std::abs(received.energy_balance_residual[i]));
  }
  EXPECT_GT(work, 0.1);
  EXPECT_LT(residual, 1e-6 * work);
}

TEST(ControlledStream, AnInterruptedControlledRunEndsWithTheSampleAtTReached) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
  SimulationOptions o = model.options;
  o.t_end = 1000.0;
  long asked = 0;
  o.should_stop = [&] { return ++asked >= 300; };
  std::vector<double> times;
  const ModelRun run = run_model(
      model, o,
      [&](const ModelRun& chunk) {
        times.insert(times.end(), chunk.trajectory.t.begin(), chunk.trajectory.t.end());
      },
      16);
  EXPECT_EQ(run.trajectory.stats.status, Status::kInterrupted);
  ASSERT_GE(times.size(), 2u);
  EXPECT_EQ(long(times.size()), run.trajectory.stats.samples);
  EXPECT_DOUBLE_EQ(times.back(), run.trajectory.stats.t_reached);
  EXPECT_DOUBLE_EQ(run.trajectory.t.at(0), times.back());
  EXPECT_LT(run.trajectory.stats.t_reached, 1000.0);
}

TEST(ControlledStream, AGridAboveTheMemoryBoundIsRefusedUnlessStreamed) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
  SimulationOptions o = model.options;
  o.t_end = 1e6;
  o.output_every = 1e-2;  // 10⁸ samples: above the bound in memory (about 10⁷), not streamed
  try {
    simulate_controlled(*model.controller, model.system, model.q0, model.qd0, o);
    ADD_FAILURE() << "no refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("controlled run kept in memory"), std::string::npos)
        << e.what();
  }
  // streamed, the same grid starts (stopped at once)
  o.should_stop = [] { return true; };
  long calls = 0;
  const ControlledTrajectory r =
      simulate_controlled(*model.controller, model.system, model.q0, model.qd0, o,
                          [&](const ControlledTrajectory& one) {
                            ++calls;
                            EXPECT_EQ(one.samples(), 1);
                          });
  EXPECT_EQ(r.plant.stats.status, Status::kInterrupted);
  EXPECT_GE(calls, 1);
  EXPECT_EQ(calls, r.plant.stats.samples);
}

// the former sample_times(): every time in one vector, sorted, near-duplicates dropped
std::vector<double> reference_times(const SimulationOptions& o) {
  std::vector<double> v = o.output_at;
  v.push_back(o.t_start);
  v.push_back(o.t_end);
  if (o.output_every > 0.0) {
    const long count = long(std::floor((o.t_end - o.t_start) / o.output_every * (1 + 1e-12)));
    for (long i = 1; i <= count; ++i) v.push_back(o.t_start + double(i) * o.output_every);
  }
  const double a = o.t_start, b = o.t_end;
  v.erase(std::remove_if(v.begin(), v.end(),
                         [&](double t) { return !(t >= a && t <= b) || !std::isfinite(t); }),
          v.end());
  std::sort(v.begin(), v.end());
  const double eps = 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
  std::vector<double> out;
  for (double t : v) {
    if (out.empty() || t - out.back() > eps) out.push_back(t);
  }
  return out;
}

TEST(SampleGrid, HasTheTimesOfTheSortedVectorBitForBit) {
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    SimulationOptions o;
    o.t_start = trial % 3 == 0 ? 0.0 : (unit(rng) - 0.5) * std::pow(10.0, double(trial % 7));
    o.t_end = o.t_start + std::pow(10.0, 2.0 * unit(rng) - 1.0);
    o.output_every = trial % 11 == 0 ? 0.0 : (o.t_end - o.t_start) / (1.0 + 300.0 * unit(rng));
    // output_at: random times, times on and within rounding of grid points, outside, duplicates
    const int extra = trial % 6;
    for (int k = 0; k < extra; ++k) {
      const double u = unit(rng);
      const long i = long(u * 50);
      const double on_grid = o.t_start + double(i) * o.output_every;
      const double eps = 1e-12 * std::max({1.0, std::abs(o.t_start), std::abs(o.t_end)});
      switch (k % 5) {
        case 0:
          o.output_at.push_back(o.t_start + u * (o.t_end - o.t_start));
          break;
        case 1:
          o.output_at.push_back(on_grid);
          break;
        case 2:
          o.output_at.push_back(on_grid - 0.5 * eps);
          break;
        case 3:
          o.output_at.push_back(on_grid + 0.7 * eps);
          break;
        case 4:
          o.output_at.push_back(o.t_end + 1.0);
          break;
      }
      if (k == 3) o.output_at.push_back(o.output_at.back());
    }
    const std::vector<double> expected = reference_times(o);
    const detail::SampleGrid grid(o, kMaxStreamedSamples, "(test)");
    ASSERT_EQ(grid.size(), expected.size()) << "trial " << trial;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      ASSERT_TRUE(same_bits(grid[i], expected[i])) << "trial " << trial << " sample " << i;
      ASSERT_EQ(grid.upper_bound(expected[i]), i + 1) << "trial " << trial;
    }
    ++cases;
  }
  EXPECT_EQ(cases, 400);
}

TEST(SampleGrid, TenToTheNineSamplesTakeNoMemory) {
  // 10^9 − 1 regular times, computed on demand: the last is t_end within rounding
  SimulationOptions o;
  o.t_end = 1.0;
  o.output_every = 1.0 / (kMaxStreamedSamples - 2.0);
  const detail::SampleGrid grid(o, kMaxStreamedSamples, "(test)");
  EXPECT_GE(double(grid.size()), kMaxStreamedSamples - 2.0);
  EXPECT_LE(double(grid.size()), kMaxStreamedSamples);
  EXPECT_EQ(grid[0], 0.0);
  EXPECT_NEAR(grid[grid.size() - 1], 1.0, 1e-12);
  EXPECT_NEAR(grid[grid.size() / 2], 0.5, 1e-8);
}

// the message of the std::invalid_argument that simulate() throws, or "" if it does not
std::string refusal(const SimulationOptions& o) {
  const gallery::Example ex = gallery::pendulum();
  try {
    simulate(ex.system, ex.q0, ex.qd0, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

void expect_names(const std::string& message, const std::vector<std::string>& parts) {
  for (const auto& p : parts) {
    EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
  }
}

TEST(SampleGrid, AGridAboveTheBoundIsRefusedBeforeIntegratingNamingTheCountAndTheBound) {
  long steps = 0;
  auto counting = [&](SimulationOptions o) {
    o.progress = [&](const ProgressReport&) { ++steps; };
    return o;
  };
  auto sink = [](const Trajectory&) {};

  // t_end 1e300: the count overflows a long; refused (streamed or not)
  SimulationOptions huge;
  huge.t_end = 1e300;
  expect_names(refusal(counting(huge)),
               {"ukdyn::simulate: the output grid (output_every = 0.01, t_start = 0, "
                "t_end = 1e+300) has 1e+302 samples, more than the bound of ",
                "kMaxStoredValues", "output_every", "t_end"});
  huge.sample_sink = sink;
  expect_names(refusal(counting(huge)),
               {"has 1e+302 samples, more than the bound of 1000000000 of a streamed run "
                "(kMaxStreamedSamples)"});

  // t_end 1e9 with the default spacing: 10^11 samples
  SimulationOptions long_run;
  long_run.t_end = 1e9;
  long_run.sample_sink = sink;
  expect_names(refusal(counting(long_run)),
               {"t_end = 1e+09", "has 100000000002 samples, more than the bound of 1000000000"});

  // every 1e-9 on a 1 s run: 10^9 + 2 (t_start and t_end with the regular times)
  SimulationOptions tiny;
  tiny.output_every = 1e-9;
  tiny.sample_sink = sink;
  expect_names(refusal(counting(tiny)),
               {"output_every = 1e-09, t_start = 0, t_end = 1) has 1000000002 samples, more "
                "than the bound of 1000000000"});

  // in memory the bound is 2^28 values: the pendulum stores 1 + 5·2 + 1 + 2·1 + 9 = 23 per
  // sample, so 11671106 samples at most; 10^8 are refused, 10^7 + 1 are not (not run here)
  SimulationOptions stored;
  stored.t_end = 1e6;
  expect_names(refusal(counting(stored)),
               {"has 100000002 samples, more than the bound of 11671106 of a run kept in "
                "memory (kMaxStoredValues = 2^28 values, 23 per sample"});

  // a spacing below the resolution of t
  SimulationOptions fine;
  fine.t_start = 1e6;
  fine.t_end = 1e6 + 1e-3;
  fine.output_every = 1e-9;
  expect_names(refusal(counting(fine)),
               {"output_every = 1e-09 is below the resolution of the sample times"});
  EXPECT_EQ(steps, 0);  // nothing was integrated
}

// --- the command --------------------------------------------------------------------------

fs::path scratch(const std::string& name) { return test::scratch_directory("ukdyn_stream_", name); }

using test::Command;
using test::read_text;

// the rows of a CSV (after the header); each must be complete (ends with a newline, same width)
std::vector<std::vector<double>> csv_rows(const fs::path& path, std::vector<std::string>& header) {
  const std::string text = read_text(path);
  EXPECT_FALSE(text.empty());
  if (text.empty()) return {};
  EXPECT_EQ(text.back(), '\n');
  std::stringstream in(text);
  std::string line;
  std::getline(in, line);
  header.clear();
  {
    std::stringstream h(line);
    for (std::string f; std::getline(h, f, ',');) header.push_back(f);
  }
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream r(line);
    for (std::string f; std::getline(r, f, ',');) row.push_back(std::strtod(f.c_str(), nullptr));
    EXPECT_EQ(row.size(), header.size()) << "row " << rows.size() + 1;
    rows.push_back(std::move(row));
  }
  return rows;
}

const std::string kStreamModel = std::string(UKDYN_TEST_DATA_DIR) + "/stream_pendulum.yaml";

TEST(Cli, RunStreamsTheCsvWhileItRunsAndAnInterruptLeavesRowsMatchingTheSummary) {
  const fs::path dir = scratch("interrupt"), out = dir / "out";
  Command run({"run", kStreamModel, "-o", out.string(), "--no-plots"}, dir / "stdout.txt");
  // the CSV's temporary appears and grows while the run goes (rows written before the end:
  // the first chunk of 4096 rows is 1.5 MB, 41 s of the model's time; the deadline only bounds
  // a broken run, and is far above the sanitizer build's few seconds on a loaded machine)
  std::uintmax_t seen = 0;
  const auto deadline = Clock::now() + std::chrono::seconds(600);
  while (seen < 300000 && Clock::now() < deadline) {
    if (fs::exists(out)) {
      for (const auto& e : fs::directory_iterator(out)) {
        if (e.path().filename().string().rfind(".trajectory.csv.tmp-", 0) == 0) {
          std::error_code ec;
          seen = std::max(seen, fs::file_size(e.path(), ec));
        }
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(seen, 300000u) << "no streamed rows before the end of the run";
  EXPECT_FALSE(fs::exists(out / "trajectory.csv"));  // not under its final name yet
  ASSERT_EQ(::kill(run.pid(), SIGINT), 0);
  EXPECT_EQ(run.wait(), 128 + SIGINT) << run.stderr_text();

  // a complete CSV, renamed, with as many rows as the summary's samples, the last at t_reached
  const nlohmann::json summary = nlohmann::json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(summary["status"], "interrupted");
  std::vector<std::string> header;
  const auto rows = csv_rows(out / "trajectory.csv", header);
  ASSERT_GE(rows.size(), 1000u);  // 300 kB of rows were out before the signal
  EXPECT_EQ(long(rows.size()), summary["samples"].get<long>());
  EXPECT_EQ(summary["t_start"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(rows.back()[0], summary["t_reached"].get<double>());
  const std::size_t x = std::size_t(std::find(header.begin(), header.end(), "x") - header.begin());
  EXPECT_DOUBLE_EQ(summary["final_state"]["q"]["x"].get<double>(), rows.back()[x]);
  // every 0.01 s; the last at the end of the step where the signal was seen (docs/simulation.md)
  for (std::size_t i = 1; i + 1 < rows.size(); ++i) {
    ASSERT_NEAR(rows[i][0] - rows[i - 1][0], 0.01, 1e-9) << "row " << i;
  }
  EXPECT_GT(rows.back()[0], rows[rows.size() - 2][0]);
  EXPECT_LE(rows.back()[0] - rows[rows.size() - 2][0], 0.01 + 1e-9);
  const std::string out_text = read_text(dir / "stdout.txt");
  EXPECT_NE(out_text.find("  " + std::to_string(rows.size()) + " samples to t = "),
            std::string::npos)
      << out_text;
}

TEST(Cli, AGridAboveTheBoundIsRefusedAtOnceNamingTheOption) {
  const fs::path dir = scratch("refused");
  // every 1e-9 on a 1 s run (reliability report, D7): refused when the model is read, before
  // the run, exit 3, at output: every's value (line 7, column 17), without "ukdyn::simulate:";
  // `ukdyn check` refuses it the same way
  for (const char* command : {"run", "check"}) {
    std::vector<std::string> args = {command,
                                     std::string(UKDYN_TEST_DATA_DIR) + "/stream_every_tiny.yaml"};
    if (std::string(command) == "run") {
      for (const char* a : {"-o", "", "--no-plots"}) args.emplace_back(a);
      args[3] = (dir / "tiny").string();
    }
    Command run(args, dir / (std::string(command) + "_tiny.txt"));
    EXPECT_EQ(run.wait(), 3) << command << ": " << run.stderr_text();
    expect_names(run.stderr_text(),
                 {"stream_every_tiny.yaml:7:17: error: the output grid (output_every = "
                  "1e-09, t_start = 0, t_end = 1) has 1000000002 samples, more than the bound of "
                  "1000000000 of a streamed run",
                  "output: every:"});
    EXPECT_EQ(run.stderr_text().find("ukdyn::"), std::string::npos) << run.stderr_text();
    EXPECT_FALSE(fs::exists(dir / "tiny" / "trajectory.csv"));
  }
  // --t-end 1e300 (the count overflowed, D7): the flag's fault, exit 2, naming it
  {
    Command run({"run", "--example", "pendulum", "--t-end", "1e300", "-o", (dir / "huge").string(),
                 "--no-plots"},
                dir / "huge.txt");
    EXPECT_EQ(run.wait(), 2) << run.stderr_text();
    expect_names(run.stderr_text(),
                 {"error: --t-end 1e300: the output grid (output_every = 0.01, t_start = 0, "
                  "t_end = 1e+300) has 1e+302 samples"});
    EXPECT_EQ(run.stderr_text().find("ukdyn::"), std::string::npos) << run.stderr_text();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
