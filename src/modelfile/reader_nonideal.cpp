// SPDX-License-Identifier: BSD-3-Clause
// Model files, the non-ideal forces (modelfile/reader.hpp): nonideal: → Coulomb and viscous
// friction and the forces given by their C (Udwadia–Kalaba's non-ideal constraint forces). Every
// error names file:line:column and gives a hint.
#include "ukdyn/modelfile/model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/options.hpp"

#include "modelfile/initial_keep.hpp"
#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

namespace {
// the largest coefficient of friction a model may give: far above any material's (a few at
// most), so that a contact meant never to slip can be written as one, and far below the
// magnitudes at which mu N overflows or swamps the other forces (mu = 1e150 made Q non-finite at
// t = 0, which named no friction)
constexpr double kMaxFrictionCoefficient = 1e6;
}  // namespace

double Reader::friction_coefficient(const YAML::Node& node, const std::string& what) {
  const double v = number(node, what);
  if (!(v >= 0.0)) fail(node, what + " must be >= 0, got " + brief(v));
  if (!(v <= kMaxFrictionCoefficient)) {
    fail(node,
         what + " must be in [0, " + brief(kMaxFrictionCoefficient) + "] (a coefficient of " +
             "friction), got " + brief(v),
         "dry friction between materials has mu between about 0.05 and 1.5 (docs/friction.md)");
  }
  return v;
}

SurfaceVelocityFn Reader::surface_velocity(const YAML::Node& node, std::size_t count) {
  const std::string what = "surface_velocity";
  const auto rows = rows_of(node, what);
  if (rows.size() != count) {
    fail(node,
         "surface_velocity needs " + format_number(count) + " entries, one per sliding coordinate",
         "the velocity of the surface under the contact, e.g. [V, 0] for a belt moving at V");
  }
  // [u; u'], u' = (du/dq) q' + du/dt
  std::vector<Expr> u, u_dot;
  for (const auto& r : rows) {
    const Expr e = expression(r, what);
    if (const std::string* v = velocity_in(*set_, e, velocities_)) {
      fail(r, "surface_velocity depends on the velocity '" + *v + "'",
           "the surface velocity may depend on the coordinates and t only");
    }
    u.push_back(e);
    u_dot.push_back(time_derivative(e));
  }
  u.insert(u.end(), u_dot.begin(), u_dot.end());
  const Program p = compile(u, node, what);
  const InputLayout layout = layout_;
  const Index k = Index(count);
  // (its signature carries no scratch: buffers of the call, evaluate_local)
  return [p, layout, k](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t, Eigen::Ref<VectorXd> uo, Eigen::Ref<VectorXd> udo) {
    evaluate_local(
        p, layout.size(), [&](double* in) { layout.fill(in, q, qd, t); },
        [&](const double* out) {
          for (Index r = 0; r < k; ++r) {
            uo[r] = out[r];
            udo[r] = out[k + r];
          }
        });
  };
}

std::vector<Index> Reader::normal_coordinates(const YAML::Node& root, const YAML::Node& f,
                                              const std::vector<Index>& sliding) {
  const Index n = Index(coordinates_.size());
  std::vector<Index> p;
  if (const YAML::Node nn = f["normal_coordinates"]) {
    if (!nn.IsSequence() || nn.size() == 0)
      fail(nn, "normal_coordinates must be a non-empty list of coordinate names",
           "the translation coordinates of the body at the contact, e.g. normal_coordinates: "
           "[x, y] (docs/friction.md §1)");
    for (const auto& c : nn) {
      const Index i = coordinate(c);
      if (std::find(p.begin(), p.end(), i) != p.end())
        fail(c, "normal_coordinates: '" + c.Scalar() + "' is listed twice");
      p.push_back(i);
    }
    return p;
  }
  // each coordinate's unit as units: gives it ("" when not given)
  std::vector<std::string> unit(static_cast<std::size_t>(n));
  std::string length = "m";
  if (const YAML::Node u = root["units"]; u && u.IsMap()) {
    for (const auto& kv : u) {
      const std::string& key = kv.first.Scalar();
      if (!kv.second.IsScalar()) continue;  // (read_units refuses it)
      if (key == "length") length = kv.second.Scalar();
      for (Index i = 0; i < n; ++i)
        if (names_coordinate(key, coordinates_[std::size_t(i)]))
          unit[std::size_t(i)] = kv.second.Scalar();
    }
  }
  // the sliding coordinates' unit: one length, known or not
  std::vector<Index> slides = sliding;
  if (slides.empty())
    for (Index i = 0; i < n; ++i) slides.push_back(i);
  std::string of_sliding;
  Index first = -1;
  for (const Index i : slides) {
    const std::string& u = unit[std::size_t(i)];
    if (u.empty()) continue;
    if (first < 0) {
      of_sliding = u;
      first = i;
    } else if (u != of_sliding) {
      fail(
          f["coordinates"] ? f["coordinates"] : f,
          "Coulomb friction's sliding coordinates must be lengths of one unit: '" +
              coordinates_[std::size_t(first)] + "' is in " + of_sliding + ", '" +
              coordinates_[std::size_t(i)] + "' in " + u,
          "list only the Cartesian coordinates of the contact under coordinates: (docs/friction.md "
          "§1)");
    }
  }
  for (const Index i : slides) {
    const std::string& u = unit[std::size_t(i)];
    // (an angle among them: the friction would slide along x', y' and θ' as one vector — the
    // default sliding coordinates are all of them; a rod's impact on a rough floor in (x, y, th)
    // with units {th: rad} took a normal impulse of 3.42 for 1.68 at its impact, silently)
    if (u == "rad" || u == "deg")
      fail(f["coordinates"] ? f["coordinates"] : f,
           "Coulomb friction's sliding coordinates must be lengths: '" +
               coordinates_[std::size_t(i)] + "' is an angle (in " + u + ")" +
               (f["coordinates"] ? "" : ", and without coordinates: every coordinate slides"),
           "list only the Cartesian coordinates of the contact under coordinates:, e.g. "
           "coordinates: [x] for a point on a floor (docs/friction.md §1)");
  }
  if (of_sliding.empty()) of_sliding = length;
  for (Index i = 0; i < n; ++i) {
    const std::string& u = unit[std::size_t(i)];
    if (u.empty() || u == of_sliding) p.push_back(i);
  }
  if (Index(p.size()) == n) p.clear();  // all: N = |R|, as without units
  return p;
}

void Reader::check_friction_normals(const YAML::Node& root, const System& sys) {
  const Index n = sys.coordinate_count();
  std::vector<std::string> unit(static_cast<std::size_t>(n));
  if (const YAML::Node u = root["units"]; u && u.IsMap()) {
    for (const auto& kv : u)
      for (Index i = 0; i < n; ++i)
        if (kv.second.IsScalar() &&
            names_coordinate(kv.first.Scalar(), coordinates_[std::size_t(i)]))
          unit[std::size_t(i)] = kv.second.Scalar();
  }
  std::size_t entry = 0;
  for (const FrictionContact& contact : sys.friction_contacts()) {
    if (contact.kinematics) continue;
    if (entry >= coulomb_entries_.size()) break;
    const YAML::Node& f = coulomb_entries_[entry++];
    const std::string name = sys.constraint(contact.normal_constraint).name();
    // the normal row's coordinates (all n for dense rows)
    std::vector<Index> row = sys.constraint(contact.normal_constraint).model().columns();
    if (row.empty())
      for (Index i = 0; i < n; ++i) row.push_back(i);
    const auto& p = contact.normal_coordinates;
    auto in_p = [&](Index i) { return p.empty() || std::find(p.begin(), p.end(), i) != p.end(); };
    std::vector<std::string> read, left;
    for (const Index i : row) {
      const std::string& c = coordinates_[std::size_t(i)];
      const std::string& u = unit[std::size_t(i)];
      (in_p(i) ? read : left).push_back(u.empty() ? c : c + " (" + u + ")");
    }
    if (read.empty()) {
      fail(f["constraint"],
           "the friction on '" + name + "' cannot read its normal force: its row involves " +
               join(left) + ", none in the sliding coordinates' length unit",
           "give the translation coordinates of the body at the contact as normal_coordinates: "
           "[...] (docs/friction.md §1)");
    }
    if (f["normal_coordinates"] || read.size() < 2) continue;
    // several coordinates of the row read: fine when each is a length (a sliding coordinate,
    // or one in the length unit); one of unknown unit may be an angle (y + s*sin(th)), whose
    // entry would add a torque to N
    std::vector<std::string> unknown;
    for (const Index i : row) {
      if (!in_p(i) || !unit[std::size_t(i)].empty()) continue;
      if (std::find(contact.coordinates.begin(), contact.coordinates.end(), i) !=
          contact.coordinates.end())
        continue;
      unknown.push_back(coordinates_[std::size_t(i)]);
    }
    if (unknown.empty()) continue;
    fail(f["constraint"],
         "the friction on '" + name + "' reads its normal force N on " + join(read) +
             ", of which " + join(unknown) +
             " have no unit: if one is an angle, N would add a torque to the force "
             "(N = |R_p|, docs/friction.md §1)",
         "say which are angles under units: (units: {" + unknown.back() +
             ": rad}; the others in the length unit or without a unit count as lengths), or "
             "give the translation coordinates of the body at the contact as "
             "normal_coordinates: [...]");
  }
}

double Reader::default_regularization_velocity(const YAML::Node& root) {
  // eps [m/s] · (s per time unit / m per length unit): exactly eps when they are alike (mm, ms)
  UnitSystem units;
  if (const YAML::Node u = root["units"]; u && u.IsMap()) read_unit_system(u, units);
  return CoulombFriction{}.regularization_velocity * (units.seconds() / units.metres());
}

void Reader::read_nonideal(const YAML::Node& root, SystemBuilder& builder) {
  const YAML::Node ns = root["nonideal"];
  if (!ns) return;
  if (!ns.IsSequence()) fail(ns, "nonideal must be a list");
  int index = 0;
  std::map<std::string, int> coulomb_on;  // constraint → the entry that gives it Coulomb friction
  for (const auto& f : ns) {
    ++index;
    if (!f.IsMap()) fail(f, "a non-ideal force must be a mapping");
    for (const auto& kv : f) {
      static const std::set<std::string> keys = {
          "friction",          "constraint",  "mu",
          "mu_static",         "coordinates", "regularization_velocity",
          "surface_velocity",  "c",           "C",
          "normal_coordinates"};
      if (!keys.count(kv.first.Scalar())) {
        fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in a non-ideal force",
             "the keys are friction, constraint, mu, mu_static, coordinates, "
             "normal_coordinates, regularization_velocity, surface_velocity (coulomb), c "
             "(viscous), C");
      }
    }
    std::vector<Index> coords;
    if (const YAML::Node cn = f["coordinates"]) {
      if (!cn.IsSequence()) fail(cn, "coordinates must be a list of coordinate names");
      for (const auto& c : cn) coords.push_back(coordinate(c));
    }
    if (f["friction"]) {
      const std::string law = f["friction"].Scalar();
      if (law == "coulomb") {
        if (!f["constraint"])
          fail(f, "coulomb friction needs the constraint that gives N",
               "{friction: coulomb, constraint: plane, mu: 0.3}");
        const std::string on = f["constraint"].Scalar();
        if (std::find(constraint_names_.begin(), constraint_names_.end(), on) ==
            constraint_names_.end()) {
          fail(f["constraint"], "no constraint named '" + on + "'",
               constraint_names_.empty()
                   ? "the model has no constraint: Coulomb friction needs the contact or "
                     "constraint that gives its normal force N (an empty contacts: list gives none)"
                   : "the constraints are " + join(constraint_names_));
        }
        // (one contact, one friction law: its stick state is the constraint's)
        if (const auto [it, first] = coulomb_on.emplace(on, index); !first) {
          fail(f["constraint"],
               "constraint '" + on + "' has Coulomb friction already (non-ideal force " +
                   std::to_string(it->second) + ")",
               "one coulomb friction per constraint: list every sliding coordinate under its "
               "coordinates:");
        }
        if (!f["mu"]) fail(f, "coulomb friction needs mu");
        CoulombFriction spec;
        spec.constraint = on;
        spec.mu = friction_coefficient(f["mu"], "coulomb friction on '" + on + "': mu");
        spec.coordinates = coords;
        if (const auto pc = point_contacts_.find(on); pc != point_contacts_.end()) {
          // a robot's contact: the friction slides the contact point (ContactKinematics)
          if (const YAML::Node cn = f["coordinates"])
            fail(cn,
                 "the friction at contact '" + on +
                     "' slides the contact point itself: it takes no coordinates",
                 "leave coordinates out: the sliding velocity is the velocity of the link's "
                 "point at the contact, tangent to the plane (docs/contact.md)");
          if (const YAML::Node un = f["surface_velocity"])
            fail(un, "a surface velocity under a robot's contact is not supported yet",
                 "leave surface_velocity out");
          if (const YAML::Node nn = f["normal_coordinates"])
            fail(nn,
                 "the friction at contact '" + on +
                     "' reads its normal force at the contact point: it takes no "
                     "normal_coordinates",
                 "leave normal_coordinates out");
          try {
            spec.kinematics = pc->second();
          } catch (const std::invalid_argument& e) {
            std::string m = e.what();
            if (const auto k = m.find(": "); k != std::string::npos) m.erase(0, k + 2);
            fail(f["constraint"], m);
          }
        }
        spec.regularization_velocity = default_regularization_velocity(root);
        if (const YAML::Node rv = f["regularization_velocity"]) {
          spec.regularization_velocity = number(rv, "regularization_velocity");
          if (!(spec.regularization_velocity > 0)) {
            fail(rv, "regularization_velocity must be > 0, got " + rv.Scalar(),
                 "the speed below which the friction force is scaled down, e.g. 1e-4; "
                 "docs/friction.md");
          }
        }
        if (spec.mu < 0) fail(f["mu"], "mu must be >= 0");
        if (const YAML::Node ms = f["mu_static"]) {
          spec.mu_static = friction_coefficient(ms, "coulomb friction on '" + on + "': mu_static");
          if (!(*spec.mu_static >= spec.mu)) {
            fail(ms, "mu_static must be >= mu (the kinetic coefficient)");
          }
        }
        if (const YAML::Node un = f["surface_velocity"]) {
          spec.surface_velocity =
              surface_velocity(un, coords.empty() ? coordinates_.size() : coords.size());
        }
        if (!spec.kinematics) {
          spec.normal_coordinates = normal_coordinates(root, f, coords);
          coulomb_entries_.push_back(f);
        }
        NonIdealForce force = coulomb_friction(spec);
        // (the entry a run's refusal of the contact points at: its stick constraint's name)
        positions_.constraints["stick." + force.name()] = position(f);
        builder.add(std::move(force));
      } else if (law == "viscous") {
        if (const YAML::Node nn = f["normal_coordinates"])
          fail(nn,
               "normal_coordinates belong to Coulomb friction (the coordinates its N is read on)",
               "leave normal_coordinates out of a viscous friction");
        if (!f["c"])
          fail(f, "viscous friction needs its coefficient c", "{friction: viscous, c: 0.3}");
        ViscousFriction spec;
        spec.coefficient = number(f["c"], "c");
        spec.coordinates = coords;
        spec.name = "viscous." + format_number(index);
        if (spec.coefficient < 0) fail(f["c"], "c must be >= 0");
        builder.add(viscous_friction(spec));
      } else {
        fail(f["friction"], "unknown friction law '" + law + "'",
             "the laws are coulomb and viscous");
      }
    } else if (f["C"]) {
      // C(q, q', t, N_c, lambda_c)
      const auto rows = rows_of(f["C"], "C");
      const Index n = Index(coordinates_.size());
      if (Index(rows.size()) != n)
        fail(f["C"], "C must have " + format_number(n) + " entries, one per coordinate",
             cut_flow_list_hint(f["C"], "C"));
      std::vector<Expr> C;
      C.reserve(rows.size());
      for (const auto& r : rows) C.push_back(expression(r, "C", true));
      note_switches(C);
      const Program Cp = compile(C, f["C"], "C");
      const InputLayout layout = layout_;
      const std::vector<std::string> names = input_constraints_;
      sizes_->fit(layout.size(), Cp);
      // a robot's system scratch is its tree's: C then evaluates with buffers of the call
      const bool own_buffers = robot_ != nullptr;
      NonIdealForce force(
          "C." + format_number(index),
          NonIdealForce::Binder([Cp, layout, names, own_buffers](const System& sys) -> NonIdealFn {
            std::vector<Index> ks;
            ks.reserve(names.size());
            for (const auto& nm : names) ks.push_back(sys.constraint_index(nm));
            return [Cp, layout, ks, own_buffers](
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, const IdealForceInfo& ideal, Eigen::Ref<VectorXd> Cout) {
              // [q; q'; t], then N_c and lambda_c (first row of each constraint)
              const std::size_t base = std::size_t(2 * layout.n + 1);
              const auto fill = [&](double* in) {
                layout.fill(in, q, qd, t);
                for (std::size_t i = 0; i < ks.size(); ++i) {
                  in[base + i] = ideal.normal_force(ks[i]);
                  in[base + ks.size() + i] = ideal.lambda(ks[i])[0];
                }
              };
              if (own_buffers) {
                evaluate_local(Cp, layout.size(), fill, [&](const double* v) {
                  for (Index i = 0; i < Cout.size(); ++i) Cout[i] = v[i];
                });
                return;
              }
              ModelBuffers& b = model_buffers(ideal.scratch());
              fill(b.in.data());
              Cp.evaluate(b.in.data(), Cout.data(), b.scratch.data());
            };
          }));
      builder.add(force);
    } else {
      fail(f, "a non-ideal force needs 'friction' (coulomb, viscous) or 'C'");
    }
  }
}

}  // namespace ukdyn::model_reader
