// SPDX-License-Identifier: BSD-3-Clause
// Redundant contacts and roundoff (issue #31; docs/contact.md, "Redundant contacts"): a box on its
// four bottom corners — W singular, the LCP's split a vertex that leaves one corner unloaded at
// zero gap — slides on the ground, and is thrown across a belt (a rigid body on a driven
// prismatic joint), each against its closed form. Nothing leaves or hits the floor: the unloaded
// corner's gap and gap rate, roundoff of the closed corners' (1e-16 m/s), used to be taken for
// impacts (two at 7.8e-17 m/s on the ground, one of them "separating"), the box's stop for a
// release, and on the belt the roundoff impact's LCP failed the run (u13 03, u14 05). The same
// in mm, g and ms: the thresholds are relative to each contact's scales.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// a model's units: metres, kilograms and seconds per unit of its lengths, masses and times
struct Units {
  const char* what;
  double L, M, T;
};
const Units kUnits[] = {{"m, kg, s", 1.0, 1.0, 1.0}, {"mm, g, ms", 1e-3, 1e-3, 1e-3}};

// column `name` of field f (width n) at sample i
double at(const Trajectory& tr, const std::vector<double>& f, const std::string& name,
          std::size_t i) {
  const auto& names = tr.coordinate_names;
  std::size_t c = 0;
  while (c < names.size() && names[c] != name) ++c;
  EXPECT_LT(c, names.size()) << name;
  return c < names.size() ? f[i * std::size_t(tr.n) + c] : 0.0;
}

// the run sampled at `times` (in the model's time unit; its end t_end): ok, no stick refused and
// no impact, release or rest — nothing leaves or hits the floor
Trajectory run_at(Model& m, std::vector<double> times, double t_end) {
  m.options.t_end = t_end;
  m.options.output_at = std::move(times);
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.stick_refusals, 0);
  // (the list holds the corners' sticks too since h15/events: no impact, release or rest)
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.kind == ContactEvent::Kind::kStick || e.kind == ContactEvent::Kind::kSlip) continue;
    ADD_FAILURE() << "contact event at t = " << e.t << ": kind " << int(e.kind) << ", g' before "
                  << e.speed_before << ", impulse " << e.impulse;
  }
  return tr;
}

// A box (m = 3, 2a × 2b × 2c) on its four bottom corners (Coulomb, mu = 0.4) launched at v0
// along x (u13 03): x'' = −mu g until it stops at x* = v0² / (2 mu g) at t* = v0 / (mu g), then
// rests. Written in units of L metres, M kilograms and T seconds.
constexpr const char* kSlidingBox = R"(
parameters: {L: 1, M: 1, T: 1}
bodies:
  - {name: box, type: rigid, mass: 3/M, inertia: [(3/M)*((0.1/L)^2+(0.05/L)^2)/3,
     (3/M)*((0.2/L)^2+(0.05/L)^2)/3, (3/M)*((0.2/L)^2+(0.1/L)^2)/3],
     position: [0, 0, 0.05/L], velocity: [2*T/L, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -9.81*T^2/L]}
contacts:
  - {name: c1, body: box, point: [0.2/L, 0.1/L, -0.05/L]}
  - {name: c2, body: box, point: [-0.2/L, 0.1/L, -0.05/L]}
  - {name: c3, body: box, point: [0.2/L, -0.1/L, -0.05/L]}
  - {name: c4, body: box, point: [-0.2/L, -0.1/L, -0.05/L]}
nonideal:
  - {friction: coulomb, constraint: c1, mu: 0.4}
  - {friction: coulomb, constraint: c2, mu: 0.4}
  - {friction: coulomb, constraint: c3, mu: 0.4}
  - {friction: coulomb, constraint: c4, mu: 0.4}
simulate: {rtol: 1e-10, atol: 1e-12}
)";

TEST(ContactRedundant, BoxOnFourCornersSlidesAndStopsWithoutContactEvents) {
  const double v0 = 2.0, mu = 0.4, t_stop = v0 / (mu * kG), x_stop = v0 * v0 / (2.0 * mu * kG);
  for (const Units& u : kUnits) {
    SCOPED_TRACE(u.what);
    Model m = parse_model(kSlidingBox, "<box>", {{"L", u.L}, {"M", u.M}, {"T", u.T}});
    // (in seconds: a sample every 0.05 s, and 1 ms either side of the stop)
    std::vector<double> times;
    for (int k = 1; k <= 20; ++k) times.push_back(0.05 * k);
    times.push_back(t_stop - 1e-3);
    times.push_back(t_stop + 1e-3);
    std::sort(times.begin(), times.end());
    for (double& t : times) t /= u.T;
    const Trajectory tr = run_at(m, times, 1.0 / u.T);
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i] * u.T;  // (s)
      const double s = std::min(t, t_stop);
      const double x = v0 * s - 0.5 * mu * kG * s * s, v = v0 - mu * kG * s;
      // x to 1e-9 m and x' to 1e-9 m/s, in the model's units: the stop at t* and x* to 1e-9
      // (x' 1 ms either side of t* is mu g 1e-3 and 0)
      EXPECT_NEAR(at(tr, tr.q, "box.x", i), x / u.L, 1e-9 / u.L) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.qd, "box.x", i), v * u.T / u.L, 1e-9 * u.T / u.L) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.qd, "box.y", i), 0.0, 1e-9 * u.T / u.L) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "box.z", i), 0.05 / u.L, 1e-12 / u.L) << "t = " << t;
    }
    EXPECT_NEAR(at(tr, tr.q, "box.x", tr.t.size() - 1), x_stop / u.L, 1e-9 / u.L);
    // the stop is listed: the corners the joint stick holds stick at t* (early by v_stop /
    // (mu g)), none slips (3 of the 4: one corner's stick rows are redundant with theirs)
    std::size_t sticks = 0;
    for (const ContactEvent& e : tr.stats.contact_events) {
      EXPECT_EQ(e.kind, ContactEvent::Kind::kStick);
      EXPECT_NEAR(e.t * u.T, t_stop, 1e-6);
      ++sticks;
    }
    EXPECT_GE(sticks, 1u);
    EXPECT_LE(sticks, 4u);
  }
}

// A box (m = 3, 0.4 × 0.3 × 0.1) on its four bottom corners (Coulomb, mu = 0.3, mu_s = 0.4) on a
// belt: a rigid body of mass Mb on a prismatic joint driven at V along x (u14 05). The box is
// thrown across it at vy = 1: its velocity relative to the belt, v_rel = (−V, vy) at first,
// shrinks along its own direction at mu g, v = (V, 0) + (−V, vy)(1 − mu g t / |v_rel0|), until
// t* = |v_rel0| / (mu g); then it rides with the belt. V = 2 failed at t = 0.4935 (the LCP of a
// roundoff "impact" of the unloaded corner had no solution), V = 0 at t = 0.0202; Mb = 1 ran
// with three roundoff impacts at 1e-18 m/s.
constexpr const char* kBelt = R"(
parameters: {L: 1, M: 1, T: 1, Mb: 50, V: 2, vy: 1, a: 0.2, b: 0.15, c: 0.05}
bodies:
  - {name: belt, type: rigid, mass: Mb/M, inertia: [10/(M*L^2), 10/(M*L^2), 10/(M*L^2)],
     velocity: [V*T/L, 0, 0]}
  - {name: box, type: rigid, mass: 3/M, inertia: [(3/M)*(4*b^2+4*c^2)/(12*L^2),
     (3/M)*(4*a^2+4*c^2)/(12*L^2), (3/M)*(4*a^2+4*b^2)/(12*L^2)],
     position: [0, 0, c/L], velocity: [0, vy*T/L, 0]}
joints:
  - {name: drive, type: prismatic, parent: ground, child: belt, parent_axis: [1, 0, 0],
     child_axis: [1, 0, 0], drive: (V*T/L)*t}
forces:
  - {type: gravity, g: [0, 0, -9.81*T^2/L]}
contacts:
  - {name: c1, body: box, point: [-a/L, -b/L, -c/L], plane: {body: belt}}
  - {name: c2, body: box, point: [a/L, -b/L, -c/L], plane: {body: belt}}
  - {name: c3, body: box, point: [-a/L, b/L, -c/L], plane: {body: belt}}
  - {name: c4, body: box, point: [a/L, b/L, -c/L], plane: {body: belt}}
nonideal:
  - {friction: coulomb, constraint: c1, mu: 0.3, mu_static: 0.4}
  - {friction: coulomb, constraint: c2, mu: 0.3, mu_static: 0.4}
  - {friction: coulomb, constraint: c3, mu: 0.3, mu_static: 0.4}
  - {friction: coulomb, constraint: c4, mu: 0.3, mu_static: 0.4}
)";

TEST(ContactRedundant, BoxThrownAcrossABeltSlidesToItsSpeedWithoutContactEvents) {
  const double mu = 0.3, vy = 1.0;
  struct Case {
    double V, Mb;
  };
  for (const Units& u : kUnits) {
    for (const Case c : {Case{2.0, 50.0}, Case{0.0, 50.0}, Case{2.0, 1.0}, Case{0.0, 1.0}}) {
      // (in mm, g and ms the first case only)
      if (u.L != 1.0 && !(c.V == 2.0 && c.Mb == 50.0)) continue;
      SCOPED_TRACE(std::string(u.what) + ", V = " + std::to_string(c.V) +
                   ", Mb = " + std::to_string(c.Mb));
      Model m = parse_model(kBelt, "<belt>",
                            {{"L", u.L}, {"M", u.M}, {"T", u.T}, {"V", c.V}, {"Mb", c.Mb}});
      const double v_rel0 = std::hypot(c.V, vy), t_star = v_rel0 / (mu * kG);
      std::vector<double> times;
      for (int k = 1; k <= 15; ++k) times.push_back(0.1 * k);
      times.push_back(t_star - 1e-3);
      times.push_back(t_star + 1e-3);
      std::sort(times.begin(), times.end());
      for (double& t : times) t /= u.T;
      const Trajectory tr = run_at(m, times, 1.5 / u.T);
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i] * u.T;
        // the share of v_rel left, and its integral (the path relative to the belt)
        const double s = std::min(t, t_star);
        const double f = 1.0 - mu * kG * s / v_rel0;
        const double path = s - 0.5 * mu * kG * s * s / v_rel0;
        const double vu = u.T / u.L;  // (model speed units per m/s)
        EXPECT_NEAR(at(tr, tr.qd, "box.x", i), (c.V - c.V * f) * vu, 1e-9 * vu) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.qd, "box.y", i), vy * f * vu, 1e-9 * vu) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.qd, "box.z", i), 0.0, 1e-9 * vu) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.q, "box.x", i), (c.V * t - c.V * path) / u.L, 1e-9 / u.L)
            << "t = " << t;
        EXPECT_NEAR(at(tr, tr.q, "box.y", i), vy * path / u.L, 1e-9 / u.L) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.q, "box.z", i), 0.05 / u.L, 1e-12 / u.L) << "t = " << t;
        // the belt keeps its drive
        EXPECT_NEAR(at(tr, tr.qd, "belt.x", i), c.V * vu, 1e-9 * vu) << "t = " << t;
      }
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
