// SPDX-License-Identifier: BSD-3-Clause
// contacts: in robot model files (modelfile/reader_robot_contacts.cpp, issue #31 item 3), each
// against a closed form: a one-link pendulum (tests/data/contact_pendulum.urdf: hinge about y at
// height H = 0.5 m, mass m = 2 kg at L_c = 0.6 m, I_hinge = 0.05 + m L_c², tip sphere r = 0.05 at
// L = 0.8 m) released horizontal falls on the floor z = 0 at sin θ* = (H − r) / L and bounces:
// θ'⁺ = −e θ'⁻ at every impact, the kinetic energy at the k-th impact e^(2k) T₁ with
// T₁ = m g L_c sin θ* (from the contact pose), the energy balance certified; resting on the floor
// its contact force is m g L_c / L, and a torque −k t lifts it off at t = m g L_c cos θ* / k (a
// located release); and the errors a user meets, located. A disk (contact_slider_disk.urdf: a
// wheel of radius 0.2 tilted by initial: q about x on a vertical slider from 0.5 m) hits the
// floor at t₀ = √(2 (0.5 − 0.2 sin β) / g) (the impulse at the rim turns it towards flat, which
// it reaches near 0.378 s: the run ends before); one with no bounce whose impact turns it flat
// stops the run naming the contact, as a bodies model's coin does.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/core/status.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kData = UKDYN_TEST_DATA_DIR;
constexpr double kG = 9.81;
// the pendulum's numbers (contact_pendulum.urdf) and its contact
constexpr double kM = 2.0, kLc = 0.6, kL = 0.8, kH = 0.5, kR = 0.05, kI = 0.05 + kM * kLc * kLc;

Model robot_model(const std::string& text) { return parse_model(text, kData + "/robot.yaml"); }

std::vector<ContactEvent> events_of(const Trajectory& tr, ContactEvent::Kind kind) {
  std::vector<ContactEvent> out;
  for (const auto& e : tr.stats.contact_events) {
    if (e.kind == kind) out.push_back(e);
  }
  return out;
}

constexpr const char* kBouncing = R"(
robot: {urdf: contact_pendulum.urdf}
contacts:
  - {name: tip, link: rod, point: [0.8, 0, 0], shape: sphere, radius: 0.05, restitution: 0.5}
simulate: {t_end: 0.9, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)";

TEST(ModelRobotContacts, PendulumTipBouncesOnTheFloorWithNewtonsLaw) {
  const double e = 0.5;
  Model m = robot_model(kBouncing);
  ASSERT_EQ(m.system.constraint_count(), 1);
  EXPECT_TRUE(m.system.constraint(0).is_unilateral());
  EXPECT_EQ(m.system.constraint(0).restitution(), e);
  const Trajectory first = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(first.stats.status, Status::kOk) << first.stats.message;
  const auto impacts = events_of(first, ContactEvent::Kind::kImpact);
  // (t_end 0.9 s: six impacts, before their accumulation point near 0.914 s; the rest is
  // PendulumTipComesToRestAtTheAccumulationPoint)
  ASSERT_EQ(impacts.size(), 6u);
  // the impact pose and the first approach speed from the energy: ½ I θ'² = m g L_c sin θ*
  const double s = (kH - kR) / kL, th = std::asin(s);
  const double T1 = kM * kG * kLc * s, w1 = std::sqrt(2.0 * T1 / kI);
  const double A = -kL * std::cos(th);  // g' = A θ'
  std::vector<double> at;
  for (std::size_t k = 0; k < 6; ++k) {
    const double ek = std::pow(e, double(k));
    EXPECT_NEAR(impacts[k].speed_before, A * ek * w1, 1e-8 * w1) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_after, -e * impacts[k].speed_before, 1e-12) << "impact " << k;
    // T⁻ = e^(2k) T₁, T⁺ − T⁻ = −(1 − e²) e^(2k) T₁
    EXPECT_NEAR(impacts[k].energy_change, -(1.0 - e * e) * ek * ek * T1, 1e-8 * T1)
        << "impact " << k;
    at.push_back(impacts[k].t);
  }
  // the pose at the impacts: θ = θ*; θ' just after = −e θ' just before (1 DOF)
  m.options.output_at = at;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  std::size_t found = 0;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    for (std::size_t k = 0; k < at.size(); ++k) {
      if (tr.t[i] != at[k]) continue;
      ++found;
      EXPECT_NEAR(tr.q[i], th, 1e-9) << "impact " << k;
    }
  }
  EXPECT_GE(found, at.size());
  // the energy balance: all that is lost is the impacts' work, and the run is certified
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  double lost = 0.0;
  for (const auto& ev : tr.stats.contact_events) lost += ev.energy_change;
  EXPECT_NEAR(tr.work_impact.back(), lost, 1e-9 * T1);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-7 * T1);
  // the energy left after six impacts, relative to the contact pose, is e^12 T₁: E(0.9) − E(0)
  // = e^12 T₁ − T₁ (E(0) = T₁ + the contact pose's potential)
  EXPECT_EQ(tr.t.back(), 0.9);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), (std::pow(e, 12) - 1.0) * T1, 1e-8 * T1);
}

// The impacts accumulate: the approach speeds fall as e^k, so the rest criterion (an approach
// below 1e-6 of the fastest: docs/contact.md, "Rest") takes the impact k with e^k < 1e-6, the
// 21st for e = 0.5 (0.5^20 = 9.5e-7), which closes the contact; then the tip rests on the floor
// (θ = θ*, θ' = 0; its force: PendulumRestsOnTheFloorUntilATorqueLiftsIt).
// (A flight that began a few ulps below the gap's zero, as the roundoff of the sphere's offset
// gives, once sought its next impact below −1e-9, and this run stalled at its 9th impact.)
TEST(ModelRobotContacts, PendulumTipComesToRestAtTheAccumulationPoint) {
  const double e = 0.5;
  std::string text = kBouncing;
  text.replace(text.find("t_end: 0.9"), 10, "t_end: 1.2");
  Model m = robot_model(text);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
  const auto rests = events_of(tr, ContactEvent::Kind::kRest);
  ASSERT_EQ(impacts.size(), 20u);
  ASSERT_EQ(rests.size(), 1u);
  const double s = (kH - kR) / kL, th = std::asin(s);
  const double w1 = std::sqrt(2.0 * kM * kG * kLc * s / kI);
  const double A = -kL * std::cos(th);
  EXPECT_NEAR(rests[0].speed_before, A * std::pow(e, 20) * w1, 1e-3 * std::pow(e, 20) * w1);
  EXPECT_EQ(rests[0].speed_after, 0.0);
  // the rest comes after the sixth impact (0.9 s > its time) and before 0.92 s: the flights
  // after impact k last about 2 e^k θ'₁ / α, α = m g L_c cos θ* / I, a geometric sum
  EXPECT_GT(rests[0].t, 0.9);
  EXPECT_LT(rests[0].t, 0.92);
  EXPECT_GT(rests[0].t, impacts.back().t);
  // at rest on the floor: θ = θ*, θ' = 0
  EXPECT_NEAR(tr.q.back(), th, 1e-9);
  EXPECT_NEAR(tr.qd.back(), 0.0, 1e-9);
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  double lost = 0.0;
  for (const auto& ev : tr.stats.contact_events) lost += ev.energy_change;
  EXPECT_NEAR(tr.work_impact.back(), lost, 1e-9 * kM * kG * kLc);
  // the run's columns (`ukdyn run`, Python): gap.tip = h − r − L sin θ at every sample
  const ModelRun run = run_model(m);
  const auto& cols = run.extra_columns;
  const auto gap = std::find_if(cols.begin(), cols.end(),
                                [](const CsvColumn& c) { return c.name == "gap.tip"; });
  ASSERT_NE(gap, cols.end());
  ASSERT_EQ(gap->values.size(), run.trajectory.t.size());
  ASSERT_GE(gap->values.size(), 2u);
  for (std::size_t i = 0; i < gap->values.size(); ++i) {
    EXPECT_NEAR(gap->values[i], kH - kR - kL * std::sin(run.trajectory.q[i]), 1e-12)
        << "sample " << i;
  }
}

// resting on the floor, then lifted by a torque −k t
constexpr const char* kResting = R"(
parameters: {k: 20}
robot: {urdf: contact_pendulum.urdf, torques: {hinge: -k*t}}
contacts:
  - name: tip
    link: rod
    point: [0.8, 0, 0]
    shape: sphere
    radius: 0.05
    plane: {body: ground, point: [0, 0, 0], normal: [0, 0, 1]}
initial: {q: {hinge: asin(0.5625)}}
simulate: {t_end: 0.8, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
)";

TEST(ModelRobotContacts, PendulumRestsOnTheFloorUntilATorqueLiftsIt) {
  const double k = 20.0, s = (kH - kR) / kL, c = std::sqrt(1.0 - s * s);
  const double t_release = kM * kG * kLc * c / k;
  Model m = robot_model(kResting);
  ASSERT_NEAR(m.q0[0], std::asin(s), 1e-15);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // one event: the release, located where the force reaches zero
  ASSERT_EQ(tr.stats.contact_events.size(), 1u);
  EXPECT_EQ(tr.stats.contact_events[0].kind, ContactEvent::Kind::kRelease);
  EXPECT_NEAR(tr.stats.contact_events[0].t, t_release, 1e-8);
  // before it: at rest on the floor, the force (m g L_c cos θ* − k t) / (L cos θ*)
  int checked = 0;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    if (t < t_release - 1e-6) {
      EXPECT_NEAR(tr.q[i], std::asin(s), 1e-10) << "t = " << t;
      EXPECT_NEAR(tr.qd[i], 0.0, 1e-10) << "t = " << t;
      EXPECT_NEAR(tr.lambda[i], (kM * kG * kLc * c - k * t) / (kL * c), 1e-8) << "t = " << t;
      ++checked;
    } else if (t > t_release + 1e-6) {
      // lifted: the force is zero and the tip rises (θ below θ*)
      EXPECT_NEAR(tr.lambda[i], 0.0, 1e-12) << "t = " << t;
      EXPECT_LT(tr.q[i], std::asin(s)) << "t = " << t;
    }
  }
  EXPECT_GE(checked, 9);
  // at rest at t = 0 the force is the static m g L_c / L
  EXPECT_NEAR(tr.lambda[0], kM * kG * kLc / kL, 1e-8);
}

// the message and line of a model's ModelError
struct Failure {
  std::string text;
  int line = -1;
};
Failure failure_of(const std::string& contact) {
  try {
    robot_model("robot: {urdf: contact_pendulum.urdf}\ncontacts:\n  - " + contact + "\n");
  } catch (const ModelError& e) {
    return {e.message() + " | " + e.hint(), e.line()};
  }
  return {"no error", -1};
}

TEST(ModelRobotContacts, ErrorsNameTheContactAndTheKey) {
  const auto expect = [](const std::string& contact, const std::string& part) {
    const Failure f = failure_of(contact);
    EXPECT_NE(f.text.find(part), std::string::npos) << contact << " → " << f.text;
    EXPECT_EQ(f.line, 3) << contact;
  };
  expect("{name: tip, link: rod, colour: red}", "unknown key 'colour' in contact 'tip'");
  expect("{name: tip, link: shin}", "contact 'tip': no link 'shin'");
  expect("{name: tip, link: rod, shape: sphere, radus: 0.1}",
         "unknown key 'radus' in contact 'tip' | did you mean 'radius'?");
  expect("{name: tip, link: rod, plane: {normals: [0, 0, 1]}}",
         "unknown key 'normals' in the plane of contact 'tip' | did you mean 'normal'?");
  expect("{name: tip, body: rod}", "names its link, not a body | link: rod");
  // the keys listed are those a robot's contact takes: `body` is not one (u15 10)
  {
    const Failure f = failure_of("{name: tip, link: rod, stiffness: 1e5}");
    EXPECT_NE(f.text.find("the keys are name, link, point, shape, radius, axis, plane, "
                          "restitution, restitution_law"),
              std::string::npos)
        << f.text;
    EXPECT_EQ(f.text.find("body"), std::string::npos) << f.text;
  }
  // the hints name this robot's links (its last), not an example's
  expect("{name: tip}", "contact 'tip' needs link: the link its point is fixed on | link: rod");
  // a contact on a link welded to the world against a plane of the world: its gap never changes
  expect("{name: tip, link: base}",
         "contact 'tip': link 'base' and the plane are both welded to the world");
  expect("{name: tip, link: rod, shape: sphere}", "contact 'tip': a sphere needs radius");
  expect("{name: tip, link: rod, radius: 0.1}", "contact 'tip': a point has no radius");
  expect("{name: tip, link: rod, shape: sphere, radius: -1}", "radius must be > 0");
  // (the rod's z axis, a disk's default axis, is the floor's normal at q = 0)
  expect("{name: tip, link: rod, shape: disk, radius: 0.1}",
         "constraint 'tip': the disk lies flat on its plane at the start (|n·a| = 1)");
  expect("{name: tip, link: rod, shape: disk}", "contact 'tip': a disk needs radius");
  expect("{name: tip, link: rod, shape: disk, radius: 0.1, axis: [0, 0, 0]}",
         "contact 'tip': the disk's axis is zero");
  expect("{name: tip, link: rod, shape: disk, radius: 0.1, axis: [1, 0]}",
         "contact 'tip': axis must be a list of 3 numbers");
  expect("{name: tip, link: rod, shape: cube}", "shape must be point, sphere or disk, got 'cube'");
  // a bodies model's box, with its size: named as the shape a robot lacks (u18 06d: it was
  // "unknown key 'size'")
  expect("{name: tip, link: rod, shape: box, size: [0.1, 0.1, 0.1]}",
         "shape must be point, sphere or disk, got 'box' | a robot's contacts are points");
  expect("{name: tip, link: rod, shape: sphere, radius: 0.1, axis: [0, 0, 1]}",
         "axis is for disks only");
  expect("{name: tip, link: rod, plane: {normal: [0, 0, 0]}}", "the plane's normal is zero");
  expect("{name: tip, link: rod, restitution: 1.5}",
         "the restitution of contact 'tip' must lie in [0, 1]");
  expect("{name: tip, link: rod, restitution_law: elastic}", "must be newton or poisson");
  expect("{name: tip, link: rod, plane: {link: rod}}", "the plane is on the contact's own link");
  expect("{name: tip, link: rod, plane: {body: table}}", "on the ground or on a link");
  // a name taken by a loop
  try {
    robot_model(
        "robot:\n  urdf: contact_pendulum.urdf\n  loops: [{name: tip, type: distance, link_a: rod, "
        "link_b: world, point_b: [0, 0, 0], length: 0.5}]\ncontacts:\n  - {name: tip, link: "
        "rod}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("contact 'tip': the name is taken"), std::string::npos)
        << e.message();
    EXPECT_EQ(e.line(), 5);
  }
  // a requirement named like a contact: refused, naming the contact, at the requirement's name
  // (the same rule as a bodies model's: tests/modelfile/test_model_control.cpp; u22 08)
  try {
    robot_model(
        "robot: {urdf: contact_pendulum.urdf}\ncontacts:\n  - {name: tip, link: rod}\ncontrol:\n"
        "  requirements:\n    - {name: tip, holonomic: hinge - 0.1}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.message(), "the name 'tip' is taken by the contact 'tip'") << e.message();
    EXPECT_EQ(e.line(), 6);
    EXPECT_EQ(e.column(), 14);
  }
  // Coulomb friction at a robot's contact slides the contact point: coordinates: refused there
  // (tests/simulation/test_contact_bodies_friction.cpp has the motion and the other errors)
  try {
    robot_model(
        "robot: {urdf: contact_pendulum.urdf}\ncontacts:\n  - {name: tip, link: rod}\nnonideal:\n"
        "  - {friction: coulomb, constraint: tip, mu: 0.3, coordinates: [hinge]}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("the friction at contact 'tip' slides the contact point itself"),
              std::string::npos)
        << e.message();
    EXPECT_EQ(e.line(), 5);
  }
  // an initial state that penetrates: the run names the contact and its gap 0.5 − 0.8 sin 1.2
  const Model m = robot_model(
      "robot: {urdf: contact_pendulum.urdf}\ncontacts:\n  - {name: tip, link: rod, point: "
      "[0.8, 0, 0]}\ninitial: {q: {hinge: 1.2}}\n");
  try {
    simulate(m.system, m.q0, m.qd0, m.options);
    ADD_FAILURE() << "no error";
  } catch (const InconsistentInitialState& e) {
    EXPECT_NE(std::string(e.what()).find("the unilateral constraint 'tip' is penetrated"),
              std::string::npos)
        << e.what();
    ASSERT_EQ(e.constraints().size(), 1u);
    EXPECT_EQ(e.constraints()[0], "tip");
    // said to be a penetration (Python's cause "penetrated"): projection does not act on a gap,
    // project_initial cannot help (u15 10)
    EXPECT_TRUE(contacts_penetrated(m, e));
  }
  // a Coulomb friction on a constraint of a model with none (contacts: []): no empty list in
  // the hint (u15 10)
  try {
    robot_model(
        "robot: {urdf: contact_pendulum.urdf}\ncontacts: []\nnonideal:\n"
        "  - {friction: coulomb, constraint: tip, mu: 0.3}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.message(), "no constraint named 'tip'");
    EXPECT_NE(e.hint().find("the model has no constraint"), std::string::npos) << e.hint();
  }
  // urdf: . is a directory, not a missing file (u15 10)
  try {
    robot_model("robot: {urdf: .}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("is a directory, not a URDF file"), std::string::npos)
        << e.message();
  }
}

constexpr const char* kSliderDisk = R"(
robot: {urdf: contact_slider_disk.urdf}
contacts:
  - {name: rim, link: wheel, shape: disk, radius: 0.2, axis: [0, 0, 1], restitution: 0.4}
initial: {q: {tilt: 0.5}}
simulate: {t_end: 0.35, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)";

TEST(ModelRobotContacts, DiskOnASliderHitsTheFloorAtTheFreeFallTime) {
  const double beta = 0.5, r = 0.2, e = 0.4;
  const Model m = robot_model(kSliderDisk);
  ASSERT_EQ(m.system.constraint_count(), 1);
  EXPECT_TRUE(m.system.constraint(0).is_unilateral());
  EXPECT_EQ(m.system.constraint(0).restitution(), e);
  EXPECT_NEAR(m.q0[1], beta, 0.0);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  const double t0 = std::sqrt(2.0 * (0.5 - r * std::sin(beta)) / kG);
  EXPECT_NEAR(impacts[0].t, t0, 1e-9);
  EXPECT_NEAR(impacts[0].speed_before, -kG * t0, 1e-8);
  EXPECT_NEAR(impacts[0].speed_after, e * kG * t0, 1e-8);
  // the gap at the start: the rim's lowest point r sin β below the centre
  auto scratch = m.system.constraint(0).model().make_scratch(2);
  VectorXd g(1), gd(1);
  m.system.constraint(0).model().violation(m.q0, m.qd0, 0.0, scratch.get(), g, gd);
  EXPECT_NEAR(g[0], 0.5 - r * std::sin(beta), 1e-15);
}

TEST(ModelRobotContacts, DiskFlatAtTheStartOrTurnedFlatIsAClearError) {
  // flat at the start (tilt 0): located at the contact, naming it
  try {
    robot_model(std::string(kSliderDisk)
                    .replace(std::string(kSliderDisk).find("tilt: 0.5"), 9, "tilt: 0.0"));
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("'rim': the disk lies flat on its plane at the start"),
              std::string::npos)
        << e.message();
    EXPECT_EQ(e.line(), 4);
  }
  // a slight tilt and no bounce: the impact spins the wheel towards flat, q_tilt' < 0, and the
  // closed contact carries it there; the run stops naming the contact and the cause, keeping
  // the samples before
  std::string text = kSliderDisk;
  text.replace(text.find("tilt: 0.5"), 9, "tilt: 0.1");
  text.replace(text.find("restitution: 0.4"), 16, "restitution: 0.0");
  text.replace(text.find("every: 0.01"), 11, "every: 0.001");
  const Model m = robot_model(text);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_NE(tr.stats.status, Status::kOk);
  EXPECT_NE(tr.stats.message.find("'rim'"), std::string::npos) << tr.stats.message;
  EXPECT_NE(tr.stats.message.find("lies flat"), std::string::npos) << tr.stats.message;
  const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, std::sqrt(2.0 * (0.5 - 0.2 * std::sin(0.1)) / kG), 1e-9);
  ASSERT_GE(tr.t.size(), 2u);
  EXPECT_GT(tr.t.back(), impacts[0].t);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
