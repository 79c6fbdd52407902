// SPDX-License-Identifier: BSD-3-Clause
// Private to the model-file reader: the reader of a multibody model's sections (bodies:,
// joints:, forces: in reader_multibody.cpp; contacts: in reader_contacts.cpp).
#pragma once

#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/multibody/multibody.hpp"

#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

using mb::BodyId;
using mb::BodyKind;
using mb::Frame;
using mb::kGround;
using mb::Vector3d;

// Reads the sections of a multibody model for one Reader (which owns the expression set and the
// errors).
class MultibodyReader {
 public:
  MultibodyReader(Reader& reader, const YAML::Node& root) : r_(reader), root_(root) {}
  Model read();

 private:
  struct BodyDecl {
    std::string name;
    BodyKind kind;
    YAML::Node node;
  };
  struct JointDecl {
    std::string name;
    mb::JointType type;
    YAML::Node node;
    double radius = 0.0;  // a contact's (its drawn point: modelfile/visual_contacts.cpp)
    std::string box;      // a box's corner: the box entry's name (friction names the box)
  };

  // the file's structure
  void refuse_generalized_keys();
  void declare_bodies();
  void declare_joints();
  void read_bodies();
  void read_joints();
  void read_forces();
  void read_contacts();           // reader_contacts.cpp
  void read_contact_frictions();  // reader_contacts.cpp: nonideal: at the contacts
  // a box contact's corners in the body frame (none for another shape; reader_contacts.cpp)
  std::vector<Vector3d> box_corners(const YAML::Node& c, const std::string& what,
                                    const std::string& shape, const Vector3d& p, BodyKind kind,
                                    int dims);

  // pieces
  const YAML::Node& check_map(const YAML::Node& node, const std::string& what,
                              const std::string& example);
  void check_keys(const YAML::Node& map, const std::set<std::string>& keys,
                  const std::string& what);
  YAML::Node require(const YAML::Node& map, const std::string& key, const std::string& what,
                     const std::string& example);
  std::string name_of(const YAML::Node& map, const std::string& what, const std::string& fallback);
  double positive(const YAML::Node& node, const std::string& what);
  double non_negative(const YAML::Node& node, const std::string& what);
  Vector3d vec(const YAML::Node& node, const std::string& what, int min_entries, int max_entries);
  Eigen::Quaterniond orientation(const YAML::Node& node, const std::string& what);
  BodyId body(const YAML::Node& node, const std::string& what);
  bool planar(BodyId b) const {
    return b != kGround && bodies_[std::size_t(b)].kind == BodyKind::kPlanar;
  }
  Frame frame(const YAML::Node& j, const std::string& side, bool planar_joint,
              const std::string& what);
  Vector3d point(const YAML::Node& j, const std::string& key, bool planar_joint,
                 const std::string& what);
  mb::MotionFn drive(const YAML::Node& node, const std::string& what);
  mb::WrenchFn wrench(const YAML::Node& f, bool planar_body, const std::string& what);
  void add_switches();
  mb::JointFriction friction(const YAML::Node& node, const std::string& what);

  Reader& r_;
  YAML::Node root_;
  std::vector<BodyDecl> bodies_;
  std::vector<JointDecl> joints_;
  std::vector<JointDecl> contacts_;  // contacts: (names unique among the constraints)
  // the spring-dampers' entries and points, checked at the initial pose after the build
  struct SpringDecl {
    YAML::Node node;
    std::string what;
    BodyId a, b;
    Vector3d pa, pb;
  };
  std::vector<SpringDecl> springs_;
  mb::Multibody builder_;
};

}  // namespace ukdyn::model_reader
