// SPDX-License-Identifier: BSD-3-Clause
// The robot's part of the viewer's scene (modelfile/visual.hpp, viewer_scene_json).
#pragma once

#include <nlohmann/json.hpp>

namespace ukdyn {

struct Model;

namespace detail {

/// The scene's `robot` entry of a model with a robot (model.robot set): its links (each
/// link's joint: parent index, kind, origin xyz and quaternion w x y z, axis, coordinates),
/// when there are any its URDF visuals (`visuals`: link index, -1 the world; the origin; the
/// shape's dimensions; a mesh's format and `file`, its index in `meshes`, or the problem that
/// keeps it from being drawn; colour, opacity), the mesh files (`meshes`: base64, each file
/// once) and its loops (`loops`: type, link indices and points).
/// Cost O(links + visuals + bytes of the meshes).
nlohmann::json robot_scene(const Model& model);

}  // namespace detail
}  // namespace ukdyn
