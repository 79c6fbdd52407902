// SPDX-License-Identifier: BSD-3-Clause
// The contacts the viewer draws without `visual: contacts:` (modelfile/visual_contacts.hpp):
// where a contacts: entry touches its plane — a point itself, a sphere's point nearest the plane
// c − r n, a disk's rim's lowest point c − r (n − s a) / |n − s a| (s = n · a; the direction of
// steepest descent in the disk's plane, as the gap g = n · d − r √(1 − s²) of docs/contact.md) —
// and the plane's normal, in the world at q.
#include "modelfile/visual_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "dynamics/internal.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn::detail {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// the contact's point: c − r n (a sphere; r = 0: a point), or a disk's rim's lowest point
// c − r (n − s a) / |n − s a| with its axis a (the centre when it lies flat: no single point)
Vector3d contact_point(const Vector3d& c, const Vector3d& n, double r, const Vector3d* a) {
  if (a == nullptr) return c - r * n;
  const Vector3d down = n - n.dot(*a) * *a;
  const double h = down.norm();
  return h > 0.0 ? Vector3d(c - (r / h) * down) : c;
}

// The friction f (tangent axes, into f) that sample i's Qc_nonideal holds when it is this
// contact's alone: Qc_nonideal on the contact's columns = J_nᵀ λ + J_tᵀ f (its friction and the
// normal row's share of it), by least squares, accepted when that fits to 1e-6 of ‖Qc_nonideal‖
// and ‖f‖ is within 1e-6 of its full magnitude `full`. It reads a contact sliding from rest
// whose impending motion a_rel is roundoff (a control holds the body where it is: the run's
// friction takes the holding force's direction, Run::start_sliding), whose direction a_rel
// cannot give. False otherwise (another friction or constraint shares the columns: a_rel
// decides). Cost O(columns · rows²).
bool applied_friction(const Trajectory& traj, Index i, const MatrixXd& J,
                      const std::vector<Index>& columns, double full, Vector3d& f) {
  const Index n = traj.n, d = J.rows() - 1;
  if (traj.Qc_nonideal.size() < std::size_t((i + 1) * n) || !(full > 0.0)) return false;
  VectorXd Q(Index(columns.size()));
  for (std::size_t j = 0; j < columns.size(); ++j)
    Q[Index(j)] = traj.Qc_nonideal[std::size_t(i * n + columns[j])];
  const double size = Q.norm();
  if (!(size > 0.0)) return false;
  const Eigen::ColPivHouseholderQR<MatrixXd> qr(J.transpose());
  const VectorXd x = qr.solve(Q);
  if (!((J.transpose() * x - Q).norm() <= 1e-6 * size)) return false;
  if (!(std::abs(x.tail(d).norm() - full) <= 1e-6 * full)) return false;
  f.setZero();
  f.head(d) = x.tail(d);
  return true;
}

// The columns visual.contact.<name>.fx, .fy (, .fz) of contact c's Coulomb friction at a
// contact point (VisualContact::axes), at the samples of traj: f_W = Σ f_i t_i with, in the
// contact's tangent axes, f = the holding force lambda.stick (scale_stick_multipliers) while it
// holds (at a sliding speed |v| = |T q'| within the located stop speed 100 eps, or within 1e-6 of
// the run's fastest slip), else the sliding law f = −mu N v / sqrt(|v|² + eps²); at rest with the
// stick constraint off (it slides from rest along its slip hint) −mu N a_rel / |a_rel|, a_rel the
// impending motion T q'' + T' q'; with N = |lambda_total.<name>| (a contact's gap has a unit
// normal: its multiplier is the normal force). Cost O(samples · cost of the kinematics).
void add_friction_columns(const Model& model, const Trajectory& traj, const VisualContact& c,
                          std::vector<CsvColumn>& out) {
  if (!c.axes) return;
  const System& sys = model.system;
  const FrictionContact* fc = nullptr;
  for (const FrictionContact& f : sys.friction_contacts())
    if (f.kinematics && sys.constraint(f.normal_constraint).name() == c.name) fc = &f;
  if (fc == nullptr) return;
  const auto u = std::find(traj.unilateral.begin(), traj.unilateral.end(), fc->normal_constraint);
  if (u == traj.unilateral.end()) return;
  const std::size_t un = traj.unilateral.size(), ui = std::size_t(u - traj.unilateral.begin());
  const Index N = traj.samples(), n = traj.n, d = fc->kinematics.tangents,
              stick = sys.row_offset(fc->stick_constraint);
  const std::vector<Index>& columns = fc->kinematics.columns;
  std::unique_ptr<ConstraintScratch> scratch;
  if (fc->kinematics.make_scratch) scratch = fc->kinematics.make_scratch(n);
  // (the samples' lambda.stick are the holding force already: scale_stick_multipliers)
  MatrixXd J(1 + d, Index(columns.size()));
  VectorXd bias(1 + d), qd_c(Index(columns.size())), qdd_c(qd_c.size()), a_rel(d);
  static const char* const kParts[] = {"fx", "fy", "fz"};
  std::vector<CsvColumn> cols;
  for (int k = 0; k < c.dimensions; ++k)
    cols.push_back(
        {"visual.contact." + c.name + "." + kParts[k], std::vector<double>(std::size_t(N))});
  Matrix3d axes;
  // the sliding velocity (in the tangent axes) at sample i
  const auto sliding_velocity = [&](Index i) {
    const Eigen::Map<const VectorXd> q(traj.q.data() + i * n, n), qd(traj.qd.data() + i * n, n);
    fc->kinematics.evaluate(q, qd, traj.t[std::size_t(i)], scratch.get(), J, bias);
    for (std::size_t j = 0; j < columns.size(); ++j) qd_c[Index(j)] = qd[columns[j]];
    Vector3d v = Vector3d::Zero();
    for (Index a = 0; a < d; ++a) v[a] = J.row(1 + a).dot(qd_c);
    return v;
  };
  // held: within the located stop speed 100 eps, or within 1e-6 of the run's fastest slip (a
  // stuck contact drifts at the integrator's tolerance, 1e-7 mm/s in a model in mm: above
  // 100 eps there)
  double fastest = 0.0;
  for (Index i = 0; i < N; ++i) fastest = std::max(fastest, sliding_velocity(i).norm());
  const double held_below = std::max(100.0 * fc->eps, 1e-6 * fastest);
  for (Index i = 0; i < N; ++i) {
    const Eigen::Map<const VectorXd> q(traj.q.data() + i * n, n), qd(traj.qd.data() + i * n, n);
    const Vector3d v = sliding_velocity(i);  // (J at sample i)
    Vector3d f = Vector3d::Zero();           // in the tangent axes
    for (Index a = 0; a < d; ++a) f[a] = traj.lambda[std::size_t(i * traj.m + stick + a)];
    if (v.norm() <= 100.0 * fc->eps && f.isZero(0.0)) {
      // at rest (|v| <= 100 eps, where the law's slip hint acts) with its stick constraint off
      // (exactly zero multipliers): it slides from rest along its slip hint, against the impending
      // motion a_rel = T q'' + T' q' (the run's Run::start_sliding), at the full magnitude, unless
      // a_rel is roundoff of its terms (held without load: no friction)
      const Eigen::Map<const VectorXd> qdd(traj.qdd.data() + i * n, n);
      for (std::size_t j = 0; j < columns.size(); ++j) qdd_c[Index(j)] = qdd[columns[j]];
      a_rel = bias.tail(d) + J.bottomRows(d) * qdd_c;
      const double terms = bias.tail(d).norm() + J.bottomRows(d).norm() * qdd_c.norm();
      const double normal = std::abs(traj.lambda_total[std::size_t(i) * un + ui]);
      if (!applied_friction(traj, i, J, columns, fc->mu * normal, f) &&
          a_rel.norm() > 1e-8 * terms) {
        f.head(d) = -fc->mu * normal / a_rel.norm() * a_rel;
      }
    } else if (v.norm() <= held_below) {
      // held: f = the holding force lambda.stick (in force units)
    } else {
      const double normal = std::abs(traj.lambda_total[std::size_t(i) * un + ui]);
      f = -fc->mu * normal / std::sqrt(v.squaredNorm() + fc->eps * fc->eps) * v;
    }
    c.axes(q, axes);
    const Vector3d fw = f[0] * axes.col(1) + f[1] * axes.col(2);
    for (int k = 0; k < c.dimensions; ++k) cols[std::size_t(k)].values[std::size_t(i)] = fw[k];
  }
  for (CsvColumn& col : cols) out.push_back(std::move(col));
}

// The columns visual.contact.<name>.Qf.<coordinate> of the Coulomb friction on the sliding
// coordinates of visual contact c (the coordinate path): the generalized friction force on each,
// lambda.stick.<friction>[.j] while the contact holds (its stick multipliers not all zero: the
// whole holding force, scale_stick_multipliers), else Qc_nonideal.<coordinate> (the sliding
// law). Not their sum: while the contact holds, Qc_nonideal on its coordinates has the stick
// rows' non-ideal share already, which the holding force includes (another contact's sliding
// friction carried: the ladder's floor). Cost O(samples · coordinates).
void add_coordinate_friction_columns(const Model& model, const Trajectory& traj,
                                     const VisualContact& c, std::vector<CsvColumn>& out) {
  const System& sys = model.system;
  const FrictionContact* fc = nullptr;
  for (const FrictionContact& f : sys.friction_contacts()) {
    if (!f.kinematics && f.mu > 0.0 && f.normal_constraint >= 0 && f.stick_constraint >= 0 &&
        sys.constraint(f.normal_constraint).name() == c.name)
      fc = &f;
  }
  if (fc == nullptr || traj.n != sys.coordinate_count() || traj.m != sys.constraint_rows()) return;
  const Index N = traj.samples(), n = traj.n, stick = sys.row_offset(fc->stick_constraint),
              d = sys.constraint(fc->stick_constraint).rows();
  const std::size_t nc = fc->coordinates.size();
  if (d != Index(nc)) return;
  std::vector<CsvColumn> cols;
  for (Index coordinate : fc->coordinates) {
    cols.push_back(
        {"visual.contact." + c.name + ".Qf." + sys.coordinate_names()[std::size_t(coordinate)],
         std::vector<double>(std::size_t(N))});
  }
  for (Index i = 0; i < N; ++i) {
    const double* lambda = traj.lambda.data() + i * traj.m + stick;
    const bool held = !Eigen::Map<const VectorXd>(lambda, d).isZero(0.0);
    for (std::size_t j = 0; j < nc; ++j) {
      cols[j].values[std::size_t(i)] =
          held ? lambda[j] : traj.Qc_nonideal[std::size_t(i * n + fc->coordinates[j])];
    }
  }
  for (CsvColumn& col : cols) out.push_back(std::move(col));
}

}  // namespace

VisualContact robot_visual_contact(std::string name, std::shared_ptr<const tree::Tree> tree,
                                   const tree::LinkPoint& at, const Vector3d* axis, double radius,
                                   const tree::LinkFrame& plane) {
  VisualContact c;
  c.name = std::move(name);
  c.dimensions = 3;
  // (for the robot's scene: the point's link and the plane, drawn with the links)
  c.link = int(at.link);
  c.link_point = at.p;
  c.plane_link = int(plane.link);
  c.plane_point = plane.p;
  c.plane_normal = plane.R.col(2);
  const bool disk = axis != nullptr;
  const Vector3d a_L = disk ? axis->normalized() : Vector3d::Zero();
  c.geometry = [tree, at, disk, a_L, radius, plane](const Eigen::Ref<const VectorXd>& q,
                                                    Vector3d& point, Vector3d& normal) {
    // forward kinematics of the links; the plane's normal, the centre and the disk's axis
    tree::TreeData d(*tree);
    tree::forward_kinematics(*tree, q, d);
    const auto R_W = [&](Index link) {
      return link < 0 ? Matrix3d::Identity() : d.R_WL[std::size_t(link)];
    };
    normal = R_W(plane.link) * plane.R.col(2);
    const Vector3d centre = at.link < 0 ? at.p : tree::world_point(d, at.link, at.p);
    const Vector3d a_W = R_W(at.link) * a_L;
    point = contact_point(centre, normal, radius, disk ? &a_W : nullptr);
  };
  // the friction's axes (tree::contact_kinematics): the plane's z, x, y in the world
  c.axes = [tree, plane](const Eigen::Ref<const VectorXd>& q, Matrix3d& axes) {
    Matrix3d R = plane.R;
    if (plane.link >= 0) {
      tree::TreeData d(*tree);
      tree::forward_kinematics(*tree, q, d);
      R = d.R_WL[std::size_t(plane.link)] * plane.R;
    }
    axes << R.col(2), R.col(0), R.col(1);
  };
  return c;
}

VisualContact bodies_visual_contact(std::shared_ptr<const mb::MultibodyModel> model,
                                    const mb::JointInfo& joint, double radius) {
  VisualContact c;
  c.name = joint.name;
  c.dimensions = joint.planar ? 2 : 3;
  // a disk in a planar model is a circle in the plane: its contact is a sphere's
  const bool disk = joint.type == mb::JointType::kContactDisk && !joint.planar;
  const mb::BodyId P = joint.parent, C = joint.child;
  const mb::Frame fp = joint.frame_parent, fc = joint.frame_child;
  const Vector3d n_P = fp.R.col(joint.planar ? 1 : 2), a_C = fc.R.col(2);
  if (joint.type == mb::JointType::kContactSpheres ||
      joint.type == mb::JointType::kContactDiskSphere ||
      joint.type == mb::JointType::kContactSphereBox) {
    // two spheres: the normal is the line of the centres o → c (inside the other: c → o), the
    // point the contact sphere's nearest to the other's surface, c − r n; a disk and a sphere
    // (mb::contact_disk_sphere): the point the disk's nearest to the sphere's centre o,
    // c + a with a = −r w/|w| beyond the rim or −w on the face (w = d − (k·d) k, d = c − o, k
    // the disk's axis), the normal from o to it
    const double side = joint.side == mb::SphereSide::kInside ? -1.0 : 1.0;
    // a sphere and a box (mb::contact_sphere_box): the normal from the box's nearest point to
    // the centre (inside it: the nearest face's), the point c − r n
    const bool on_disk = joint.type == mb::JointType::kContactDiskSphere;
    const bool on_box = joint.type == mb::JointType::kContactSphereBox;
    const Vector3d half = joint.box_half;
    const int box_axes = joint.planar ? 2 : 3;
    const auto touch = [model, P, C, fp, fc, a_C, radius, side, on_disk, on_box, half, box_axes](
                           const Eigen::Ref<const VectorXd>& q, Vector3d& point, Vector3d& normal) {
      const Vector3d o = mb::world_point(*model, q, P, fp.p),
                     centre = mb::world_point(*model, q, C, fc.p);
      if (on_box) {
        const Matrix3d R =
            (P == mb::kGround ? Matrix3d::Identity()
                              : Matrix3d(mb::body_pose(*model, q, P).R_WB.toRotationMatrix())) *
            fp.R;
        Vector3d u = R.transpose() * (centre - o), m = Vector3d::Zero();
        Eigen::Index face = 0;
        (u.head(box_axes).cwiseAbs() - half.head(box_axes)).maxCoeff(&face);
        for (int i = 0; i < box_axes; ++i) {
          const double excess = std::abs(u[i]) - half[i];
          if (excess > 0.0) m[i] = std::copysign(excess, u[i]);
        }
        if (m.isZero()) m[face] = u[face] < 0.0 ? -1.0 : 1.0;
        normal = (R * m).normalized();
        point = centre - radius * normal;
        return;
      }
      if (on_disk) {
        const Vector3d k = mb::body_pose(*model, q, C).R_WB.toRotationMatrix() * a_C;
        const Vector3d d = centre - o, w = d - k.dot(d) * k;
        const double rho = w.norm();
        const Vector3d a = rho > radius ? Vector3d(-radius * w / rho) : Vector3d(-w);
        point = centre + a;
        normal = (d + a).normalized();
        return;
      }
      normal = side * (centre - o).normalized();
      point = centre - radius * normal;
    };
    c.geometry = touch;
    // the friction's axes (mb::detail::relative_contact_kinematics): n, t_1 = e × n/|e × n|,
    // t_2 = n × t_1 with e the world axis least aligned with n at the start (planar:
    // t_1 = n × e_z)
    const bool planar = joint.planar;
    Vector3d e = Vector3d::UnitZ();
    if (!planar) {
      Vector3d point0, n0;
      touch(model->q0, point0, n0);
      Eigen::Index axis = 0;
      n0.cwiseAbs().minCoeff(&axis);
      e = Vector3d::Unit(axis);
    }
    c.axes = [touch, e, planar](const Eigen::Ref<const VectorXd>& q, Matrix3d& axes) {
      Vector3d point, n;
      touch(q, point, n);
      const Vector3d t1 = planar ? Vector3d(n.cross(Vector3d::UnitZ())) : e.cross(n).normalized();
      axes << n, t1, planar ? Vector3d::Zero() : Vector3d(n.cross(t1));
    };
    return c;
  }
  c.geometry = [model, P, C, fp, fc, n_P, a_C, disk, radius](const Eigen::Ref<const VectorXd>& q,
                                                             Vector3d& point, Vector3d& normal) {
    // the plane's normal (the ground's is fixed), the centre and the disk's axis
    const auto rotation = [&](mb::BodyId b) {
      return b == mb::kGround ? Matrix3d::Identity()
                              : mb::body_pose(*model, q, b).R_WB.toRotationMatrix();
    };
    normal = rotation(P) * n_P;
    const Vector3d centre = mb::world_point(*model, q, C, fc.p);
    const Vector3d a_W = rotation(C) * a_C;
    point = contact_point(centre, normal, radius, disk ? &a_W : nullptr);
  };
  // the friction's axes (mb::detail::contact_kinematics): the plane's normal and its frame's x
  // (and y) axes, turned with the plane's body
  const bool planar = joint.planar;
  c.axes = [model, P, fp, planar](const Eigen::Ref<const VectorXd>& q, Matrix3d& axes) {
    const Matrix3d R = P == mb::kGround
                           ? fp.R
                           : Matrix3d(mb::body_pose(*model, q, P).R_WB.toRotationMatrix() * fp.R);
    if (planar) {
      axes << R.col(1).normalized(), R.col(0).normalized(), Vector3d::Zero();
    } else {
      axes << R.col(2).normalized(), R.col(0).normalized(), R.col(1).normalized();
    }
  };
  return c;
}

void scale_stick_multipliers(const Model& model, Trajectory& traj) {
  const System& sys = model.system;
  const Index N = traj.samples(), n = traj.n;
  if (N == 0 || n != sys.coordinate_count() || traj.m != sys.constraint_rows()) return;
  for (const FrictionContact& fc : sys.friction_contacts()) {
    if (fc.normal_constraint < 0 || fc.stick_constraint < 0) continue;
    const Constraint& normal = sys.constraint(fc.normal_constraint);
    const Index rows = normal.rows(), stick = sys.row_offset(fc.stick_constraint),
                d = sys.constraint(fc.stick_constraint).rows();
    const std::unique_ptr<ConstraintScratch> scratch = normal.model().make_scratch(n);
    MatrixXd A(rows, n);
    VectorXd b(rows), row(n);
    for (Index i = 0; i < N; ++i) {
      // (a contact that does not stick: its multipliers are 0, nothing to scale)
      double* lambda = traj.lambda.data() + i * traj.m + stick;
      if (Eigen::Map<const VectorXd>(lambda, d).isZero(0.0)) continue;
      const Eigen::Map<const VectorXd> q(traj.q.data() + i * n, n), qd(traj.qd.data() + i * n, n);
      normal.model().acceleration_form(q, qd, traj.t[std::size_t(i)], scratch.get(), A, b);
      Eigen::Map<VectorXd>(lambda, d) *= detail::normal_row_unit(A, rows, row);
    }
  }
}

void add_contact_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out) {
  const Index N = traj.samples(), n = traj.n;
  static const char* const kParts[] = {"x", "y", "z", "nx", "ny", "nz"};
  for (const VisualContact& c : model.visual.contacts) {
    add_friction_columns(model, traj, c, out);
    add_coordinate_friction_columns(model, traj, c, out);
    if (!c.geometry) continue;
    // the point's components, then the normal's (as visual: contacts: orders them)
    const int dims = c.dimensions;
    std::vector<CsvColumn> cols;
    for (int k = 0; k < 2 * dims; ++k) {
      const char* part = kParts[k < dims ? k : 3 + (k - dims)];
      cols.push_back(
          {"visual.contact." + c.name + "." + part, std::vector<double>(std::size_t(N))});
    }
    Vector3d point, normal;
    for (Index i = 0; i < N; ++i) {
      c.geometry(Eigen::Map<const VectorXd>(traj.q.data() + i * n, n), point, normal);
      for (int k = 0; k < dims; ++k) {
        cols[std::size_t(k)].values[std::size_t(i)] = point[k];
        cols[std::size_t(dims + k)].values[std::size_t(i)] = normal[k];
      }
    }
    for (CsvColumn& col : cols) out.push_back(std::move(col));
  }
}

}  // namespace ukdyn::detail
