// SPDX-License-Identifier: BSD-3-Clause
// Joints between planar bodies (x, y, theta): the rows of each kind, in closed form through the
// vector rows of JointModel (docs/multibody.md, "Planar joints").
#include <cmath>
#include <stdexcept>

#include "multibody/internal.hpp"

namespace ukdyn::mb::detail {
namespace {

// d = o_C − o_P, the child frame's origin relative to the parent frame's (world)
VecExpr origin_difference(const Joint& j) {
  return VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
}

// the in-plane angle of a planar frame in its body
double frame_angle(const Frame& f) { return std::atan2(f.R(1, 0), f.R(0, 0)); }

Row dot(const VecExpr& a, const VecExpr& b) {
  Row r;
  r.kind = Row::kDot;
  r.a = a;
  r.b = b;
  return r;
}

// (theta_C + alpha_C) − (theta_P + alpha_P) = c(t): the relative angle of the frames
Row relative_angle(const Joint& j, const BodyRef& P, const BodyRef& C) {
  Row r;
  r.kind = Row::kLinear;
  if (!C.ground()) r.terms.push_back({C.offset + 2, 1.0});
  if (!P.ground()) r.terms.push_back({P.offset + 2, -1.0});
  r.c.c0 = frame_angle(j.frame_parent) - frame_angle(j.frame_child);
  return r;
}

}  // namespace

std::vector<Row> planar_joint_rows(const Joint& j, const BodyRef& P, const BodyRef& C) {
  const VecExpr d = origin_difference(j);
  const VecExpr ex = VecExpr::constant(Vector3d::UnitX()),
                ey = VecExpr::constant(Vector3d::UnitY());
  // the parent frame's y axis, as a body vector of the parent
  const VecExpr yP = VecExpr::body_vector(0, j.frame_parent.R.col(1));
  switch (j.type) {
    case JointType::kRevolute:  // d = 0
      return {dot(d, ex), dot(d, ey)};
    case JointType::kPrismatic:  // d · y_P = 0, relative angle constant
      return {dot(d, yP), relative_angle(j, P, C)};
    case JointType::kWeld:  // d = 0, relative angle constant
      return {dot(d, ex), dot(d, ey), relative_angle(j, P, C)};
    case JointType::kDistance: {  // (|d|² − L²)/(2L) = 0
      Row r;
      r.kind = Row::kDistance;
      r.a = d;
      r.length = j.length;
      return {r};
    }
    case JointType::kPointOnLine:  // d · y_P = 0: o_C on the x line of F_P
      return {dot(d, yP)};
    default:
      break;
  }
  throw std::invalid_argument(std::string("ukdyn::mb::Multibody::build: joint '") + j.name +
                              "': a " + to_string(j.type) +
                              " joint is not defined between planar bodies (planar kinds: "
                              "revolute, prismatic, weld, distance, point_on_line, gear)");
}

Row planar_drive_row(const Joint& j, const BodyRef& P, const BodyRef& C) {
  Row r;
  if (j.type == JointType::kRevolute) {
    // (theta_C + alpha_C) − (theta_P + alpha_P) = f(t)
    r = relative_angle(j, P, C);
  } else if (j.type == JointType::kPrismatic) {
    // d · x_P = f(t)
    r = dot(origin_difference(j), VecExpr::body_vector(0, j.frame_parent.R.col(0)));
  } else {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name +
                                "': a drive needs a revolute or prismatic joint, got " +
                                to_string(j.type));
  }
  r.c.motion = std::make_shared<const MotionFn>(j.drive);
  return r;
}

}  // namespace ukdyn::mb::detail
