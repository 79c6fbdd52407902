// SPDX-License-Identifier: BSD-3-Clause
// Joints between rigid bodies and particles in space: the rows of each kind as dot products of
// the frames' axes and of the origin difference d = o_C − o_P (docs/multibody.md, "Spatial
// joints"). Every row is closed form (JointModel).
#include <stdexcept>

#include "multibody/internal.hpp"

namespace ukdyn::mb::detail {
namespace {

Row dot_rows(const VecExpr& a, const VecExpr& b) {
  Row r;
  r.kind = Row::kDot;
  r.a = a;
  r.b = b;
  return r;
}

}  // namespace

std::vector<Row> spatial_joint_rows(const Joint& j, const BodyRef&, const BodyRef&) {
  const VecExpr d = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
  const auto axis = [&](int slot, int c) {
    const Frame& f = slot == 0 ? j.frame_parent : j.frame_child;
    return VecExpr::body_vector(slot, f.R.col(c));
  };
  const VecExpr xP = axis(0, 0), yP = axis(0, 1), zP = axis(0, 2);
  const VecExpr xC = axis(1, 0), yC = axis(1, 1), zC = axis(1, 2);
  // d = 0 (3 rows, world components)
  const std::vector<Row> point = {dot_rows(d, VecExpr::constant(Vector3d::UnitX())),
                                  dot_rows(d, VecExpr::constant(Vector3d::UnitY())),
                                  dot_rows(d, VecExpr::constant(Vector3d::UnitZ()))};
  // z_C ∥ z_P: z_P · x_C = 0, z_P · y_C = 0
  const std::vector<Row> parallel = {dot_rows(zP, xC), dot_rows(zP, yC)};
  std::vector<Row> rows;
  const auto add = [&rows](const std::vector<Row>& more) {
    rows.insert(rows.end(), more.begin(), more.end());
  };
  switch (j.type) {
    case JointType::kSpherical:
      add(point);
      break;
    case JointType::kRevolute:  // common point, common z axis
      add(point);
      add(parallel);
      break;
    case JointType::kUniversal:  // common point, z_P ⊥ z_C
      add(point);
      rows.push_back(dot_rows(zP, zC));
      break;
    case JointType::kCylindrical:  // common z axis: parallel, o_C on the z line of F_P
      add(parallel);
      add({dot_rows(d, xP), dot_rows(d, yP)});
      break;
    case JointType::kPrismatic:  // cylindrical without the turn: x_P · y_C = 0
      add(parallel);
      rows.push_back(dot_rows(xP, yC));
      add({dot_rows(d, xP), dot_rows(d, yP)});
      break;
    case JointType::kPlanar:  // parallel planes, o_C in the xy plane of F_P
      add(parallel);
      rows.push_back(dot_rows(d, zP));
      break;
    case JointType::kWeld:
      add(point);
      add(parallel);
      rows.push_back(dot_rows(xP, yC));
      break;
    case JointType::kDistance: {
      Row r;
      r.kind = Row::kDistance;
      r.a = d;
      r.length = j.length;
      rows.push_back(r);
      break;
    }
    case JointType::kPointOnLine:
      add({dot_rows(d, xP), dot_rows(d, yP)});
      break;
    case JointType::kPointOnPlane:
      rows.push_back(dot_rows(d, zP));
      break;
    default:
      throw std::invalid_argument(std::string("ukdyn::mb::Multibody::build: joint '") + j.name +
                                  "': " + to_string(j.type) + " is not a spatial joint kind");
  }
  return rows;
}

Row spatial_drive_row(const Joint& j, const BodyRef&, const BodyRef&) {
  if (j.type != JointType::kPrismatic &&
      j.type != JointType::kCylindrical) {  // revolute: elsewhere
    throw std::invalid_argument(
        "ukdyn::mb::Multibody::build: joint '" + j.name +
        "': a spatial drive needs a revolute (its angle), prismatic or cylindrical joint (its "
        "slide d · z_P = f(t)), got " +
        to_string(j.type));
  }
  // d · z_P = f(t)
  Row r;
  r.kind = Row::kDot;
  r.a = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
  r.b = VecExpr::body_vector(0, j.frame_parent.R.col(2));
  r.c.motion = std::make_shared<const MotionFn>(j.drive);
  return r;
}

}  // namespace ukdyn::mb::detail
