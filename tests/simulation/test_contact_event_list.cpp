// SPDX-License-Identifier: BSD-3-Clause
// The list of a run's contact events (RunStatistics::contact_events, summary.json's
// `contact_events`; issue #31, docs/contact.md "In a run"): every contact released at one instant
// listed with its force before (a block on two legs lifted through its centre of mass), the
// sticks and slips of Coulomb friction with their times, speeds, holding force and mu_s N (a
// block that slides and stops on an incline, a block pushed by a growing force), the counts and
// rest time per sample of a sweep (the bouncing ball over its restitution, on 1 and 2 threads),
// and a penetrated contact's own cause. Every number against a closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <ukdyn/dynamics/contact.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/ensemble.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Kind = ContactEvent::Kind;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<ContactEvent> of_kind(const Trajectory& tr, Kind kind) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.kind == kind) out.push_back(e);
  }
  return out;
}

// a block (mass m, inertia J) on two legs at x = ∓a, lifted by F = k t through its centre of
// mass: each leg carries (m g − k t)/2 until both release together at t* = m g / k; then
// y = k (t − t*)³ / (6 m), th = 0
constexpr const char* kTwoLegs = R"(
name: block on two legs
parameters: {m: 2, g: 9.81, a: 0.5, J: 0.1, k: 32.7}
coordinates: [y, th]
kinetic_energy: 0.5*m*y_dot^2 + 0.5*J*th_dot^2
potential_energy: m*g*y
forces: [k*t, 0]
constraints:
  - {name: left, holonomic: y - a*sin(th), unilateral: true}
  - {name: right, holonomic: y + a*sin(th), unilateral: true}
simulate: {t_end: 1, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output:
  every: 0.01
)";

TEST(ContactEventList, BothLegsOfALiftedBlockAreReleasedAtTheClosedFormTime) {
  const Model m = parse_model(std::string(kTwoLegs), "<string>");
  const ModelRun run = run_model(m, m.options);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double mg = 2.0 * 9.81, t_star = mg / 32.7;
  // both legs, once each, at t* (located to the bisection's 1e-14 and the error control's
  // multiplier: the force is linear in t, so t* to about rtol)
  const std::vector<ContactEvent> releases = of_kind(tr, Kind::kRelease);
  ASSERT_EQ(releases.size(), 2u);
  EXPECT_EQ(tr.stats.contact_events.size(), 2u);
  EXPECT_NE(releases[0].constraint, releases[1].constraint);
  for (const ContactEvent& e : releases) {
    SCOPED_TRACE(tr.constraint_names[std::size_t(e.constraint)]);
    EXPECT_NEAR(e.t, t_star, 1e-8);
    EXPECT_EQ(e.t, releases[0].t);  // the same instant
    // the force each leg carried just before: (m g − k t*)/2 = 0, to the location's width
    EXPECT_NEAR(e.force_before, 0.0, 1e-7 * mg);
    EXPECT_NEAR(e.speed_before, 0.0, 1e-9);
    EXPECT_TRUE(std::isnan(e.holding_force));
    EXPECT_TRUE(e.friction.empty());
  }
  // and the block then rises as the closed form says (neither leg hit again)
  const std::size_t last = tr.t.size() - 1;
  const double dt = tr.t[last] - t_star;
  EXPECT_NEAR(tr.q[last * 2], 32.7 * dt * dt * dt / (6.0 * 2.0), 1e-8);
  EXPECT_NEAR(tr.q[last * 2 + 1], 0.0, 1e-9);
  // summary.json lists both, with the force before
  const nlohmann::json j = nlohmann::json::parse(summary_json(tr, m.options));
  ASSERT_EQ(j["contact_events"].size(), 2u);
  for (const auto& e : j["contact_events"]) {
    EXPECT_EQ(e["kind"], "release");
    EXPECT_NEAR(e["force_before"].get<double>(), 0.0, 1e-7 * mg);
  }
}

TEST(ContactEventList, NoEventWhileTheLegsCarryTheBlock) {
  // lifted by k t < m g until t_end: the legs stay loaded, nothing is listed
  const Model m = parse_model(std::string(kTwoLegs), "<string>", {{"k", 9.81}});
  const ModelRun run = run_model(m, m.options);
  EXPECT_TRUE(of_kind(run.trajectory, Kind::kRelease).empty());
  EXPECT_TRUE(run.trajectory.stats.contact_events.empty());
}

// block_slide_stick.yaml: launched at v0 down a slope alpha with mu > tan(alpha), it decelerates
// at g (mu cos alpha − sin alpha) and sticks at v0 / that (early by v_stop / that)
TEST(ContactEventList, TheSlidingBlockSticksAtTheClosedFormTime) {
  const Model m =
      parse_model(read_text(std::string(UKDYN_EXAMPLES_DIR) + "/block_slide_stick.yaml"),
                  "block_slide_stick.yaml");
  const ModelRun run = run_model(m, m.options);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double g = 9.81, alpha = 0.3, mu = 0.5, v0 = 2.0;
  const double decel = g * (mu * std::cos(alpha) - std::sin(alpha));
  ASSERT_EQ(m.system.friction_contacts().size(), 1u);
  const double v_stop = 100.0 * m.system.friction_contacts()[0].eps;
  const std::vector<ContactEvent> sticks = of_kind(tr, Kind::kStick);
  ASSERT_EQ(sticks.size(), 1u);
  EXPECT_EQ(tr.stats.contact_events.size(), 1u);
  const ContactEvent& e = sticks[0];
  EXPECT_NEAR(e.t, (v0 - v_stop) / decel, 1e-8);
  EXPECT_NEAR(e.t, 1.1192742, 1e-7);  // (v_stop = 1e-7 m/s: 5.6e-8 s early)
  EXPECT_EQ(tr.constraint_names[std::size_t(e.constraint)], "plane");
  EXPECT_EQ(e.friction, m.system.nonideal_name(m.system.friction_contacts()[0].force));
  // the sliding speed before (the stop's v_stop) and after (stuck)
  EXPECT_NEAR(e.speed_before, v_stop, 1e-3 * v_stop);
  EXPECT_NEAR(e.speed_after, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(e.holding_force));
  // summary.json has the list though the model has no unilateral contact
  const nlohmann::json j = nlohmann::json::parse(summary_json(tr, m.options));
  ASSERT_EQ(j["contact_events"].size(), 1u);
  EXPECT_EQ(j["contact_events"][0]["kind"], "stick");
  EXPECT_EQ(j["contact_events"][0]["contact"], "plane");
  EXPECT_EQ(j["contact_events"][0]["friction"], e.friction);
  EXPECT_NEAR(j["contact_events"][0]["t"].get<double>(), e.t, 1e-15);
}

// a block (m) at rest on a rough floor (mu 0.4, mu_s 0.5), pushed by F = c t: it holds until
// c t = mu_s m g, then slides; the holding force there is mu_s N = mu_s m g
constexpr const char* kPushed = R"(
name: pushed block
parameters: {m: 2, g: 9.81, c: 4}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
forces: [c*t, 0]
constraints:
  - {name: floor, holonomic: y}
nonideal:
  - {friction: coulomb, constraint: floor, mu: 0.4, mu_static: 0.5}
simulate: {t_end: 4, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output:
  every: 0.01
)";

TEST(ContactEventList, APushedBlockSlipsWhereTheForceReachesMuStaticN) {
  const Model m = parse_model(std::string(kPushed), "<string>");
  const ModelRun run = run_model(m, m.options);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double mg = 2.0 * 9.81, limit = 0.5 * mg;
  const std::vector<ContactEvent> slips = of_kind(tr, Kind::kSlip);
  ASSERT_EQ(slips.size(), 1u);
  EXPECT_EQ(tr.stats.contact_events.size(), 1u);
  const ContactEvent& e = slips[0];
  EXPECT_NEAR(e.t, limit / 4.0, 1e-9);
  const std::string name = m.system.nonideal_name(m.system.friction_contacts()[0].force);
  EXPECT_EQ(e.friction, name);
  EXPECT_EQ(tr.constraint_names[std::size_t(e.constraint)], "floor");
  EXPECT_NEAR(e.holding_force, limit, 1e-8 * limit);
  EXPECT_NEAR(e.friction_limit, limit, 1e-8 * limit);
  EXPECT_NEAR(e.speed_before, 0.0, 1e-12);
  const nlohmann::json j = nlohmann::json::parse(summary_json(tr, m.options));
  ASSERT_EQ(j["contact_events"].size(), 1u);
  EXPECT_EQ(j["contact_events"][0]["kind"], "slip");
  EXPECT_EQ(j["contact_events"][0]["friction"], name);
  EXPECT_NEAR(j["contact_events"][0]["holding_force"].get<double>(), limit, 1e-8 * limit);
  EXPECT_NEAR(j["contact_events"][0]["friction_limit"].get<double>(), limit, 1e-8 * limit);
}

// the bouncing ball over its restitution e: impact k (k = 0, 1, …) at speed e^k v0; the rest
// criterion (kRestFraction = 1e-6 of the fastest, v0) closes the contact at the first K with
// e^K < 1e-6: K impacts and one rest, the rest at t_K = t0 + 2 t0 e (1 − e^K)/(1 − e), within
// 2 t0 e^(K+1)/(1 − e) of t∞ = t0 (1 + 2e/(1 − e)) (t0 = √(2 h0/g)); e = 0: one plastic impact,
// the rest at t0
TEST(ContactEventList, ASweepOverRestitutionCountsTheImpactsAndTheRestTime) {
  EnsembleModel model;
  model.file = std::string(UKDYN_EXAMPLES_DIR) + "/bouncing_ball.yaml";
  model.text = read_text(model.file);
  model.settings["t_end"] = 4.0;
  const std::vector<double> es = {0.0, 0.3, 0.5, 0.7};
  std::vector<EnsembleSample> samples;
  for (double e : es) {
    EnsembleSample s;
    s.parameters["e"] = e;
    samples.push_back(s);
  }
  EnsembleOptions o;
  o.threads = 1;
  const EnsembleResult one = run_ensemble(model, samples, o);
  o.threads = 2;
  const EnsembleResult two = run_ensemble(model, samples, o);
  const EnsembleTable t1 = ensemble_table(one, samples), t2 = ensemble_table(two, samples);
  auto col = [](const EnsembleTable& t, const std::string& name) -> const std::vector<double>& {
    for (const CsvColumn& c : t.numbers) {
      if (c.name == name) return c.values;
    }
    ADD_FAILURE() << "no column " << name;
    static const std::vector<double> none(4, std::nan(""));
    return none;
  };
  const double g = 9.81, t0 = std::sqrt(2.0 / g);
  for (std::size_t i = 0; i < es.size(); ++i) {
    const double e = es[i];
    SCOPED_TRACE("e = " + std::to_string(e));
    ASSERT_TRUE(one.samples[i].ok()) << one.samples[i].message;
    if (e == 0.0) {
      // one plastic impact at t0 ends the motion: rest_time is t0, the limit of t∞ as e → 0
      EXPECT_EQ(col(t1, "impacts")[i], 1.0);
      EXPECT_EQ(col(t1, "releases")[i], 0.0);
      EXPECT_NEAR(col(t1, "rest_time")[i], t0, 1e-8);
      continue;
    }
    int K = 0;
    while (std::pow(e, K) >= 1e-6) ++K;
    EXPECT_EQ(col(t1, "impacts")[i], double(K + 1));
    EXPECT_EQ(col(t1, "releases")[i], 0.0);
    EXPECT_EQ(col(t1, "sticks")[i], 0.0);
    EXPECT_EQ(col(t1, "slips")[i], 0.0);
    const double t_K = t0 + 2.0 * t0 * e * (1.0 - std::pow(e, K)) / (1.0 - e);
    const double t_inf = t0 * (1.0 + 2.0 * e / (1.0 - e));
    EXPECT_NEAR(col(t1, "rest_time")[i], t_K, 1e-8);
    EXPECT_NEAR(col(t1, "rest_time")[i], t_inf - t0 * std::pow(e, K + 1) / (1.0 - e),
                t0 * std::pow(e, K + 1) / (1.0 - e) + 1e-8);
  }
  // on 2 threads, the same table bit for bit
  ASSERT_EQ(t1.numbers.size(), t2.numbers.size());
  for (std::size_t c = 0; c < t1.numbers.size(); ++c) {
    EXPECT_EQ(t1.numbers[c].name, t2.numbers[c].name);
    if (t1.numbers[c].name == "rest_time" || t1.numbers[c].name == "impacts") {
      EXPECT_EQ(t1.numbers[c].values, t2.numbers[c].values) << t1.numbers[c].name;
    }
  }
}

TEST(ContactEventList, AModelWithoutContactsOrFrictionHasNoEventColumns) {
  EnsembleModel model;
  model.file = std::string(UKDYN_EXAMPLES_DIR) + "/pendulum.yaml";
  model.text = read_text(model.file);
  model.settings["t_end"] = 0.1;
  const std::vector<EnsembleSample> samples(1);
  const EnsembleResult r = run_ensemble(model, samples, {});
  for (const CsvColumn& c : ensemble_table(r, samples).numbers) {
    EXPECT_NE(c.name, "impacts");
    EXPECT_NE(c.name, "rest_time");
  }
}

TEST(ContactEventList, APenetratedContactIsItsOwnCause) {
  Model m = parse_model(read_text(std::string(UKDYN_EXAMPLES_DIR) + "/bouncing_ball.yaml"),
                        "bouncing_ball.yaml", {{"h0", -0.25}});
  for (bool project : {false, true}) {
    m.options.project_initial = project;
    try {
      simulate(m.system, m.q0, m.qd0, m.options);
      ADD_FAILURE() << "no error";
    } catch (const InconsistentInitialState& e) {
      EXPECT_EQ(e.cause(), InconsistentInitialState::Cause::kPenetrated);
      EXPECT_TRUE(contacts_penetrated(m, e));
      ASSERT_EQ(e.constraints().size(), 1u);
      EXPECT_EQ(e.constraints()[0], "floor");
    }
  }
  // the model file's error: at the contact, with the hint to move the state
  try {
    run_model(m, m.options);
    ADD_FAILURE() << "no error";
  } catch (const InconsistentInitialState& e) {
    const ModelError located = locate_run_error(m, e);
    EXPECT_NE(located.hint().find("change the initial q so that its gap is >= 0"),
              std::string::npos)
        << located.hint();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
