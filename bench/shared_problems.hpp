// SPDX-License-Identifier: BSD-3-Clause
// The shared benchmark problems P1, P2, P3 (bench/data/README.md) as read from
// bench/data/problems.json, for every program that builds them (bench_multibody_problems with
// ukdyn's multibody layer, bench_mujoco with MuJoCo).
#pragma once

#include <fstream>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace shared_problems {

// reference coordinates at T (shared README, from a run at accuracy 1e-10)
inline const std::map<std::string, double> kReference = {{"P1", -2.1392711},
                                                         {"P2", 3.1507615},
                                                         {"P3_N8", -1.4271540},
                                                         {"P3_N32", -1.3904325},
                                                         {"P3_N128", -1.3939935}};

// Each link's frame has its origin at the proximal hinge and x along the link.
struct Link {
  std::string name;
  int parent = -1;        // link index, −1: the ground (parents come first)
  Eigen::Vector2d joint;  // hinge in the parent link's frame (ground: world)
  double phi0 = 0, length = 0, mass = 0, com_x = 0;
  Eigen::Vector3d I_com;  // about the link's own axis, then the two transverse ones (z last)
};
struct Closure {
  int b1 = 0, b2 = -1;     // links (b2 = −1: the ground)
  Eigen::Vector2d p1, p2;  // points in the links' frames (ground: world)
};
struct Problem {
  std::string id, coord_name;
  bool particles = false;  // (bench_multibody_problems) P1's point masses as particles
  double T = 0, V_eq = 0, reference = 0;
  std::vector<Link> links;
  std::vector<Closure> closures;
};

inline Eigen::Vector2d point(const nlohmann::json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>()};
}

// The problems of problems.json at `path`; `who` names the program in errors.
// @throws std::runtime_error when the file cannot be read or a link comes before its parent
inline std::vector<Problem> load(const std::string& path, const std::string& who) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(who + ": cannot read " + path + " (use --problems=PATH)");
  const nlohmann::json j = nlohmann::json::parse(in);
  std::vector<Problem> out;
  for (const auto& p : j.at("problems")) {
    Problem r;
    r.id = p.at("id");
    r.coord_name = p.at("coord_name");
    r.T = p.at("T");
    r.V_eq = p.at("V_eq");
    r.reference = kReference.at(r.id);
    for (const auto& l : p.at("links")) {
      Link k;
      k.name = l.at("name");
      k.parent = l.at("parent");
      k.joint = point(l.at("joint_in_parent"));
      k.phi0 = l.at("phi0");
      k.length = l.at("length");
      k.mass = l.at("mass");
      k.com_x = l.at("com_x");
      for (int a = 0; a < 3; ++a) k.I_com[a] = l.at("I_com").at(a);
      if (k.parent >= int(r.links.size())) {
        throw std::runtime_error(who + ": " + r.id + ": link " + k.name +
                                 " comes before its parent");
      }
      r.links.push_back(k);
    }
    for (const auto& c : p.at("closures")) {
      r.closures.push_back({c.at("b1"), c.at("b2"), point(c.at("p1")), point(c.at("p2"))});
    }
    out.push_back(r);
  }
  return out;
}

// Writes records (a JSON array, the record format of bench/data/README.md) to path, one record
// per line; returns the exit code for main (1 when the file cannot be written, said on stderr).
inline int write_records(const std::string& path, const nlohmann::ordered_json& records,
                         const std::string& who) {
  std::ofstream out(path);
  if (!out) {
    std::cerr << who << ": cannot write '" << path << "'\n";
    return 1;
  }
  out << "[\n";
  for (std::size_t i = 0; i < records.size(); ++i) {
    out << "  " << records[i].dump() << (i + 1 < records.size() ? ",\n" : "\n");
  }
  out << "]\n";
  return 0;
}

}  // namespace shared_problems
