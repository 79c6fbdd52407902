// SPDX-License-Identifier: BSD-3-Clause
// The viewer page's data from a run's samples (app/viewer_page.hpp): python/ukdyn/viewer.py's
// scene_data, rule for rule, so that the command's page and Python's are the same.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "viewer_page.hpp"

namespace ukdyn::cli {
namespace {

using json = nlohmann::ordered_json;

constexpr const char* kAxes[] = {"x", "y", "z"};

// a whole number below 1e15 as a JSON integer, else the double (viewer.py: int(r) when
// r.is_integer() and abs(r) < 1e15)
json number(double r) {
  if (std::trunc(r) == r && std::fabs(r) < 1e15) return json(static_cast<std::int64_t>(r));
  return json(r);
}

// the text of a JSON string, or "" (scene.get(key, ""))
std::string text_of(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

// scene.get(key, []) as an array
json list_of(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_array() ? *it : json::array();
}

int dimensions_of(const json& item) {
  const auto it = item.find("dimensions");
  return it != item.end() && it->is_number_integer() ? std::clamp(it->get<int>(), 0, 3) : 2;
}

// Python's truth of a JSON value (None, "", [], {}, 0 and false are false)
bool truthy(const json& j) {
  if (j.is_null()) return false;
  if (j.is_boolean()) return j.get<bool>();
  if (j.is_number()) return j.get<double>() != 0.0;
  // (nlohmann's empty() is false for every string: a string's emptiness is its text's)
  if (j.is_string()) return !j.get_ref<const std::string&>().empty();
  if (j.is_array() || j.is_object()) return !j.empty();
  return true;
}

// Columns of the decimated samples as compact JSON arrays, rounded (viewer.py's _Packer).
class Packer {
 public:
  Packer(const ViewerColumns& run, std::vector<std::size_t> keep, int digits)
      : run_(run), keep_(std::move(keep)), digits_(digits) {}

  bool has(const std::string& name) const { return index(name) != run_.names.size(); }

  // the samples shown of a column (a column the scene needs and the run lacks: an error)
  std::vector<double> raw(const std::string& name) const {
    const std::size_t k = index(name);
    if (k == run_.names.size()) {
      throw std::runtime_error("the trajectory has no column '" + name +
                               "', which the viewer draws");
    }
    const std::vector<double>& column = run_.columns.at(k);
    std::vector<double> out;
    out.reserve(keep_.size());
    for (const std::size_t i : keep_) {
      if (i >= column.size()) throw std::runtime_error("the column '" + name + "' is short");
      out.push_back(column[i]);
    }
    return out;
  }

  json pack(const std::string& name, int digits = -1) const {
    json out = json::array();
    for (const double v : raw(name))
      out.push_back(round_significant(v, digits < 0 ? digits_ : digits));
    return out;
  }

  // v rounded as pack() rounds
  json rounded(double v) const { return round_significant(v, digits_); }

  json pack_fixed(const std::string& name, int decimals) const {
    json out = json::array();
    for (const double v : raw(name)) out.push_back(round_fixed(v, decimals));
    return out;
  }

  // [pack(c) if has(c) else None for c in names]
  json pack_or_null(const std::vector<std::string>& names) const {
    json out = json::array();
    for (const std::string& c : names) out.push_back(has(c) ? pack(c) : json(nullptr));
    return out;
  }

  bool has_any(const std::vector<std::string>& names) const {
    return std::any_of(names.begin(), names.end(), [&](const std::string& c) { return has(c); });
  }

 private:
  // the first column of that name (names.size(): none)
  std::size_t index(const std::string& name) const {
    const auto it = std::find(run_.names.begin(), run_.names.end(), name);
    return std::size_t(it - run_.names.begin());
  }

  const ViewerColumns& run_;
  std::vector<std::size_t> keep_;
  int digits_;
};

// The decimal places that keep positions to 1e-4 of the scene's extent (the largest spread of
// the positions along x, y or z; their largest magnitude when nothing moves), viewer.py's
// _position_decimals.
int position_decimals(const std::vector<std::vector<double>>& axes) {
  double extent = 0.0, largest = 0.0;
  for (const std::vector<double>& values : axes) {
    bool any = false;
    double lo = 0.0, hi = 0.0, big = 0.0;
    for (const double v : values) {
      if (!std::isfinite(v)) continue;
      lo = any ? std::min(lo, v) : v;
      hi = any ? std::max(hi, v) : v;
      big = std::max(big, std::fabs(v));
      any = true;
    }
    if (any) {
      extent = std::max(extent, hi - lo);
      largest = std::max(largest, big);
    }
  }
  if (!(extent > 0)) extent = largest != 0.0 ? largest : 1.0;
  return 4 - static_cast<int>(std::floor(std::log10(extent)));
}

// |v| of a vector of rounded components as Python sums them (viewer.py's _scale): the squares
// of whole numbers exactly, as Python's integers, a float from the first float on
__extension__ typedef __int128 Int128;  // (GCC and clang; __extension__: no -Wpedantic)

double magnitude(const std::vector<const json*>& components) {
  bool whole = true;
  Int128 exact = 0;
  double sum = 0.0;
  for (const json* c : components) {
    if (c->is_null()) continue;
    if (c->is_number_integer()) {
      const auto k = static_cast<Int128>(c->get<std::int64_t>());
      if (whole) {
        exact += k * k;
      } else {
        sum = sum + static_cast<double>(k * k);
      }
    } else {
      const double x = c->get<double>();
      if (!std::isfinite(x)) continue;
      if (whole) {
        sum = static_cast<double>(exact) + x * x;
        whole = false;
      } else {
        sum += x * x;
      }
    }
  }
  return std::sqrt(whole ? static_cast<double>(exact) : sum);
}

// The magnitude drawn a quarter of the scene long: the 90th percentile of the vectors' non-zero
// magnitudes (1 when there is none), viewer.py's _scale.
double arrow_scale(std::vector<double> norms) {
  std::sort(norms.begin(), norms.end());
  std::erase_if(norms, [](double n) { return !(n > 0); });
  if (norms.empty()) return 1.0;
  const auto k = static_cast<std::size_t>(0.9 * static_cast<double>(norms.size()));
  return norms[std::min(norms.size() - 1, k)];
}

// A requirement row: its name, its error column, its desired column ("" when none).
struct RequirementRow {
  std::string row, error, desired;
};

// error.<row> and desired_<row> with the row's dots written as underscores (viewer.py's
// _requirement_rows)
std::vector<RequirementRow> requirement_rows(const std::vector<std::string>& names) {
  std::vector<RequirementRow> out;
  for (const std::string& name : names) {
    if (name.rfind("error.", 0) != 0) continue;
    const std::string row = name.substr(6);
    std::string desired = "desired_" + row;
    std::replace(desired.begin(), desired.end(), '.', '_');
    const bool present = std::find(names.begin(), names.end(), desired) != names.end();
    out.push_back({row, name, present ? desired : std::string()});
  }
  return out;
}

// The requirements whose desired value is a path in the scene (viewer.py's _desired_paths): a
// requirement whose rows <name>.0, .1 (, .2) are, in some order, the positions of a visual
// point or a body's centre, to 1e-9 of the scene's extent at every sample shown.
json desired_paths(const json& scene, const Packer& p, const std::vector<RequirementRow>& rows,
                   const std::vector<std::pair<std::string, std::vector<double>>>& actual,
                   int decimals) {
  struct Part {
    long k;
    std::string row, desired;
    auto operator<=>(const Part&) const = default;
  };
  std::vector<std::pair<std::string, std::vector<Part>>> groups;  // in the order first met
  for (const RequirementRow& r : rows) {
    const std::size_t dot = r.row.rfind('.');
    if (dot == std::string::npos || dot == 0 || r.desired.empty()) continue;
    const std::string base = r.row.substr(0, dot), k = r.row.substr(dot + 1);
    if (k.empty() || !std::all_of(k.begin(), k.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    const long index = k.size() > 9 ? 1000000000L : std::stol(k);
    auto it =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == base; });
    if (it == groups.end()) it = groups.insert(groups.end(), {base, {}});
    it->second.push_back({index, r.row, r.desired});
  }
  struct Candidate {
    std::string prefix, name;
    int dimensions;
  };
  std::vector<Candidate> candidates;
  for (const json& pt : list_of(scene, "points")) {
    candidates.push_back(
        {"visual." + text_of(pt, "name") + ".", text_of(pt, "name"), dimensions_of(pt)});
  }
  for (const json& b : list_of(scene, "bodies")) {
    candidates.push_back(
        {text_of(b, "name") + ".", text_of(b, "name"), text_of(b, "kind") == "planar" ? 2 : 3});
  }
  const double tolerance = 1e-9 * std::pow(10.0, 4 - decimals);
  const auto actual_of = [&](const std::string& row) -> const std::vector<double>& {
    // (the last of a name, as a dict's assignment keeps)
    for (auto it = actual.rbegin(); it != actual.rend(); ++it) {
      if (it->first == row) return it->second;
    }
    throw std::logic_error("viewer: no actual values of " + row);
  };
  json out = json::array();
  for (auto& [base, parts] : groups) {
    std::sort(parts.begin(), parts.end());
    if (parts.size() != 2 && parts.size() != 3) continue;
    bool in_order = true;
    for (std::size_t i = 0; i < parts.size(); ++i) in_order = in_order && parts[i].k == long(i);
    if (!in_order) continue;
    std::vector<const std::vector<double>*> values_of;
    for (const Part& part : parts) values_of.push_back(&actual_of(part.row));
    for (const Candidate& c : candidates) {
      if (std::size_t(c.dimensions) != parts.size()) continue;
      std::vector<std::string> axes;
      for (int a = 0; a < c.dimensions; ++a) axes.push_back(c.prefix + kAxes[a]);
      if (!std::all_of(axes.begin(), axes.end(), [&](const std::string& s) { return p.has(s); }))
        continue;
      // which row is which axis: each axis the one row that equals it throughout
      std::vector<std::size_t> order;
      for (const std::string& axis : axes) {
        const std::vector<double> along = p.raw(axis);
        bool found = false;
        for (std::size_t r = 0; r < values_of.size() && !found; ++r) {
          if (std::find(order.begin(), order.end(), r) != order.end()) continue;
          const std::vector<double>& values = *values_of[r];
          bool same = true;
          for (std::size_t i = 0; i < std::min(values.size(), along.size()) && same; ++i) {
            same = std::isfinite(values[i]) && std::fabs(values[i] - along[i]) <= tolerance;
          }
          if (same) {
            order.push_back(r);
            found = true;
          }
        }
        if (!found) break;
      }
      if (order.size() == std::size_t(c.dimensions)) {
        json q = json::array();
        for (const std::size_t r : order) q.push_back(p.pack_fixed(parts[r].desired, decimals));
        out.push_back({{"requirement", base}, {"of", c.name}, {"q", q}});
        break;
      }
    }
  }
  return out;
}

// The torque (world axes) of the generalized forces Q = (Q0, Qx, Qy, Qz) on a unit quaternion
// u = (w, x, y, z), per sample: tau = 1/2 E(u) Q, E(u) = [-v | w I + [v]x] (omega = 2 E(u) u',
// so tau . omega = Q . u'), viewer.py's _quaternion_torque operation for operation.
std::array<std::vector<double>, 3> quaternion_torque(const std::array<std::vector<double>, 4>& u,
                                                     const std::array<std::vector<double>, 4>& Q) {
  std::array<std::vector<double>, 3> out;
  const std::size_t n = std::min(u[0].size(), Q[0].size());
  for (std::size_t i = 0; i < n; ++i) {
    const double w = u[0][i], x = u[1][i], y = u[2][i], z = u[3][i];
    const double q0 = Q[0][i], qx = Q[1][i], qy = Q[2][i], qz = Q[3][i];
    out[0].push_back(0.5 * (w * qx - x * q0 + (y * qz - z * qy)));
    out[1].push_back(0.5 * (w * qy - y * q0 + (z * qx - x * qz)));
    out[2].push_back(0.5 * (w * qz - z * q0 + (x * qy - y * qx)));
  }
  return out;
}

// The friction force at a contact in the scene's axes, per frame shown: F = map Q_f, Q_f each
// sliding coordinate's generalized friction force (the sum of its columns, one each: the run's
// visual.contact.<name>.Qf.<coordinate>, the stick constraint's whole multiplier while the
// contact holds and Qc_nonideal.<coordinate> while it slides; the scene's "friction",
// src/modelfile/visual.cpp). The page draws its part across the normal. (viewer.py's
// _friction_force)
json friction_force(const Packer& p, const json& friction) {
  std::vector<std::vector<double>> sums;
  for (const json& columns : list_of(friction, "columns")) {
    std::vector<double> total;
    for (const json& column : columns) {
      const std::vector<double> values = p.raw(column.get<std::string>());
      if (total.empty()) {
        total = values;
      } else {
        for (std::size_t i = 0; i < total.size() && i < values.size(); ++i) total[i] += values[i];
      }
    }
    sums.push_back(std::move(total));
  }
  json out = json::array();
  for (const json& row : list_of(friction, "map")) {
    json comp = json::array();
    const std::size_t frames = sums.empty() ? 0 : sums.front().size();
    for (std::size_t i = 0; i < frames; ++i) {
      double f = 0.0;
      for (std::size_t j = 0; j < row.size() && j < sums.size(); ++j)
        f += row[j].get<double>() * sums[j][i];
      comp.push_back(p.rounded(f));
    }
    out.push_back(comp);
  }
  return out;
}

}  // namespace

std::vector<std::size_t> shown_frames(const std::vector<double>& t, const ViewerOptions& options) {
  const std::size_t n = t.size();
  if (n == 0) return {};
  const double span = t.back() - t.front();
  std::size_t wanted = 1;
  if (span > 0) {
    const double frames = std::ceil(span * options.fps) + 1.0;
    wanted = frames >= double(options.max_frames) ? options.max_frames
                                                  : std::max<std::size_t>(2, std::size_t(frames));
  }
  std::vector<std::size_t> out;
  if (wanted >= n) {
    for (std::size_t i = 0; i < n; ++i) out.push_back(i);
    return out;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < wanted; ++i) {
    const double target =
        t.front() + span * double(i) / double(std::max<std::size_t>(wanted - 1, 1));
    while (k + 1 < n && t[k + 1] <= target) ++k;
    if (out.empty() || out.back() != k) out.push_back(k);
  }
  if (out.back() != n - 1) out.push_back(n - 1);
  return out;
}

json round_significant(double v, int digits) {
  if (!std::isfinite(v)) return json(nullptr);
  if (v == 0.0) return json(0);
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", std::clamp(digits, 1, 40), v);
  return number(std::strtod(text, nullptr));
}

json round_fixed(double v, int decimals) {
  if (!std::isfinite(v)) return json(nullptr);
  // Python's limits: beyond 323 places a double is unchanged; beyond 10^308 it is 0
  if (decimals > 323) return number(v);
  if (decimals < -308) return json(0);
  if (decimals >= 0) {
    // %.*f rounds the exact binary value half to even (glibc), as Python's dtoa does
    const int size = std::snprintf(nullptr, 0, "%.*f", decimals, v);
    std::string text(std::size_t(size) + 1, '\0');
    std::snprintf(text.data(), text.size(), "%.*f", decimals, v);
    return number(std::strtod(text.c_str(), nullptr));
  }
  // to a multiple of 10^m: the exact digits of the whole part, rounded half to even as a
  // decimal string (a fraction left over makes an exact half round up)
  const std::size_t m = std::size_t(-decimals);
  const double whole = std::floor(std::fabs(v));
  const bool fraction = whole != std::fabs(v);
  char buffer[400];
  std::snprintf(buffer, sizeof buffer, "%.0f", whole);
  std::string digits(buffer);
  if (digits.size() < m + 1) digits.insert(0, m + 1 - digits.size(), '0');
  std::string kept = digits.substr(0, digits.size() - m);
  const int compare = digits.compare(digits.size() - m, m, "5" + std::string(m - 1, '0'));
  if (compare > 0 || (compare == 0 && (fraction || (kept.back() - '0') % 2 == 1))) {
    std::size_t i = kept.size();
    while (i > 0 && kept[i - 1] == '9') kept[--i] = '0';
    if (i == 0) {
      kept.insert(0, "1");
    } else {
      ++kept[i - 1];
    }
  }
  const std::string text = (v < 0 ? "-" : "") + kept + std::string(m, '0');
  return number(std::strtod(text.c_str(), nullptr));
}

json read_contact_events(const std::filesystem::path& summary) {
  std::ifstream in(summary);
  if (!in) return json::array();
  const json j = json::parse(in, nullptr, false);
  if (!j.is_object()) return json::array();
  const json events = list_of(j, "contact_events");
  json out = json::array();
  for (const json& e : events) {
    if (e.is_object()) out.push_back(e);
  }
  return out;
}

std::vector<std::string> point_columns(const json& scene) {
  std::vector<std::string> out;
  for (const json& pt : list_of(scene, "points")) {
    for (int a = 0; a < dimensions_of(pt); ++a) {
      out.push_back("visual." + text_of(pt, "name") + "." + kAxes[a]);
    }
  }
  return out;
}

std::vector<std::string> nonfinite_warnings(const json& scene,
                                            const std::map<std::string, double>& first) {
  std::vector<std::string> out;
  for (const json& pt : list_of(scene, "points")) {
    const std::string name = text_of(pt, "name");
    // the earliest (time, axis) at which a component is not finite
    bool bad = false;
    double t = 0.0;
    int axis = 0;
    for (int a = 0; a < dimensions_of(pt); ++a) {
      const auto it = first.find("visual." + name + "." + kAxes[a]);
      if (it == first.end()) continue;
      if (!bad || it->second < t) {
        t = it->second;
        axis = a;
      }
      bad = true;
    }
    if (!bad) continue;
    const json expressions = list_of(pt, "expressions");
    std::string what = kAxes[axis];
    if (std::size_t(axis) < expressions.size() && expressions[std::size_t(axis)].is_string()) {
      what += ": " + expressions[std::size_t(axis)].get<std::string>();
    }
    char when[40];
    std::snprintf(when, sizeof when, "%.9g", t);
    out.push_back("warning: visual point '" + name + "' is not finite from t = " + when +
                  " (its expression " + what + "); the viewer hides it while so");
  }
  return out;
}

json viewer_page_data(const json& scene, const ViewerColumns& run, const ViewerOptions& options,
                      const json& contact_events) {
  const auto t_column = std::find(run.names.begin(), run.names.end(), "t");
  const std::vector<double> no_t;
  const std::vector<double>& t_all = t_column != run.names.end()
                                         ? run.columns.at(std::size_t(t_column - run.names.begin()))
                                         : no_t;
  const std::vector<std::size_t> keep = shown_frames(t_all, options);
  const Packer p(run, keep, options.digits);
  json data;
  data["model"] = scene.contains("model") ? scene["model"] : json("");
  data["planar"] = scene.contains("planar") ? truthy(scene["planar"]) : true;
  data["t"] = keep.empty() ? json::array() : p.pack("t", 7);
  data["energy"] = p.has("energy") ? p.pack("energy", 6) : json(nullptr);
  data["bodies"] = json::array();
  data["joints"] = json::array();
  data["points"] = json::array();
  data["links"] = list_of(scene, "links");
  data["trails"] = list_of(scene, "trails");
  data["frames"] = json::array();
  data["requirements"] = json::array();
  // each coordinate's unit, where known (the page labels forces by them)
  data["units"] = json::object();
  const json coordinates = list_of(scene, "coordinates");
  const json coordinate_units = list_of(scene, "coordinate_units");
  for (std::size_t k = 0; k < std::min(coordinates.size(), coordinate_units.size()); ++k) {
    if (truthy(coordinate_units[k]))
      data["units"][coordinates[k].get<std::string>()] = coordinate_units[k];
  }

  // positions to 1e-4 of the scene's extent, angles and quaternions to 1e-4
  std::vector<std::vector<std::string>> along(3);
  for (const json& b : list_of(scene, "bodies")) {
    for (int a = 0; a < 3; ++a)
      along[std::size_t(a)].push_back(text_of(b, "name") + "." + kAxes[a]);
  }
  for (const char* section : {"points", "frames"}) {
    for (const json& pt : list_of(scene, section)) {
      for (int a = 0; a < dimensions_of(pt); ++a) {
        along[std::size_t(a)].push_back("visual." + text_of(pt, "name") + "." + kAxes[a]);
      }
    }
  }
  std::vector<std::vector<double>> positions(3);
  for (std::size_t a = 0; a < 3; ++a) {
    for (const std::string& c : along[a]) {
      if (!p.has(c)) continue;
      const std::vector<double> values = p.raw(c);
      positions[a].insert(positions[a].end(), values.begin(), values.end());
    }
  }
  const int decimals = keep.empty() ? 4 : position_decimals(positions);

  // bodies: planar (x, y, theta), rigid (x, y, z, u0..u3), particle (x, y, z)
  for (const json& b : list_of(scene, "bodies")) {
    const std::string name = text_of(b, "name"), kind = text_of(b, "kind");
    std::vector<std::string> keys;
    if (kind == "planar") {
      keys = {"x", "y", "theta"};
    } else if (kind == "rigid") {
      keys = {"x", "y", "z", "u0", "u1", "u2", "u3"};
    } else if (kind == "particle") {
      keys = {"x", "y", "z"};
    } else {
      throw std::runtime_error("the body '" + name + "' is of an unknown kind '" + kind + "'");
    }
    json body = b;
    json q = json::array();
    for (const std::string& k : keys) {
      const bool is_position = k == "x" || k == "y" || k == "z";
      q.push_back(p.pack_fixed(name + "." + k, is_position ? decimals : 4));
    }
    body["q"] = q;
    const std::vector<std::string> control = {
        "Qc_control." + name + ".x", "Qc_control." + name + ".y", "Qc_control." + name + ".z"};
    if (p.has_any(control)) body["control"] = p.pack_or_null(control);
    // the control torque: a planar body's about z (Qc_control.<b>.theta); a rigid body's from
    // the generalized forces on its quaternion (quaternion_torque)
    const std::string theta = "Qc_control." + name + ".theta";
    std::vector<std::string> quaternion;
    for (const char* k : {"u0", "u1", "u2", "u3"})
      quaternion.push_back("Qc_control." + name + "." + k);
    if (kind == "planar" && p.has(theta)) {
      body["control_torque"] = json::array({nullptr, nullptr, p.pack(theta)});
    } else if (kind == "rigid" && std::all_of(quaternion.begin(), quaternion.end(),
                                              [&](const std::string& c) { return p.has(c); })) {
      std::array<std::vector<double>, 4> u, Q;
      for (std::size_t k = 0; k < 4; ++k) {
        u[k] = p.raw(name + ".u" + std::to_string(k));
        Q[k] = p.raw(quaternion[k]);
      }
      json torque = json::array();
      for (const std::vector<double>& c : quaternion_torque(u, Q)) {
        json values = json::array();
        for (const double v : c) values.push_back(p.rounded(v));
        torque.push_back(values);
      }
      body["control_torque"] = torque;
    }
    data["bodies"].push_back(body);
  }
  // joints: the reaction force at the child's point, ideal and non-ideal (friction), and the
  // reaction torque, ideal and non-ideal (a revolute joint's friction torque)
  for (const json& j : list_of(scene, "joints")) {
    json joint = j;
    const std::string base = "reaction." + text_of(j, "name") + ".";
    for (const auto& [key, prefix] : {std::pair{"ideal", ""}, std::pair{"nonideal", "friction_"}}) {
      for (const auto& [suffix, parts] : {std::pair{"", "f"}, std::pair{"_torque", "t"}}) {
        std::vector<std::string> cols;
        for (const char* a : kAxes) cols.push_back(base + prefix + parts + a);
        if (p.has_any(cols)) joint[std::string(key) + suffix] = p.pack_or_null(cols);
      }
    }
    data["joints"].push_back(joint);
  }
  // points of a visual: section; a point whose components are each exactly a coordinate
  // carries the generalized constraint (and control) forces of those coordinates
  for (const json& pt : list_of(scene, "points")) {
    json point = pt;
    const std::string name = text_of(pt, "name");
    const int dimensions = dimensions_of(pt);
    json q = json::array();
    for (int a = 0; a < dimensions; ++a)
      q.push_back(p.pack_fixed("visual." + name + "." + kAxes[a], decimals));
    point["q"] = q;
    json same =
        pt.contains("coordinates") && truthy(pt["coordinates"]) ? pt["coordinates"] : json::array();
    if (same.empty()) {
      for (int a = 0; a < dimensions; ++a) same.push_back(nullptr);
    }
    const bool all_coordinates =
        !same.empty() &&
        std::all_of(same.begin(), same.end(), [](const json& s) { return truthy(s); });
    if (all_coordinates) {
      for (const auto& [key, prefix] :
           {std::pair{"ideal", "Qc_ideal."}, std::pair{"nonideal", "Qc_nonideal."},
            std::pair{"control", "Qc_control."}}) {
        std::vector<std::string> cols;
        for (const json& s : same)
          cols.push_back(prefix + (s.is_string() ? s.get<std::string>() : s.dump()));
        if (std::all_of(cols.begin(), cols.end(), [&](const std::string& c) { return p.has(c); })) {
          json forces = json::array();
          for (const std::string& c : cols) forces.push_back(p.pack(c));
          point[key] = forces;
        }
      }
    }
    data["points"].push_back(point);
  }
  // frames of a visual: section: origin, and angle about z or quaternion
  for (const json& fr : list_of(scene, "frames")) {
    json frame = fr;
    const std::string name = text_of(fr, "name");
    json q = json::array(), r = json::array();
    for (int a = 0; a < dimensions_of(fr); ++a)
      q.push_back(p.pack_fixed("visual." + name + "." + kAxes[a], decimals));
    frame["q"] = q;
    const bool quaternion = fr.contains("quaternion") && truthy(fr["quaternion"]);
    const std::vector<std::string> parts = quaternion
                                               ? std::vector<std::string>{"qw", "qx", "qy", "qz"}
                                               : std::vector<std::string>{"angle"};
    for (const std::string& c : parts) r.push_back(p.pack_fixed("visual." + name + "." + c, 4));
    frame["r"] = r;
    data["frames"].push_back(frame);
  }
  // a robot's links: each link's joint with its coordinates' samples, to 1e-4 (the page
  // computes the frames)
  if (scene.contains("robot") && truthy(scene["robot"])) {
    json robot = scene["robot"];
    robot["links"] = json::array();
    for (const json& l : list_of(scene["robot"], "links")) {
      json link = l;
      json q = json::array();
      for (const json& c : list_of(l, "coordinates"))
        q.push_back(p.pack_fixed(c.is_string() ? c.get<std::string>() : c.dump(), 4));
      link["q"] = q;
      robot["links"].push_back(link);
    }
    data["robot"] = robot;
  }
  // contacts of visual: contacts: the contact point, the direction its force pushes, the
  // force's magnitude (lambda.<name>), and the impacts (time and contact)
  if (truthy(list_of(scene, "contacts"))) {
    data["contacts"] = json::array();
    std::vector<std::string> drawn;
    for (const json& c : list_of(scene, "contacts")) {
      json contact = c;
      const std::string name = text_of(c, "name"), base = "visual.contact." + name + ".";
      json q = json::array(), n = json::array();
      for (int a = 0; a < dimensions_of(c); ++a) {
        q.push_back(p.pack_fixed(base + kAxes[a], decimals));
        n.push_back(p.pack_fixed(base + "n" + kAxes[a], 4));
      }
      contact["q"] = q;
      contact["n"] = n;
      // the contact's whole multiplier (lambda_total: with its share of the non-ideal forces)
      contact["force"] =
          p.pack(p.has("lambda_total." + name) ? "lambda_total." + name : "lambda." + name);
      if (c.contains("friction") && truthy(c["friction"]))
        contact["friction_force"] = friction_force(p, c["friction"]);
      data["contacts"].push_back(contact);
      drawn.push_back(name);
    }
    json impacts = json::array();
    for (const json& e : contact_events.is_array() ? contact_events : json::array()) {
      if (!e.is_object()) continue;
      const std::string kind = text_of(e, "kind"), contact = text_of(e, "contact");
      const auto t = e.find("t");
      if ((kind != "impact" && kind != "rest") || t == e.end() || !t->is_number() ||
          !e["contact"].is_string() ||
          std::find(drawn.begin(), drawn.end(), contact) == drawn.end())
        continue;
      impacts.push_back({{"t", round_significant(t->get<double>(), 7)}, {"contact", contact}});
    }
    data["impacts"] = impacts;
  }
  // the control's requirements: each row's error, and where the requirement says what is
  // desired, the desired and the actual value (actual = desired + error)
  const std::vector<RequirementRow> rows = requirement_rows(run.names);
  std::vector<std::pair<std::string, std::vector<double>>> actual;
  for (const RequirementRow& row : rows) {
    json entry = {{"name", row.row}, {"error", p.pack(row.error)}};
    if (!row.desired.empty()) {
      const std::vector<double> desired = p.raw(row.desired), error = p.raw(row.error);
      std::vector<double> values(std::min(desired.size(), error.size()));
      for (std::size_t i = 0; i < values.size(); ++i) values[i] = desired[i] + error[i];
      entry["desired"] = p.pack(row.desired);
      json packed = json::array();
      for (const double v : values) packed.push_back(round_significant(v, options.digits));
      entry["actual"] = packed;
      actual.emplace_back(row.row, std::move(values));
    }
    data["requirements"].push_back(entry);
  }
  data["desired_paths"] = desired_paths(scene, p, rows, actual, decimals);
  for (const json& path : data["desired_paths"]) {
    json& trails = data["trails"];
    if (std::find(trails.begin(), trails.end(), path["of"]) == trails.end())
      trails.push_back(path["of"]);
  }
  // a kind of force that is zero throughout draws no arrows; nor does a torque that is
  // round-off: at most 1e-9 of the largest joint force times the scene's extent
  const char* const kinds[] = {"ideal",        "nonideal",        "control",
                               "ideal_torque", "nonideal_torque", "control_torque"};
  double largest_force = 0.0;
  for (const json& j : data["joints"]) {
    for (const char* key : {"ideal", "nonideal"}) {
      if (!j.contains(key)) continue;
      for (const json& c : j[key]) {
        if (!truthy(c)) continue;
        for (const json& v : c) {
          if (!v.is_null()) largest_force = std::max(largest_force, std::fabs(v.get<double>()));
        }
      }
    }
  }
  const double extent = std::pow(10.0, 4 - decimals);
  for (const char* section : {"joints", "points", "bodies"}) {
    for (json& item : data[section]) {
      for (const std::string key : kinds) {
        if (!item.contains(key)) continue;
        const double floor = key.ends_with("_torque") ? 1e-9 * largest_force * extent : 0.0;
        bool any = false;
        for (const json& c : item[key]) {
          if (!truthy(c)) continue;
          for (const json& v : c) any = any || (!v.is_null() && std::fabs(v.get<double>()) > floor);
        }
        if (!any) item.erase(key);
      }
    }
  }
  // the scales of the force (and torque) arrows: the largest of each kind over the run
  json scales;
  for (const std::string key : kinds) {
    std::vector<double> norms;
    for (const char* section : {"joints", "points", "bodies"}) {
      for (const json& item : data[section]) {
        if (!item.contains(key) || !truthy(item[key])) continue;
        std::vector<const json*> comps;
        for (const json& c : item[key]) {
          if (!c.is_null()) comps.push_back(&c);
        }
        if (comps.empty()) continue;
        std::size_t samples = comps.front()->size();
        for (const json* c : comps) samples = std::min(samples, c->size());
        for (std::size_t i = 0; i < samples; ++i) {
          std::vector<const json*> vector;
          for (const json* c : comps) vector.push_back(&(*c)[i]);
          norms.push_back(magnitude(vector));
        }
      }
    }
    scales[key] = arrow_scale(std::move(norms));
  }
  if (data.contains("contacts")) {
    std::vector<double> norms;
    for (const json& c : data["contacts"]) {
      for (const json& v : c["force"]) norms.push_back(magnitude({&v}));
    }
    scales["contact"] = arrow_scale(std::move(norms));
  }
  data["force_scale"] = scales;
  return data;
}

}  // namespace ukdyn::cli
