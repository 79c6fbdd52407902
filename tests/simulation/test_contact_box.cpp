// SPDX-License-Identifier: BSD-3-Clause
// Box contacts on bodies models (issue #31, docs/contact.md, "Contacts on bodies": `shape: box,
// size: [hx, hy, hz]` on a plane expands into one point contact per corner, `<name>.<k>`):
// Housner's rocking block as a planar box against the same block on two point contacts (the
// same events, to 1e-12) and against examples/models/rocking_block.yaml in natural coordinates
// (the same events; the angular velocity kept at r = 1 − (3/2) sin²α by each impact), a spatial
// box dropped flat (its four bottom corners land at once, at the free fall's time and speed,
// and it rests at its half-height with m g shared by them), and the errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/contact_runs.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// Housner's block (width 2b, height 2h, mass m) tilted by th0 on its right bottom corner, at the
// origin, on a rough floor (μ = 1), as a planar body; `contacts` its contacts: and friction.
std::string rocking_block(const std::string& contacts) {
  return "parameters: {m: 1, b: 0.2, h: 0.5, g: 9.81, th0: 0.2, mu: 1}\n"
         "bodies:\n"
         "  - {name: block, type: planar, mass: m, inertia: m*(b^2 + h^2)/3,\n"
         "     position: [-b*cos(th0) + h*sin(th0), b*sin(th0) + h*cos(th0)], angle: -th0}\n"
         "forces:\n"
         "  - {type: gravity, g: [0, -g]}\n" +
         contacts +
         "simulate: {t_end: 2, integrator: dopri5, rtol: 1e-10, atol: 1e-12}\n"
         "output: {every: 0.01}\n";
}

// a run's events as (contact name, kind, t, impulse, speed before, speed after)
struct Event {
  std::string contact;
  ContactEvent::Kind kind;
  double t, impulse, before, after;
};
std::vector<Event> events(const Model& m, const Trajectory& tr) {
  std::vector<Event> out;
  for (const ContactEvent& e : tr.stats.contact_events) {
    out.push_back({m.system.constraint(e.constraint).name(), e.kind, e.t, e.impulse, e.speed_before,
                   e.speed_after});
  }
  return out;
}

// The box's corners 0 (−b, −h) and 1 (+b, −h) are the block's bottom corners, left and right;
// its top corners 2 and 3 never touch. The box runs as the two point contacts do: the same
// events, at the same times, with the same impulses (1e-12), and the same motion.
TEST(ContactBox, RockingBlockAsABoxRunsAsItsTwoCornerContacts) {
  const Model box =
      parse_model(rocking_block("contacts:\n"
                                "  - {name: base, body: block, shape: box, size: [b, h]}\n"
                                "nonideal:\n"
                                "  - {friction: coulomb, constraint: base, mu: mu}\n"));
  const Model two =
      parse_model(rocking_block("contacts:\n"
                                "  - {name: left, body: block, point: [-b, -h]}\n"
                                "  - {name: right, body: block, point: [b, -h]}\n"
                                "nonideal:\n"
                                "  - {friction: coulomb, constraint: left, mu: mu}\n"
                                "  - {friction: coulomb, constraint: right, mu: mu}\n"));
  for (const char* c : {"base.0", "base.1", "base.2", "base.3"}) {
    EXPECT_TRUE(box.system.constraint(box.system.constraint_index(c)).is_unilateral()) << c;
    EXPECT_GE(box.system.constraint_index(std::string("stick.coulomb.") + c), 0) << c;
  }
  const Trajectory tb = simulate(box.system, box.q0, box.qd0, box.options);
  const Trajectory t2 = simulate(two.system, two.q0, two.qd0, two.options);
  ASSERT_EQ(tb.stats.status, Status::kOk) << tb.stats.message;
  ASSERT_EQ(t2.stats.status, Status::kOk) << t2.stats.message;
  const std::vector<Event> eb = events(box, tb), e2 = events(two, t2);
  ASSERT_EQ(eb.size(), e2.size());
  ASSERT_GE(eb.size(), 6u);
  for (std::size_t i = 0; i < eb.size(); ++i) {
    EXPECT_EQ(eb[i].contact, e2[i].contact == "left" ? "base.0" : "base.1") << "event " << i;
    EXPECT_EQ(eb[i].kind, e2[i].kind) << "event " << i;
    EXPECT_NEAR(eb[i].t, e2[i].t, 1e-12) << "event " << i;
    EXPECT_NEAR(eb[i].impulse, e2[i].impulse, 1e-12) << "event " << i;
    EXPECT_NEAR(eb[i].before, e2[i].before, 1e-12) << "event " << i;
    EXPECT_NEAR(eb[i].after, e2[i].after, 1e-12) << "event " << i;
  }
  ASSERT_EQ(tb.t.size(), t2.t.size());
  for (std::size_t i = 0; i < tb.q.size(); ++i) EXPECT_NEAR(tb.q[i], t2.q[i], 1e-12) << i;
}

// The same block in natural coordinates (examples/models/rocking_block.yaml: its bottom corners'
// positions, contacts `left` and `right`, friction along x1, x2): the same sequence of impacts
// and releases at the same times (to the runs' tolerance, 1e-7), and each impact keeps the
// angular momentum about the landing corner, so the corners' speeds drop by
// r = 1 − (3/2) sin²α, α = atan(b/h) (0.7931), from one impact to the next.
TEST(ContactBox, RockingBlockAsABoxRunsAsTheNaturalCoordinatesModel) {
  const Model box =
      parse_model(rocking_block("contacts:\n"
                                "  - {name: base, body: block, shape: box, size: [b, h]}\n"
                                "nonideal:\n"
                                "  - {friction: coulomb, constraint: base, mu: mu}\n"));
  const Model nat = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/rocking_block.yaml");
  const Trajectory tb = simulate(box.system, box.q0, box.qd0, box.options);
  const Trajectory tn = simulate(nat.system, nat.q0, nat.qd0, nat.options);
  ASSERT_EQ(tb.stats.status, Status::kOk) << tb.stats.message;
  ASSERT_EQ(tn.stats.status, Status::kOk) << tn.stats.message;
  const std::vector<Event> eb = events(box, tb), en = events(nat, tn);
  ASSERT_EQ(eb.size(), en.size());
  for (std::size_t i = 0; i < eb.size(); ++i) {
    EXPECT_EQ(eb[i].contact, en[i].contact == "left" ? "base.0" : "base.1") << "event " << i;
    EXPECT_EQ(eb[i].kind, en[i].kind) << "event " << i;
    EXPECT_NEAR(eb[i].t, en[i].t, 1e-7) << "event " << i;
  }
  // the impacts' speeds before, each r times the previous one's
  const double alpha = std::atan(0.2 / 0.5), r = 1 - 1.5 * std::sin(alpha) * std::sin(alpha);
  std::vector<double> before;
  for (const Event& e : eb) {
    if (e.kind == ContactEvent::Kind::kImpact) before.push_back(e.before);
  }
  ASSERT_GE(before.size(), 3u);
  for (std::size_t i = 1; i < 3; ++i)
    EXPECT_NEAR(before[i] / before[i - 1], r, 1e-8) << "impact " << i;
  // the first one's by energy: the block falls from th0 onto its face, its centre dropping by
  // d sin(α + th0)·… : ω² = 2 m g Δy / I_O, I_O = 4/3 m d², d = √(b² + h²); the landing corner's
  // speed 2 b ω
  const double b = 0.2, h = 0.5, th0 = 0.2, d = std::hypot(b, h);
  const double dy = d * std::cos(alpha - th0) - h;
  const double w = std::sqrt(2 * kG * dy / (4.0 / 3.0 * d * d));
  EXPECT_NEAR(before[0], -2 * b * w, 1e-8);
}

// A spatial box (half-extents 0.2, 0.1, 0.05, m = 2) dropped flat from h0 = 0.5 above the floor
// (e = 0.5): its four bottom corners (k = 0…3, −hz) land at once at t0 = √(2 h0/g), at
// v0 = −√(2 g h0), with impulses that sum to (1 + e) m |v0| and no rotation; after the bounces
// (an accumulation of impacts) it rests level at its half-height with the four corners carrying
// m g between them.
TEST(ContactBox, SpatialBoxDroppedFlatLandsOnItsFourCornersAtOnceAndRests) {
  const double m_ = 2.0, hz = 0.05, h0 = 0.5, e = 0.5;
  const Model m = parse_model(
      "parameters: {m: 2, hx: 0.2, hy: 0.1, hz: 0.05}\n"
      "bodies:\n"
      "  - {name: lid, type: rigid, mass: m, inertia: [m*(hy^2 + hz^2)/3, m*(hx^2 + hz^2)/3, "
      "m*(hx^2 + hy^2)/3], position: [0.3, -0.2, 0.55], visual: {shape: box, size: [0.4, 0.2, "
      "0.1]}}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -9.81]}\n"
      "contacts:\n"
      "  - {name: floor, body: lid, shape: box, size: [hx, hy, hz], restitution: 0.5}\n"
      "simulate: {t_end: 2, integrator: dopri5, rtol: 1e-10, atol: 1e-12}\n"
      "output: {every: 0.01}\n");
  const ModelRun run = run_model(m);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double t0 = std::sqrt(2 * h0 / kG), v0 = -std::sqrt(2 * kG * h0);
  // the first impact: the four bottom corners land at t0, together; the impulse (1 + e) m |v0|
  // is split among them evenly (the split of redundant contacts is not unique: the least-norm
  // one, not a vertex of the LCP's solutions — two diagonal corners — docs/contact.md), each
  // event at v0 and leaving at −e v0
  const std::size_t nq = 7;
  const std::size_t at0 = testing::sample_at(tr, 0.31);
  for (int c = 0; c < 4; ++c) {
    // (each bottom corner 0.5 m − |v| t above the floor before it lands)
    const Index k = m.system.constraint_index("floor." + std::to_string(c));
    EXPECT_NEAR(testing::gap_of(m.system, k, Eigen::Map<const VectorXd>(&tr.q[nq * at0], Index(nq)),
                                Eigen::Map<const VectorXd>(&tr.qd[nq * at0], Index(nq)))[0],
                h0 - 0.5 * kG * 0.31 * 0.31, 1e-9)
        << "corner " << c;
  }
  double impulse = 0;
  int landed = 0;
  for (const ContactEvent& ev : tr.stats.contact_events) {
    if (std::abs(ev.t - t0) > 1e-6) continue;
    const std::string name = m.system.constraint(ev.constraint).name();
    EXPECT_TRUE(name == "floor.0" || name == "floor.1" || name == "floor.2" || name == "floor.3")
        << name;
    EXPECT_EQ(ev.kind, ContactEvent::Kind::kImpact) << name;
    EXPECT_NEAR(ev.t, t0, 1e-9) << name;
    EXPECT_NEAR(ev.speed_before, v0, 1e-8) << name;
    EXPECT_NEAR(ev.speed_after, -e * v0, 1e-8) << name;
    EXPECT_NEAR(ev.impulse, -(1 + e) * m_ * v0 / 4, 1e-8) << name;
    impulse += ev.impulse;
    ++landed;
  }
  EXPECT_EQ(landed, 4);
  EXPECT_NEAR(impulse, -(1 + e) * m_ * v0, 1e-8);
  for (int c = 4; c < 8; ++c) {
    const Index k = m.system.constraint_index("floor." + std::to_string(c));
    EXPECT_TRUE(testing::events_of(tr, k, ContactEvent::Kind::kImpact).empty()) << "corner " << c;
  }
  // at the end: at rest at z = hz, level (the quaternion (1, 0, 0, 0)), m g on the four corners
  const std::size_t last = tr.t.size() - 1, n = nq, nc = std::size_t(m.system.constraint_count());
  EXPECT_NEAR(tr.q[n * last + 0], 0.3, 1e-9);
  EXPECT_NEAR(tr.q[n * last + 1], -0.2, 1e-9);
  EXPECT_NEAR(tr.q[n * last + 2], hz, 1e-9);
  EXPECT_NEAR(tr.q[n * last + 3], 1.0, 1e-9);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(tr.qd[n * last + i], 0.0, 1e-9) << i;
  double carried = 0;
  for (int c = 0; c < 4; ++c)
    carried +=
        tr.lambda[nc * last + std::size_t(m.system.constraint_index("floor." + std::to_string(c)))];
  EXPECT_NEAR(carried, m_ * kG, 1e-7);
  // the viewer's contact points are the corners: at the end (0.3 ∓ 0.2, −0.2 ∓ 0.1, 0.05 ∓ 0.05),
  // the floor's normal e_z
  const auto value = [&](const std::string& name) {
    for (const CsvColumn& c : run.extra_columns) {
      if (c.name == name) return c.values.back();
    }
    ADD_FAILURE() << "no column " << name;
    return 0.0;
  };
  for (int c = 0; c < 8; ++c) {
    const std::string at = "visual.contact.floor." + std::to_string(c) + ".";
    EXPECT_NEAR(value(at + "x"), 0.3 + (c & 1 ? 0.2 : -0.2), 1e-9) << c;
    EXPECT_NEAR(value(at + "y"), -0.2 + (c & 2 ? 0.1 : -0.1), 1e-9) << c;
    EXPECT_NEAR(value(at + "z"), c & 4 ? 0.1 : 0.0, 1e-9) << c;
    EXPECT_NEAR(value(at + "nz"), 1.0, 1e-15) << c;
  }
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-7);
}

// ---- errors -------------------------------------------------------------------------------------

TEST(ContactBox, BadBoxContactsGetAClearErrorWithItsPlace) {
  const auto expect = [](const std::string& contact, const std::string& where,
                         const std::string& what, const std::string& type = "rigid") {
    const std::string body =
        type == "planar"
            ? "  - {name: a, type: planar, mass: 1, inertia: 1, position: [0, 1]}\n"
            : "  - {name: a, type: " + type + ", mass: 1" +
                  (type == "rigid" ? ", inertia: [1, 1, 1]" : "") + ", position: [0, 0, 1]}\n";
    testing::expect_model_error("bodies:\n" + body + "contacts:\n  - " + contact + "\n", where,
                                what);
  };
  expect("{name: c, body: a, shape: box, size: [0.1, 0, 0.1]}", "4:48",
         "contact 'c': the box's half-extents must be > 0, got 0");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, -1]}", "4:53",
         "contact 'c': the box's half-extents must be > 0, got -1");
  expect("{name: c, body: a, shape: box}", "4:5", "contact 'c' (a box) needs 'size'");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1]}", "4:42",
         "contact 'c' size must be a list of 3 numbers");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1]}", "4:42",
         "contact 'c' size must be a list of 2 numbers", "planar");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, size: [0.1, 0.1, 0.1]}", "4:58",
         "contact 'c': size is for a box, not a sphere");
  expect("{name: c, body: a, size: [0.1, 0.1, 0.1]}", "4:30",
         "contact 'c': size is for a box, not a point");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1], radius: 0.1}", "4:67",
         "contact 'c': a box has no radius");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1], sphere: {radius: 0.1}}", "4:67",
         "contact 'c': a box against a sphere is not supported");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1]}", "4:31",
         "contact 'c': a particle has no orientation, so it cannot carry a box", "particle");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1], axis: [0, 0, 1]}", "4:65",
         "contact 'c': axis is for a disk, not a box");
  // the box's name is its friction's: unique among the contacts (a corner's name <name>.<k> is
  // no identifier, which no other entry can take)
  expect("{name: c.2, body: a}", "4:12", "a contact: the name 'c.2' is not an identifier");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1]}\n  - {name: c, body: a}", "5:12",
         "contact 'c' is declared twice");
  // a corner below the floor at the start: the run's inconsistent initial state names it
  Model m = parse_model(
      "bodies:\n"
      "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0.05]}\n"
      "contacts:\n"
      "  - {name: c, body: a, shape: box, size: [0.1, 0.1, 0.1]}\n"
      "simulate: {t_end: 0.1}\n");
  try {
    simulate(m.system, m.q0, m.qd0, m.options);
    ADD_FAILURE() << "no error";
  } catch (const InconsistentInitialState& e) {
    EXPECT_NE(std::string(e.what()).find("the unilateral constraint 'c.0' is penetrated"),
              std::string::npos)
        << e.what();
  }
  // friction on the box: each corner's; on a corner: that one's; twice: refused
  const std::string text =
      "bodies:\n"
      "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
      "contacts:\n"
      "  - {name: c, body: a, shape: box, size: [0.1, 0.1, 0.1]}\n"
      "nonideal:\n";
  const Model all = parse_model(text + "  - {friction: coulomb, constraint: c, mu: 0.3}\n");
  for (int k = 0; k < 8; ++k)
    EXPECT_GE(all.system.constraint_index("stick.coulomb.c." + std::to_string(k)), 0) << k;
  const Model one = parse_model(text + "  - {friction: coulomb, constraint: c.5, mu: 0.3}\n");
  EXPECT_GE(one.system.constraint_index("stick.coulomb.c.5"), 0);
  EXPECT_EQ(one.system.friction_contacts().size(), 1u);
  try {
    parse_model(text + "  - {friction: coulomb, constraint: c.5, mu: 0.3}\n" +
                "  - {friction: coulomb, constraint: c, mu: 0.3}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 7);
    EXPECT_NE(e.message().find("the friction at contact 'c' is declared twice (at 'c.5')"),
              std::string::npos)
        << e.message();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
