// SPDX-License-Identifier: BSD-3-Clause
// The control: section of a model file (docs/model-format.md; the API is docs/control.md):
//   control:
//     requirements:
//       - {name: track, holonomic: x - sin(t), dynamics: {omega: 2, zeta: 1}}
//       - {name: v, nonholonomic: x_dot - 1, dynamics: {rate: 3}}
//     law: gauss | weighted        (weighted: N: [[...], ...], a matrix of expressions)
//     actuated: [x]                (default: every coordinate)
//     nominal: {m: 1.2}            (parameters the controller believes)
//     robust: {bound: 0.5, boundary_layer: 0.01, relative_bound: 0, gain_uncertainty: 0}
// Each requirement is read like a constraint (holonomic:, nonholonomic:, A: with b:, active:)
// and handed to ControllerBuilder with its error dynamics.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <yaml-cpp/yaml.h>

#include "modelfile/reader.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/multibody.hpp"

namespace ukdyn::model_reader {
namespace {

// the keys of a mapping must be among `keys`
template <class Fail>
void only_keys(const YAML::Node& map, const std::set<std::string>& keys, const std::string& what,
               Fail fail) {
  for (const auto& kv : map) {
    if (!keys.count(kv.first.Scalar())) {
      std::vector<std::string> list(keys.begin(), keys.end());
      fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in " + what,
           "the keys are " + join(list));
    }
  }
}

// The column of the actuation matrix S of a joint's own effort u (Q_c = S u), when it does not
// depend on the coordinates (ControllerBuilder::actuation takes a constant S); otherwise empty,
// with `why` saying why. A planar revolute joint: the torque u on the child and −u on the parent
// (rows of their angles). A planar prismatic joint on the ground: the force u along the slide
// direction d (the parent frame's x axis, fixed) at the child's joint point, whose offset r from
// the child's centre of mass is fixed too (the joint holds the child's angle at α_P − α_C):
// rows (d_x, d_y, r × d) of the child's (x, y, theta) — the virtual work u δs of the slide s.
VectorXd actuation_of_joint(const mb::MultibodyModel& m, const mb::JointInfo& j, std::string& why) {
  const Index n = m.system.coordinate_count();
  const auto angle_of = [&](mb::BodyId b) { return m.bodies[std::size_t(b)].offset + 2; };
  if (!j.planar && (j.type == mb::JointType::kRevolute || j.type == mb::JointType::kPrismatic)) {
    why =
        "is a spatial joint: the generalized force of its effort depends on the bodies' "
        "orientations, and the controller's actuation matrix is constant (planar revolute joints "
        "and planar prismatic joints on the ground can be actuated)";
    return {};
  }
  if (j.type == mb::JointType::kRevolute) {
    VectorXd s = VectorXd::Zero(n);
    s[angle_of(j.child)] += 1.0;
    if (j.parent != mb::kGround) s[angle_of(j.parent)] -= 1.0;
    return s;
  }
  if (j.type == mb::JointType::kPrismatic) {
    if (j.parent != mb::kGround) {
      why =
          "is a prismatic joint between two bodies: its force turns with the parent body, and the "
          "controller's actuation matrix is constant (a prismatic joint on the ground can be "
          "actuated)";
      return {};
    }
    const double alpha_p = std::atan2(j.frame_parent.R(1, 0), j.frame_parent.R(0, 0));
    const double alpha_c = std::atan2(j.frame_child.R(1, 0), j.frame_child.R(0, 0));
    const double theta = alpha_p - alpha_c;  // the child's angle the joint holds
    const double dx = std::cos(alpha_p), dy = std::sin(alpha_p);
    const double px = j.frame_child.p.x(), py = j.frame_child.p.y();
    const double rx = std::cos(theta) * px - std::sin(theta) * py;
    const double ry = std::sin(theta) * px + std::cos(theta) * py;
    const Index o = m.bodies[std::size_t(j.child)].offset;
    VectorXd s = VectorXd::Zero(n);
    s[o] = dx;
    s[o + 1] = dy;
    s[o + 2] = rx * dy - ry * dx;
    return s;
  }
  why = std::string("is a ") + mb::to_string(j.type) +
        " joint: only revolute and prismatic joints have a coordinate of their own to actuate";
  return {};
}

// A library message without the C++ function that gave it ("ukdyn::ControllerBuilder::build: the
// weight N …" → "the weight N …"): a model file's reader names the file, line and key instead.
std::string api_free(const std::string& message) {
  if (message.rfind("ukdyn::", 0) == 0) {
    if (const auto k = message.find(": "); k != std::string::npos) return message.substr(k + 2);
  }
  return message;
}

}  // namespace

ErrorDynamics Reader::read_error_dynamics(const YAML::Node& r, const std::string& what,
                                          ConstraintKind kind) {
  const YAML::Node d = r["dynamics"];
  if (!d) return ErrorDynamics::none();
  if (!d.IsMap()) {
    fail(d, "the dynamics of " + what + " must be a mapping",
         "{omega: 2, zeta: 1} or {alpha: 4, beta: 2} (holonomic), {rate: 3} (nonholonomic)");
  }
  only_keys(
      d, {"omega", "zeta", "alpha", "beta", "rate"}, "the dynamics of " + what,
      [this](const YAML::Node& at, const std::string& m, const std::string& h) { fail(at, m, h); });
  // the ranges are ErrorDynamics' own: its refusal becomes an error at the dynamics
  const auto checked = [&](auto make) {
    try {
      return make();
    } catch (const std::invalid_argument& e) {
      // (ErrorDynamics' words for a C++ caller: its name, and its advice to use none())
      std::string message = api_free(e.what());
      if (const auto k = message.find(" (for no error dynamics"); k != std::string::npos)
        message.erase(k);
      fail(d, "the dynamics of " + what + ": " + message,
           "the gains must be positive numbers (omit dynamics: for none)");
    }
  };
  const bool holonomic = kind == ConstraintKind::kHolonomic;
  if (d["rate"]) {
    if (holonomic || d.size() != 1) {
      fail(d,
           "rate: gives first-order error dynamics e' + rate e = 0, for a nonholonomic "
           "requirement alone",
           holonomic ? "a holonomic requirement takes {omega, zeta} or {alpha, beta}"
                     : "write {rate: k} only");
    }
    const double k = number(d["rate"], "rate");
    return checked([k] { return ErrorDynamics::first_order(k); });
  }
  if (!holonomic) {
    fail(d, what + " is not holonomic: its error dynamics are first order, {rate: k}",
         "e' + k e = 0 with e the requirement's value");
  }
  if (d["omega"] || d["zeta"]) {
    if (d["alpha"] || d["beta"]) fail(d, "give {omega, zeta} or {alpha, beta}, not both");
    if (!d["omega"]) fail(d, "zeta needs omega", "{omega: 2, zeta: 1}");
    const double omega = number(d["omega"], "omega");
    const double zeta = d["zeta"] ? number(d["zeta"], "zeta") : 1.0;
    return checked([omega, zeta] { return ErrorDynamics::second_order(omega, zeta); });
  }
  const double alpha = d["alpha"] ? number(d["alpha"], "alpha") : 0.0;
  const double beta = d["beta"] ? number(d["beta"], "beta") : 0.0;
  return checked([alpha, beta] { return ErrorDynamics::gains(alpha, beta); });
}

WeightFn Reader::read_weight(const YAML::Node& N, bool& constant, MatrixXd& value) {
  const Index n = Index(coordinates_.size());
  const std::string hint =
      "N is n × n: one list of " + format_number(n) + " entries per coordinate";
  if (!N.IsSequence() || Index(N.size()) != n)
    fail(N, "N must be a list of " + format_number(n) + " rows", hint);
  std::vector<Expr> entries;
  constant = true;
  for (const auto& row : N) {
    if (!row.IsSequence() || Index(row.size()) != n)
      fail(row, "each row of N must have " + format_number(n) + " entries", hint);
    for (const auto& e : row) {
      entries.push_back(expression(e, "N"));
      if (!set_->inputs_of(entries.back()).empty()) constant = false;
    }
  }
  const Program p = compile(entries, N, "N");
  if (constant) {
    std::vector<double> in(std::size_t(p.inputs()), 0.0), scratch(std::size_t(p.scratch_size()));
    MatrixXd transposed(n, n);  // the entries come row by row: column-major, that is Nᵀ
    p.evaluate(in.data(), transposed.data(), scratch.data());
    value = transposed.transpose();
    return {};
  }
  const InputLayout layout = layout_;
  // (its signature carries no scratch: buffers of the call, evaluate_local)
  return [p, layout, n](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t, Eigen::Ref<MatrixXd> W) {
    evaluate_local(
        p, layout.size(), [&](double* in) { layout.fill(in, q, qd, t); },
        [&](const double* out) {
          for (Index i = 0; i < n; ++i) {
            for (Index j = 0; j < n; ++j) W(i, j) = out[i * n + j];
          }
        });
  };
}

// The desired value of each row of a holonomic or nonholonomic requirement written as
// φ = actual(q) − desired(t) (ψ = actual(q, q') − desired(t)). It becomes the output expression
// desired_<row>, which the plots and the viewer draw against actual = φ + desired
// (python/ukdyn/plotting.py). The actual value is known when the file declares it: an output
// expression or a coordinate of a visual point E whose difference from the row, E − φ, depends
// on t and the parameters alone (the state terms cancel exactly) — then desired = E − φ, the
// constants of the kinematics (a tool point's height above its base, an offset frame) accounted
// for. Else it is minus the terms of φ (as written, not expanded) that depend on t and the
// parameters alone; a row whose terms all depend on the state, or none does, has none. Called
// by read_output, before read_control checks the requirements (which are skipped here when not
// even named: read_control says what is wrong with them).
void Reader::note_desired(const YAML::Node& root) {
  const YAML::Node c = root["control"];
  if (!c || !c.IsMap() || !c["requirements"] || !c["requirements"].IsSequence()) return;
  const std::vector<Expr> declared = declared_kinematics(root);
  for (const auto& r : c["requirements"]) {
    if (!r.IsMap() || !r["name"] || !r["name"].IsScalar() || !is_identifier(r["name"].Scalar()))
      continue;
    const YAML::Node h = r["holonomic"] ? r["holonomic"] : r["nonholonomic"];
    if (h) {
      const std::string name = r["name"].Scalar();
      note_desired_rows(h, name, "requirement '" + name + "'", declared);
    }
    // a pose requirement's rows 0..2 are the point's position minus `position`: that is the
    // desired path (desired_<name>_0 … _2; the viewer draws it, docs/robots.md)
    const YAML::Node pose = r["pose"];
    if (pose && pose.IsMap() && pose["position"] && pose["position"].IsSequence() &&
        pose["position"].size() == 3) {
      const std::string name = r["name"].Scalar();
      for (std::size_t i = 0; i < 3; ++i) {
        desired_outputs_.emplace_back(
            "desired_" + name + "_" + format_number(i),
            expression(pose["position"][i], "requirement '" + name + "' position"));
      }
    }
  }
}

// The kinematic quantities the file declares: its output expressions and the coordinates of its
// visual points, in that order (those that do not read are left out here: read_output and
// read_visual report them)
std::vector<Expr> Reader::declared_kinematics(const YAML::Node& root) {
  std::vector<YAML::Node> nodes;
  const YAML::Node out = root["output"];
  if (out && out.IsMap() && out["expressions"] && out["expressions"].IsMap()) {
    for (const auto& kv : out["expressions"]) nodes.push_back(kv.second);
  }
  const YAML::Node v = root["visual"];
  if (v && v.IsMap() && v["points"] && v["points"].IsMap()) {
    for (const auto& kv : v["points"]) {
      const YAML::Node at = kv.second.IsMap() ? kv.second["at"] : kv.second;
      if (!at || !at.IsSequence()) continue;
      for (const auto& e : at) nodes.push_back(e);
    }
  }
  std::vector<Expr> found;
  for (const YAML::Node& node : nodes) {
    if (!node.IsScalar()) continue;
    try {
      found.push_back(set_->parse(node.Scalar()));
    } catch (const std::exception&) {  // (reported where it is read)
    }
  }
  return found;
}

void Reader::note_desired_rows(const YAML::Node& h, const std::string& name,
                               const std::string& what, const std::vector<Expr>& declared) {
  const auto phis = rows_of(h, what);
  const Index time = 2 * layout_.n;  // t's input
  const auto of_time_alone = [&](Expr e) {
    const std::vector<Index> in = set_->inputs_of(e);
    return std::all_of(in.begin(), in.end(), [&](Index k) { return k == time; });
  };
  for (std::size_t i = 0; i < phis.size(); ++i) {
    const Expr phi = expression(phis[i], what);
    if (of_time_alone(phi)) continue;  // (no actual value: not a tracking row)
    const std::vector<Index> inputs = set_->inputs_of(phi);
    const bool depends_on_time = std::find(inputs.begin(), inputs.end(), time) != inputs.end();
    const std::string column =
        "desired_" + (phis.size() == 1 ? name : name + "_" + format_number(i));
    // the actual value declared: desired = E − φ, exactly
    bool matched = false;
    for (const Expr E : declared) {
      const Expr desired = set_->subtract(E, phi);
      if (!of_time_alone(desired)) continue;
      // (E is the error itself, declared as an output: not the actual value)
      if (set_->is_literal_zero(desired) && depends_on_time) continue;
      desired_outputs_.emplace_back(column, desired);
      matched = true;
      break;
    }
    if (matched) continue;
    // else the terms of t and the parameters alone
    std::vector<Expr> of_time;
    for (const Expr term : set_->terms(phi)) {
      if (of_time_alone(term)) of_time.push_back(term);
    }
    if (of_time.empty()) continue;
    desired_outputs_.emplace_back(column, set_->negate(set_->sum(of_time)));
  }
}

void Reader::read_control(const YAML::Node& root, Model& model) {
  const YAML::Node c = root["control"];
  if (!c) return;
  auto failer = [this](const YAML::Node& at, const std::string& m, const std::string& h) {
    fail(at, m, h);
  };
  if (!c.IsMap()) {
    fail(c, "control must be a mapping",
         "control: {requirements: [{name: track, holonomic: x - sin(t)}], law: gauss}");
  }
  only_keys(c, {"requirements", "law", "N", "actuated", "nominal", "robust"}, "control", failer);

  // the controller's own model: the plant, or the plant with the nominal parameters
  Reader* ctl = this;
  std::unique_ptr<Reader> nominal_reader;
  System nominal = model.system;
  if (const YAML::Node nom = c["nominal"]) {
    if (!nom.IsMap()) fail(nom, "nominal must be a mapping parameter: value", "{m: 1.2}");
    std::map<std::string, double> values = overrides_;
    for (const auto& kv : nom) {
      const std::string name = kv.first.Scalar();
      if (!parameters_.count(name)) {
        std::vector<std::string> known;
        for (const auto& p : parameters_) known.push_back(p.first);
        fail(kv.first, "nominal: the model has no parameter '" + name + "'",
             known.empty() ? "declare it under parameters:" : "its parameters are " + join(known));
      }
      values[name] = number(kv.second, "nominal " + name);
    }
    nominal_reader = std::make_unique<Reader>(file_, values, given_tables_);
    try {
      nominal = nominal_reader->read_plant(root).system;
    } catch (const ModelError& e) {
      // the plant read with the nominal parameters: say so (the plant itself was fine)
      std::string given;
      for (const auto& kv : nom) {
        given += (given.empty() ? "" : ", ") + kv.first.Scalar() + ": " + kv.second.Scalar();
      }
      throw ModelError(e.file(), e.line(), e.column(),
                       "with the controller's nominal parameters (control: nominal: {" + given +
                           "}): " + e.message(),
                       e.hint().empty() ? "check the values under nominal:" : e.hint());
    }
    ctl = nominal_reader.get();
  }
  ControllerBuilder builder(nominal);

  // requirements
  const YAML::Node rs = c["requirements"];
  if (!rs || !rs.IsSequence() || rs.size() == 0) {
    fail(rs ? rs : c, "control needs a list of requirements",
         "requirements: [{name: track, holonomic: x - sin(t), dynamics: {omega: 2, zeta: 1}}]");
  }
  // the names taken, each with what holds it (u22 08: a requirement named like a bodies model's
  // contact was accepted, like a robot's refused): `constraints:` and a robot's loops and
  // contacts (constraint_names_), the plant's joints and contacts (its constraints; a box entry's
  // corner contacts <name>.<k> take <name>), then each requirement read
  std::map<std::string, std::string> taken;
  for (const auto& name : constraint_names_) taken.emplace(name, "the constraint '" + name + "'");
  for (const Constraint& k : model.system.constraints()) {
    std::string name = k.name();
    if (k.is_unilateral()) {
      const auto dot = name.rfind('.');
      if (dot != std::string::npos && dot + 1 < name.size() &&
          name.find_first_not_of("0123456789", dot + 1) == std::string::npos)
        name.resize(dot);
      taken[name] = "the contact '" + name + "'";
    } else {
      taken.emplace(name, "the joint '" + name + "'");
    }
  }
  for (const auto& r : rs) {
    if (!r.IsMap() || !r["name"]) {
      fail(r, "a requirement is a mapping with a name and its expression",
           "{name: track, holonomic: x - sin(t), dynamics: {omega: 2, zeta: 1}}");
    }
    const std::string name = r["name"].Scalar();
    if (!is_identifier(name)) fail(r["name"], "a requirement's name must be an identifier");
    if (const auto [it, fresh] = taken.emplace(name, "another requirement"); !fresh) {
      fail(r["name"], "the name '" + name + "' is taken by " + it->second,
           "give the requirement a name of its own: a requirement's name is unique among the "
           "model's constraints, joints, contacts and requirements (its columns error." +
               name + " sit beside the constraints' lambda.<name>)");
    }
    only_keys(r, {"name", "holonomic", "nonholonomic", "A", "b", "active", "dynamics", "pose"},
              "requirement '" + name + "'", failer);
    const std::string what = "requirement '" + name + "'";
    // pose: a robot's link point in task space (modelfile/reader_urdf.cpp)
    const Constraint req =
        r["pose"] ? ctl->read_pose_requirement(r, name, what) : ctl->read_constraint(r, name, what);
    const ErrorDynamics d = ctl->read_error_dynamics(r, what, req.kind());
    try {
      builder.require(req, d);
    } catch (const std::invalid_argument& e) {
      fail(r, e.what());
    }
  }

  // law
  const std::string law = c["law"] ? c["law"].Scalar() : "gauss";
  if (law == "gauss") {
    if (c["N"]) fail(c["N"], "N is the weight of law: weighted", "add law: weighted");
    builder.gauss();
  } else if (law == "weighted") {
    if (!c["N"]) fail(c["law"], "law: weighted needs the weight N: [[...], ...]");
    bool constant = false;
    MatrixXd value;
    WeightFn fn = ctl->read_weight(c["N"], constant, value);
    try {
      if (constant) {
        builder.weighted(value);
      } else {
        builder.weighted(std::move(fn));
      }
    } catch (const std::invalid_argument& e) {
      fail(c["N"], api_free(e.what()),
           "a weight is a symmetric positive definite n × n matrix: [[1, 0], [0, 4]]");
    }
  } else {
    fail(c["law"], "unknown law '" + law + "'", "the laws are gauss and weighted");
  }

  // actuation: coordinates (either spelling, as S's unit columns) and, in a multibody model,
  // joints (the generalized force of the joint's own effort: actuation_of_joint)
  if (const YAML::Node a = c["actuated"]) {
    if (!a.IsSequence() || a.size() == 0)
      fail(a, "actuated must be a list of coordinates", "actuated: [x]");
    const std::vector<std::string>& system_names = model.system.coordinate_names();
    const Index n = Index(system_names.size());
    std::vector<std::string> names;  // the System's names of the actuated coordinates
    std::vector<std::string> given;  // every entry, for "listed twice"
    std::vector<VectorXd> columns;   // S's columns, in order
    bool joints = false;
    for (const auto& x : a) {
      const std::string entry = x.Scalar();
      // (crank.x or crank_x: names_coordinate; the list holds the reader's spelling)
      const auto known = std::find_if(
          coordinates_.begin(), coordinates_.end(),
          [&](const std::string& coordinate) { return names_coordinate(entry, coordinate); });
      if (known != coordinates_.end()) {
        const Index k = Index(known - coordinates_.begin());
        const std::string& name = system_names[std::size_t(k)];
        if (std::find(given.begin(), given.end(), name) != given.end())
          fail(x, "actuated: '" + entry + "' is listed twice");
        given.push_back(name);
        names.push_back(name);
        columns.push_back(VectorXd::Unit(n, k));
        continue;
      }
      const bool is_joint =
          model.multibody &&
          std::any_of(model.multibody->joints.begin(), model.multibody->joints.end(),
                      [&](const mb::JointInfo& j) { return j.name == entry; });
      if (!is_joint) {
        std::vector<std::string> choices = coordinates_;
        if (model.multibody) {
          for (const auto& j : model.multibody->joints) choices.push_back(j.name);
        }
        fail(x,
             "actuated: '" + entry + "' is not a coordinate" +
                 (model.multibody ? std::string(" or a joint") : std::string()),
             (model.multibody ? "the coordinates and joints are " : "the coordinates are ") +
                 join(choices));
      }
      if (std::find(given.begin(), given.end(), entry) != given.end())
        fail(x, "actuated: '" + entry + "' is listed twice");
      given.push_back(entry);
      const mb::MultibodyModel& mbm = *model.multibody;
      std::string why;
      VectorXd column = actuation_of_joint(mbm, mbm.joints[std::size_t(mbm.joint(entry))], why);
      if (column.size() == 0)
        fail(x, "actuated: joint '" + entry + "' " + why,
             "actuate body coordinates instead (<body>_theta, <body>_x, …)");
      columns.push_back(std::move(column));
      joints = true;
    }
    try {
      if (joints) {
        MatrixXd S(n, Index(columns.size()));
        for (Index j = 0; j < S.cols(); ++j) S.col(j) = columns[std::size_t(j)];
        builder.actuation(S);
      } else {
        builder.actuated(names);
      }
    } catch (const std::invalid_argument& e) {
      fail(a, e.what());
    }
  }

  // robust term
  if (const YAML::Node rb = c["robust"]) {
    if (!rb.IsMap()) fail(rb, "robust must be a mapping", "{bound: 0.5, boundary_layer: 0.01}");
    only_keys(rb, {"bound", "relative_bound", "gain_uncertainty", "boundary_layer"}, "robust",
              failer);
    RobustControl settings;
    // each number's range checked at its key (the builder checks them again)
    auto in_range = [&](const char* key, bool ok, const char* range) {
      if (!ok) fail(rb[key], std::string("robust ") + key + " must be " + range);
    };
    if (rb["bound"]) settings.bound = number(rb["bound"], "bound");
    in_range("bound", settings.bound >= 0.0 && std::isfinite(settings.bound), ">= 0");
    if (rb["relative_bound"])
      settings.relative_bound = number(rb["relative_bound"], "relative_bound");
    in_range("relative_bound",
             settings.relative_bound >= 0.0 && std::isfinite(settings.relative_bound), ">= 0");
    if (rb["gain_uncertainty"])
      settings.gain_uncertainty = number(rb["gain_uncertainty"], "gain_uncertainty");
    in_range("gain_uncertainty",
             settings.gain_uncertainty >= 0.0 && settings.gain_uncertainty < 1.0, "in [0, 1)");
    if (!rb["boundary_layer"])
      fail(rb, "robust needs boundary_layer (> 0)", "{bound: 0.5, boundary_layer: 0.01}");
    settings.boundary_layer = number(rb["boundary_layer"], "boundary_layer");
    in_range("boundary_layer",
             settings.boundary_layer > 0.0 && std::isfinite(settings.boundary_layer), "> 0");
    builder.robust(settings);
  }

  try {
    model.controller = std::make_shared<const Controller>(builder.build());
  } catch (const std::invalid_argument& e) {
    fail(c, api_free(e.what()));
  }
}

}  // namespace ukdyn::model_reader
