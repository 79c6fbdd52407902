// SPDX-License-Identifier: BSD-3-Clause
// The model file's `visual:` section and the bodies' `visual:` entries: how the browser viewer
// draws the model (modelfile/visual.hpp, docs/viewer.md). Nothing here changes the dynamics.
#include <algorithm>
#include <array>
#include <cctype>
#include <set>

#include "modelfile/reader.hpp"
#include "ukdyn/multibody/multibody.hpp"

namespace ukdyn::model_reader {
namespace {

// the colour names a model file may use besides #rrggbb (matplotlib's tab10 shades)
const std::array<std::pair<const char*, const char*>, 13> kColours = {{{"blue", "#1f77b4"},
                                                                       {"orange", "#ff7f0e"},
                                                                       {"green", "#2ca02c"},
                                                                       {"red", "#d62728"},
                                                                       {"purple", "#9467bd"},
                                                                       {"brown", "#8c564b"},
                                                                       {"pink", "#e377c2"},
                                                                       {"grey", "#7f7f7f"},
                                                                       {"gray", "#7f7f7f"},
                                                                       {"olive", "#bcbd22"},
                                                                       {"cyan", "#17becf"},
                                                                       {"black", "#000000"},
                                                                       {"white", "#ffffff"}}};

std::string colour_names() {
  std::string s;
  for (const auto& [name, hex] : kColours) s += (s.empty() ? "" : ", ") + std::string(name);
  return s;
}

// the names of the unilateral constraints of the file's constraints: (the gaps)
std::vector<std::pair<std::string, YAML::Node>> unilateral_gaps(const YAML::Node& root) {
  std::vector<std::pair<std::string, YAML::Node>> out;
  const YAML::Node cs = root["constraints"];
  if (!cs || !cs.IsSequence()) return out;
  for (const auto& c : cs) {
    bool unilateral = false;
    if (!c.IsMap() || !c["unilateral"] || !c["holonomic"] || !c["name"]) continue;
    if (!YAML::convert<bool>::decode(c["unilateral"], unilateral) || !unilateral) continue;
    out.emplace_back(c["name"].Scalar(), c["holonomic"]);
  }
  return out;
}

}  // namespace

void Reader::add_gap_outputs(const YAML::Node& root, Model& model, std::vector<Expr>& outputs) {
  for (const auto& [name, holonomic] : unilateral_gaps(root)) {
    const std::string column = "gap." + name;
    if (std::find(model.output_names.begin(), model.output_names.end(), column) !=
        model.output_names.end())
      continue;  // (the file's own output of that name)
    model.output_names.push_back(column);
    outputs.push_back(expression(holonomic, "the gap of constraint '" + name + "'"));
    std::vector<Index> reads;
    for (const Index k : set_->inputs_of(outputs.back()))
      if (k < Index(coordinates_.size())) reads.push_back(k);
    gap_reads_.emplace_back(column, std::move(reads));
  }
}

void Reader::label_gaps(Model& model) const {
  for (const auto& [column, reads] : gap_reads_) {
    const auto at = std::find(model.output_names.begin(), model.output_names.end(), column);
    if (at == model.output_names.end()) continue;
    std::string& unit = model.output_units[std::size_t(at - model.output_names.begin())];
    if (!unit.empty() || reads.empty()) continue;  // (given by units:, or a constant gap)
    // the unit the coordinates read share (none when they differ, or when one has none: a
    // coordinate whose unit nobody gives is never guessed a length — it may be an angle)
    const auto unit_of = [&](Index k) {
      const std::size_t j = std::size_t(k);
      return j < model.coordinate_units.size() ? model.coordinate_units[j] : std::string();
    };
    const std::string first = unit_of(reads.front());
    if (std::all_of(reads.begin(), reads.end(), [&](Index k) { return unit_of(k) == first; }))
      unit = first;
  }
}

void Reader::read_visual(const YAML::Node& root, Model& model, std::vector<Expr>& outputs) {
  const auto check_keys = [&](const YAML::Node& map, const std::set<std::string>& keys,
                              const std::string& what) {
    for (const auto& kv : map) {
      if (!keys.count(kv.first.Scalar())) {
        fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in " + what,
             "the keys are " + join(std::vector<std::string>(keys.begin(), keys.end())));
      }
    }
  };
  // map's color: "#rrggbb" or a name; a bare #… is a YAML comment, which leaves the value
  // empty (located at the key then: the empty value has no place of its own)
  const auto colour = [&](const YAML::Node& map, const std::string& what) -> std::string {
    const std::string hint =
        "color: \"#d62728\" (quoted: # starts a YAML comment) or one of " + colour_names();
    const YAML::Node node = map["color"];
    if (!node.IsScalar() || node.Scalar().empty()) {
      for (const auto& kv : map) {
        if (kv.first.Scalar() == "color") fail(kv.first, what + ": the colour is empty", hint);
      }
    }
    const std::string s = node.Scalar();
    for (const auto& [name, hex] : kColours) {
      if (s == name) return hex;
    }
    const bool hex =
        s.size() == 7 && s[0] == '#' && std::all_of(s.begin() + 1, s.end(), [](char c) {
          return std::isxdigit(static_cast<unsigned char>(c));
        });
    if (!hex) fail(node, what + ": unknown colour '" + s + "'", hint);
    return s;
  };
  const auto positive = [&](const YAML::Node& node, const std::string& what) {
    const double v = number(node, what);
    if (!(v > 0.0)) fail(node, what + " must be > 0, got " + brief(v));
    return v;
  };

  // bodies: - {name: crank, …, visual: {shape: box, size: [L, 0.05, 0.05], color: red}} or a
  // list of such solids
  if (model.multibody && root["bodies"] && root["bodies"].IsSequence()) {
    std::size_t index = 0;
    for (const auto& b : root["bodies"]) {
      const std::string name = model.multibody->bodies.at(index++).name;
      const YAML::Node v = b["visual"];
      if (!v) continue;
      const std::string what = "body '" + name + "' visual";
      const std::string example = "{shape: box, size: [1, 0.05, 0.05], color: \"#1f77b4\"}";
      std::vector<YAML::Node> solids;
      if (v.IsMap()) {
        solids.push_back(v);
      } else if (v.IsSequence()) {
        for (const auto& s : v) solids.push_back(s);
      } else {
        fail(v, what + " must be a solid or a list of solids", example);
      }
      std::vector<VisualShape> shapes;
      for (const YAML::Node& s : solids) {
        if (!s.IsMap()) fail(s, what + ": a solid must be a mapping", example);
        check_keys(s, {"shape", "size", "radius", "length", "axis", "offset", "color"}, what);
        VisualShape shape;
        const YAML::Node kind = s["shape"];
        if (!kind) fail(s, what + " needs 'shape'", "box, cylinder, capsule or sphere");
        shape.shape = kind.Scalar();
        if (shape.shape == "box") {
          const YAML::Node size = s["size"];
          if (!size || !size.IsSequence() || size.size() != 3)
            fail(size ? size : s, what + ": a box needs size: [x, y, z] (its edges)", example);
          for (std::size_t i = 0; i < 3; ++i) shape.size[Index(i)] = positive(size[i], what);
        } else if (shape.shape == "cylinder" || shape.shape == "capsule" ||
                   shape.shape == "sphere") {
          if (!s["radius"])
            fail(s, what + ": a " + shape.shape + " needs radius",
                 "{shape: " + shape.shape + ", radius: 0.05" +
                     (shape.shape == "sphere" ? "}" : ", length: 1, axis: x}"));
          shape.size[0] = positive(s["radius"], what + " radius");
          if (shape.shape != "sphere") {
            if (!s["length"])
              fail(s, what + ": a " + shape.shape + " needs length",
                   "{shape: " + shape.shape + ", radius: 0.05, length: 1, axis: x}");
            shape.size[1] = number(s["length"], what + " length");
            if (!(shape.size[1] >= 0.0)) fail(s["length"], what + " length must be >= 0");
          }
        } else {
          fail(kind, what + ": unknown shape '" + shape.shape + "'",
               "box, cylinder, capsule or sphere");
        }
        if (const YAML::Node a = s["axis"]) {
          if (!a.IsScalar() || (a.Scalar() != "x" && a.Scalar() != "y" && a.Scalar() != "z"))
            fail(a, what + ": axis must be x, y or z (a body axis)");
          shape.axis = a.Scalar()[0];
        }
        if (const YAML::Node o = s["offset"]) {
          if (!o.IsSequence() || o.size() < 2 || o.size() > 3)
            fail(o, what + ": offset must be [x, y] or [x, y, z] (body coordinates)");
          for (std::size_t i = 0; i < o.size(); ++i)
            shape.offset[Index(i)] = number(o[i], what + " offset");
        }
        if (s["color"]) shape.color = colour(s, what);
        shapes.push_back(shape);
      }
      model.visual.bodies.emplace_back(name, std::move(shapes));
    }
  }

  // visual: {points: {bob: [x, y]} or {bob: {at: [x, y], color: red, radius: 0.05}},
  //          links: [[pivot, bob]], trails: [bob]}
  const YAML::Node v = root["visual"];
  if (!v) return;
  const std::string example = "{points: {pivot: [0, 0], bob: [x, y]}, links: [[pivot, bob]]}";
  if (!v.IsMap()) fail(v, "visual must be a mapping", example);
  check_keys(v, {"points", "links", "trails", "frames", "contacts"}, "visual");
  std::set<std::string> names;
  if (const YAML::Node ps = v["points"]) {
    if (!ps.IsMap()) fail(ps, "visual: points must map names to positions", example);
    for (const auto& kv : ps) {
      VisualPoint p;
      p.name = kv.first.Scalar();
      const std::string what = "visual point '" + p.name + "'";
      if (!is_identifier(p.name))
        fail(kv.first, what + ": the name is not an identifier",
             "letters, digits and _, not starting with a digit");
      if (!names.insert(p.name).second) fail(kv.first, what + " is given twice");
      YAML::Node at = kv.second;
      if (at.IsMap()) {
        check_keys(at, {"at", "color", "radius"}, what);
        if (at["color"]) p.color = colour(at, what);
        if (at["radius"]) p.radius = positive(at["radius"], what + " radius");
        if (!at["at"])
          fail(at, what + " needs at: [x, y] or [x, y, z]", "{at: [x, y], color: red}");
        at = at["at"];
      }
      if (!at.IsSequence() || at.size() < 2 || at.size() > 3)
        fail(at, what + " must be [x, y] or [x, y, z] (expressions of the coordinates and t)",
             "bob: [L*sin(theta), -L*cos(theta)]");
      p.dimensions = int(at.size());
      const char* axes[] = {"x", "y", "z"};
      for (std::size_t i = 0; i < at.size(); ++i) {
        model.visual.columns.push_back("visual." + p.name + "." + axes[i]);
        outputs.push_back(expression(at[i], what + " " + axes[i]));
        const std::string text = at[i].IsScalar() ? at[i].Scalar() : std::string();
        const auto c = std::find(coordinates_.begin(), coordinates_.end(), text);
        p.coordinates.push_back(c == coordinates_.end() ? -1 : int(c - coordinates_.begin()));
        p.expressions.push_back(text);
      }
      model.visual.points.push_back(p);
    }
  }
  // frames: {hoop: {at: [x, y], angle: theta, size: 0.3}} or {at: [x, y, z], quaternion: [...]}
  if (const YAML::Node fs = v["frames"]) {
    const std::string frame_example = "{hoop: {at: [x, y], angle: theta, size: 0.3}}";
    if (!fs.IsMap()) fail(fs, "visual: frames must map names to frames", frame_example);
    for (const auto& kv : fs) {
      VisualFrame f;
      f.name = kv.first.Scalar();
      const std::string what = "visual frame '" + f.name + "'";
      if (!is_identifier(f.name))
        fail(kv.first, what + ": the name is not an identifier",
             "letters, digits and _, not starting with a digit");
      if (!names.insert(f.name).second) fail(kv.first, what + ": the name is given twice");
      const YAML::Node m = kv.second;
      if (!m.IsMap()) fail(m, what + " must be a mapping", frame_example);
      check_keys(m, {"at", "angle", "quaternion", "size"}, what);
      const YAML::Node at = m["at"];
      if (!at || !at.IsSequence() || at.size() < 2 || at.size() > 3)
        fail(at ? at : m, what + ": at must be [x, y] or [x, y, z] (its origin)", frame_example);
      if (bool(m["angle"]) == bool(m["quaternion"]))
        fail(m, what + " needs either angle (about z) or quaternion [w, x, y, z]", frame_example);
      if (m["size"]) f.size = positive(m["size"], what + " size");
      f.dimensions = int(at.size());
      f.quaternion = bool(m["quaternion"]);
      const char* axes[] = {"x", "y", "z"};
      for (std::size_t i = 0; i < at.size(); ++i) {
        model.visual.columns.push_back("visual." + f.name + "." + axes[i]);
        outputs.push_back(expression(at[i], what + " " + axes[i]));
      }
      if (f.quaternion) {
        const YAML::Node q = m["quaternion"];
        if (!q.IsSequence() || q.size() != 4)
          fail(q, what + ": quaternion must be [w, x, y, z] (expressions)", "[u0, u1, u2, u3]");
        const char* parts[] = {"qw", "qx", "qy", "qz"};
        for (std::size_t i = 0; i < 4; ++i) {
          model.visual.columns.push_back("visual." + f.name + "." + parts[i]);
          outputs.push_back(expression(q[i], what + " quaternion"));
        }
      } else {
        model.visual.columns.push_back("visual." + f.name + ".angle");
        outputs.push_back(expression(m["angle"], what + " angle"));
      }
      model.visual.frames.push_back(f);
    }
  }
  // contacts: {floor: {at: [0, y - r], normal: [0, 1]}}: a unilateral constraint's contact
  // point and the direction its force pushes (a bodies or robot model's contacts: entries are
  // drawn already: an entry here replaces that of its name)
  if (const YAML::Node cs = v["contacts"]) {
    const std::string contact_example = "{floor: {at: [x, y - r], normal: [0, 1]}}";
    if (!cs.IsMap())
      fail(cs, "visual: contacts must map constraint names to contacts", contact_example);
    // (the system's: a bodies model's contacts: are unilateral constraints too)
    std::vector<std::string> unilateral;
    for (const Constraint& c : model.system.constraints()) {
      if (c.is_unilateral()) unilateral.push_back(c.name());
    }
    std::set<std::string> seen;
    for (const auto& kv : cs) {
      VisualContact c;
      c.name = kv.first.Scalar();
      const std::string what = "visual contact '" + c.name + "'";
      if (std::find(unilateral.begin(), unilateral.end(), c.name) == unilateral.end())
        fail(kv.first, what + ": there is no unilateral constraint of that name",
             unilateral.empty() ? "declare it under constraints: with unilateral: true (bodies "
                                  "models: under contacts:)"
                                : "the unilateral constraints are " + join(unilateral));
      if (!seen.insert(c.name).second) fail(kv.first, what + " is given twice");
      const YAML::Node m = kv.second;
      if (!m.IsMap()) fail(m, what + " must be a mapping", contact_example);
      check_keys(m, {"at", "normal"}, what);
      const YAML::Node at = m["at"], normal = m["normal"];
      if (!at || !at.IsSequence() || at.size() < 2 || at.size() > 3)
        fail(at ? at : m, what + ": at must be [x, y] or [x, y, z] (the contact point)",
             contact_example);
      if (!normal || !normal.IsSequence() || normal.size() != at.size())
        fail(normal ? normal : m,
             what +
                 ": normal must have as many components as at (the direction the contact "
                 "pushes)",
             contact_example);
      c.dimensions = int(at.size());
      const char* axes[] = {"x", "y", "z"};
      const char* normals[] = {"nx", "ny", "nz"};
      for (std::size_t i = 0; i < at.size(); ++i) {
        model.visual.columns.push_back("visual.contact." + c.name + "." + axes[i]);
        outputs.push_back(expression(at[i], what + " " + axes[i]));
      }
      bool zero = true;  // (every component identically 0: no direction to draw)
      for (std::size_t i = 0; i < normal.size(); ++i) {
        model.visual.columns.push_back("visual.contact." + c.name + "." + normals[i]);
        outputs.push_back(expression(normal[i], what + " normal"));
        zero = zero && set_->is_zero(outputs.back());
      }
      if (zero)
        fail(normal, what + ": normal is zero; it must give the direction the contact pushes",
             contact_example);
      // (it replaces the drawn contact of a contacts: entry of its name, whose friction axes it
      // keeps: the friction at a contact point is drawn from them)
      auto& drawn = model.visual.contacts;
      for (const VisualContact& d : drawn)
        if (d.name == c.name) c.axes = d.axes;
      drawn.erase(std::remove_if(drawn.begin(), drawn.end(),
                                 [&](const VisualContact& d) { return d.name == c.name; }),
                  drawn.end());
      model.visual.contacts.push_back(c);
    }
  }
  if (const YAML::Node ls = v["links"]) {
    if (!ls.IsSequence()) fail(ls, "visual: links must be a list of point pairs", example);
    for (const auto& l : ls) {
      if (!l.IsSequence() || l.size() != 2)
        fail(l, "visual: a link is a pair of point names", "[pivot, bob]");
      for (std::size_t i = 0; i < 2; ++i) {
        if (!names.count(l[i].Scalar()))
          fail(l[i], "visual: the link names '" + l[i].Scalar() + "', which is not a point",
               names.empty() ? "declare it under visual: points:"
                             : "the points are " +
                                   join(std::vector<std::string>(names.begin(), names.end())));
      }
      model.visual.links.emplace_back(l[0].Scalar(), l[1].Scalar());
    }
  }
  if (const YAML::Node ts = v["trails"]) {
    if (!ts.IsSequence()) fail(ts, "visual: trails must be a list of names", "[bob]");
    std::set<std::string> known = names;
    if (model.multibody) {
      for (const auto& b : model.multibody->bodies) known.insert(b.name);
    }
    for (const auto& t : ts) {
      if (!t.IsScalar() || !known.count(t.Scalar()))
        fail(t,
             "visual: the trail names '" + (t.IsScalar() ? t.Scalar() : std::string()) +
                 "', which is not a point" + (model.multibody ? " or a body" : ""),
             known.empty()
                 ? "declare it under visual: points:"
                 : "the names are " + join(std::vector<std::string>(known.begin(), known.end())));
      model.visual.trails.push_back(t.Scalar());
    }
  }
}

}  // namespace ukdyn::model_reader
