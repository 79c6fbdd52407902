// SPDX-License-Identifier: BSD-3-Clause
// The one parse of a URDF file through urdfdom, shared by the tree's import (urdf.cpp) and the
// visual geometry's (urdf_visual.cpp).
#pragma once

#include <string>

#include <urdf_parser/urdf_parser.h>

namespace ukdyn::tree::detail {

/// A URDF file parsed: urdfdom's model and the file's text (where its errors are located,
/// urdf_xml.hpp).
struct UrdfFile {
  urdf::ModelInterfaceSharedPtr model;  ///< never null
  std::string text;                     ///< the file's bytes
};

/// The URDF file at `path` checked as XML (check_urdf_xml) and parsed by urdfdom, with urdfdom's
/// messages (console_bridge's, which are process-wide) captured under a lock. `who` starts every
/// error ("ukdyn::tree::load_urdf: <path>: "). @throws std::invalid_argument: no such file, or not
/// a valid URDF (malformed XML, urdfdom's message, not a tree), located at the element
/// ("<path>:12:3: ") when the message names one. Cost: two parses of the file (TinyXML's, then
/// urdfdom's own).
UrdfFile parse_urdf_file(const std::string& path, const std::string& who);

}  // namespace ukdyn::tree::detail
