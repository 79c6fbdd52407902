// SPDX-License-Identifier: BSD-3-Clause
// The one parse of a URDF file through urdfdom, shared by the tree's import (urdf.cpp) and the
// visual geometry's (urdf_visual.cpp).
#pragma once

#include <string>

#include <urdf_parser/urdf_parser.h>

namespace ukdyn::tree::detail {

/// The URDF file at `path` parsed by urdfdom, with urdfdom's messages (console_bridge's, which
/// are process-wide) captured under a lock. `who` starts every error ("ukdyn::tree::load_urdf:
/// <path>: "). @throws std::invalid_argument: no such file, or not a valid URDF (with urdfdom's
/// message). Cost: one parse of the file.
urdf::ModelInterfaceSharedPtr parse_urdf_file(const std::string& path, const std::string& who);

}  // namespace ukdyn::tree::detail
