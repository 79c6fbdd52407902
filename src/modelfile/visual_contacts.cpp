// SPDX-License-Identifier: BSD-3-Clause
// The contacts the viewer draws without `visual: contacts:` (modelfile/visual_contacts.hpp):
// where a contacts: entry touches its plane — a point itself, a sphere's point nearest the plane
// c − r n, a disk's rim's lowest point c − r (n − s a) / |n − s a| (s = n · a; the direction of
// steepest descent in the disk's plane, as the gap g = n · d − r √(1 − s²) of docs/contact.md) —
// and the plane's normal, in the world at q.
#include "modelfile/visual_contacts.hpp"

#include <cmath>
#include <string>
#include <utility>

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

}  // namespace

VisualContact robot_visual_contact(std::string name, std::shared_ptr<const tree::Tree> tree,
                                   const tree::LinkPoint& at, const Vector3d* axis, double radius,
                                   const tree::LinkFrame& plane) {
  VisualContact c;
  c.name = std::move(name);
  c.dimensions = 3;
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
  if (joint.type == mb::JointType::kContactSpheres) {
    // two spheres: the normal is the line of the centres o → c, the point the contact sphere's
    // nearest to the other, c − r n
    c.geometry = [model, P, C, fp, fc, radius](const Eigen::Ref<const VectorXd>& q, Vector3d& point,
                                               Vector3d& normal) {
      const Vector3d o = mb::world_point(*model, q, P, fp.p),
                     centre = mb::world_point(*model, q, C, fc.p);
      normal = (centre - o).normalized();
      point = centre - radius * normal;
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
  return c;
}

void add_contact_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out) {
  const Index N = traj.samples(), n = traj.n;
  static const char* const kParts[] = {"x", "y", "z", "nx", "ny", "nz"};
  for (const VisualContact& c : model.visual.contacts) {
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
