// SPDX-License-Identifier: BSD-3-Clause
// Coulomb friction at a robot's disk contact and on a plane of a link (issue #31;
// tree::contact_kinematics, tree::disk_contact_kinematics; docs/contact.md, "Contacts on robots"):
// the rows [n; t_1; t_2] J_rel at random states of the 7-DOF arm against the relative velocity of
// the two material points at the contact point from differences of their positions, row 0
// against the contact row's A, the bias against differences of the rows along q'; a wheel in
// joint coordinates as an upright disk (the sphere's closed form: rolls from
// t* = v0 / (3.75 mu g) at 0.8 v0); a block on a free platform (a plane of a link) sliding until
// the two move together at the closed-form instant, the friction's work closing the balance,
// as a point and as a disk; the refusals that remain.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "support/contact_runs.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;
const std::string kData = UKDYN_TEST_DATA_DIR;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using tree::LinkDisk;
using tree::LinkFrame;
using tree::LinkPoint;
constexpr auto* at = &testing::coordinate_at;

// ---- the rows against the material points' relative velocity ----------------------------------

// the plane frame whose z axis is the unit normal n (x, y ⊥ n)
LinkFrame plane_frame(Index link, const Vector3d& p, const Vector3d& n) {
  const Vector3d z = n.normalized(), x = z.unitOrthogonal();
  LinkFrame f{link, p, Matrix3d::Identity()};
  f.R << x, z.cross(x), z;
  return f;
}

// world position of link `link`'s material point p_L at q (the world's: p_L itself)
Vector3d material_point(const tree::Tree& t, const VectorXd& q, Index link, const Vector3d& p_L) {
  if (link < 0) return p_L;
  tree::TreeData d(t);
  tree::forward_kinematics(t, q, d);
  return tree::world_point(d, link, p_L);
}

TEST(TreeContactFriction, RowsAreTheRelativeVelocityOfTheMaterialPointsAndTheBiasTheirRate) {
  const tree::Tree panda = tree::load_urdf(kData + "/panda_arm.urdf");
  const Index tool = panda.link_index("panda_tool"), l3 = panda.link_index("panda_link3");
  const Vector3d centre(0.01, 0.02, 0.05), axis(0.3, -0.2, 1.0);
  const double r = 0.04;
  const std::vector<LinkFrame> planes = {
      plane_frame(-1, Vector3d(0.3, -0.1, 0.2), Vector3d(0.3, -0.5, 1.0)),
      plane_frame(l3, Vector3d(0.05, 0.1, -0.02), Vector3d(0.2, 1.0, -0.4))};
  // (states from Eigen's Random: std::rand, the same sequence in every run of this test)
  std::srand(15);
  int checked = 0;
  for (int trial = 0; trial < 5; ++trial) {
    const VectorXd q = 1.5 * VectorXd::Random(7), qd = VectorXd::Random(7);
    for (const LinkFrame& plane : planes) {
      for (const bool disk : {false, true}) {
        const LinkDisk shape{tool, centre, axis, r};
        const ContactKinematics kin =
            disk ? tree::disk_contact_kinematics(panda, "c", shape, plane)
                 : tree::contact_kinematics(panda, "c", {tool, centre}, r, plane);
        const Constraint row = disk
                                   ? tree::disk_contact_constraint(panda, "c", shape, plane, q)
                                   : tree::contact_constraint(panda, "c", {tool, centre}, r, plane);
        ASSERT_EQ(kin.tangents, 2);
        ASSERT_EQ(kin.columns.size(), 7u);
        auto scratch = kin.make_scratch(7);
        MatrixXd J(3, 7), Jp(3, 7), Jm(3, 7);
        VectorXd bias(3), unused(3);
        kin.evaluate(q, qd, 0.0, scratch.get(), J, bias);
        // the plane's axes n, t_1, t_2 and the contact point x from forward kinematics
        tree::TreeData d(panda);
        tree::forward_kinematics(panda, q, d);
        const Matrix3d R =
            plane.link < 0 ? plane.R : Matrix3d(d.R_WL[std::size_t(plane.link)] * plane.R);
        const Vector3d n = R.col(2), c = tree::world_point(d, tool, centre);
        const Vector3d a = d.R_WL[std::size_t(tool)] * axis.normalized();
        const Vector3d x =
            disk ? Vector3d(c - r * (n - n.dot(a) * a).normalized()) : Vector3d(c - r * n);
        // the material points at x of the two links, moved along q' by ± h
        const auto local = [&](Index link) -> Vector3d {
          if (link < 0) return x;
          return d.R_WL[std::size_t(link)].transpose() *
                 (x - tree::world_point(d, link, Vector3d::Zero()));
        };
        const Vector3d xC = local(tool), xP = local(plane.link);
        const double h = 1e-6;
        const Vector3d v_rel = (material_point(panda, q + h * qd, tool, xC) -
                                material_point(panda, q - h * qd, tool, xC) -
                                material_point(panda, q + h * qd, plane.link, xP) +
                                material_point(panda, q - h * qd, plane.link, xP)) /
                               (2.0 * h);
        const Vector3d rows[3] = {n, R.col(0), R.col(1)};
        for (int i = 0; i < 3; ++i)
          EXPECT_NEAR(J.row(i).dot(qd), rows[i].dot(v_rel), 1e-8 * (1.0 + v_rel.norm()))
              << "trial " << trial << " plane " << plane.link << " disk " << disk << " row " << i;
        // row 0 is the contact row's A, bias[0] its −b (g'' = A q'' − b)
        auto row_scratch = row.model().make_scratch(7);
        MatrixXd A(1, 7);
        VectorXd b(1);
        row.model().acceleration_form(q, qd, 0.0, row_scratch.get(), A, b);
        EXPECT_NEAR((J.row(0) - A.row(0)).norm(), 0.0, 1e-12 * (1.0 + A.norm()));
        EXPECT_NEAR(bias[0], -b[0], 1e-10 * (1.0 + std::abs(b[0])));
        // the bias is T' q': central differences of the rows along q'
        kin.evaluate(q + h * qd, qd, 0.0, scratch.get(), Jp, unused);
        kin.evaluate(q - h * qd, qd, 0.0, scratch.get(), Jm, unused);
        const VectorXd fd = (Jp - Jm) * qd / (2.0 * h);
        EXPECT_NEAR((bias - fd).norm(), 0.0, 1e-7 * (1.0 + fd.norm()))
            << "trial " << trial << " plane " << plane.link << " disk " << disk;
        EXPECT_GT(bias.tail(2).norm(), 0.01);  // (a real check: the rates are not small)
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 20);
}

// ---- runs against closed forms -----------------------------------------------------------------

// the multiplier of constraint `name`'s first row at sample i
constexpr auto* lambda_of = &testing::first_multiplier;

// the model `text` (its URDF in tests/data) run and sampled at `times`: it ends ok, refusing no
// stick, with one event (the located stick), and the friction's work `work` (closed form) closes
// its energy balance
Trajectory run_model(const std::string& text, std::vector<double> times, double work) {
  Model m = parse_model(text, kData + "/robot.yaml");
  m.options.output_at = std::move(times);
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.stick_refusals, 0);
  EXPECT_EQ(tr.stats.events, 1);
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  EXPECT_NEAR(tr.work_nonideal.back(), work, 1e-7);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_nonideal.back(), 1e-8);
  return tr;
}

// a robot model: `urdf` (in tests/data) with the contact `contact` named "c" and Coulomb friction
// mu there, launched with q' = {`launch`}, run to t_end to tight tolerances
std::string friction_model(const std::string& urdf, const std::string& contact, double mu,
                           const std::string& launch, double t_end) {
  return "robot: {urdf: " + urdf + "}\ncontacts:\n  - {name: c, " + contact +
         "}\nnonideal:\n  - {friction: coulomb, constraint: c, mu: " + std::to_string(mu) +
         "}\ninitial:\n  q_dot: {" + launch + "}\nsimulate: {t_end: " + std::to_string(t_end) +
         ", integrator: dopri5, rtol: 1e-11, atol: 1e-13}\noutput: {every: 0}\n";
}

// tests/data/rolling_wheel.urdf: prismatic x (carriage 1 kg), prismatic z (carriage 1 kg), pitch
// about y of a wheel (2 kg, r = 0.1, I = ½ m r² = 0.01), a sphere of radius r at the wheel's
// centre, or an upright disk of axis y (its lowest point r below the centre: the same closed
// form), on the floor. Launched along x at v0 without spin: N = (m_z + m_w) g = 3 g (the x
// carriage does not move in z), the carriages and the wheel decelerate at a = mu N / 4, the
// wheel spins up at phi'' = r mu N / I, and the contact point's speed v − r phi' vanishes at
// t* = v0 / (a + r² mu N / I) = v0 / (3.75 mu g), v* = 0.8 v0; then it rolls (stuck, no
// friction). The friction: −mu N on x and its moment r mu N on the pitch while it slides; its
// work ½ M v*² + ½ I (v*/r)² − ½ M v0².
TEST(TreeContactFriction, WheelAsASphereOrAnUprightDiskRollsFromTheClosedFormInstant) {
  const double v0 = 1.2, mu = 0.25, r = 0.1, I = 0.01, N = 3.0 * kG, M = 4.0;
  const double a = mu * N / M, alpha = r * mu * N / I;
  const double t_star = v0 / (a + r * alpha), v_star = v0 - a * t_star;
  EXPECT_NEAR(t_star, v0 / (3.75 * mu * kG), 1e-15);
  const double loss =
      0.5 * M * v0 * v0 - 0.5 * M * v_star * v_star - 0.5 * I * (v_star / r) * (v_star / r);
  for (const std::string shape : {"link: wheel, shape: sphere, radius: 0.1",
                                  "link: wheel, shape: disk, radius: 0.1, axis: [0, 1, 0]"}) {
    const Trajectory tr = run_model(friction_model("rolling_wheel.urdf", shape, mu, "x: 1.2", 0.5),
                                    {0.02, 0.08, t_star - 1e-4, t_star + 1e-4, 0.3, 0.5}, -loss);
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i];
      const bool sliding = t < t_star;
      EXPECT_NEAR(at(tr, tr.qd, "x", i), sliding ? v0 - a * t : v_star, 1e-8)
          << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.qd, "pitch", i), sliding ? alpha * t : v_star / r, 1e-7)
          << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "z", i), 0.0, 1e-9) << shape << " t = " << t;
      // the physical normal force N = 3 g; the gap row's A is e_z on z: lambda = N
      EXPECT_NEAR(lambda_of(tr, "c", i), N, 1e-7) << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.Qc_nonideal, "x", i), sliding ? -mu * N : 0.0, 1e-7)
          << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.Qc_nonideal, "pitch", i), sliding ? r * mu * N : 0.0, 1e-8)
          << shape << " t = " << t;
    }
  }
}

// tests/data/block_platform.urdf: a platform (M = 3 kg) free on prismatic px, a block on
// prismatic bx (carriage 0.5 kg) and bz (block 1.5 kg), its contact on the platform's top (a plane
// of the link "platform"). The platform launched at V0 under the block at rest: N = 1.5 g, the
// friction mu N pushes the block (mass m = 2 along x: v_b = mu N t / m) and holds the platform
// back (v_p = V0 − mu N t / M), so the slip v_p − v_b closes at mu N (1/m + 1/M) until
// t* = V0 / (mu N (1/m + 1/M)); then both move at V* = M V0 / (M + m), stuck. The friction's work:
// −½ (m M / (m + M)) V0². The contact as a point at the block's origin, or as a disk (r = 0.05,
// axis y, centre r above) whose lowest point is that point.
TEST(TreeContactFriction, BlockOnAFreePlatformSlidesUntilTheyMoveTogether) {
  const double V0 = 1.5, mu = 0.3, M = 3.0, m = 2.0, N = 1.5 * kG;
  const double k = mu * N * (1.0 / m + 1.0 / M), t_star = V0 / k, V_star = M * V0 / (M + m);
  const double work = -0.5 * m * M / (m + M) * V0 * V0;
  for (const std::string shape :
       {"link: block, plane: {link: platform}",
        "link: block, shape: disk, radius: 0.05, point: [0, 0, 0.05], axis: [0, 1, 0], plane: "
        "{link: platform, point: [0, 0, 0], normal: [0, 0, 1]}"}) {
    const std::string text = friction_model("block_platform.urdf", shape, mu, "px: 1.5", 0.8);
    const Trajectory tr =
        run_model(text, {0.05, 0.2, t_star - 1e-4, t_star + 1e-4, 0.6, 0.8}, work);
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i];
      const bool sliding = t < t_star;
      const double vb = sliding ? mu * N / m * t : V_star,
                   vp = sliding ? V0 - mu * N / M * t : V_star;
      EXPECT_NEAR(at(tr, tr.qd, "bx", i), vb, 1e-8) << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.qd, "px", i), vp, 1e-8) << shape << " t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "bz", i), 0.0, 1e-9) << shape << " t = " << t;
      EXPECT_NEAR(lambda_of(tr, "c", i), N, 1e-7) << shape << " t = " << t;
      // the friction pushes the block and holds the platform back while they slide
      EXPECT_NEAR(at(tr, tr.Qc_nonideal, "bx", i), sliding ? mu * N : 0.0, 1e-7) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.Qc_nonideal, "px", i), sliding ? -mu * N : 0.0, 1e-7) << "t = " << t;
    }
  }
}

// a disk on a plane of a link takes friction (both were refused); coordinates stay refused
TEST(TreeContactFriction,
     RobotContactFrictionOnALinksPlaneAtADiskIsReadAndStillRefusesCoordinates) {
  const std::string head = R"(
robot: {urdf: block_platform.urdf}
contacts:
  - {name: pad, link: block, shape: disk, radius: 0.05, point: [0, 0, 0.05], axis: [0, 1, 0],
     plane: {link: platform}}
nonideal:
)";
  const auto error_of = [&](const std::string& entry) -> std::string {
    try {
      parse_model(head + entry, kData + "/robot.yaml");
    } catch (const ModelError& e) {
      return std::to_string(e.line()) + ":" + std::to_string(e.column()) + " " + e.message();
    }
    return "no error";
  };
  EXPECT_EQ(error_of("  - {friction: coulomb, constraint: pad, mu: 0.3}\n"), "no error");
  const std::string coords =
      error_of("  - {friction: coulomb, constraint: pad, mu: 0.3, coordinates: [bx]}\n");
  EXPECT_EQ(coords.substr(0, 5), "7:64 ") << coords;
  EXPECT_NE(coords.find("it takes no coordinates"), std::string::npos) << coords;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
