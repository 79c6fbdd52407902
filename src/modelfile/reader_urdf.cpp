// SPDX-License-Identifier: BSD-3-Clause
// Robot model files: robot: names a URDF (read through tree::load_urdf) and adds what URDF
// cannot say (docs/robots.md, "Model files"):
//   robot:
//     urdf: panda_arm.urdf          the file, relative to the model file
//     gravity: [0, 0, -9.81]        (default), numbers or expressions of the parameters
//     torques: {panda_joint1: 2*sin(t), …}   joint torques, expressions of q, q_dot, t
//     loops:                        loop closures between link points (or a link and the world)
//       - {name: rod, type: distance, link_a: panda_tool, point_a: [0, 0, 0.05],
//          link_b: world, point_b: [0.4, 0, 0.6], length: 0.3}
//       - {name: ball, type: point, link_a: …, point_a: …, link_b: …, point_b: …}
//       - {name: hinge, type: revolute, …, axis_a: [0, 0, 1], axis_b: [0, 0, 1]}
//       - {name: glue, type: weld, …, rpy_a: [0, 0, 0], rpy_b: [0, 0, 1.57]}
//     nonideal: as in any model file (viscous, Coulomb friction on a constraint or loop, C)
//   contacts: unilateral contacts of link points and spheres with planes (top level, the syntax
//     of bodies models with link: for body:; modelfile/reader_robot_contacts.cpp)
// The coordinates are the joints' names (a floating base's <link>_x … <link>_u3), so initial:,
// constraints:, output: and control: name them as in any model file. A .urdf file given alone
// (ukdyn run arm.urdf, ukdyn.load("arm.urdf")) is read as `robot: {urdf: arm.urdf}`.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"
#include "ukdyn/multibody/tree_visual.hpp"

#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

namespace {

// the keys of a model file that describe the plant otherwise (a robot's is its URDF)
const std::vector<std::string> kOtherPlantKeys = {
    "coordinates", "kinetic_energy", "potential_energy", "mass_matrix", "bodies",
    "joints",      "forces"};

const std::vector<std::string> kRobotKeys = {
    "urdf", "gravity", "torques", "loops", "friction_regularization", "urdf_units"};
const std::vector<std::string> kLoopKeys = {"name",  "type",   "link_a", "point_a",
                                            "rpy_a", "axis_a", "link_b", "point_b",
                                            "rpy_b", "axis_b", "length"};

// a coordinate's name as an expression input: every character that an identifier cannot hold
// ('.', '-', …) read as '_' (names_coordinate accepts both spellings of '.')
std::string identifier_for(const std::string& name) {
  std::string s = name;
  for (char& c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) c = '_';
  }
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) s.insert(0, "_");
  return s;
}

// load_urdf's message without its function's name (the reader says where instead)
std::string urdf_message(const std::invalid_argument& e) {
  std::string m = e.what();
  const std::string prefix = "ukdyn::tree::load_urdf: ";
  if (m.rfind(prefix, 0) == 0) m.erase(0, prefix.size());
  return m;
}

}  // namespace

bool is_urdf_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".urdf";
}

std::string urdf_model_text(const std::string& path) {
  // the file's own name, single-quoted for YAML ('' stands for ')
  std::string name = std::filesystem::path(path).filename().string(), quoted;
  for (char c : name) quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return "robot: {urdf: '" + quoted + "'}\n";
}

Model Reader::read_robot(const YAML::Node& root) {
  const YAML::Node r = root["robot"];
  if (!r.IsMap()) {
    fail(r,
         "robot must be a mapping with urdf: and optionally gravity, torques, loops, "
         "friction_regularization",
         "robot: {urdf: arm.urdf}");
  }
  for (const auto& kv : r) {
    if (std::find(kRobotKeys.begin(), kRobotKeys.end(), kv.first.Scalar()) == kRobotKeys.end())
      fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in robot",
           "the keys are " + join(kRobotKeys));
  }
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (std::find(kOtherPlantKeys.begin(), kOtherPlantKeys.end(), key) != kOtherPlantKeys.end())
      fail(kv.first, "'" + key + "' does not go with 'robot:'",
           "a robot's links, joints and dynamics come from its URDF; add loops, torques, "
           "constraints between joints and non-ideal forces instead");
  }
  const YAML::Node u = r["urdf"];
  if (!u || !u.IsScalar() || u.Scalar().empty())
    fail(u ? u : r, "robot needs urdf: the URDF file's path (relative to the model file)",
         "robot: {urdf: arm.urdf}");
  // the URDF, relative to this file's directory
  const std::filesystem::path path = model_relative_path(file_, u.Scalar());
  const bool alone = std::filesystem::path(file_) == path;  // `ukdyn run arm.urdf`
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    fail(u, "urdf: " + u.Scalar() + " is a directory, not a URDF file",
         "name the robot's .urdf file (relative to the model file): robot: {urdf: arm.urdf}");
  // URDF is SI (metres, kilograms, seconds): its numbers are converted into the model's units
  // (units:), unless urdf_units: model says the file is written in them already
  UnitSystem model_units;
  if (const YAML::Node uu = root["units"]; uu && uu.IsMap()) read_unit_system(uu, model_units);
  tree::UnitScale scale;
  bool convert = true;
  if (const YAML::Node uu = r["urdf_units"]) {
    const std::string v = uu.IsScalar() ? uu.Scalar() : std::string();
    if (v != "si" && v != "model")
      fail(uu, "robot urdf_units must be si or model, got '" + v + "'",
           "si (the default: URDF's metres, kilograms, seconds, converted into the model's "
           "units:) or model (the file is written in the model's units already)");
    convert = v == "si";
  }
  if (convert) {
    scale.length = 1.0 / model_units.metres();
    scale.mass = 1.0 / model_units.kilograms();
    scale.time = model_units.per_second();
  }
  // URDF's world says nothing of gravity: 9.81 m/s² down, in the model's units, whichever units
  // the file is written in (with urdf_units: model it was 9.81 of the model's: 1000 g in mm, ms)
  const tree::Vector3d g_default(
      0.0, 0.0, -9.81 * model_units.seconds() * model_units.seconds() / model_units.metres());
  tree::Tree robot = [&] {
    try {
      return tree::load_urdf(path.string(), g_default, scale);
    } catch (const std::invalid_argument& e) {
      const std::string m = urdf_message(e);  // "<path>[:line:column]: what"
      if (alone) {
        // a URDF given alone: the error is the file's own, at the element when it was found
        // (named once: "arm.urdf:12:3: error: not a valid URDF: …")
        int line = 0, column = 0;
        std::string what = m;
        const std::string p = path.string();
        if (m.rfind(p + ":", 0) == 0) {
          what = m.substr(p.size() + 1);
          int used = 0;
          if (std::sscanf(what.c_str(), "%d:%d: %n", &line, &column, &used) == 2 && used > 0) {
            what.erase(0, std::size_t(used));
          } else {
            line = column = 0;
            if (what.rfind(' ', 0) == 0) what.erase(0, 1);
          }
        }
        throw ModelError(p, line, column, what);
      }
      fail(u, m,
           m.find("no such file") != std::string::npos
               ? "urdf: is relative to the model file's directory (" +
                     (std::filesystem::path(file_).parent_path().empty()
                          ? std::string(".")
                          : std::filesystem::path(file_).parent_path().string()) +
                     "); check the name and its directory"
               : "the line:column after the URDF's name is the element at fault in the URDF");
    }
  }();
  // coordinates: the joints' names as identifiers
  std::set<std::string> seen;
  for (const std::string& name : robot.coordinate_names()) {
    const std::string id = identifier_for(name);
    if (id == "t" || parameters_.count(id) || !seen.insert(id).second)
      fail(u,
           "coordinate '" + id + "' (joint '" + name + "' of " + path.string() +
               ") clashes with time, a parameter or another joint",
           "rename the parameter or the joint");
    if (id != name) renamed_.emplace_back(name, id);
    coordinates_.push_back(id);
    velocities_.push_back(id + "_dot");
    chain_.emplace_back(id, id + "_dot");
  }
  // the named constraints (between joints, written as expressions)
  make_expression_set(root, constraint_names(root));
  // gravity: the URDF's world says nothing of it
  if (const YAML::Node g = r["gravity"]) {
    if (!g.IsSequence() || g.size() != 3) {
      // (in the model's units: 9.81 m/s² is 0.00981 mm/ms²)
      UnitSystem units;
      if (const YAML::Node uu = root["units"]; uu && uu.IsMap()) read_unit_system(uu, units);
      const double g0 = 9.81 * units.seconds() * units.seconds() / units.metres();
      fail(g,
           "robot gravity must be a list of 3 numbers (" + units.acceleration() + ")" +
               (g.IsSequence() ? ", got " + format_number(g.size()) + " items" : ""),
           "gravity: [0, 0, " + format_number(-g0, 6) + "]" +
               (units.is_si() ? "" : " (9.81 m/s² in " + units.acceleration() + ")"));
    }
    const tree::Vector3d gv(number(g[0], "gravity"), number(g[1], "gravity"),
                            number(g[2], "gravity"));
    // (loaded again with it: rebuilding the tree from its links reversed the order of a link's
    // children, so that the coordinates named above, and initial: by those names, went to
    // other joints — u17 04, a wheel beside a belt on one base)
    robot = tree::load_urdf(path.string(), gv, scale);
  }
  // torques: {joint: expression}, one generalized force per named coordinate
  const Index n = robot.coordinate_count();
  tree::JointTorqueFn tau;
  if (const YAML::Node T = r["torques"]) {
    if (!T.IsMap()) fail(T, "robot torques must map joint names to expressions", "{joint1: 0.5}");
    std::vector<Expr> out(std::size_t(n), set_->constant(0.0));
    std::set<Index> given;
    for (const auto& kv : T) {
      const Index k = coordinate(kv.first);
      if (!given.insert(k).second)
        fail(kv.first, "torque of '" + kv.first.Scalar() + "' given twice");
      out[std::size_t(k)] = expression(kv.second, "torque of " + kv.first.Scalar());
    }
    const Program p = compile(out, T, "robot torques");
    const InputLayout layout = layout_;
    // (no scratch in its signature: buffers of the call, evaluate_local)
    tau = [p, layout](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      double t, Eigen::Ref<VectorXd> out_tau) {
      evaluate_local(
          p, layout.size(), [&](double* in) { layout.fill(in, q, qd, t); },
          [&](const double* v) {
            for (Index i = 0; i < out_tau.size(); ++i) out_tau[i] = v[i];
          });
    };
  }
  // URDF's joint friction: regularized at 1e-6 rad/s (m/s) in the model's units (units:, so
  // that a model in mm, g, ms moves as in SI), or at robot: friction_regularization: eps (in
  // rad, or length, per time unit) for every joint
  tree::FrictionRegularization eps;
  if (const YAML::Node uu = root["units"]; uu && uu.IsMap()) {
    UnitSystem units;
    read_unit_system(uu, units);
    eps.angular = tree::kJointFrictionRegularization * units.seconds();
    eps.linear = eps.angular / units.metres();
  }
  if (const YAML::Node fr = r["friction_regularization"]) {
    const double e = number(fr, "robot friction_regularization");
    if (!(std::isfinite(e) && e > 0.0))
      fail(fr, "robot friction_regularization must be a finite number > 0, got " + fr.Scalar(),
           "the joint rate (rad or length per time unit) below which URDF's joint friction is "
           "scaled down, e.g. 1e-6 in SI units (docs/robots.md)");
    eps.angular = eps.linear = e;
  }
  SystemBuilder builder = tree::system_builder(robot, tau, eps);
  // loops: closures between link points (each kept for the viewer too)
  std::set<std::string> loop_names;
  std::vector<VisualLoop> drawn_loops;
  if (const YAML::Node L = r["loops"]) {
    if (!L.IsSequence())
      fail(L, "robot loops must be a list",
           "loops: [{name: rod, type: distance, link_a: a, link_b: b, length: 0.3}]");
    for (const auto& c : L) {
      if (!c.IsMap()) fail(c, "a loop is a mapping", "{name: rod, type: point, link_a: a, …}");
      for (const auto& kv : c) {
        if (std::find(kLoopKeys.begin(), kLoopKeys.end(), kv.first.Scalar()) == kLoopKeys.end())
          fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in a loop",
               "the keys are " + join(kLoopKeys));
      }
      if (!c["name"] || !is_identifier(c["name"].Scalar()))
        fail(c, "a loop needs a name (an identifier)", "name: knee");
      const std::string name = c["name"].Scalar();
      if (!loop_names.insert(name).second) fail(c["name"], "loop '" + name + "' is given twice");
      const std::string type = c["type"] ? c["type"].Scalar() : "";
      if (type != "point" && type != "distance" && type != "weld" && type != "revolute")
        fail(c["type"] ? c["type"] : c,
             "loop '" + name + "': type must be point, distance, revolute or weld",
             "point: two link points held together (3 rows); distance: at a length (1 row); "
             "revolute: a hinge, point and axis_a ∥ axis_b (5 rows); weld: two frames held "
             "together (6 rows)");
      // keys that belong to other types
      const auto refuse = [&](const char* key, const char* types) {
        if (c[key])
          fail(c[key], "loop '" + name + "': " + key + " is for " + types + " loops only",
               "the keys of a " + type + " loop: name, type, link_a, point_a, link_b, point_b" +
                   (type == "distance"   ? ", length"
                    : type == "revolute" ? ", axis_a, axis_b"
                    : type == "weld"     ? ", rpy_a, rpy_b"
                                         : ""));
      };
      if (type != "weld") refuse("rpy_a", "weld"), refuse("rpy_b", "weld");
      if (type != "revolute") refuse("axis_a", "revolute"), refuse("axis_b", "revolute");
      if (type != "distance") refuse("length", "distance");
      // a list of 3 numbers
      const auto vector3 = [&](const YAML::Node& v, const char* key, const char* hint) {
        if (!v.IsSequence() || v.size() != 3)
          fail(v, "loop '" + name + "': " + key + " must be a list of 3 numbers", hint);
        tree::Vector3d x;
        for (std::size_t i = 0; i < 3; ++i) x[Index(i)] = number(v[i], key);
        return x;
      };
      auto end = [&](const char* link_key, const char* point_key) {
        tree::LinkPoint lp;
        const YAML::Node l = c[link_key];
        if (!l) fail(c, "loop '" + name + "' needs " + link_key, "a link's name, or world");
        if (l.Scalar() != "world") {
          try {
            lp.link = robot.link_index(l.Scalar());
          } catch (const std::invalid_argument&) {
            std::vector<std::string> names;
            for (Index i = 0; i < robot.link_count(); ++i) names.push_back(robot.link(i).name);
            fail(l, "loop '" + name + "': no link '" + l.Scalar() + "' in " + path.string(),
                 "the links are world, " + join(names));
          }
        }
        if (const YAML::Node p = c[point_key])
          lp.p = vector3(p, point_key, "[x, y, z] in the link's frame (the world's for world)");
        return lp;
      };
      const tree::LinkPoint a = end("link_a", "point_a"), b = end("link_b", "point_b");
      const auto link_name = [&](const tree::LinkPoint& lp) {
        return lp.link < 0 ? std::string("world") : robot.link(lp.link).name;
      };
      drawn_loops.push_back({name, type, link_name(a), link_name(b), a.p, b.p});
      // a weld's frame: the point and URDF's roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll))
      const auto frame = [&](const tree::LinkPoint& lp, const char* rpy_key) {
        tree::LinkFrame f{lp.link, lp.p, tree::Matrix3d::Identity()};
        if (const YAML::Node v = c[rpy_key]) {
          const tree::Vector3d rpy = vector3(v, rpy_key, "[roll, pitch, yaw] (rad), as URDF's");
          f.R = (Eigen::AngleAxisd(rpy.z(), tree::Vector3d::UnitZ()) *
                 Eigen::AngleAxisd(rpy.y(), tree::Vector3d::UnitY()) *
                 Eigen::AngleAxisd(rpy.x(), tree::Vector3d::UnitX()))
                    .toRotationMatrix();
        }
        return f;
      };
      try {
        if (type == "point") {
          builder.add(tree::point_constraint(robot, name, a, b));
        } else if (type == "distance") {
          if (!c["length"]) fail(c, "loop '" + name + "' needs length", "length: 0.3");
          const double length = number(c["length"], "length");
          if (length == 0.0)
            fail(c["length"],
                 "loop '" + name +
                     "': a distance loop of length 0 holds the two "
                     "points together, which its row cannot (its direction is undefined there)",
                 "use type: point for two points held together (3 rows)");
          if (!(std::isfinite(length) && length > 0.0))
            fail(c["length"],
                 "loop '" + name + "': length must be a finite number > 0, got " +
                     format_number(length),
                 "the distance at which the two points are kept, e.g. length: 0.3");
          builder.add(tree::distance_constraint(robot, name, a, b, length));
        } else if (type == "weld") {
          builder.add(tree::weld_constraint(robot, name, frame(a, "rpy_a"), frame(b, "rpy_b")));
        } else {
          // the hinge's axis in each link's frame; axis_b defaults to axis_a
          if (!c["axis_a"])
            fail(c, "loop '" + name + "' needs axis_a", "axis_a: [0, 0, 1] in link_a's frame");
          const tree::Vector3d ua = vector3(c["axis_a"], "axis_a", "[x, y, z] in link_a's frame");
          const tree::Vector3d ub =
              c["axis_b"] ? vector3(c["axis_b"], "axis_b", "[x, y, z] in link_b's frame") : ua;
          builder.add(tree::revolute_constraint(robot, name, a, ua, b, ub));
        }
        constraint_names_.push_back(name);
      } catch (const std::invalid_argument& e) {
        std::string m = e.what();
        if (const auto k = m.find(": "); k != std::string::npos) m.erase(0, k + 2);
        fail(c, m);
      }
    }
  }
  // contacts: unilateral gaps of link points, spheres and disks with planes (each drawn)
  std::vector<VisualContact> drawn_contacts;
  read_robot_contacts(root, robot, path.string(), loop_names, builder, drawn_contacts);
  // (their entries locate their errors at run time: a contact penetrated at the start)
  if (const YAML::Node cs = root["contacts"]; cs && cs.IsSequence()) {
    for (const auto& c : cs) {
      if (c.IsMap() && c["name"] && c["name"].IsScalar())
        positions_.constraints.emplace(c["name"].Scalar(), position(c));
    }
  }
  read_constraints(root, builder);
  // non-ideal forces: robot_ set first, so that their compiled C evaluates with buffers of its
  // own (the tree's callables own the system's scratch)
  robot_ = std::make_shared<const tree::Tree>(robot);
  read_nonideal(root, builder);
  // (the expressions' switches are not located on a robot yet: the tree's callables own the
  // system's scratch, which the compiled switching functions would need)
  switch_sources_.clear();
  constraint_switch_sources_.clear();
  const auto build = [&]() -> System {
    try {
      return builder.build();
    } catch (const std::invalid_argument& e) {
      fail(r, e.what());
    }
  };
  Model model{.system = build()};
  model.q0 = robot.neutral();
  model.qd0 = VectorXd::Zero(n);
  model.robot = robot_;
  model.robot_torques = tau;
  // what the viewer draws: the URDF's visual geometry and the loops
  model.visual.robot = tree::load_urdf_visuals(path.string(), scale.length);
  model.visual.loops = std::move(drawn_loops);
  model.visual.contacts = std::move(drawn_contacts);
  return model;
}

void Reader::refuse_renamed(const YAML::Node& node, const std::string& what) {
  // the URDF name as written, between characters that no identifier holds: "hip-1" in
  // "2*hip-1" but not in "ship-1" or "hip-10"; O(renamed · length)
  const std::string& text = node.Scalar();
  const auto word = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
  };
  for (const auto& [name, id] : renamed_) {
    for (std::size_t k = text.find(name); k != std::string::npos; k = text.find(name, k + 1)) {
      const std::size_t end = k + name.size();
      if ((k > 0 && word(text[k - 1])) || (end < text.size() && word(text[end]))) continue;
      YAML::Mark m = node.Mark();
      m.column += int(k) + (node.Tag() == "!" ? 1 : 0);
      fail_at(m,
              "in " + what + ": '" + name + "' is the robot's coordinate '" + name +
                  "' (a URDF name), which expressions write " + id +
                  " (as written it would read as arithmetic on other names)",
              "write " + id +
                  " for the joint, or put spaces around the operator if you mean "
                  "the arithmetic");
    }
  }
}

Constraint Reader::read_pose_requirement(const YAML::Node& r, const std::string& name,
                                         const std::string& what) {
  const YAML::Node pose = r["pose"];
  const std::string example =
      "pose: {link: tool, point: [0, 0, 0], position: [0.4, 0.1*sin(t), 0.5], orientation: "
      "[cos(t/2), 0, 0, sin(t/2)]}";
  if (!robot_) fail(pose, what + ": a pose requirement needs a robot: (a URDF)", example);
  if (!pose.IsMap()) fail(pose, what + ": pose must be a mapping", example);
  for (const auto& kv : pose) {
    const std::string key = kv.first.Scalar();
    if (key != "link" && key != "point" && key != "position" && key != "orientation")
      fail(kv.first, "unknown key '" + key + "' in the pose of " + what,
           "the keys are link, point, position, orientation");
  }
  for (const char* key : {"holonomic", "nonholonomic", "A", "b"}) {
    if (r[key]) fail(r[key], what + ": give either pose or " + key + ", not both");
  }
  const tree::Tree& robot = *robot_;
  tree::LinkPoint at;
  const YAML::Node link = pose["link"];
  if (!link) fail(pose, what + ": pose needs link:", example);
  try {
    at.link = robot.link_index(link.Scalar());
  } catch (const std::invalid_argument&) {
    fail(link, what + ": no link '" + link.Scalar() + "' in the robot");
  }
  if (const YAML::Node p = pose["point"]) {
    if (!p.IsSequence() || p.size() != 3)
      fail(p, what + ": point must be a list of 3 numbers", "[x, y, z] in the link's frame");
    for (std::size_t i = 0; i < 3; ++i) at.p[Index(i)] = number(p[i], "point");
  }
  // [p; u] as expressions of t, and their first and second derivatives
  const std::size_t t_input = coordinates_.size() * 2;
  std::vector<Expr> value;
  auto read_list = [&](const char* key, std::size_t size, const char* hint) {
    const YAML::Node l = pose[key];
    if (!l.IsSequence() || l.size() != size) {
      // a comma inside an expression of a flow list [… if(c, a, b)] splits it in YAML
      bool cut = false;
      if (l.IsSequence()) {
        for (const auto& e : l) {
          const std::string& x = e.IsScalar() ? e.Scalar() : std::string();
          cut = cut || std::count(x.begin(), x.end(), '(') != std::count(x.begin(), x.end(), ')');
        }
      }
      fail(l,
           what + ": " + key + " must be a list of " + format_number(size) + " expressions" +
               (l.IsSequence() ? ", got " + format_number(l.size()) + " items" : ""),
           cut ? "YAML splits a flow list […] at every comma, also inside if(c, a, b) or "
                 "atan2(y, x): quote an expression that holds commas (\"if(t - 1, (t - 1)^3, "
                 "0)\") or write the list in block style"
               : hint);
    }
    for (const auto& e : l) {
      const Expr x = expression(e, what + " " + key);
      for (const Index in : set_->inputs_of(x)) {
        if (std::size_t(in) != t_input)
          fail(e, what + ": " + key + " may depend on t and the parameters only, not on '" +
                      set_->input_names()[std::size_t(in)] + "'");
      }
      value.push_back(x);
    }
  };
  if (!pose["position"]) fail(pose, what + ": pose needs position:", example);
  read_list("position", 3, "[x(t), y(t), z(t)] in the world");
  const bool oriented = bool(pose["orientation"]);
  if (oriented) read_list("orientation", 4, "a unit quaternion [w, x, y, z] of t");
  std::vector<Expr> outputs = value;
  for (int order = 0; order < 2; ++order) {
    const std::size_t from = outputs.size() - value.size();
    for (std::size_t k = 0; k < value.size(); ++k)
      outputs.push_back(set_->diff(outputs[from + k], "t"));
  }
  const Program program = compile(outputs, pose, what);
  const InputLayout layout = layout_;
  const std::size_t w = value.size();  // 3 or 7 values per derivative order
  // the desired pose at t: p, p', p''; R(u), ω = 2 vec(u' ⊗ u*), ω' = 2 vec(u'' ⊗ u*)
  auto path = [program, layout, w](double t, tree::PoseSample& d) {
    evaluate_local(
        program, layout.size(), [&](double* in) { in[2 * layout.n] = t; },
        [&](const double* v) {
          d.p = tree::Vector3d(v[0], v[1], v[2]);
          d.v = tree::Vector3d(v[w], v[w + 1], v[w + 2]);
          d.a = tree::Vector3d(v[2 * w], v[2 * w + 1], v[2 * w + 2]);
          if (w == 3) return;
          const Eigen::Quaterniond u(v[3], v[4], v[5], v[6]);
          const auto rate = [&](const double* du) {
            // vec(du ⊗ u*) = u0 du_v − du0 u_v − du_v × u_v
            const tree::Vector3d uv(u.x(), u.y(), u.z()), dv(du[1], du[2], du[3]);
            return tree::Vector3d(2.0 * (u.w() * dv - du[0] * uv - dv.cross(uv)));
          };
          d.R = u.normalized().toRotationMatrix();
          d.w = rate(v + w + 3);
          d.w_dot = rate(v + 2 * w + 3);
        });
  };
  if (oriented) {
    // a quaternion of unit norm at the start (its derivatives assume it stays so)
    double norm = 0.0;
    evaluate_local(
        program, layout.size(), [&](double* in) { in[2 * layout.n] = 0.0; },
        [&](const double* v) {
          norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
        });
    if (std::abs(norm - 1.0) > 1e-9)
      fail(pose["orientation"],
           what + ": orientation must be a unit quaternion, its norm at t = 0 is " + brief(norm),
           "[cos(a/2), x sin(a/2), y sin(a/2), z sin(a/2)] for a rotation by a about the unit "
           "axis (x, y, z)");
  }
  return tree::pose_requirement(robot, name, at, path, oriented);
}

}  // namespace ukdyn::model_reader
