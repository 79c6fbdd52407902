// SPDX-License-Identifier: BSD-3-Clause
// Test support: the message of loading a URDF file that ukdyn::tree::load_urdf refuses.
#pragma once

#include <stdexcept>
#include <string>

#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::testing {

// the std::invalid_argument that loading `path` raises, or "(no error)"
inline std::string urdf_load_error(const std::string& path) {
  try {
    tree::load_urdf(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace ukdyn::testing
