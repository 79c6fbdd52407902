// SPDX-License-Identifier: BSD-3-Clause
// Ensembles (simulation/ensemble.hpp): sweeps checked against closed forms (a block's stopping
// distance over mu, a small pendulum's motion over L), every result bitwise the same on 1, 2 and 4
// threads and the same as one run_model of the model read with the sample's overrides, failing
// and refused samples recorded without stopping the others, cancellation keeping the finished
// samples, and the table's files. CI runs this program under ThreadSanitizer too (.ci/run).
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/ensemble.hpp>
#include <ukdyn/simulation/sampling.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

EnsembleModel model_of(const std::string& path) {
  EnsembleModel m;
  m.text = read_text(path);
  m.file = path;
  return m;
}

const std::string kBlock = std::string(UKDYN_EXAMPLES_DIR) + "/block_slide_stick.yaml";
const std::string kPendulum = std::string(UKDYN_TEST_DATA_DIR) + "/ensemble_pendulum.yaml";

// every number of two results, bitwise (the wall time aside)
void expect_same(const EnsembleResult& a, const EnsembleResult& b) {
  ASSERT_EQ(a.samples.size(), b.samples.size());
  EXPECT_EQ(a.recorded, b.recorded);
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    SCOPED_TRACE("sample " + std::to_string(i));
    const SampleResult &x = a.samples[i], &y = b.samples[i];
    EXPECT_EQ(x.outcome, y.outcome);
    EXPECT_EQ(x.stats.status, y.stats.status);
    EXPECT_EQ(x.stats.steps, y.stats.steps);
    EXPECT_EQ(x.stats.evaluations, y.stats.evaluations);
    EXPECT_EQ(x.stats.t_reached, y.stats.t_reached);
    EXPECT_EQ(x.stats.energy_balance, y.stats.energy_balance);
    EXPECT_EQ(x.stats.max_position_violation, y.stats.max_position_violation);
    EXPECT_EQ(x.message, y.message);
    ASSERT_EQ(x.values.size(), y.values.size());
    for (std::size_t k = 0; k < x.values.size(); ++k) {
      // NaN where a time was not reached: the same in both
      if (std::isnan(x.values[k])) {
        EXPECT_TRUE(std::isnan(y.values[k]));
      } else {
        EXPECT_EQ(x.values[k], y.values[k]) << a.recorded[k % a.recorded.size()];
      }
    }
  }
}

std::size_t column(const EnsembleResult& r, const std::string& name) {
  for (std::size_t j = 0; j < r.recorded.size(); ++j) {
    if (r.recorded[j] == name) return j;
  }
  ADD_FAILURE() << "no column " << name;
  return 0;
}

TEST(Ensemble, StoppingDistanceOverMu) {
  // a block launched at v0 down a slope alpha stops after s = v0² / (2 g (mu cos a − sin a))
  // when mu > tan(alpha) (block_slide_stick.yaml: v0 = 2, alpha = 0.3, g = 9.81), and sticks
  const EnsembleModel m = model_of(kBlock);
  std::vector<EnsembleSample> samples;
  for (double mu : {0.5, 0.6, 0.7, 0.9}) samples.push_back({{{"mu", mu}}, {}, {}});
  EnsembleOptions o;
  o.threads = 2;
  const EnsembleResult r = run_ensemble(m, samples, o);
  ASSERT_EQ(r.samples.size(), 4u);
  EXPECT_TRUE(r.at.empty());
  const std::size_t s = column(r, "s"), v = column(r, "v");
  for (std::size_t i = 0; i < 4; ++i) {
    const double mu = samples[i].parameters.at("mu");
    const SampleResult& x = r.samples[i];
    ASSERT_TRUE(x.ok()) << x.message;
    const double expected = 4.0 / (2 * 9.81 * (mu * std::cos(0.3) - std::sin(0.3)));
    EXPECT_NEAR(x.values[s], expected, 1e-7 * expected) << "mu = " << mu;
    EXPECT_NEAR(x.values[v], 0.0, 1e-9);
    EXPECT_EQ(x.stats.t_reached, 2.0);
  }
  EXPECT_EQ(r.failed(), 0u);
}

TEST(Ensemble, SmallPendulumOverLengthAtRequestedTimes) {
  // theta(t) = theta0 cos(sqrt(g/L) t) to O(theta0³): with theta0 = 0.01 the period is longer by
  // theta0²/16, a phase error of omega t theta0²/16
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples;
  for (double L : {0.5, 1.0, 2.0}) samples.push_back({{{"L", L}}, {}, {}});
  EnsembleOptions o;
  o.threads = 2;
  o.at = {0.3, 0.7};
  const EnsembleResult r = run_ensemble(m, samples, o);
  const std::size_t theta = column(r, "theta"), n_rec = r.recorded.size();
  for (std::size_t i = 0; i < 3; ++i) {
    const double L = samples[i].parameters.at("L"), w = std::sqrt(9.81 / L);
    ASSERT_TRUE(r.samples[i].ok()) << r.samples[i].message;
    for (std::size_t k = 0; k < 2; ++k) {
      const double t = o.at[k], theta0 = 0.01;
      const double tol = 1.5 * theta0 * theta0 * theta0 * (w * t / 16 + 0.01);
      EXPECT_NEAR(r.samples[i].values[k * n_rec + theta], theta0 * std::cos(w * t), tol)
          << "L = " << L << ", t = " << t;
      // x = L sin(theta)
      EXPECT_NEAR(r.samples[i].values[k * n_rec + column(r, "x")],
                  L * std::sin(r.samples[i].values[k * n_rec + theta]), 1e-9 * L);
    }
  }
}

TEST(Ensemble, SamplesAreBitwiseTheSameOnAnyNumberOfThreads) {
  // parameters (the model read again), initial states (the model shared) and options, mixed
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples;
  for (int i = 0; i < 9; ++i) {
    EnsembleSample s;
    if (i % 3 != 1) s.parameters["L"] = 0.5 + 0.25 * i;
    if (i % 3 == 1) {
      // a velocity along the circle at theta0 = 0.01: x x' + y y' = 0
      s.initial["x_dot"] = 0.01 * i;
      s.initial["y_dot"] = 0.01 * i * std::tan(0.01);
    }
    if (i % 4 == 0) s.settings["rtol"] = 1e-8;
    samples.push_back(s);
  }
  EnsembleOptions o;
  o.at = {0.25, 0.5};
  o.threads = 1;
  const EnsembleResult one = run_ensemble(m, samples, o);
  o.threads = 2;
  const EnsembleResult two = run_ensemble(m, samples, o);
  o.threads = 4;
  const EnsembleResult four = run_ensemble(m, samples, o);
  expect_same(one, two);
  expect_same(one, four);
  for (const auto& s : one.samples) EXPECT_TRUE(s.ok()) << s.message;

  // and each sample is the run of the model read with its overrides, with `at` as output_at
  for (std::size_t i : {std::size_t(0), std::size_t(3)}) {
    const Model model = parse_model(m.text, m.file, samples[i].parameters);
    SimulationOptions so = model.options;
    for (const auto& kv : samples[i].settings) set_option(so, kv.first, kv.second);
    so.output_at = o.at;
    const ModelRun run = run_model(model, so);
    EXPECT_EQ(run.trajectory.stats.steps, one.samples[i].stats.steps);
    const auto cols = run.columns();
    for (std::size_t k = 0; k < 2; ++k) {
      std::size_t row = 0;
      while (run.trajectory.t[row] != o.at[k]) ++row;
      for (const auto& c : cols) {
        if (c.name == "theta") {
          EXPECT_EQ(c.values[row],
                    one.samples[i].values[k * one.recorded.size() + column(one, "theta")]);
        }
      }
    }
  }
}

TEST(Ensemble, FailingSamplesAreRecordedAndTheOthersRun) {
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples(5);
  samples[1].parameters["L"] = 0.0;      // the constraint's 1/(2L): the model cannot be read
  samples[2].settings["max_steps"] = 3;  // the integrator gives up
  samples[3].settings["t_end"] = 0.1;    // `at` beyond the run: refused by the run's settings
  EnsembleOptions o;
  o.threads = 2;
  o.at = {0.5};
  std::vector<EnsembleProgress> seen;
  o.progress = [&](const EnsembleProgress& p) { seen.push_back(p); };
  const EnsembleResult r = run_ensemble(m, samples, o);
  EXPECT_TRUE(r.samples[0].ok());
  EXPECT_TRUE(r.samples[4].ok());
  EXPECT_EQ(r.samples[1].outcome, SampleOutcome::kRefused);
  EXPECT_NE(r.samples[1].message.find("ensemble_pendulum.yaml"), std::string::npos)
      << r.samples[1].message;
  EXPECT_EQ(r.samples[2].outcome, SampleOutcome::kRun);
  EXPECT_EQ(r.samples[2].stats.status, Status::kIntegratorFailure);
  EXPECT_NE(r.samples[2].message.find("max_steps"), std::string::npos) << r.samples[2].message;
  EXPECT_TRUE(std::isnan(r.samples[2].values[0]));  // t = 0.5 not reached
  EXPECT_EQ(r.samples[3].outcome, SampleOutcome::kRefused);
  EXPECT_NE(r.samples[3].message.find("output_at"), std::string::npos) << r.samples[3].message;
  EXPECT_EQ(r.failed(), 3u);
  EXPECT_EQ(r.ok(), 2u);
  EXPECT_EQ(r.interrupted_samples() + r.not_run(), 0u);
  // one progress report per sample, the last one complete
  ASSERT_EQ(seen.size(), 5u);
  EXPECT_EQ(seen.back().done, 5u);
  EXPECT_EQ(seen.back().failed, 3u);
  EXPECT_EQ(seen.back().total, 5u);

  const EnsembleTable t = ensemble_table(r, samples);
  EXPECT_EQ(t.status[1], "refused");
  EXPECT_EQ(t.status[2], "integrator failure");
  EXPECT_EQ(t.numbers[0].name, "sample");
  EXPECT_EQ(t.numbers[1].name, "L");
  EXPECT_TRUE(std::isnan(t.numbers[1].values[0]));
  EXPECT_EQ(t.numbers[1].values[1], 0.0);
}

TEST(Ensemble, StopKeepsTheFinishedSamples) {
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples;
  for (int i = 0; i < 6; ++i) samples.push_back({{{"L", 1.0 + 0.1 * i}}, {}, {}});
  EnsembleOptions o;
  o.threads = 1;
  o.at = {0.5};
  const EnsembleResult all = run_ensemble(m, samples, o);

  // stopped between samples: after two
  std::atomic<std::size_t> done{0};
  o.progress = [&](const EnsembleProgress& p) { done = p.done; };
  o.should_stop = [&] { return done.load() >= 2; };
  const EnsembleResult part = run_ensemble(m, samples, o);
  EXPECT_TRUE(part.interrupted);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(part.samples[i].ok());
    EXPECT_EQ(part.samples[i].values, all.samples[i].values);
  }
  for (std::size_t i = 2; i < 6; ++i) {
    EXPECT_EQ(part.samples[i].outcome, SampleOutcome::kNotRun);
    EXPECT_EQ(ensemble_table(part, samples).status[i], "not run");
  }
  // (repro u14/11: the samples never started counted as failed)
  EXPECT_EQ(part.ok(), 2u);
  EXPECT_EQ(part.failed(), 0u);
  EXPECT_EQ(part.interrupted_samples(), 0u);
  EXPECT_EQ(part.not_run(), 4u);

  // stopped inside a run: that run ends interrupted, with its samples up to there
  std::atomic<long> asked{0};
  o.progress = nullptr;
  o.should_stop = [&] { return ++asked > 40; };
  const EnsembleResult inside = run_ensemble(m, samples, o);
  EXPECT_TRUE(inside.interrupted);
  EXPECT_EQ(inside.samples[0].outcome, SampleOutcome::kRun);
  EXPECT_EQ(inside.samples[0].stats.status, Status::kInterrupted);
  EXPECT_LT(inside.samples[0].stats.t_reached, 1.0);
  EXPECT_EQ(inside.samples[5].outcome, SampleOutcome::kNotRun);
  // one interrupted, five not run, none failed
  EXPECT_EQ(inside.ok(), 0u);
  EXPECT_EQ(inside.failed(), 0u);
  EXPECT_EQ(inside.interrupted_samples(), 1u);
  EXPECT_EQ(inside.not_run(), 5u);
}

// A progress callback that throws (reproducers 2026-11-28, cpp_ensemble_progress_throws.cpp:
// std::terminate from a worker thread): the exception comes out of run_ensemble, on one thread
// and on several, and the ensemble stops — fewer callbacks than samples.
TEST(Ensemble, AProgressCallbackThatThrowsPropagatesOutOfRunEnsemble) {
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples;
  for (int i = 0; i < 40; ++i) samples.push_back({{{"L", 1.0 + 0.01 * i}}, {}, {}});
  for (const unsigned threads : {1u, 2u, 4u}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    EnsembleOptions o;
    o.threads = threads;
    std::atomic<std::size_t> calls{0};
    o.progress = [&](const EnsembleProgress& p) {
      ++calls;
      if (p.done == 10) throw std::runtime_error("progress failed");
    };
    try {
      run_ensemble(m, samples, o);
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "progress failed");
    }
    // the 10th sample threw; the samples under way on the other threads may still end
    EXPECT_GE(calls.load(), 10u);
    EXPECT_LE(calls.load(), 10u + threads - 1);
  }
  // an exception that is not a std::exception leaves no worker either
  EnsembleOptions o;
  o.threads = 2;
  o.progress = [](const EnsembleProgress&) { throw 42; };
  EXPECT_THROW(run_ensemble(m, samples, o), int);
}

TEST(Ensemble, MisuseNamesTheSampleAndTheName) {
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples(2);
  samples[1].parameters["mu"] = 1;
  try {
    run_ensemble(m, samples, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "ukdyn::run_ensemble: sample 1: the model has no parameter 'mu' (its "
                 "parameters are L, g, m, theta0)");
  }
  EnsembleOptions o;
  o.outputs = {"no_such_column"};
  try {
    run_ensemble(m, std::vector<EnsembleSample>(3), o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "the output 'no_such_column' is not a column of the model's trajectory.csv"),
              std::string::npos)
        << e.what();
  }
  // a design's names resolve to parameters, initial values and options
  const Model model = parse_model(m.text, m.file);
  DesignTable d{{"L", "x_dot", "rtol"}, {{1.0, 0.1, 1e-8}}};
  const auto s = samples_of_design(model, d);
  EXPECT_EQ(s[0].parameters.at("L"), 1.0);
  EXPECT_EQ(s[0].initial.at("x_dot"), 0.1);
  EXPECT_EQ(s[0].settings.at("rtol"), 1e-8);
  d.names[0] = "Lx";
  EXPECT_THROW(samples_of_design(model, d), std::invalid_argument);
}

TEST(Ensemble, ABodysCoordinatesAreSetByEitherSpelling) {
  // a planar body thrown under gravity (the bodies format: its coordinates are ball.x, ball.y,
  // ball.theta; ball_x … in expressions): a sample sets x'(0) and y'(0) as ball.x_dot or as
  // ball_x_dot, and y(T) = vy T − g T²/2, x(T) = vx T (closed form) either way; a grid of the
  // command line's form names the dotted coordinate
  EnsembleModel m;
  m.file = "ball.yaml";
  m.text = R"(
parameters: {g: 9.81}
bodies:
  - {name: ball, type: planar, mass: 1, inertia: 0.1, position: [0, 0], angle: 0}
forces:
  - {type: gravity, g: [0, -g]}
simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
)";
  std::vector<EnsembleSample> samples(2);
  samples[0].initial = {{"ball.x_dot", 1.5}, {"ball.y_dot", 2.0}};
  samples[1].initial = {{"ball_x_dot", 1.5}, {"ball_y_dot", 2.0}};
  const EnsembleResult r = run_ensemble(m, samples, {});
  const std::size_t x = column(r, "ball.x"), y = column(r, "ball.y");
  for (const SampleResult& s : r.samples) {
    ASSERT_TRUE(s.ok()) << s.message;
    EXPECT_NEAR(s.values[x], 1.5 * 0.5, 1e-10);
    EXPECT_NEAR(s.values[y], 2.0 * 0.5 - 9.81 * 0.25 / 2, 1e-10);
  }
  EXPECT_EQ(r.samples[0].values, r.samples[1].values);
  // both spellings of one coordinate in one sample: refused, naming both
  samples[0].initial["ball_x_dot"] = 1.0;
  try {
    run_ensemble(m, samples, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'ball.x_dot' and 'ball_x_dot' set the same coordinate"),
              std::string::npos)
        << e.what();
  }
  // --grid ball.x_dot=0:1:3, as `ukdyn sweep` reads it
  const GridAxis axis = parse_grid_axis("ball.x_dot=0:1:3");
  EXPECT_EQ(axis.name, "ball.x_dot");
  EXPECT_THROW(parse_grid_axis("ball..x=0:1:3"), std::invalid_argument);
  EXPECT_THROW(parse_grid_axis("ball.=0:1:3"), std::invalid_argument);
  const Model model = parse_model(m.text, m.file);
  const auto s = samples_of_design(model, DesignTable{{"ball_y_dot"}, {{3.0}}});
  EXPECT_EQ(s[0].initial.at("ball_y_dot"), 3.0);
}

TEST(Ensemble, TableFilesHoldEveryRow) {
  const EnsembleModel m = model_of(kPendulum);
  std::vector<EnsembleSample> samples;
  for (double L : {1.0, 2.0}) samples.push_back({{{"L", L}}, {}, {}});
  EnsembleOptions o;
  o.at = {0.5};
  o.keep_trajectories = true;
  const EnsembleResult r = run_ensemble(m, samples, o);
  ASSERT_FALSE(r.samples[0].trajectory.empty());
  EXPECT_EQ(r.samples[0].trajectory[0].name, "t");
  EXPECT_EQ(r.samples[0].trajectory[0].values.size(), 101u);  // every 0.01 s to 1 s
  const EnsembleTable t = ensemble_table(r, samples);
  const auto dir = std::filesystem::temp_directory_path() / "ukdyn_test_ensemble";
  std::filesystem::create_directories(dir);
  write_ensemble_csv(t, (dir / "ensemble.csv").string());
  std::ifstream in(dir / "ensemble.csv");
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header.rfind("sample,L,status_code,ok,steps,", 0), 0u) << header;
  EXPECT_NE(header.find(",theta@0.5,status,message"), std::string::npos) << header;
  EXPECT_EQ(row.rfind("0,1,0,1,", 0), 0u) << row;
  EXPECT_EQ(row.substr(row.size() - 4), ",ok,");
  write_ensemble_hdf5(t, (dir / "ensemble.h5").string(), R"({"model": "pendulum"})");
  const auto back = read_table_hdf5((dir / "ensemble.h5").string());
  ASSERT_EQ(back.size(), t.numbers.size());
  EXPECT_EQ(back.back().values, t.numbers.back().values);
  const std::string summary = read_hdf5_string_attribute((dir / "ensemble.h5").string(), "summary");
  EXPECT_NE(summary.find("\"status\": ["), std::string::npos) << summary;
  std::filesystem::remove_all(dir);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
