// SPDX-License-Identifier: BSD-3-Clause
// Diagnoses that name the cause (issue #14, items 4 and 6, and D18 of the reliability report):
// constant sub-expressions that are not finite real doubles, duplicate YAML keys and documents,
// contradictory and locking constraints, files that are not model files.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kData = std::string(UKDYN_TEST_DATA_DIR) + "/diagnoses/";

// the error a model text raises, or "" when it loads
std::string error_of(const std::string& text) {
  try {
    parse_model(text, "m.yaml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

std::string error_of_file(const std::string& path) {
  try {
    load_model(path);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// a one-coordinate model whose potential is `V` (line 3, from column 19)
std::string with_potential(const std::string& V) {
  return "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\npotential_energy: " + V +
         "\ninitial: {q: {x: 0.5}}\n";
}

// ---- D12: constant sub-expressions, located at their function or operator --------------------

TEST(ModelDiagnoses, ComplexConstantsAreLocatedAtTheirFunction) {
  std::string e = error_of(with_potential("acos(2)*x"));
  EXPECT_TRUE(contains(e,
                       "m.yaml:3:19: error: in potential_energy: cannot evaluate: acos(2) is "
                       "complex"))
      << e;
  // (-8)^(1/3): the '^' is the 5th character
  e = error_of(with_potential("(-8)^(1/3)*x"));
  EXPECT_TRUE(contains(e, "m.yaml:3:23: error:")) << e;
  EXPECT_TRUE(contains(e, "is complex")) << e;
  // named as written, not by GiNaC's value (sqrt(-1) is I: the message said "(I) is complex (I)")
  e = error_of(with_potential("sqrt(-1)*x"));
  EXPECT_TRUE(contains(e,
                       "m.yaml:3:19: error: in potential_energy: cannot evaluate: sqrt(-1) is "
                       "complex (I)"))
      << e;
}

TEST(ModelDiagnoses, OverflowingConstantsAreLocated) {
  std::string e = error_of(with_potential("exp(1000)*x"));
  EXPECT_TRUE(contains(e, "m.yaml:3:19: error:")) << e;
  EXPECT_TRUE(contains(e, "exp(1000) overflows a double")) << e;
  e = error_of(with_potential("10^400*x"));
  EXPECT_TRUE(contains(e, "m.yaml:3:21: error:")) << e;
  EXPECT_TRUE(contains(e, "overflows a double")) << e;
  e = error_of(with_potential("x + sinh(1e6)"));
  EXPECT_TRUE(contains(e, "m.yaml:3:23: error:")) << e;
  EXPECT_TRUE(contains(e, "overflows a double")) << e;
  e = error_of(with_potential("1e300*1e300*x"));
  EXPECT_TRUE(contains(e, "overflows a double")) << e;
}

TEST(ModelDiagnoses, TangentAtItsPoleToWithinRoundoffIsRefused) {
  std::string e = error_of(with_potential("tan(pi/2)*x"));
  EXPECT_TRUE(contains(e, "m.yaml:3:19: error:")) << e;
  EXPECT_TRUE(contains(e, "tan is at its pole")) << e;
  // with a parameter: tan(3*pi/2) too
  e = error_of("parameters: {a: 4.71238898038469}\n" + with_potential("tan(a)*x"));
  EXPECT_TRUE(contains(e, "m.yaml:4:19: error:")) << e;
  EXPECT_TRUE(contains(e, "tan is at its pole")) << e;
}

TEST(ModelDiagnoses, LargeButFiniteConstantsAreKept) {
  // exp(700) ≈ 1.0e304, 10^300, tan(1.57) ≈ 1255.8, acos(1) = 0, (-8)^3: all finite and real
  for (const char* V : {"exp(700)*x", "10^300*x", "tan(1.57)*x", "acos(1)*x", "(-8)^3*x",
                        "sinh(700)*x^2", "x*tan(pi/4)"}) {
    EXPECT_EQ(error_of(with_potential(V)), "") << V;
  }
  const Model m = parse_model(with_potential("tan(1.57)*x"));
  // Q = -dV/dx = -tan(1.57) = -1255.7655915007897 (closed form)
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], -1255.7655915007897, 1e-9);
}

// ---- D9: duplicate keys and a second document ------------------------------------------------

TEST(ModelDiagnoses, DuplicateKeysAreErrorsAtTheSecondCopy) {
  // a parameter given twice: the second k (column 20), the first named by line and column
  std::string e = error_of_file(kData + "dup_keys_precedence.yaml");
  EXPECT_TRUE(contains(e,
                       "dup_keys_precedence.yaml:1:20: error: the key 'k' is given twice in "
                       "this mapping (first at line 1, column 14)"))
      << e;
  // a top-level key given twice
  e = error_of("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\nkinetic_energy: x_dot^2\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:1: error: the key 'kinetic_energy' is given twice")) << e;
  EXPECT_TRUE(contains(e, "first at line 2")) << e;
  // deep inside: a constraint's entry
  e = error_of(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\nconstraints:\n"
      "  - name: c\n    holonomic: x\n    holonomic: y\n");
  EXPECT_TRUE(contains(e, "m.yaml:6:5: error: the key 'holonomic' is given twice")) << e;
}

TEST(ModelDiagnoses, ASecondDocumentIsAnError) {
  const std::string e = error_of_file(kData + "yaml_multi_doc.yaml");
  EXPECT_TRUE(contains(e, "yaml_multi_doc.yaml:3:")) << e;
  EXPECT_TRUE(contains(e, "a second YAML document")) << e;
}

TEST(ModelDiagnoses, SelfReferencingAliasAndDeepNesting) {
  std::string e = error_of("coordinates: &c [x, *c]\nkinetic_energy: 0.5*x_dot^2\n");
  EXPECT_TRUE(contains(e, "m.yaml:1:21: error: this alias refers to a node that contains it")) << e;
  e = error_of("name: " + std::string(100000, '[') + "\n");
  // (yaml-cpp marks where it gave up: the end of the brackets)
  EXPECT_TRUE(contains(e, "m.yaml:2:1: error: the YAML nests too deep")) << e;
}

// ---- D18: not a model file --------------------------------------------------------------------

TEST(ModelDiagnoses, DirectoryEmptyFileXmlAndDevZero) {
  std::string e = error_of_file(kData);
  EXPECT_TRUE(contains(e, "is a directory, not a model file")) << e;
  const auto dir = std::filesystem::temp_directory_path() / "ukdyn_test_model_diagnoses";
  std::filesystem::create_directories(dir);
  const std::string empty = (dir / "empty.yaml").string();
  { std::ofstream(empty) << "# nothing\n"; }
  e = error_of_file(empty);
  EXPECT_TRUE(contains(e, "the model file is empty")) << e;
  EXPECT_TRUE(contains(e, "empty.yaml:1:1: error:")) << e;  // located, as every reader error
  // XML where a YAML model file is expected: said so, with the way to a robot model file
  const std::string xml = (dir / "robot.yaml").string();
  { std::ofstream(xml) << "<?xml version=\"1.0\"?>\n<robot name=\"r\"></robot>\n"; }
  e = error_of_file(xml);
  EXPECT_TRUE(contains(e, "robot.yaml:1:1: error: this looks like an XML file")) << e;
  EXPECT_TRUE(contains(e, "robot: {urdf: arm.urdf} (docs/robots.md)")) << e;
  // a .urdf is read as a URDF (issue #30): one without links is refused, the file named, at its
  // <robot> (u23 07)
  const std::string urdf = (dir / "robot.urdf").string();
  { std::ofstream(urdf) << "<?xml version=\"1.0\"?>\n<robot name=\"r\"></robot>\n"; }
  e = error_of_file(urdf);
  EXPECT_TRUE(contains(e, "robot.urdf:2:1: error: not a valid URDF: No link elements")) << e;
  if (std::filesystem::exists("/dev/zero")) {
    e = error_of_file("/dev/zero");
    EXPECT_TRUE(contains(e, "larger than 64 MB")) << e;
  }
  std::filesystem::remove_all(dir);
}

TEST(ModelDiagnoses, ANulByteIsNamedWhereItIs) {
  // yaml-cpp's own message was "unknown escape character: <newline>"
  std::string text = "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2";
  text += '\0';
  text += "\n";
  const std::string e = error_of(text);
  EXPECT_TRUE(contains(e, "m.yaml:2:28: error: the model text holds a NUL byte")) << e;
}

TEST(ModelDiagnoses, FlowMappingCommaSuggestsQuoting) {
  const std::string e = error_of_file(kData + "yaml_flow_comma.yaml");
  EXPECT_TRUE(contains(e, "yaml_flow_comma.yaml:18:")) << e;
  EXPECT_TRUE(contains(e, "quote the expression")) << e;
}

// an expression of a flow list split at its commas into more entries than coordinates
// (review 2026-11-27: push.yaml, push3.yaml): the count's error says to quote it, and how
TEST(ModelDiagnoses, FlowListCommaSuggestsQuotingWhenTheCountIsWrong) {
  std::string e = error_of_file(kData + "flow_list_cut.yaml");
  EXPECT_TRUE(contains(e,
                       "flow_list_cut.yaml:7:9: error: forces must have 2 entries, one per "
                       "coordinate (hint: inside YAML brackets [...] a comma ends an entry, so "
                       "the commas inside an expression's parentheses split it: quote the "
                       "expression (forces: [\"if(t - 0.5, F, 0)\", 0]) or write the list in "
                       "block style, one entry per line)"))
      << e;
  e = error_of_file(kData + "flow_list_cut_short.yaml");
  EXPECT_TRUE(contains(e, "quote the expression (forces: [\"if(t - 0.5, F, 0)\"])")) << e;
  // quoted, or a list of the wrong length with balanced entries: no such hint
  e = error_of(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\n"
      "forces: [\"if(t - 0.5, 1, 0)\", 0, 1]\n");
  EXPECT_TRUE(contains(e, "forces must have 2 entries, one per coordinate")) << e;
  EXPECT_FALSE(contains(e, "hint")) << e;
  e = error_of(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\n"
      "nonideal:\n  - {C: [max(x, 0), 0, y]}\n");
  EXPECT_TRUE(contains(e, "C must have 2 entries")) << e;
  EXPECT_TRUE(contains(e, "quote the expression (C: [\"max(x, 0)\", 0, y])")) << e;
}

TEST(ModelDiagnoses, RegularizationVelocityZeroIsLocatedAtItsEntry) {
  const std::string e = error_of_file(kData + "coulomb_regularization_zero.yaml");
  EXPECT_TRUE(contains(e,
                       "coulomb_regularization_zero.yaml:8:78: error: "
                       "regularization_velocity must be > 0"))
      << e;
}

TEST(ModelDiagnoses, SpringWhosePointsCoincideIsRefused) {
  const std::string e = error_of_file(kData + "mb_spring_zero_length.yaml");
  EXPECT_TRUE(contains(e,
                       "mb_spring_zero_length.yaml:5:5: error: force 's': its two points "
                       "coincide"))
      << e;
}

// ---- D11: contradictory and locking constraints ----------------------------------------------

TEST(ModelDiagnoses, ContradictoryConstraintsAreNamedByCheckAndRun) {
  for (const char* file : {"inconsistent_noproj.yaml", "inconsistent_constraints.yaml"}) {
    const Model m = load_model(kData + file);
    const CheckReport r = check_model(m);
    EXPECT_EQ(r.contradictory, (std::vector<std::string>{"at0", "at1"})) << file;
    EXPECT_TRUE(r.redundant.empty()) << file;
    ASSERT_FALSE(r.ok());
    EXPECT_TRUE(contains(r.problems.front(), "contradict each other")) << r.problems.front();
    try {
      run_model(m);
      ADD_FAILURE() << file << ": ran";
    } catch (const InconsistentInitialState& e) {
      EXPECT_EQ(e.cause(), InconsistentInitialState::Cause::kContradictory) << file;
      const std::string what = e.what();
      EXPECT_TRUE(contains(what, "the constraints 'at0', 'at1' contradict each other")) << what;
      EXPECT_FALSE(contains(what, "project_initial")) << what;
      // x = 0 and x = 1: the least-squares x = 1/2 leaves (1/2, -1/2), norm 1/sqrt(2)
      EXPECT_TRUE(contains(what, "least violation is 0.707")) << what;
    }
  }
  // 1 = 0
  const Model m = load_model(kData + "constraint_const.yaml");
  const CheckReport r = check_model(m);
  EXPECT_EQ(r.contradictory, (std::vector<std::string>{"c"}));
  try {
    run_model(m);
    ADD_FAILURE() << "ran";
  } catch (const InconsistentInitialState& e) {
    EXPECT_EQ(e.cause(), InconsistentInitialState::Cause::kContradictory);
    EXPECT_TRUE(contains(e.what(), "the constraint 'c' cannot be satisfied")) << e.what();
  }
}

// A contact that starts penetrated: the run refuses to start, with `project: true` or without
// (projection does not act on a unilateral gap), so check reports it as a problem with the run's
// message and hint, and never advises `project: true` for it (u22 07: it said "ok" with project:
// true, and advised it without)
TEST(ModelDiagnoses, APenetratedContactIsAProblemOfCheckWithOrWithoutProjection) {
  const std::string ball = R"(bodies:
  - {name: ball, type: rigid, mass: 1, inertia: 0.004, position: [0, 0, 0.05]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: 0.1}
)";
  for (const bool project : {false, true}) {
    const Model m = parse_model(ball + (project ? "initial: {project: true}\n" : ""), "p.yaml");
    const CheckReport r = check_model(m);
    EXPECT_EQ(r.penetrated, std::vector<std::string>{"floor"}) << project;
    ASSERT_EQ(r.problems.size(), 1u) << project;
    // the gap: 0.05 − 0.1
    EXPECT_TRUE(contains(r.problems[0],
                         "the unilateral constraint 'floor' is penetrated at the initial state: "
                         "its gap is -0.05 (a unilateral constraint needs a gap >= 0"))
        << r.problems[0];
    EXPECT_TRUE(contains(r.problems[0], "`project: true` does not act on a unilateral gap"))
        << r.problems[0];
    EXPECT_FALSE(contains(r.problems[0], "`initial: project:` is not true")) << r.problems[0];
    // the run agrees
    try {
      run_model(m);
      ADD_FAILURE() << "ran, project " << project;
    } catch (const InconsistentInitialState& e) {
      EXPECT_EQ(e.cause(), InconsistentInitialState::Cause::kPenetrated);
      EXPECT_TRUE(contains(e.what(), "its gap is -0.05")) << e.what();
    }
  }
  // touching (gap 0) and open (gap 0.1): no problem
  for (const char* z : {"0.1", "0.2"}) {
    std::string text = ball;
    text.replace(text.find("0.05]"), 4, z);
    const CheckReport r = check_model(parse_model(text, "p.yaml"));
    EXPECT_TRUE(r.penetrated.empty()) << z;
    EXPECT_TRUE(r.ok()) << z << ": " << (r.problems.empty() ? "" : r.problems[0]);
  }
}

// ---- Painlevé's rod at the start (u24 06) ---------------------------------------------------

// Painlevé's rod (tests/data/painleve_rod.yaml; docs/contact.md, "Painlevé"): a planar rod
// (m, length 2l, I = m l²/3) on its end A at tan θ = 2, sliding away from itself on a rough
// floor, whose critical mu is mu_c = (1 + 3c²)/(3 s c) = 4/3. Past it (mu = 1.4) the run's start
// refuses the contact and `check` says the same, located at the friction's entry (where mu is
// given: line 13, column 5), with the normalized principal minor 1 − mu/mu_c = −0.05; just below
// (mu = 1.33) check passes and the run starts with N = m g/(1 + 3c² − 3 mu s c). The same in
// mm, g, ms (painleve_rod_mm_g_ms.yaml: m = 1000 g, l = 1000 mm, g = 9.81e-3 mm/ms², whose
// force unit g·mm/ms² is the newton: the same N).
TEST(ModelDiagnoses, PainlevesRodPastItsCriticalMuIsRefusedByCheckAndRunAtTheFriction) {
  const double th = std::atan(2.0), c = std::cos(th), s = std::sin(th);
  const double mu_c = (1.0 + 3.0 * c * c) / (3.0 * s * c);
  ASSERT_NEAR(mu_c, 4.0 / 3.0, 1e-14);
  const std::string message =
      ":13:5: error: the initial state's contacts: contacts at t = 0: Painlevé's paradox at the "
      "contact 'floor' (mu = 1.4): with its sliding friction the contact problem (the LCP of the "
      "normal forces) has no solution or several — the friction turns the contact's effective "
      "normal compliance negative (principal minor -0.05 of the normalized W + F); for this "
      "contact's angle the critical mu is 1.333. Rigid-body contact with Coulomb friction is "
      "inconsistent or indeterminate here: lower mu, or model the contact as compliant "
      "(docs/contact.md, \"Painlevé\")";
  // (the minor the message names: 1 − mu/mu_c, to its 3 digits)
  EXPECT_NEAR(1.0 - 1.4 / mu_c, -0.05, 1e-12);
  for (const char* file : {"painleve_rod.yaml", "painleve_rod_mm_g_ms.yaml"}) {
    const std::string path = std::string(UKDYN_TEST_DATA_DIR) + "/" + file;
    const Model bad = load_model(path);
    const CheckReport r = check_model(bad);
    ASSERT_EQ(r.problems.size(), 1u) << file;
    EXPECT_EQ(r.problems[0], path + message) << file;
    try {
      run_model(bad);
      ADD_FAILURE() << "ran past the critical mu: " << file;
    } catch (const std::invalid_argument& e) {
      // (the run's own text; `ukdyn run` locates it as check does: cli.painleve_run*)
      EXPECT_EQ(path + ":13:5: error: " + user_message(e), path + message) << file;
    }
    // just below mu_c: no problem, and the start's normal force is the closed form's
    const double mu = 1.33;
    const Model good = load_model(path, {{"mu", mu}});
    const CheckReport ok = check_model(good);
    EXPECT_TRUE(ok.ok()) << file << ": " << (ok.problems.empty() ? "" : ok.problems[0]);
    const ModelRun run = run_model(good);
    const Trajectory& tr = run.trajectory;
    ASSERT_EQ(tr.stats.status, Status::kOk) << file << ": " << tr.stats.message;
    ASSERT_FALSE(tr.t.empty());
    const std::size_t y = std::size_t(good.system.coordinate_index("rod.y"));
    const double N = 1.0 * 9.81 / (1.0 + 3.0 * c * c - 3.0 * mu * s * c);
    EXPECT_NEAR(tr.Qc_ideal[y] + tr.Qc_nonideal[y], N, 1e-8 * N) << file;
  }
}

// A value out of range that comes from `--set` (load_model's overrides) names the override before
// the file's location of the value (u24 10), also through a parameter derived from it; without
// the override, the file's message alone
TEST(ModelDiagnoses, AnOverrideOutOfRangeIsNamedAtTheValueItReaches) {
  const std::string path = std::string(UKDYN_TEST_DATA_DIR) + "/painleve_rod.yaml";
  const std::string at = path + ":11:59: error: ";
  const std::string rest =
      "contact 'floor': the restitution must lie in [0, 1], got 1.5 "
      "(hint: restitution: 0.5)";
  try {
    load_model(path, {{"e", 1.5}});
    ADD_FAILURE() << "loaded with e = 1.5";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()), at + "--set e=1.5: " + rest);
  }
  // the restitution reads a parameter derived from the override: e2 = e / 2
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("e: 0}"), 5, "e: 0, e2: e/2}");
  text.replace(text.find("restitution: e}"), 15, "restitution: e2}");
  try {
    parse_model(text, "d.yaml", {{"e", 3.0}});
    ADD_FAILURE() << "loaded with e2 = 1.5";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()), "d.yaml:11:59: error: --set e=3: " + rest);
  }
  // no override: the file's message only
  text.replace(text.find("e: 0,"), 5, "e: 3,");
  try {
    parse_model(text, "d.yaml");
    ADD_FAILURE() << "loaded with e2 = 1.5";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()), "d.yaml:11:59: error: " + rest);
  }
}

// The causes are typed (front ends read cause(), not the message): a pendulum started off its
// rod is kNotProjected without projection, and consistent after it
TEST(ModelDiagnoses, InconsistentInitialStateIsTypedByItsCause) {
  const std::string text =
      "coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\nforces: [0, -9.81]\n"
      "constraints:\n  - {name: rod, holonomic: x^2 + y^2 - 1}\n"
      "initial: {q: {x: 1.1, y: 0}}\nsimulate: {t_end: 0.01}\n";
  Model m = parse_model(text, "m.yaml");
  try {
    run_model(m);
    ADD_FAILURE() << "ran from an inconsistent state";
  } catch (const InconsistentInitialState& e) {
    EXPECT_EQ(e.cause(), InconsistentInitialState::Cause::kNotProjected);
    EXPECT_TRUE(contains(e.what(), "inconsistent initial conditions at t = 0: ")) << e.what();
  }
  m.options.project_initial = true;
  const ModelRun run = run_model(m);
  // projected onto the rod in the M-norm (M = I): (1, 0)
  EXPECT_NEAR(run.trajectory.q[0], 1.0, 1e-12);
  EXPECT_NEAR(run.trajectory.q[1], 0.0, 1e-12);
}

TEST(ModelDiagnoses, ConsistentRedundantConstraintsAreNotContradictory) {
  // x = 1 twice over, started at x = 0.5 with projection: redundant, consistent
  const Model m = parse_model(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2+y_dot^2)\n"
      "constraints:\n  - {name: a, holonomic: x - 1}\n  - {name: b, holonomic: 2*x - 2}\n"
      "initial: {q: {x: 0.5}, project: true}\nsimulate: {t_end: 0.1}\n");
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.contradictory.empty());
  EXPECT_EQ(r.redundant, (std::vector<std::string>{"b"}));
  const ModelRun run = run_model(m);
  EXPECT_EQ(run.trajectory.stats.status, Status::kOk);
}

TEST(ModelDiagnoses, FourBarLockUpIsReportedAsLockUp) {
  // the crank angle where |BD| = lb + lr: (lc cos θ − d)² + (lc sin θ)² = 0.64 gives
  // cos θ = (0.09 + 1 − 0.64)/0.6 = 0.75, θ = t = acos(0.75) = 0.7227 s
  Model m = load_model(kData + "fourbar_lockup.yaml");
  m.options.t_end = 1.0;
  const ModelRun run = run_model(m);
  const RunStatistics& s = run.trajectory.stats;
  EXPECT_NE(s.status, Status::kOk);
  EXPECT_NEAR(s.t_reached, std::acos(0.75), 2e-3);
  EXPECT_TRUE(contains(s.message, "the constraints have no solution near t = ")) << s.message;
  EXPECT_TRUE(contains(s.message, "the mechanism locks up")) << s.message;
  EXPECT_TRUE(contains(s.message, "'drive'")) << s.message;
}

// ---- initial: every key is checked (a coordinate written straight under it was ignored) ----

TEST(ModelDiagnoses, InitialKeysAreCheckedAndCoordinatesPointedToQ) {
  const std::string head = "coordinates: [x, th]\nkinetic_energy: 0.5*x_dot^2 + 0.5*th_dot^2\n";
  std::string e = error_of(head + "initial: {q: {x: 0}, th: 1}\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:22: error: unknown key 'th' in initial")) << e;
  EXPECT_TRUE(contains(e, "initial: {q: {th: 1}, q_dot: {th: 0}}")) << e;
  e = error_of(head + "initial: {th_dot: 1}\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:11: error: unknown key 'th_dot' in initial")) << e;
  EXPECT_TRUE(contains(e, "q: {th: 1}")) << e;
  e = error_of(head + "initial: {qdot: {x: 1}}\n");
  EXPECT_TRUE(contains(e, "unknown key 'qdot' in initial (hint: initial has q, q_dot and project)"))
      << e;
  // project is a boolean, not any word
  e = error_of(head + "initial: {q: {x: 0}, project: maybe}\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:31: error: initial project must be true or false")) << e;
  EXPECT_EQ(error_of(head + "initial: {q: {x: 0.5}, q_dot: {th: 2}, project: false}\n"), "");
  const Model m =
      parse_model(head + "initial: {q: {x: 0.5}, q_dot: {th: 2}, project: false}\n", "m.yaml");
  EXPECT_EQ(m.q0[0], 0.5);
  EXPECT_EQ(m.qd0[1], 2.0);
  EXPECT_FALSE(m.project_initial);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
