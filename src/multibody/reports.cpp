// SPDX-License-Identifier: BSD-3-Clause
// Reports of a multibody model: poses, velocities, energies and momenta of the bodies; the
// reaction of each joint (ideal and friction parts) reduced to the joint point; driving efforts;
// and the poses of every body at every sample of a trajectory, for animation.
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <stdexcept>

#include "multibody/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::mb {

using detail::BodyRef;

Pose body_pose(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q, BodyId b) {
  const BodyInfo& info = mb.bodies.at(std::size_t(b));
  const Index o = info.offset;
  Pose p;
  switch (info.kind) {
    case BodyKind::kParticle:
      p.p_WB = q.segment<3>(o);
      break;
    case BodyKind::kPlanar:
      p.p_WB = Vector3d(q[o], q[o + 1], 0.0);
      p.R_WB = Quaterniond(Eigen::AngleAxisd(q[o + 2], Vector3d::UnitZ()));
      break;
    case BodyKind::kRigid:
      p.p_WB = q.segment<3>(o);
      p.R_WB = Quaterniond(q[o + 3], q[o + 4], q[o + 5], q[o + 6]).normalized();
      break;
  }
  return p;
}

std::pair<Vector3d, Vector3d> body_velocity(const MultibodyModel& mb,
                                            const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, BodyId b) {
  const BodyInfo& info = mb.bodies.at(std::size_t(b));
  const BodyRef ref = detail::body_ref(mb.bodies, b);
  const Index o = info.offset;
  const Vector3d v =
      info.kind == BodyKind::kPlanar ? Vector3d(qd[o], qd[o + 1], 0.0) : Vector3d(qd.segment<3>(o));
  return {v, detail::angular_velocity_W(ref, q, qd)};
}

double kinetic_energy(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, BodyId b) {
  const BodyInfo& info = mb.bodies.at(std::size_t(b));
  const auto [v, w] = body_velocity(mb, q, qd, b);
  double T = 0.5 * info.mass * v.squaredNorm();
  if (info.kind == BodyKind::kPlanar) T += 0.5 * info.inertia.z() * w.z() * w.z();
  if (info.kind == BodyKind::kRigid) {
    // ω_B = R_WBᵀ ω_W;  ½ ω_Bᵀ J ω_B
    const Vector3d wB = detail::rotation_WB(detail::body_ref(mb.bodies, b), q).transpose() * w;
    T += 0.5 * wB.dot(info.inertia.asDiagonal() * wB);
  }
  return T;
}

double total_energy(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, double t) {
  double E = mb.system.potential_energy(q, t);
  for (BodyId b = 0; b < BodyId(mb.bodies.size()); ++b) E += kinetic_energy(mb, q, qd, b);
  return E;
}

std::pair<Vector3d, Vector3d> momentum(const MultibodyModel& mb,
                                       const Eigen::Ref<const VectorXd>& q,
                                       const Eigen::Ref<const VectorXd>& qd) {
  Vector3d P = Vector3d::Zero(), L = Vector3d::Zero();
  for (BodyId b = 0; b < BodyId(mb.bodies.size()); ++b) {
    const BodyInfo& info = mb.bodies[std::size_t(b)];
    const auto [v, w] = body_velocity(mb, q, qd, b);
    const Vector3d r = body_pose(mb, q, b).p_WB;
    P += info.mass * v;
    L += r.cross(info.mass * v);
    if (info.kind == BodyKind::kPlanar) L.z() += info.inertia.z() * w.z();
    if (info.kind == BodyKind::kRigid) {
      // R J Rᵀ ω_W
      const Matrix3d R = detail::rotation_WB(detail::body_ref(mb.bodies, b), q);
      L += R * (info.inertia.asDiagonal() * (R.transpose() * w));
    }
  }
  return {P, L};
}

Vector3d world_point(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q, BodyId b,
                     const Vector3d& p) {
  detail::VecKin k;
  const VectorXd zero = VectorXd::Zero(q.size());
  BodyRef ref = detail::body_ref(mb.bodies, b);
  detail::add_body_vector(ref, q, zero, p, true, 1.0, k);
  if (ref.kind == BodyKind::kRigid) {
    // the quadratic R(u) carries |u|²: divide the rotated part by it
    const double u2 = q.segment<4>(ref.offset + 3).squaredNorm();
    k.x = q.segment<3>(ref.offset) + (k.x - q.segment<3>(ref.offset)) / u2;
  }
  return k.x;
}

namespace {

// generalized force g (n) on body b → (force, torque about its centre of mass), world frame
std::pair<Vector3d, Vector3d> wrench_of(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& g) {
  const Index o = b.offset;
  switch (b.kind) {
    case BodyKind::kParticle:
      return {g.segment<3>(o), Vector3d::Zero()};
    case BodyKind::kPlanar:
      return {Vector3d(g[o], g[o + 1], 0.0), Vector3d(0.0, 0.0, g[o + 2])};
    case BodyKind::kRigid: {
      // g_u = 2 G_vᵀ tau + (part along u, which no torque makes): tau = G_v g_u / (2 |u|²)
      const detail::Vector4d u = q.segment<4>(o + 3);
      return {g.segment<3>(o), detail::G_v(u) * g.segment<4>(o + 3) / (2.0 * u.squaredNorm())};
    }
  }
  return {};
}

// Σ A_kᵀ lambda_k over the listed constraints (n)
VectorXd shares_of(const System& sys, const std::vector<Index>& ks,
                   const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                   double t, const Eigen::Ref<const VectorXd>& lambda) {
  VectorXd g = VectorXd::Zero(sys.coordinate_count());
  for (Index k : ks) {
    const Constraint& c = sys.constraint(k);
    MatrixXd A(c.rows(), sys.coordinate_count());
    VectorXd b(c.rows());
    auto scratch = c.model().make_scratch(sys.coordinate_count());
    c.model().acceleration_form(q, qd, t, scratch.get(), A, b);
    g += A.transpose() * lambda.segment(sys.row_offset(k), c.rows());
  }
  return g;
}

// reduce a generalized force on the reporting body of joint j to the joint point
void reduce(const MultibodyModel& mb, const JointInfo& J, const Eigen::Ref<const VectorXd>& q,
            const Eigen::Ref<const VectorXd>& g, Vector3d& F, Vector3d& tau, BodyId& on) {
  on = J.child != kGround ? J.child : J.parent;
  const Vector3d p = J.child != kGround ? J.frame_child.p : J.frame_parent.p;
  const BodyRef ref = detail::body_ref(mb.bodies, on);
  const auto [f, t] = wrench_of(ref, q, g);
  const Vector3d r = body_pose(mb, q, on).p_WB;
  const Vector3d x = world_point(mb, q, on, p);
  F = f;
  tau = t - (x - r).cross(f);
}

}  // namespace

JointReaction joint_reaction(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t,
                             const Eigen::Ref<const VectorXd>& lambda, Index j) {
  const JointInfo& J = mb.joints.at(std::size_t(j));
  if (q.size() != mb.system.coordinate_count() || qd.size() != mb.system.coordinate_count() ||
      lambda.size() != mb.system.constraint_rows()) {
    throw std::invalid_argument(
        "ukdyn::mb::joint_reaction: q, qd need " + format_number(mb.system.coordinate_count()) +
        " entries and lambda " + format_number(mb.system.constraint_rows()));
  }
  std::vector<Index> ks;
  for (Index k : J.constraints) {
    if (k != J.drive) ks.push_back(k);
  }
  const VectorXd g = shares_of(mb.system, ks, q, qd, t, lambda);
  JointReaction r;
  reduce(mb, J, q, g, r.force_W, r.torque_W, r.body);
  const Matrix3d R = detail::rotation_WB(detail::body_ref(mb.bodies, r.body), q);
  r.force_B = R.transpose() * r.force_W;
  r.torque_B = R.transpose() * r.torque_W;
  return r;
}

JointReaction joint_reaction(const MultibodyModel& mb, Workspace& ws,
                             const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t, Index j) {
  JointReaction r = joint_reaction(mb, q, qd, t, ws.lambda, j);
  const JointInfo& J = mb.joints.at(std::size_t(j));
  if (J.friction < 0) return r;
  // the friction's C, evaluated as the non-ideal stage did (it reads the joint's share)
  compute_shares(mb.system, ws);
  const IdealForceInfo ideal(mb.system, ws);
  Joint spec;
  spec.name = J.name;
  spec.type = J.type;
  spec.parent = J.parent;
  spec.child = J.child;
  spec.frame_parent = J.frame_parent;
  spec.frame_child = J.frame_child;
  spec.friction = J.friction_law;
  VectorXd C = VectorXd::Zero(q.size());
  detail::joint_friction_C(spec, detail::body_ref(mb.bodies, J.parent),
                           detail::body_ref(mb.bodies, J.child), J.planar, J.constraints.front(), q,
                           qd, ideal, C);
  BodyId on;
  reduce(mb, J, q, C, r.nonideal_force_W, r.nonideal_torque_W, on);
  return r;
}

double drive_effort(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>&,
                    const Eigen::Ref<const VectorXd>&, double,
                    const Eigen::Ref<const VectorXd>& lambda, Index j) {
  const JointInfo& J = mb.joints.at(std::size_t(j));
  if (J.drive < 0) {
    throw std::invalid_argument("ukdyn::mb::drive_effort: joint '" + J.name + "' has no drive");
  }
  // the drive row has a unit coefficient on the driven coordinate (angle or slide): its
  // multiplier is the torque (force) on the child along it
  return lambda[mb.system.row_offset(J.drive)];
}

namespace {

// a pose as 7 numbers (centre of mass, unit quaternion) and the suffixes of their columns
constexpr const char* kPoseSuffixes[7] = {".x", ".y", ".z", ".qw", ".qx", ".qy", ".qz"};
std::array<double, 7> pose_values(const Pose& p) {
  return {p.p_WB.x(), p.p_WB.y(), p.p_WB.z(), p.R_WB.w(), p.R_WB.x(), p.R_WB.y(), p.R_WB.z()};
}

}  // namespace

void write_poses_csv(const MultibodyModel& mb, const Trajectory& tr, const std::string& path) {
  if (tr.n != mb.system.coordinate_count()) {
    throw std::invalid_argument("ukdyn::mb::write_poses_csv: the trajectory has " +
                                format_number(tr.n) + " coordinates, the model " +
                                format_number(mb.system.coordinate_count()));
  }
  std::ofstream os(path);
  if (!os) throw std::runtime_error("ukdyn::mb::write_poses_csv: cannot write '" + path + "'");
  os << "t";
  for (const BodyInfo& b : mb.bodies) {
    for (const char* s : kPoseSuffixes) os << ',' << b.name << s;
  }
  os << '\n' << std::setprecision(17);
  const auto Q = Trajectory::view(tr.q, tr.n);
  for (Index i = 0; i < tr.samples(); ++i) {
    const auto q = Q.col(i);  // a view of sample i
    os << tr.t[std::size_t(i)];
    for (BodyId b = 0; b < BodyId(mb.bodies.size()); ++b) {
      for (const double v : pose_values(body_pose(mb, q, b))) os << ',' << v;
    }
    os << '\n';
  }
  if (!os) throw std::runtime_error("ukdyn::mb::write_poses_csv: error writing '" + path + "'");
}

std::vector<CsvColumn> report_csv_columns(const MultibodyModel& mb, const Trajectory& tr) {
  if (tr.n != mb.system.coordinate_count() || tr.m != mb.system.constraint_rows()) {
    throw std::invalid_argument("ukdyn::mb::report_csv_columns: the trajectory has " +
                                format_number(tr.n) + " coordinates and " + format_number(tr.m) +
                                " constraint rows, the model " +
                                format_number(mb.system.coordinate_count()) + " and " +
                                format_number(mb.system.constraint_rows()));
  }
  const std::size_t N = std::size_t(tr.samples());
  std::vector<CsvColumn> cols;
  const auto add = [&](std::string name) {
    cols.push_back(CsvColumn{std::move(name), std::vector<double>(N)});
    return cols.size() - 1;
  };
  // poses: 7 per body, without the components that are coordinates of the body (its centre
  // of mass <b>.x, <b>.y (, <b>.z) is already a standard column, with the same values); then
  // the kinetic energies. pose_column[7 b + c]: the column of component c, or −1
  const auto& coordinates = mb.system.coordinate_names();
  std::vector<std::ptrdiff_t> pose_column;
  for (const BodyInfo& b : mb.bodies) {
    for (const char* s : kPoseSuffixes) {
      const std::string name = b.name + s;
      const bool is_coordinate =
          std::find(coordinates.begin(), coordinates.end(), name) != coordinates.end();
      pose_column.push_back(is_coordinate ? -1 : std::ptrdiff_t(add(name)));
    }
  }
  const std::size_t energy0 = cols.size();
  for (const BodyInfo& b : mb.bodies) add(b.name + ".kinetic_energy");
  // joints: the reaction's components (planar: fx, fy, tz), the friction's, the drive's effort
  struct JointColumns {
    std::vector<int> components;  // indices into (force_W, torque_W) stacked
    std::size_t ideal = 0, friction = 0, drive = 0, gear = 0;
  };
  std::vector<JointColumns> jc(mb.joints.size());
  bool any_friction = false;
  for (std::size_t j = 0; j < mb.joints.size(); ++j) {
    const JointInfo& J = mb.joints[j];
    JointColumns& c = jc[j];
    const std::string base = "reaction." + J.name + ".";
    if (J.type == JointType::kGear) {  // its multiplier: the torque along joint a's angle
      c.gear = add(base + "torque");
      continue;
    }
    c.components = J.planar ? std::vector<int>{0, 1, 5} : std::vector<int>{0, 1, 2, 3, 4, 5};
    const char* names[] = {"fx", "fy", "fz", "tx", "ty", "tz"};
    c.ideal = cols.size();
    for (int k : c.components) add(base + names[k]);
    if (J.friction >= 0) {
      any_friction = true;
      c.friction = cols.size();
      for (int k : c.components) add(base + "friction_" + names[k]);
    }
    if (J.drive >= 0) c.drive = add("drive." + J.name);
  }
  const auto Q = Trajectory::view(tr.q, tr.n), Qd = Trajectory::view(tr.qd, tr.n),
             L = Trajectory::view(tr.lambda, tr.m);
  VectorXd q(tr.n), qd(tr.n), lambda(tr.m);
  std::unique_ptr<Workspace> ws;  // for the friction forces (they need an evaluation)
  if (any_friction) ws = std::make_unique<Workspace>(mb.system);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < N; ++i) {
    q = Q.col(Index(i));
    qd = Qd.col(Index(i));
    lambda = L.col(Index(i));
    const double t = tr.t[i];
    for (std::size_t b = 0; b < mb.bodies.size(); ++b) {
      const std::array<double, 7> v = pose_values(body_pose(mb, q, BodyId(b)));
      for (std::size_t c = 0; c < 7; ++c) {
        const std::ptrdiff_t col = pose_column[7 * b + c];
        if (col >= 0) cols[std::size_t(col)].values[i] = v[c];
      }
      cols[energy0 + b].values[i] = kinetic_energy(mb, q, qd, BodyId(b));
    }
    const bool evaluated =
        any_friction && forward_dynamics(mb.system, *ws, q, qd, t) == Status::kOk;
    for (std::size_t j = 0; j < mb.joints.size(); ++j) {
      const JointInfo& J = mb.joints[j];
      const JointColumns& c = jc[j];
      if (J.type == JointType::kGear) {
        cols[c.gear].values[i] = lambda[mb.system.row_offset(J.constraints.front())];
        continue;
      }
      JointReaction r;
      if (J.friction >= 0 && evaluated) {
        r = joint_reaction(mb, *ws, q, qd, t, Index(j));
      } else {
        r = joint_reaction(mb, q, qd, t, lambda, Index(j));
      }
      Eigen::Matrix<double, 6, 1> ideal, fr;
      ideal << r.force_W, r.torque_W;
      fr << r.nonideal_force_W, r.nonideal_torque_W;
      for (std::size_t k = 0; k < c.components.size(); ++k) {
        cols[c.ideal + k].values[i] = ideal[c.components[k]];
        if (J.friction >= 0) cols[c.friction + k].values[i] = evaluated ? fr[c.components[k]] : nan;
      }
      if (J.drive >= 0) cols[c.drive].values[i] = drive_effort(mb, q, qd, t, lambda, Index(j));
    }
  }
  return cols;
}

}  // namespace ukdyn::mb
