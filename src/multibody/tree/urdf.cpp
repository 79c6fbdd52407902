// SPDX-License-Identifier: BSD-3-Clause
// URDF import through urdfdom (Debian's liburdfdom-dev): the file's links and joints as a Tree.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>

#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"

#include "urdf_parse.hpp"
#include "urdf_xml.hpp"

namespace ukdyn::tree {

namespace {

// collects urdfdom's messages (it reports what is wrong only through console_bridge)
class MessageCapture final : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_WARN) return;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) error_ = true;
    if (!text_.empty()) text_ += "; ";
    text_ += text;
  }
  const std::string& text() const { return text_; }
  // urdfdom logged an error: it may still return a model, with the element it could not read
  // dropped or zeroed (an <inertial> whose mass is "heavy" comes back as mass 0, u20 02)
  bool error() const { return error_; }

 private:
  std::string text_;
  bool error_ = false;
};

// drops the links' pointers to each other (a cycle of links holds itself through their
// child_links' shared pointers: cleared before a model is refused, else never freed)
void unlink(urdf::ModelInterface& model) {
  for (auto& [name, l] : model.links_) {
    if (!l) continue;
    l->child_links.clear();
    l->child_joints.clear();
  }
}

// "<who at the element's line:column><what>" (who ends in "<path>: "), thrown
[[noreturn]] void refuse_at(const std::string& who, const std::string& text,
                            const detail::UrdfElement& at, const std::string& what) {
  throw std::invalid_argument(detail::located(who, detail::find_urdf_element(text, at)) + what);
}

// urdfdom accepts a link that is the child of two joints (a cycle, base → a → b → a, or two
// parents) and links its children into a cycle, which a walk from the root never leaves: refused
// here, naming the link and both joints, as is a link the root does not reach. Cost O(links +
// joints), at load.
// (a cycle of links holds itself through their child_links' shared pointers: they are cleared
// before the model is refused, else its links would never be freed)
void check_tree(urdf::ModelInterface& model, const std::string& text, const std::string& who) {
  const auto refuse = [&](const detail::UrdfElement& at, const std::string& what) {
    unlink(model);
    refuse_at(who, text, at, what);
  };
  std::map<std::string, std::string> parent_joint;  // child link → the first joint naming it
  for (const auto& [name, j] : model.joints_) {
    if (!j) continue;
    const auto [it, fresh] = parent_joint.emplace(j->child_link_name, name);
    if (!fresh) {
      refuse({"joint", name, "child"},
             "not a tree: link '" + j->child_link_name + "' is the child of two joints, '" +
                 it->second + "' and '" + name +
                 "' (a cycle, or two parents); a kinematic loop is closed with `loops:` of a robot "
                 "model (docs/robots.md), not in the URDF");
    }
  }
  const urdf::LinkConstSharedPtr root = model.getRoot();
  if (!root) return;
  std::set<std::string> reached;
  std::vector<urdf::LinkConstSharedPtr> stack{root};
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr l = stack.back();
    stack.pop_back();
    if (!l || !reached.insert(l->name).second) continue;
    for (const auto& c : l->child_links) stack.push_back(c);
  }
  for (const auto& [name, l] : model.links_) {
    if (!reached.count(name)) {
      refuse({"link", name, ""}, "not a tree: link '" + name +
                                     "' is not reached from the root link '" + root->name +
                                     "' (its joints form a cycle apart from the tree)");
    }
  }
}

Eigen::Quaterniond rotation(const urdf::Rotation& r) { return {r.w, r.x, r.y, r.z}; }
Vector3d to_eigen(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

}  // namespace

detail::UrdfFile detail::parse_urdf_file(const std::string& path, const std::string& who) {
  if (!std::filesystem::is_regular_file(path)) {
    // (a directory, e.g. `urdf: .`, or a device exists: say what it is)
    std::error_code ec;
    throw std::invalid_argument(
        who + (std::filesystem::is_directory(path, ec) ? "is a directory, not a URDF file"
               : std::filesystem::exists(path, ec)     ? "is not a regular file (a URDF file is)"
                                                       : "no such file"));
  }
  UrdfFile file;
  {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    file.text = std::move(bytes).str();
  }
  // XML that TinyXML (under urdfdom) would read without a word or without a place, refused here
  // with its line:column
  check_urdf_xml(file.text, who);
  // parse, with urdfdom's messages captured (console_bridge's handler is process-wide)
  static std::mutex handler_mutex;
  MessageCapture capture;
  {
    const std::lock_guard<std::mutex> lock(handler_mutex);
    console_bridge::useOutputHandler(&capture);
    try {
      file.model = urdf::parseURDF(file.text);
    } catch (...) {
      console_bridge::restorePreviousOutputHandler();
      throw;
    }
    console_bridge::restorePreviousOutputHandler();
  }
  // refused, or read with an error (an element dropped): urdfdom's message, located at the
  // element it names ("<who at line:column>not a valid URDF: …", who ending in "<path>: ")
  if (!file.model || capture.error()) {
    if (file.model) unlink(*file.model);
    throw std::invalid_argument(
        located(who, find_urdf_element(file.text, element_of_message(capture.text()))) +
        "not a valid URDF: " + (capture.text().empty() ? "urdfdom refused it" : capture.text()));
  }
  check_tree(*file.model, file.text, who);
  return file;
}

Tree load_urdf(const std::string& path, Vector3d gravity, const UnitScale& scale) {
  const std::string who = "ukdyn::tree::load_urdf: " + path + ": ";
  const detail::UrdfFile file = detail::parse_urdf_file(path, who);
  const urdf::ModelInterfaceSharedPtr& model = file.model;
  // an error at an element of the file, "<who at its line:column><what>"
  const auto refuse = [&](const detail::UrdfElement& at, const std::string& what) {
    refuse_at(who, file.text, at, what);
  };
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) throw std::invalid_argument(who + "no root link");
  // URDF's "world" link without inertial is the world itself; any other root is welded to it
  std::vector<Link> links;
  std::vector<urdf::LinkConstSharedPtr> stack;
  const bool root_is_world = root->name == "world" && !root->inertial;
  if (root_is_world) {
    for (auto c = root->child_links.rbegin(); c != root->child_links.rend(); ++c) {
      stack.push_back(*c);
    }
  } else {
    stack.push_back(root);
  }
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr l = stack.back();
    stack.pop_back();
    for (auto c = l->child_links.rbegin(); c != l->child_links.rend(); ++c) stack.push_back(*c);
    Link out;
    out.name = l->name;
    const urdf::JointConstSharedPtr j = l->parent_joint;
    if (!j || l == root) {
      out.joint.name = l->name + ".root";  // the implied weld of a fixed base
      out.joint.kind = JointKind::kFixed;
    } else {
      const std::string where = "joint '" + j->name + "' (child link '" + l->name + "'): ";
      out.joint.name = j->name;
      if (!(root_is_world && j->parent_link_name == root->name)) out.parent = j->parent_link_name;
      switch (j->type) {
        case urdf::Joint::FIXED:
          out.joint.kind = JointKind::kFixed;
          break;
        case urdf::Joint::REVOLUTE:
          out.joint.kind = JointKind::kRevolute;
          break;
        case urdf::Joint::CONTINUOUS:
          out.joint.kind = JointKind::kContinuous;
          break;
        case urdf::Joint::PRISMATIC:
          out.joint.kind = JointKind::kPrismatic;
          break;
        case urdf::Joint::FLOATING:
          out.joint.kind = JointKind::kFloating;
          break;
        default:
          refuse({"joint", j->name, ""},
                 where + "joint type " + (j->type == urdf::Joint::PLANAR ? "'planar'" : "unknown") +
                     " is not supported (fixed, revolute, continuous, prismatic, floating are)");
      }
      out.joint.p_PJ = to_eigen(j->parent_to_joint_origin_transform.position);
      out.joint.R_PJ = rotation(j->parent_to_joint_origin_transform.rotation);
      out.joint.axis = to_eigen(j->axis);
      if (j->limits) {
        if (out.joint.kind != JointKind::kContinuous) {
          out.joint.lower = j->limits->lower;
          out.joint.upper = j->limits->upper;
          if (out.joint.lower > out.joint.upper) {
            refuse({"joint", j->name, "limit"},
                   where + "its <limit> has lower = " + format_number(out.joint.lower) +
                       " > upper = " + format_number(out.joint.upper) +
                       " (swap them: lower <= upper)");
          }
        }
        out.joint.effort = j->limits->effort;
        out.joint.velocity = j->limits->velocity;
      }
      if (j->dynamics) {
        out.joint.damping = j->dynamics->damping;
        out.joint.friction = j->dynamics->friction;
      }
      // <mimic joint="ref" multiplier="m" offset="o"/>: checked by the tree, a constraint of its
      // system (urdfdom's defaults: m = 1, o = 0)
      // SI to the model's units (UnitScale): a joint's coordinate is a length (prismatic) or an
      // angle; its effort a force or a torque
      const double L = scale.length, M = scale.mass, T = scale.time;
      const bool sliding = out.joint.kind == JointKind::kPrismatic;
      const double q_unit = sliding ? L : 1.0, lever = sliding ? 1.0 : L;
      out.joint.p_PJ *= L;
      out.joint.lower *= q_unit;
      out.joint.upper *= q_unit;
      out.joint.effort *= M * L * lever / (T * T);
      out.joint.friction *= M * L * lever / (T * T);
      out.joint.damping *= M * lever * lever / T;
      out.joint.velocity *= q_unit / T;
      if (j->mimic) {
        out.joint.mimic = j->mimic->joint_name;
        // q_j = m q_ref + o: m in (j's unit)/(ref's unit), o in j's unit
        const urdf::JointConstSharedPtr ref = model->getJoint(j->mimic->joint_name);
        const double ref_unit = ref && ref->type == urdf::Joint::PRISMATIC ? L : 1.0;
        out.joint.mimic_multiplier = j->mimic->multiplier * q_unit / ref_unit;
        out.joint.mimic_offset = j->mimic->offset * q_unit;
        if (out.joint.mimic.empty()) {
          refuse({"joint", j->name, "mimic"}, where + "its <mimic> names no joint (joint=\"…\")");
        }
      }
    }
    const bool moving = out.joint.kind != JointKind::kFixed;
    if (l->inertial) {
      const urdf::Inertial& in = *l->inertial;
      const Eigen::Matrix3d R = rotation(in.origin.rotation).normalized().toRotationMatrix();
      Eigen::Matrix3d I;
      I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      out.inertial.mass = in.mass * scale.mass;
      out.inertial.com = to_eigen(in.origin.position) * scale.length;
      out.inertial.I_com = R * I * R.transpose() * (scale.mass * scale.length * scale.length);
      if (moving) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
        if (!(in.mass > 0.0) || !(eig.eigenvalues()[0] > 0.0)) {
          refuse({"link", l->name, "inertial"},
                 "link '" + l->name + "': the inertia of a moving link must be positive " +
                     "definite (mass " + format_number(in.mass) + ", principal moments " +
                     format_number(eig.eigenvalues()[0]) + ", " +
                     format_number(eig.eigenvalues()[1]) + ", " +
                     format_number(eig.eigenvalues()[2]) + ")");
        }
      }
    } else if (moving) {
      refuse({"link", l->name, ""},
             "link '" + l->name + "' moves (joint '" + out.joint.name + "') but has no <inertial>");
    }
    links.push_back(std::move(out));
  }
  try {
    return Tree(model->getName(), std::move(links), gravity);
  } catch (const std::invalid_argument& e) {
    // (the file named once, without the tree's class, at the element the message is about:
    // "<path>:7:5: joint 'j2' mimics 'j9': …")
    std::string m = e.what();
    const std::string tree_who = "ukdyn::tree::Tree: ";
    if (m.rfind(tree_who, 0) == 0) m.erase(0, tree_who.size());
    refuse_at(who, file.text, detail::element_of_message(m), m);
  }
}

}  // namespace ukdyn::tree
