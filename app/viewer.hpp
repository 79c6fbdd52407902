// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn run --viewer`: animation.html, the browser viewer of the run (docs/viewer.md), written
// by the command itself (app/viewer_page.hpp: the same page as Python's Result.save_animation,
// by the same rules, with no Python process) from the page template and three.js embedded in
// the program (app/embed_viewer.cmake writes viewer_embedded.cpp in the build tree).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace ukdyn {
struct Model;
}

namespace ukdyn::cli {

/// The page template (python/ukdyn/viewer_template.html), and Debian's three.js, OrbitControls
/// and mesh loaders (empty when the program was built without libjs-three).
extern const char* const kViewerTemplate;
extern const char* const kThreeJs;
extern const char* const kOrbitControlsJs;
extern const char* const kStlLoaderJs;
extern const char* const kObjLoaderJs;
extern const char* const kColladaLoaderJs;

/// The scripts of three.js a page of `scene` needs: three.js and OrbitControls, then the
/// loader of each mesh format ("stl", "obj", "dae") its robot's visuals embed, in that order,
/// joined by newlines (viewer.py's _three_text). Cost O(visuals).
std::string viewer_three_text(const nlohmann::ordered_json& scene);

/// Whether `ukdyn run` writes the viewer when neither --viewer nor --no-viewer is given: for
/// models with bodies or a `visual:` section.
bool viewer_by_default(const Model& model);

/// Writes dir/animation.html from the run's trajectory.csv and the model's scene
/// (viewer_scene_json), whole or not at all (a mkostemp temporary renamed over it). Returns its
/// path, or nothing after a message on stderr when it was not written: a warning when it cannot
/// be made here (no three.js, nothing to draw); an error, with `failed` set, when writing it
/// failed (an unreadable trajectory, a full disk) — a missing output, which makes the command's
/// exit code 1. Cost: two passes over trajectory.csv; memory O(frames shown × columns).
std::optional<std::filesystem::path> write_viewer(const Model& model,
                                                  const std::filesystem::path& csv,
                                                  const std::filesystem::path& dir, bool& failed);

}  // namespace ukdyn::cli
