// SPDX-License-Identifier: BSD-3-Clause
// Run settings (issue #14, items 4 and 5): a setting a run cannot use is refused up front, naming
// it (check_settings, SettingError; located in model files); max_steps holds for every method;
// the energy drift of a run in which nothing moves is its roundoff; and adaptive steps that
// leave the model's domain are retried smaller instead of ending the run.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/oscillator.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using test::oscillator;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

VectorXd one(double v) { return VectorXd::Constant(1, v); }

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// simulate's SettingError for these options on the unit oscillator: its setting and message
struct Refusal {
  std::string setting, message;
};
Refusal refusal(const SimulationOptions& o) {
  try {
    simulate(oscillator(), one(1.0), one(0.0), o);
  } catch (const SettingError& e) {
    return {e.setting(), e.what()};
  }
  ADD_FAILURE() << "the settings were accepted";
  return {};
}

// the ModelError of a model text
ModelError model_error(const std::string& text) {
  try {
    parse_model(text, "settings.yaml");
  } catch (const ModelError& e) {
    return e;
  }
  ADD_FAILURE() << "the model was accepted:\n" << text;
  return ModelError("", 0, 0, "");
}

const std::string kOscillator =
    "coordinates: [x]\n"
    "kinetic_energy: 0.5*x_dot^2\n"
    "potential_energy: 0.5*x^2\n"
    "initial: {q: {x: 1}}\n";

// --- t_end -----------------------------------------------------------------------------------

TEST(RunSettings, InfiniteOrNanEndIsRefusedNamingTEnd) {
  for (double t_end : {kInf, kNaN, -kInf}) {
    SimulationOptions o;
    o.t_end = t_end;
    const Refusal r = refusal(o);
    EXPECT_EQ(r.setting, "t_end") << r.message;
    EXPECT_TRUE(contains(r.message, "t_end")) << r.message;
  }
  SimulationOptions o;
  o.t_end = kInf;
  EXPECT_TRUE(contains(refusal(o).message, "must be a finite number")) << refusal(o).message;
}

TEST(RunSettings, EndBelowTheResolutionOfTimeIsRefusedWithTheRule) {
  SimulationOptions o;
  o.t_end = 1e-300;  // gave 0 samples and status ok
  const Refusal r = refusal(o);
  EXPECT_EQ(r.setting, "t_end");
  EXPECT_TRUE(contains(r.message,
                       "must exceed t_start (0) by more than 1e-12 max(1, |t_start|, "
                       "|t_end|) = 1e-12"))
      << r.message;
  // just above the resolution: runs, two samples (t_start and t_end)
  o.t_end = 2e-12;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 2);
  EXPECT_EQ(tr.t[1], 2e-12);
  EXPECT_NEAR(tr.q[1], std::cos(2e-12), 1e-15);
}

// --- fixed steps -----------------------------------------------------------------------------

TEST(RunSettings, FixedStepBelowTheResolutionOfTimeIsRefused) {
  for (Integrator method : {Integrator::kRK4, Integrator::kRK5}) {
    for (double step : {1e-300, 1e-20}) {  // 1e-300: was 1 step over the whole run, status ok
      SimulationOptions o;
      o.integrator = method;
      o.step = step;
      o.max_steps = std::numeric_limits<long>::max();  // (the resolution, not the count)
      const Refusal r = refusal(o);
      EXPECT_EQ(r.setting, "step") << r.message;
      EXPECT_TRUE(contains(r.message, "below the resolution of t on [0, 1]")) << r.message;
    }
  }
}

TEST(RunSettings, AdaptiveMaxStepThatMaxStepsCannotReachIsRefused) {
  // max_step = 1e-300 over [0, 1] asks for at least 1e300 steps (the Python fuzzer's hang);
  // 1e-9 asks for 1e9 > max_steps = 10^7; below the resolution of t, a step cannot advance t
  for (Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SimulationOptions o;
    o.integrator = method;
    o.max_step = 1e-9;
    Refusal r = refusal(o);
    EXPECT_EQ(r.setting, "max_step") << r.message;
    EXPECT_TRUE(contains(r.message,
                         "needs at least 1e+09 steps over [0, 1], more than "
                         "max_steps = 10000000"))
        << r.message;
    EXPECT_TRUE(contains(r.message, "--max-steps")) << r.message;
    o.max_step = 1e-300;
    o.max_steps = std::numeric_limits<long>::max();  // (the resolution, not the count)
    r = refusal(o);
    EXPECT_EQ(r.setting, "max_step") << r.message;
    EXPECT_TRUE(contains(r.message, "below the resolution of t on [0, 1]")) << r.message;
  }
  // a max_step that max_steps allows: accepted, and the run takes at least 1 / max_step steps
  SimulationOptions o;
  o.integrator = Integrator::kDopri5;
  o.max_step = 1e-2;
  o.max_steps = 1000;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(tr.t.back(), 1.0, 1e-12);
  EXPECT_GE(tr.stats.steps, 100);
  EXPECT_LE(tr.stats.steps, 1000);
}

TEST(RunSettings, FixedStepCountAboveMaxStepsIsRefusedWithHowToRaiseIt) {
  for (Integrator method : {Integrator::kRK4, Integrator::kRK5}) {
    SimulationOptions o;
    o.integrator = method;
    o.step = 1e-8;  // 10⁸ steps: ran for 52 s, ignoring max_steps
    const Refusal r = refusal(o);
    EXPECT_EQ(r.setting, "step") << r.message;
    EXPECT_TRUE(contains(r.message,
                         "takes 1e+08 steps over [0, 1], more than max_steps = "
                         "10000000"))
        << r.message;
    EXPECT_TRUE(contains(r.message, "simulate: max_steps")) << r.message;
    EXPECT_TRUE(contains(r.message, "--max-steps")) << r.message;
  }
  // exactly max_steps steps: runs them
  SimulationOptions o;
  o.integrator = Integrator::kRK4;
  o.step = 1e-2;
  o.max_steps = 100;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.steps, 100);
  o.max_steps = 99;
  EXPECT_EQ(refusal(o).setting, "step");
}

TEST(RunSettings, FixedStepCountSumsTheSegmentsBetweenBreakpoints) {
  // step 0.4: ⌈1 / 0.4⌉ = 3 steps over [0, 1], but ⌈0.5 / 0.4⌉ = 2 in each of [0, 0.5], [0.5, 1]
  SimulationOptions o;
  o.integrator = Integrator::kRK4;
  o.step = 0.4;
  o.breakpoints = {0.5};
  o.energy_balance_tolerance = kInf;  // (so coarse a step does not hold the balance to 1e-6)
  o.output_every = 0.0;
  o.max_steps = 3;
  EXPECT_EQ(refusal(o).setting, "step");
  o.max_steps = 4;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.steps, 4);
}

TEST(RunSettings, FixedStepSamplesCloserThanTheStepAreRefused) {
  for (Integrator method : {Integrator::kRK4, Integrator::kRK5}) {
    SimulationOptions o;
    o.integrator = method;
    o.step = 0.02;
    o.output_every = 0.01;
    const Refusal r = refusal(o);
    EXPECT_EQ(r.setting, "output_every") << r.message;
    EXPECT_TRUE(contains(r.message, "output_every (0.01) is below the step (0.02) of " +
                                        std::string(to_string(method))))
        << r.message;
    // equal: runs, a sample at every step
    o.output_every = 0.02;
    const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
    EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.samples(), 51);
    EXPECT_NEAR(tr.q.back(), std::cos(1.0), 1e-7);
  }
  // in a model file: at output: every
  const ModelError e = model_error(kOscillator + "simulate: {integrator: rk4, step: 0.1}\n" +
                                   "output: {every: 0.01}\n");
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.column(), 17);
  EXPECT_TRUE(contains(e.message(), "is below the step (0.1) of rk4")) << e.message();
}

// --- other settings ------------------------------------------------------------------------

TEST(RunSettings, OutputTimesOutsideTheRunOrNanAreRefused) {
  for (double t : {100.0, -0.5, kNaN}) {
    SimulationOptions o;
    o.output_at = {0.5, t};
    const Refusal r = refusal(o);
    EXPECT_EQ(r.setting, "output_at") << r.message;
    EXPECT_TRUE(contains(r.message, "(entry 1) is outside the run [0, 1]")) << r.message;
  }
}

TEST(RunSettings, NanOptionsAreRefusedUpFrontNamingThem) {
  auto with = [](auto set) {
    SimulationOptions o;
    set(o);
    return refusal(o);
  };
  EXPECT_EQ(with([](SimulationOptions& o) { o.baumgarte_alpha = kNaN; }).setting,
            "baumgarte_alpha");
  EXPECT_EQ(with([](SimulationOptions& o) { o.baumgarte_beta = kInf; }).setting, "baumgarte_beta");
  EXPECT_EQ(with([](SimulationOptions& o) { o.step = kNaN; }).setting, "step");
  EXPECT_EQ(with([](SimulationOptions& o) { o.rtol = kNaN; }).setting, "rtol");
  EXPECT_EQ(with([](SimulationOptions& o) { o.atol = kInf; }).setting, "atol");
  EXPECT_EQ(with([](SimulationOptions& o) { o.output_every = kInf; }).setting, "output_every");
  EXPECT_EQ(with([](SimulationOptions& o) { o.max_step = kNaN; }).setting, "max_step");
  EXPECT_EQ(with([](SimulationOptions& o) { o.initial_tolerance = kNaN; }).setting,
            "initial_tolerance");
  EXPECT_EQ(with([](SimulationOptions& o) { o.projection.tolerance = kNaN; }).setting,
            "projection_tolerance");
  EXPECT_EQ(with([](SimulationOptions& o) { o.max_steps = 0; }).setting, "max_steps");
  const Refusal r = with([](SimulationOptions& o) { o.baumgarte_alpha = kNaN; });
  EXPECT_TRUE(contains(r.message, "baumgarte_alpha must be a finite number >= 0, got nan"))
      << r.message;
}

TEST(RunSettings, RtolBelowRoundoffIsRaisedWithANote) {
  SimulationOptions o;
  o.rtol = 1e-30;
  o.atol = 1e-30;
  o.t_end = 0.5;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_FALSE(tr.stats.notes.empty());
  EXPECT_TRUE(contains(tr.stats.notes[0],
                       "rtol = 1e-30 is below the roundoff of double: the run "
                       "uses rtol = 2.22e-14"))
      << tr.stats.notes[0];
  // the same steps as a run at kMinimumRtol itself, and the exact solution cos t
  o.rtol = kMinimumRtol;
  const Trajectory ref = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.steps, ref.stats.steps);
  EXPECT_TRUE(ref.stats.notes.empty());
  EXPECT_NEAR(tr.q.back(), std::cos(0.5), 1e-12);
}

// --- max_steps -----------------------------------------------------------------------------

TEST(RunSettings, MaxStepsStopsAdaptiveRunsAndSaysHowToRaiseIt) {
  for (Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SimulationOptions o;
    o.integrator = method;
    o.t_end = 100.0;
    o.max_steps = 40;
    const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
    EXPECT_EQ(tr.stats.status, Status::kIntegratorFailure) << to_string(method);
    EXPECT_LE(tr.stats.steps, 40) << to_string(method);
    EXPECT_GE(tr.stats.steps, 39) << to_string(method);
    EXPECT_TRUE(contains(tr.stats.message, "max_steps = 40")) << tr.stats.message;
    EXPECT_TRUE(contains(tr.stats.message, "simulate: max_steps in a model file"))
        << tr.stats.message;
    EXPECT_GT(tr.stats.t_reached, 0.0);
    EXPECT_LT(tr.stats.t_reached, 100.0);
  }
}

TEST(RunSettings, MaxStepsCountsTheWholeRunAcrossSegments) {
  // ten segments (breakpoints at 1, 2, …, 9) of ~5 steps each: a limit of 30 stops the run
  // in the middle, where a per-segment limit never would
  SimulationOptions o;
  o.t_end = 10.0;
  for (int k = 1; k < 10; ++k) o.breakpoints.push_back(k);
  const Trajectory full = simulate(oscillator(), one(1.0), one(0.0), o);
  ASSERT_EQ(full.stats.status, Status::kOk);
  ASSERT_GT(full.stats.steps, 40);
  o.max_steps = 30;
  const Trajectory tr = simulate(oscillator(), one(1.0), one(0.0), o);
  EXPECT_EQ(tr.stats.status, Status::kIntegratorFailure) << tr.stats.message;
  EXPECT_EQ(tr.stats.steps, 30);
  EXPECT_TRUE(contains(tr.stats.message, "max_steps = 30")) << tr.stats.message;
}

TEST(RunSettings, MaxStepsFromAModelFileIsHonouredByRk4AndDopri5) {
  // the reproducer's key, accepted
  const Model big = parse_model(
      "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\n"
      "simulate: {t_end: 1, max_steps: 100000000}\n");
  EXPECT_EQ(big.options.max_steps, 100000000);
  // dopri5 stops at the model's limit
  const Model m = parse_model(kOscillator + "simulate: {t_end: 100, max_steps: 25}\n");
  EXPECT_EQ(m.options.max_steps, 25);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kIntegratorFailure);
  EXPECT_EQ(tr.stats.steps, 25);
  // rk4: 1000 steps against a limit of 999 is refused where the file gives the step
  const ModelError e = model_error(
      kOscillator + "simulate: {t_end: 1, integrator: rk4, step: 1e-3, max_steps: 999}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 45);  // at step's value
  EXPECT_TRUE(contains(e.message(), "takes 1e+03 steps over [0, 1], more than max_steps = 999"))
      << e.message();
  const Model ok = parse_model(
      kOscillator + "simulate: {t_end: 1, integrator: rk4, step: 1e-3, max_steps: 1000}\n");
  const Trajectory t4 = simulate(ok.system, ok.q0, ok.qd0, ok.options);
  EXPECT_EQ(t4.stats.status, Status::kOk);
  EXPECT_EQ(t4.stats.steps, 1000);
  // not a whole positive number
  for (const char* bad : {"0", "-5", "2.5"}) {
    const ModelError b =
        model_error(kOscillator + "simulate: {t_end: 1, max_steps: " + bad + "}\n");
    EXPECT_EQ(b.line(), 5);
    EXPECT_EQ(b.column(), 33);
    EXPECT_TRUE(contains(b.message(), "max_steps must be a whole number")) << b.message();
  }
}

TEST(RunSettings, ModelFileSettingsAreLocated) {
  // t_end below the resolution, at its value
  ModelError e = model_error(kOscillator + "simulate: {t_end: 1e-300}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 19);
  EXPECT_TRUE(contains(e.message(), "t_end (1e-300) must exceed t_start")) << e.message();
  // rk4 step below the resolution of t
  e = model_error(kOscillator + "simulate: {t_end: 1, integrator: rk4, step: 1e-300}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 45);
  EXPECT_TRUE(contains(e.message(), "below the resolution of t")) << e.message();
  // the default step of rk4 over a long run: at the simulate: mapping
  e = model_error(kOscillator + "simulate: {t_end: 100000, integrator: rk4}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 11);
  EXPECT_TRUE(contains(e.message(), "takes 1e+08 steps")) << e.message();
}

TEST(RunSettings, ModelFileSampleGridIsRefusedWhenReadAtOutputEvery) {
  // the grid `ukdyn run` would refuse (a streamed run: more than 1e9 samples) is refused when
  // the model is read (so `ukdyn check` refuses it too), at output: every's value, without the
  // C++ function's name
  ModelError e = model_error(kOscillator + "output: {every: 1e-9}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 17);
  EXPECT_EQ(e.message().rfind("the output grid (output_every = 1e-09, t_start = 0, t_end = 1) "
                              "has 1000000002 samples, more than the bound of 1000000000 of a "
                              "streamed run",
                              0),
            0u)
      << e.message();
  EXPECT_TRUE(contains(e.what(), "settings.yaml:5:17: error: the output grid")) << e.what();
  // the same key under simulate:
  e = model_error(kOscillator + "simulate:\n  t_end: 2\n  output_every: 1e-9\n");
  EXPECT_EQ(e.line(), 7);
  EXPECT_EQ(e.column(), 17);
  // the default spacing over a long t_end: at t_end's value
  e = model_error(kOscillator + "simulate: {t_end: 1e300}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 19);
  EXPECT_TRUE(contains(e.message(), "t_end = 1e+300) has 1e+302 samples")) << e.message();
  // a spacing below the resolution of the sample times
  e = model_error(kOscillator + "simulate: {t_start: 1e6, t_end: 1000000.001}\n" +
                  "output: {every: 1e-9}\n");
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.column(), 17);
  EXPECT_TRUE(contains(e.message(), "below the resolution of the sample times")) << e.message();
  EXPECT_FALSE(contains(e.what(), "ukdyn::")) << e.what();
  // a grid a streamed run accepts is accepted (10^8 samples: more than a run kept in memory may
  // hold, which simulate() refuses when it is run without a sample_sink)
  const Model m = parse_model(kOscillator + "simulate: {t_end: 1e6}\n");
  EXPECT_NO_THROW(check_run_settings(m, m.options));
  EXPECT_THROW(check_settings(m.system, m.options), SettingError);
}

// the ModelError `ukdyn run` reports for a model whose initial state it cannot start from
ModelError start_error(const std::string& text) {
  const Model m = parse_model(text, "start.yaml");
  try {
    run_model(m);
  } catch (const InconsistentInitialState& e) {
    return locate_run_error(m, e);
  }
  ADD_FAILURE() << "the run started:\n" << text;
  return ModelError("", 0, 0, "");
}

TEST(RunSettings, InconsistentInitialStatesAreLocatedAtInitialOrTheConstraint) {
  const std::string two =
      "coordinates: [x, y]\n"
      "kinetic_energy: 0.5*(x_dot^2+y_dot^2)\n"
      "constraints:\n"
      "  - {name: at0, holonomic: x}\n"
      "  - {name: at1, holonomic: x - 1}\n";
  // constraints that contradict each other: at the first one's entry (with or without initial:)
  for (const std::string& text : {two, two + "initial: {project: true}\n"}) {
    const ModelError e = start_error(text);
    EXPECT_EQ(e.line(), 4) << e.what();
    EXPECT_EQ(e.column(), 5) << e.what();
    EXPECT_EQ(e.message().rfind("the constraints 'at0', 'at1' contradict each other", 0), 0u)
        << e.message();
    EXPECT_EQ(e.hint(), "");
  }
  // 1 = 0: at the constraint
  ModelError e = start_error(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2+y_dot^2)\nconstraints:\n"
      "  - {name: other, holonomic: y}\n  - {name: c, holonomic: 1 + 0*x}\n");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.column(), 5);
  EXPECT_EQ(e.message().rfind("the constraint 'c' cannot be satisfied", 0), 0u) << e.message();
  // a state off the rod, not projected: at initial:, with the hint to project
  const std::string rod =
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2+y_dot^2)\nconstraints:\n"
      "  - {name: rod, holonomic: x^2 + y^2 - 1}\n";
  e = start_error(rod + "initial:\n  q: {x: 1.5, y: 0}\n");
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.column(), 3);
  EXPECT_EQ(e.message().rfind("inconsistent initial conditions at t = 0: constraint 'rod'", 0), 0u)
      << e.message();
  EXPECT_EQ(e.hint(), "add `project: true` under `initial:` in the model file");
  // without initial: (the state the file implies, q = 0): at the constraint it violates
  e = start_error(rod);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.column(), 5);
}

// A penetrated contact (a unilateral gap < 0 at the start) is located at the contact's entry,
// with or without `project: true`, and its hint is one that can help: projection does not act on
// a unilateral gap (the hint was to add `project: true`, also where it was there already). A
// robot's contact likewise (it was located at 1:1 of the file), and its reader's errors in an
// expression name the contact.
TEST(RunSettings, PenetratedContactsAreLocatedAtTheirEntryWithAHintThatCanHelp) {
  const std::string ball =
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2+y_dot^2)\nconstraints:\n"
      "  - {name: floor, holonomic: y, unilateral: true}\n";
  const std::string hint =
      "start with the contact open or touching: change the initial q so that its gap is >= 0 "
      "(`project: true` does not act on a unilateral gap)";
  for (const std::string initial :
       {"initial:\n  q: {y: -1}\n", "initial:\n  q: {y: -1}\n  project: true\n"}) {
    const ModelError e = start_error(ball + initial);
    EXPECT_EQ(e.line(), 4) << e.what();
    EXPECT_EQ(e.column(), 5) << e.what();
    EXPECT_EQ(e.message().rfind("inconsistent initial conditions at t = 0: the unilateral "
                                "constraint 'floor' is penetrated: its gap is -1",
                                0),
              0u)
        << e.message();
    EXPECT_EQ(e.hint(), hint);
  }
  // the pendulum of tests/data/contact_pendulum.urdf, its tip (z = 0.5, r = 0.05) below the
  // plane z = 0.7: gap −0.25
  const std::string robot =
      "robot: {urdf: contact_pendulum.urdf}\ncontacts:\n"
      "  - {name: tip, link: rod, point: [0.8, 0, 0], shape: sphere, radius: 0.05,\n"
      "     plane: {body: ground, point: [0, 0, 0.7], normal: [0, 0, 1]}}\n";
  const std::string path = std::string(UKDYN_TEST_DATA_DIR) + "/robot.yaml";
  const Model m = parse_model(robot, path);
  try {
    run_model(m);
    ADD_FAILURE() << "the run started";
  } catch (const InconsistentInitialState& x) {
    const ModelError e = locate_run_error(m, x);
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_EQ(e.column(), 5) << e.what();
    EXPECT_NE(e.message().find("the unilateral constraint 'tip' is penetrated: its gap is -0.25"),
              std::string::npos)
        << e.message();
    EXPECT_EQ(e.hint(), hint);
  }
  std::string radius = robot;
  radius.replace(radius.find("radius: 0.05"), 12, "radius: 0/0");
  try {
    parse_model(radius, path);
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_EQ(e.message(), "in contact 'tip' radius: cannot evaluate: division by zero")
        << e.what();
  }
}

// --- energy drift of a run in which nothing moves ------------------------------------------

TEST(RunSettings, EnergyDriftOfABlockAtRestIsItsRoundoff) {
  // the reproducers: a block held by friction on the floor (pushed at the friction limit), and
  // one at rest on an incline with tan(alpha) = mu; E(0) = 0 and nothing moves
  const char* models[] = {
      "parameters: {m: 1, g: 9.81, mu: 0.5}\n"
      "coordinates: [x, y]\n"
      "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
      "potential_energy: m*g*y\n"
      "forces: [mu*m*g*(1 + 1e-9*sin(1000*t)), 0]\n"
      "constraints:\n"
      "  - {name: floor, holonomic: y}\n"
      "nonideal:\n"
      "  - {friction: coulomb, constraint: floor, mu: mu}\n"
      "simulate: {t_end: 2}\n",
      "parameters: {m: 1, g: 9.81, alpha: 0.5}\n"
      "coordinates: [x, y]\n"
      "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
      "potential_energy: m*g*y\n"
      "constraints:\n"
      "  - {name: plane, holonomic: x*sin(alpha) + y*cos(alpha)}\n"
      "nonideal:\n"
      "  - {friction: coulomb, constraint: plane, mu: tan(alpha)}\n"
      "simulate: {t_end: 2}\n"};
  for (const char* text : models) {
    const Model m = parse_model(text);
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-12) << text;  // was 1.66e10 and 7.1e15
    // it is the largest |E − E0 − ΣW| (absolute: the energies are below 1 J)
    double largest = 0.0;
    for (double r : tr.energy_balance_residual) largest = std::max(largest, std::abs(r));
    EXPECT_EQ(tr.stats.energy_drift, largest);
  }
}

TEST(RunSettings, EnergyDriftStaysRelativeForRunsAboveOneJoule) {
  // the oscillator from x = 10: E = 50 J; the drift is the residual over 50 J
  SimulationOptions o;
  o.t_end = 3.0;
  const Trajectory tr = simulate(oscillator(), one(10.0), one(0.0), o);
  double largest = 0.0;
  for (double r : tr.energy_balance_residual) largest = std::max(largest, std::abs(r));
  EXPECT_DOUBLE_EQ(tr.stats.energy_drift, largest / 50.0);
}

// --- adaptive steps that leave the model's domain --------------------------------------------

// M = 1 − t: positive definite up to t = 1, where the solution x'' = 0 ends
const std::string kMassBlowup =
    "coordinates: [x]\n"
    "mass_matrix: [[1 - t]]\n"
    "forces: [0]\n"
    "initial: {q: {x: 0.25}, q_dot: {x: 1}}\n";

// occurrences of `part` in s
int count(const std::string& s, const std::string& part) {
  int n = 0;
  for (auto k = s.find(part); k != std::string::npos; k = s.find(part, k + 1)) ++n;
  return n;
}

TEST(RunSettings, AdaptiveStepsOutsideTheDomainAreRetriedSmaller) {
  for (const char* method : {"dopri5", "rkf78", "bdf"}) {
    const Model m = parse_model(kMassBlowup + "simulate: {t_end: 2, integrator: " + method + "}\n");
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    const RunStatistics& s = tr.stats;
    // was: dopri5 stopped at 0.527, bdf at 0.381
    EXPECT_GT(s.t_reached, 1.0 - 1e-12) << method << ": " << s.message;
    EXPECT_LE(s.t_reached, 1.0) << method;
    EXPECT_NE(s.status, Status::kOk) << method;
    EXPECT_NE(s.status, Status::kIntegratorFailure) << method << ": " << s.message;
    // one time in the message: the last state reached
    EXPECT_TRUE(contains(s.message, std::string(method) + ": no step beyond t = ")) << s.message;
    EXPECT_EQ(count(s.message, "t = "), 1) << s.message;
    EXPECT_GT(s.rejected_steps, 0) << method;
    // every sample is on x = 0.25 + t, x' = 1, the last one (t = 0.99) included
    ASSERT_GE(tr.samples(), 100) << method;
    EXPECT_NEAR(tr.t[99], 0.99, 1e-12);
    for (Index i = 0; i < tr.samples(); ++i) {
      EXPECT_NEAR(tr.q[std::size_t(i)], 0.25 + tr.t[std::size_t(i)], 1e-9) << method;
      EXPECT_NEAR(tr.qd[std::size_t(i)], 1.0, 1e-9) << method;
    }
  }
}

TEST(RunSettings, ANanForceAfterHalfTimeEndsAdaptiveRunsJustBeforeIt) {
  // Q = NaN for t > 0.5 (not a domain that ends smoothly): retried down to the smallest step,
  // then the run ends within rounding of 0.5 with the status of the evaluation
  const System sys =
      SystemBuilder(std::vector<std::string>{"y"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                     Eigen::Ref<VectorXd> Q) {
            Q[0] = t > 0.5 ? std::numeric_limits<double>::quiet_NaN() : -1.0;
          })
          .build();
  for (Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SimulationOptions o;
    o.integrator = method;
    const Trajectory tr = simulate(sys, one(0.0), one(0.0), o);
    EXPECT_EQ(tr.stats.status, Status::kNonFiniteInput) << tr.stats.message;
    EXPECT_NEAR(tr.stats.t_reached, 0.5, 1e-9) << to_string(method);
    EXPECT_EQ(count(tr.stats.message, "t = "), 1) << tr.stats.message;
    EXPECT_TRUE(contains(tr.stats.message, "in Q")) << tr.stats.message;
    // y = −t²/2 at the last sample
    EXPECT_NEAR(tr.q.back(), -0.5 * tr.t.back() * tr.t.back(), 1e-9);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
