// SPDX-License-Identifier: BSD-3-Clause
// Robots per RK4 step (issue #30 item 5): kinematic trees in joint coordinates against MuJoCo's
// mj_step (RK4, contacts disabled) on the same tree written as exact MJCF
// (tests/reference/tree_mjcf.hpp), against the same arm written with bodies and joints in
// absolute coordinates (multibody.hpp), task-space control against plain forward dynamics, and
// the time to load a URDF of 100 links.
//
// Robots: the 7-DOF Panda-like arm (tests/data/panda_arm.urdf, damping on joints 1-4) and the
// humanoid (examples/robots/humanoid.urdf: 26 revolute joints on a floating pelvis, 33
// coordinates, 32 DOF, damped joints), each from a fixed state with every joint moving, under
// gravity; h = 1 ms.
//
//   bench_tree_step                    Google Benchmark: wall time per step (or per load)
//   bench_tree_step --count ID STEPS   STEPS steps of one case and nothing else, for callgrind:
//     valgrind --tool=callgrind --toggle-collect='run_case*' bench_tree_step --count ID 1000
//     instructions per step = Ir / STEPS. IDs:
//       panda_rk4, humanoid_rk4            ukdyn's simulate(), RK4, default settings otherwise
//       panda_rk4_tuned, humanoid_rk4_tuned  the same with output_every = 0 (no samples between
//                                          the ends) and no energy-balance check
//       panda_mujoco, humanoid_mujoco      mj_step with mjINT_RK4
//       panda_bodies_rk4                   the arm as 7 rigid bodies and 7 spatial revolute joints
//       panda_fd, panda_control            one forward_dynamics / one compute_control (the tool's
//                                          6-D pose and a posture row) per "step"
//       panda_control_rk4                  simulate_controlled(), RK4, default settings
//       load_urdf100                       STEPS loads of a generated 100-link URDF
//       load_chain4000                     STEPS loads of a 4000-link chain (linear: u20 03)
//   bench_tree_step --check            the accuracy of each comparison (the same motion?)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include <benchmark/benchmark.h>

#include <Eigen/Eigenvalues>

#include <ukdyn/control/control.hpp>
#include <ukdyn/core/autodiff.hpp>
#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/multibody/multibody.hpp>
#include <ukdyn/multibody/tree.hpp>
#include <ukdyn/simulation/simulate.hpp>

#ifdef UKDYN_BENCH_MUJOCO
#include <mujoco/mujoco.h>

#include "reference/tree_mjcf.hpp"
#endif

namespace ukdyn::tree {
namespace {

constexpr double kStep = 1e-3;
const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";
const std::string kHumanoid = std::string(UKDYN_ROBOTS_DIR) + "/humanoid.urdf";

// ---- the robots and their states ------------------------------------------------------------

struct Robot {
  Tree tree;
  VectorXd q0, qd0;
};

Robot panda() {
  Robot r{load_urdf(kPanda), VectorXd(7), VectorXd(7)};
  r.q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  r.qd0 << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  return r;
}

// the pelvis at rest at the origin turning at ω = (0.3, −0.2, 0.5) rad/s (u' = ½ (0, ω) at u =
// 1), every joint at a fixed angle and rate
Robot humanoid() {
  Robot r{load_urdf(kHumanoid), VectorXd(), VectorXd()};
  const Index n = r.tree.coordinate_count();
  r.q0 = r.tree.neutral();
  r.qd0 = VectorXd::Zero(n);
  r.qd0.segment<4>(3) << 0, 0.15, -0.1, 0.25;
  for (Index i = 7; i < n; ++i) {
    r.q0[i] = 0.3 * std::sin(double(i));
    r.qd0[i] = 0.8 * std::cos(double(3 * i));
  }
  return r;
}

SimulationOptions rk4_options(long steps, bool tuned) {
  SimulationOptions o;
  o.integrator = Integrator::kRK4;
  o.step = kStep;
  o.t_end = double(steps) * kStep;
  if (tuned) {
    o.output_every = 0.0;
    o.energy_balance_tolerance = HUGE_VAL;
  }
  return o;
}

// ---- the Panda with bodies and joints in absolute coordinates -------------------------------

// the arm as rigid bodies (multibody.hpp): one per moving link, its fixed children's mass merged
// (the tool into link 7); the body frame at the centre of mass along the principal axes; one
// spatial revolute joint (5 rows) per revolute joint, its frames' z along the axis; URDF's
// damping as the joints' viscous friction. Links fixed to the world are the ground.
struct Bodies {
  mb::MultibodyModel model;
  mb::BodyId tool_body = mb::kGround;
  Vector3d tool_point;  // the tool frame's origin in its body's frame
};

Bodies bodies_of(const Robot& r) {
  const Tree& tree = r.tree;
  TreeData d(tree);
  forward_kinematics(tree, r.q0, d);
  const Index links = tree.link_count(), n = tree.coordinate_count();
  // per link: merged mass, com and inertia about it (link frame), then principal axes V
  std::vector<double> mass(std::size_t(links), 0.0);
  std::vector<Vector3d> com(std::size_t(links), Vector3d::Zero());
  std::vector<Matrix3d> inertia(std::size_t(links), Matrix3d::Zero());
  std::vector<Index> owner(
      static_cast<std::size_t>(links));  // the moving link (or -1) a link is part of
  for (Index i = 0; i < links; ++i) {
    const Index p = tree.parent(i);
    owner[std::size_t(i)] = tree.dofs(i) > 0 ? i : (p < 0 ? -1 : owner[std::size_t(p)]);
  }
  // each link's mass into its owner's, in the owner's frame: R, p of the link in the owner
  std::vector<Matrix3d> R_OL(static_cast<std::size_t>(links));
  std::vector<Vector3d> p_OL(static_cast<std::size_t>(links));
  for (Index i = 0; i < links; ++i) {
    const Index o = owner[std::size_t(i)];
    if (o < 0) continue;
    const std::size_t k = std::size_t(i), ko = std::size_t(o);
    R_OL[k] = d.R_WL[ko].transpose() * d.R_WL[k];
    p_OL[k] = d.R_WL[ko].transpose() * (d.p_WL[k] - d.p_WL[ko]);
    const Inertial& in = tree.link(i).inertial;
    const double m = mass[ko] + in.mass;
    const Vector3d c = R_OL[k] * in.com + p_OL[k];
    const Vector3d c_new = (mass[ko] * com[ko] + in.mass * c) / m;
    // parallel axes to the new centre
    const auto shift = [](double mk, const Vector3d& dk) {
      return Matrix3d(mk * (dk.squaredNorm() * Matrix3d::Identity() - dk * dk.transpose()));
    };
    inertia[ko] = inertia[ko] + shift(mass[ko], com[ko] - c_new) +
                  R_OL[k] * in.I_com * R_OL[k].transpose() + shift(in.mass, c - c_new);
    mass[ko] = m;
    com[ko] = c_new;
  }
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n);
  mb::Multibody sys;
  std::vector<mb::BodyId> body(std::size_t(links), mb::kGround);
  std::vector<Matrix3d> V(std::size_t(links), Matrix3d::Identity());
  for (Index i = 0; i < links; ++i) {
    const std::size_t k = std::size_t(i);
    if (tree.dofs(i) == 0) continue;
    if (tree.link(i).joint.kind != JointKind::kRevolute &&
        tree.link(i).joint.kind != JointKind::kContinuous) {
      std::fprintf(stderr, "bodies_of: revolute joints only\n");
      std::exit(1);
    }
    const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(inertia[k]);
    V[k] = eig.eigenvectors();
    if (V[k].determinant() < 0) V[k].col(2) *= -1;
    const Matrix3d R_WB = d.R_WL[k] * V[k];
    frame_jacobian(tree, d, i, com[k], J);
    body[k] = sys.add_rigid_body(tree.link(i).name, mass[k], eig.eigenvalues(),
                                 d.p_WL[k] + d.R_WL[k] * com[k], Eigen::Quaterniond(R_WB),
                                 J.bottomRows<3>() * r.qd0, J.topRows<3>() * r.qd0);
  }
  // the body a link is part of (ground for a link fixed to the world)
  const auto body_of = [&](Index l) {
    const Index o = owner[std::size_t(l)];
    return o < 0 ? mb::kGround : body[std::size_t(o)];
  };
  // a frame of link `l` (R, p in the link frame) in its body's frame (the world's for ground)
  const auto in_body = [&](Index l, const Matrix3d& R, const Vector3d& p) {
    const Index o = owner[std::size_t(l)];
    mb::Frame f;
    const Matrix3d R_WL = d.R_WL[std::size_t(l)] * R;
    const Vector3d p_W = d.p_WL[std::size_t(l)] + d.R_WL[std::size_t(l)] * p;
    if (o < 0) {
      f.R = R_WL;
      f.p = p_W;
      return f;
    }
    const std::size_t ko = std::size_t(o);
    const Matrix3d R_WB = d.R_WL[ko] * V[ko];
    const Vector3d p_WB = d.p_WL[ko] + d.R_WL[ko] * com[ko];
    f.R = R_WB.transpose() * R_WL;
    f.p = R_WB.transpose() * (p_W - p_WB);
    return f;
  };
  for (Index i = 0; i < links; ++i) {
    if (tree.dofs(i) == 0) continue;
    const Joint& j = tree.link(i).joint;
    const Index p = tree.parent(i);
    const Matrix3d R_JZ =
        Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), j.axis).toRotationMatrix();
    // on the child: the link frame (the joint frame after the motion); on the parent: the joint
    // frame at q0, i.e. the child's frame turned back by q0 about the axis
    const mb::Frame fc = in_body(i, R_JZ, Vector3d::Zero());
    mb::Frame fp;
    if (p < 0) {
      fp.R = j.R_PJ.toRotationMatrix() * R_JZ;
      fp.p = j.p_PJ;
    } else {
      fp = in_body(p, j.R_PJ.toRotationMatrix() * R_JZ, j.p_PJ);
    }
    mb::Joint joint =
        mb::revolute(j.name, p < 0 ? mb::kGround : body_of(p), fp, body[std::size_t(i)], fc);
    joint.friction.viscous = j.damping;
    sys.add_joint(joint);
  }
  sys.set_gravity(tree.gravity());
  Bodies out{sys.build(), mb::kGround, Vector3d::Zero()};
  const Index tool = tree.link_index("panda_tool");
  out.tool_body = body_of(tool);
  out.tool_point = in_body(tool, Matrix3d::Identity(), Vector3d::Zero()).p;
  return out;
}

// ---- task-space control of the Panda's tool --------------------------------------------------

// the tool's 6-D pose along a 5 cm circle turning 0.3 rad about z, and joint 3 held (posture)
struct Tracking {
  Robot robot = panda();
  System plant = make_system(robot.tree);
  Controller ctrl = build();
  Controller build() const {
    const Index tool = robot.tree.link_index("panda_tool");
    TreeData d(robot.tree);
    forward_kinematics(robot.tree, robot.q0, d);
    const Vector3d p0 = world_point(d, tool, Vector3d::Zero());
    const Matrix3d R0 = d.R_WL[std::size_t(tool)];
    const auto path = [p0, R0](double t, PoseSample& s) {
      const double w = 2.0, c = std::cos(w * t), sn = std::sin(w * t), r = 0.05;
      s.p = p0 + r * Vector3d(c - 1, sn, 0);
      s.v = r * w * Vector3d(-sn, c, 0);
      s.a = -r * w * w * Vector3d(c, sn, 0);
      s.R = Eigen::AngleAxisd(0.3 * sn, Vector3d::UnitZ()).toRotationMatrix() * R0;
      s.w = Vector3d(0, 0, 0.3 * w * c);
      s.w_dot = Vector3d(0, 0, -0.3 * w * w * sn);
    };
    const double q3 = robot.q0[2];
    return ControllerBuilder(plant)
        .require(pose_requirement(robot.tree, "tool", {tool, Vector3d::Zero()}, path),
                 ErrorDynamics::second_order(20.0, 1.0))
        .require(holonomic("posture", 1,
                           [q3](const auto& q, const auto&, auto& e) { e[0] = q[2] - q3; }),
                 ErrorDynamics::second_order(20.0, 1.0))
        .build();
  }
};

// ---- a URDF of 100 links ----------------------------------------------------------------------

// a branched tree of 100 links (a spine of 20, each spine link carrying a 4-link limb), every
// joint revolute with limits, damping, an inertial and a box visual: what a large robot file holds
std::string write_urdf100() {
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<robot name=\"hundred\">\n<link name=\"world\"/>\n";
  const auto link = [&](const std::string& name) {
    x << "<link name=\"" << name << "\"><inertial><origin xyz=\"0 0 0.05\" rpy=\"0.1 0 0\"/>"
      << "<mass value=\"1.0\"/><inertia ixx=\"0.01\" ixy=\"0.001\" ixz=\"0\" iyy=\"0.012\" "
      << "iyz=\"0\" izz=\"0.008\"/></inertial><visual><geometry><box size=\"0.05 0.05 0.1\"/>"
      << "</geometry></visual></link>\n";
  };
  const auto joint = [&](const std::string& name, const std::string& parent,
                         const std::string& child, const char* axis) {
    x << "<joint name=\"" << name << "\" type=\"revolute\"><parent link=\"" << parent
      << "\"/><child link=\"" << child << "\"/><origin xyz=\"0 0.02 0.1\" rpy=\"0 0.1 0\"/>"
      << "<axis xyz=\"" << axis << "\"/><limit lower=\"-2\" upper=\"2\" effort=\"50\" "
      << "velocity=\"3\"/><dynamics damping=\"0.1\" friction=\"0.05\"/></joint>\n";
  };
  std::string spine = "world";
  for (int s = 0; s < 20; ++s) {
    const std::string name = "spine" + std::to_string(s);
    link(name);
    joint(name + "_joint", spine, name, s % 2 ? "0 1 0" : "1 0 0");
    std::string parent = name;
    for (int k = 0; k < 4; ++k) {
      const std::string limb = name + "_limb" + std::to_string(k);
      link(limb);
      joint(limb + "_joint", parent, limb, k % 2 ? "0 0 1" : "0 1 0");
      parent = limb;
    }
    spine = name;
  }
  x << "</robot>\n";
  const auto path = std::filesystem::temp_directory_path() / "ukdyn_bench_urdf100.urdf";
  std::ofstream(path) << x.str();
  return path.string();
}

// ---- the cases ------------------------------------------------------------------------------

// one case: made once (not counted), then run(steps) (counted)
struct Case {
  std::function<void(long)> run;
  std::function<std::string()> result;  // a number to print, so that nothing is optimized away
};

struct Simulated {
  System sys;
  Robot robot;
  SimulationOptions options;
  Trajectory last;
};

Case simulated(Robot r, bool tuned) {
  auto s = std::make_shared<Simulated>(Simulated{make_system(r.tree), std::move(r), {}, {}});
  s->options = rk4_options(1, tuned);
  return {[s](long steps) {
            s->options.t_end = double(steps) * kStep;
            s->last = simulate(s->sys, s->robot.q0, s->robot.qd0, s->options);
          },
          [s] { return std::to_string(s->last.q.back()); }};
}

Case bodies_case() {
  auto b = std::make_shared<Bodies>(bodies_of(panda()));
  auto last = std::make_shared<Trajectory>();
  return {[b, last](long steps) {
            *last = simulate(b->model.system, b->model.q0, b->model.qd0, rk4_options(steps, false));
          },
          [last] { return std::to_string(last->q.back()); }};
}

Case control_case(bool control) {
  auto t = std::make_shared<Tracking>();
  auto ws = std::make_shared<Workspace>(t->plant);
  auto cws = std::make_shared<ControlWorkspace>(t->ctrl);
  return {[t, ws, cws, control](long steps) {
            for (long i = 0; i < steps; ++i) {
              if (control) {
                compute_control(t->ctrl, *cws, t->robot.q0, t->robot.qd0, 0.01 * double(i % 7));
              } else {
                forward_dynamics(t->plant, *ws, t->robot.q0, t->robot.qd0, 0.01 * double(i % 7));
              }
            }
          },
          [ws, cws] { return std::to_string(ws->qdd[0] + cws->Qc_control[0]); }};
}

Case controlled_rk4_case() {
  auto t = std::make_shared<Tracking>();
  auto last = std::make_shared<double>(0.0);
  return {[t, last](long steps) {
            const ControlledTrajectory run = simulate_controlled(
                t->ctrl, t->plant, t->robot.q0, t->robot.qd0, rk4_options(steps, false));
            *last = run.plant.q.back();
          },
          [last] { return std::to_string(*last); }};
}

// a chain of n links hanging from a fixed base (u20 03: its load was O(n³) in the subtree-mass
// check, 50 s for 4000 links)
std::string write_chain(int n) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i <= n; ++i) {
    x << "<link name=\"l" << i << "\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"0.01\"/>"
      << "<inertia ixx=\"1e-5\" ixy=\"0\" ixz=\"0\" iyy=\"1e-5\" iyz=\"0\" izz=\"1e-5\"/>"
      << "</inertial></link>\n<joint name=\"j" << i << "\" type=\"continuous\"><parent link=\"l"
      << i - 1 << "\"/><child link=\"l" << i << "\"/><origin xyz=\"0 0 -0.1\"/>"
      << "<axis xyz=\"0 1 0\"/></joint>\n";
  }
  x << "</robot>\n";
  const auto path =
      std::filesystem::temp_directory_path() / ("ukdyn_bench_chain" + std::to_string(n) + ".urdf");
  std::ofstream(path) << x.str();
  return path.string();
}

Case load_case(bool chain = false) {
  const std::string path = chain ? write_chain(4000) : write_urdf100();
  auto links = std::make_shared<Index>(0);
  return {[path, links](long loads) {
            for (long i = 0; i < loads; ++i) *links = load_urdf(path).link_count();
          },
          [links] { return std::to_string(*links) + " links"; }};
}

#ifdef UKDYN_BENCH_MUJOCO
struct MjRobot {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  ~MjRobot() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

// the same tree as exact MJCF, mjINT_RK4 at 1 ms, contacts disabled; qvel of a free joint is
// (p' in the world, ω in the body frame), ω_L = 2 E(u) u'
std::shared_ptr<MjRobot> mujoco_of(const Robot& r) {
  auto mj = std::make_shared<MjRobot>();
  const std::string file = reference::write_tree_mjcf(
      r.tree, "<option integrator='RK4' timestep='0.001'><flag contact='disable'/></option>");
  char error[1000] = "";
  mj->m = mj_loadXML(file.c_str(), nullptr, error, int(sizeof error));
  if (!mj->m) {
    std::fprintf(stderr, "MuJoCo: %s\n", error);
    std::exit(1);
  }
  mj->d = mj_makeData(mj->m);
  const Index n = r.tree.coordinate_count();
  const bool floating = mj->m->nv == n - 1;
  for (Index i = 0; i < n; ++i) mj->d->qpos[i] = r.q0[i];
  if (floating) {
    const Eigen::Vector4d u = r.q0.segment<4>(3);
    Eigen::Matrix<double, 3, 4> E;
    E << -u[1], u[0], u[3], -u[2], -u[2], -u[3], u[0], u[1], -u[3], u[2], -u[1], u[0];
    const Vector3d w = 2 * E * r.qd0.segment<4>(3);
    for (int i = 0; i < 3; ++i) mj->d->qvel[i] = r.qd0[i], mj->d->qvel[3 + i] = w[i];
    for (Index i = 7; i < n; ++i) mj->d->qvel[i - 1] = r.qd0[i];
  } else {
    for (Index i = 0; i < n; ++i) mj->d->qvel[i] = r.qd0[i];
  }
  return mj;
}

Case mujoco_case(const Robot& r) {
  auto mj = mujoco_of(r);
  auto start = std::make_shared<std::vector<double>>(mj->d->qpos, mj->d->qpos + mj->m->nq);
  auto vstart = std::make_shared<std::vector<double>>(mj->d->qvel, mj->d->qvel + mj->m->nv);
  return {[mj, start, vstart](long steps) {
            // from the same state each run
            std::copy(start->begin(), start->end(), mj->d->qpos);
            std::copy(vstart->begin(), vstart->end(), mj->d->qvel);
            mj->d->time = 0;
            for (long i = 0; i < steps; ++i) mj_step(mj->m, mj->d);
          },
          [mj] { return std::to_string(mj->d->qpos[mj->m->nq - 1]); }};
}
#endif

std::map<std::string, std::function<Case()>> cases() {
  std::map<std::string, std::function<Case()>> c = {
      {"panda_rk4", [] { return simulated(panda(), false); }},
      {"panda_rk4_tuned", [] { return simulated(panda(), true); }},
      {"humanoid_rk4", [] { return simulated(humanoid(), false); }},
      {"humanoid_rk4_tuned", [] { return simulated(humanoid(), true); }},
      {"panda_bodies_rk4", [] { return bodies_case(); }},
      {"panda_fd", [] { return control_case(false); }},
      {"panda_control", [] { return control_case(true); }},
      {"panda_control_rk4", [] { return controlled_rk4_case(); }},
      {"load_urdf100", [] { return load_case(); }},
      {"load_chain4000", [] { return load_case(true); }},
  };
#ifdef UKDYN_BENCH_MUJOCO
  c["panda_mujoco"] = [] { return mujoco_case(panda()); };
  c["humanoid_mujoco"] = [] { return mujoco_case(humanoid()); };
#endif
  return c;
}

// --check: the comparisons are of the same motion
int check() {
  const long steps = 500;
  // the bodies' Panda against the tree's: the tool point after 0.5 s
  {
    const Robot r = panda();
    const Bodies b = bodies_of(r);
    const Trajectory tb =
        simulate(b.model.system, b.model.q0, b.model.qd0, rk4_options(steps, true));
    const Trajectory tt = simulate(make_system(r.tree), r.q0, r.qd0, rk4_options(steps, true));
    TreeData d(r.tree);
    forward_kinematics(r.tree, r.q0, d);
    const Vector3d p_start = world_point(d, r.tree.link_index("panda_tool"), Vector3d::Zero());
    forward_kinematics(r.tree, Eigen::Map<const VectorXd>(&tt.q[tt.q.size() - 7], 7), d);
    const Vector3d p_tree = world_point(d, r.tree.link_index("panda_tool"), Vector3d::Zero());
    const Vector3d p_bodies =
        mb::world_point(b.model,
                        Eigen::Map<const VectorXd>(
                            &tb.q[tb.q.size() - std::size_t(b.model.q0.size())], b.model.q0.size()),
                        b.tool_body, b.tool_point);
    std::printf(
        "bodies vs tree, tool point after %ld RK4 steps: |difference| %.2e m (moved %.3f m)\n",
        steps, (p_tree - p_bodies).norm(), (p_tree - p_start).norm());
    std::printf("  bodies: %ld coordinates, %ld constraint rows\n", long(b.model.q0.size()),
                long(b.model.system.constraint_rows()));
  }
#ifdef UKDYN_BENCH_MUJOCO
  for (const auto& [name, make] : {std::pair<const char*, Robot (*)()>{"panda", panda},
                                   std::pair<const char*, Robot (*)()>{"humanoid", humanoid}}) {
    const Robot r = make();
    auto mj = mujoco_of(r);
    for (long i = 0; i < steps; ++i) mj_step(mj->m, mj->d);
    const Trajectory tt = simulate(make_system(r.tree), r.q0, r.qd0, rk4_options(steps, true));
    const Index n = r.tree.coordinate_count();
    const Eigen::Map<const VectorXd> q(&tt.q[tt.q.size() - std::size_t(n)], n),
        q_mj(mj->d->qpos, n);
    std::printf("%s: tree vs MuJoCo after %ld RK4 steps: max |q − q_MuJoCo| %.2e (moved %.3f)\n",
                name, steps, (q - q_mj).cwiseAbs().maxCoeff(), (q - r.q0).cwiseAbs().maxCoeff());
  }
#endif
  return 0;
}

}  // namespace
}  // namespace ukdyn::tree

/// The counted region of one case (outside any namespace, not inlined, for
/// `valgrind --tool=callgrind --toggle-collect='run_case*'`).
__attribute__((noinline)) void run_case(const ukdyn::tree::Case& c, long steps) { c.run(steps); }

namespace {

void register_benchmarks() {
  for (const auto& [name, make] : ukdyn::tree::cases()) {
    const bool one = name == "load_urdf100" || name == "load_chain4000" || name == "panda_fd" ||
                     name == "panda_control";
    const long steps = one ? 1 : 100;
    benchmark::RegisterBenchmark(name.c_str(), [factory = make, steps](benchmark::State& state) {
      const ukdyn::tree::Case c = factory();
      for (auto _ : state) run_case(c, steps);
      // items: steps (or loads, or evaluations); time per item = 1 / items_per_second
      state.SetItemsProcessed(state.iterations() * steps);
    });
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--check") == 0) return ukdyn::tree::check();
  if (argc == 4 && std::strcmp(argv[1], "--count") == 0) {
    const auto all = ukdyn::tree::cases();
    const auto it = all.find(argv[2]);
    if (it == all.end()) {
      std::fprintf(stderr, "bench_tree_step: unknown case '%s'; the cases are", argv[2]);
      for (const auto& [name, make] : all) std::fprintf(stderr, " %s", name.c_str());
      std::fprintf(stderr, "\n");
      return 2;
    }
    const ukdyn::tree::Case c = it->second();
    const long steps = std::atol(argv[3]);
    run_case(c, steps);
    std::printf("%s: %ld steps; %s\n", argv[2], steps, c.result().c_str());
    return 0;
  }
  register_benchmarks();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
