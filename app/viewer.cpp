// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn run --viewer`: animation.html, written by the command itself (app/viewer.hpp,
// app/viewer_page.hpp): no Python process.
#include "viewer.hpp"

#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <io/atomic_file.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/visual.hpp>

#include "terminal_text.hpp"
#include "viewer_page.hpp"

namespace ukdyn::cli {
namespace fs = std::filesystem;

bool viewer_by_default(const Model& model) {
  return model.multibody || model.robot || !model.visual.points.empty() ||
         !model.visual.frames.empty() || !model.visual.contacts.empty();
}

std::string viewer_three_text(const nlohmann::ordered_json& scene) {
  std::string three = std::string(kThreeJs) + "\n" + kOrbitControlsJs;
  // the loaders of the meshes embedded
  const auto robot = scene.find("robot");
  if (robot == scene.end() || !robot->is_object() || !robot->contains("visuals")) return three;
  const std::pair<const char*, const char*> loaders[] = {
      {"stl", kStlLoaderJs}, {"obj", kObjLoaderJs}, {"dae", kColladaLoaderJs}};
  for (const auto& [format, text] : loaders) {
    for (const auto& v : robot->at("visuals")) {
      if (v.contains("file") && v.value("format", "") == format) {
        three += std::string("\n") + text;
        break;
      }
    }
  }
  return three;
}

std::optional<fs::path> write_viewer(const Model& model, const fs::path& csv, const fs::path& dir,
                                     bool& failed) {
  // as Python's Result.show(): a page with only the grid is not written
  if (!model.multibody && model.visual.points.empty() && model.visual.frames.empty() &&
      model.visual.contacts.empty() && !model.robot && !model.controller) {
    std::fprintf(stderr,
                 "warning: nothing to draw: the model has no bodies and no visual: section (add "
                 "visual: {points: {...}, links: [...]}; docs/viewer.md): no animation.html\n");
    return std::nullopt;
  }
  if (*kThreeJs == '\0') {
    std::fprintf(stderr,
                 "warning: this ukdyn was built without three.js (Debian's libjs-three): no "
                 "animation.html\n");
    return std::nullopt;
  }
  const fs::path page = dir / "animation.html";
  try {
    // the scene, the rows shown (a visual point that is not finite is said, and hidden while
    // so), the data, the page; written whole or not at all (mkostemp, O_NOFOLLOW, rename)
    const auto scene = nlohmann::ordered_json::parse(viewer_scene_json(model));
    const ViewerOptions options;
    std::map<std::string, double> first_nonfinite;
    const ViewerColumns run = read_viewer_csv(csv, options, point_columns(scene), first_nonfinite);
    for (const std::string& line : nonfinite_warnings(scene, first_nonfinite)) {
      std::fprintf(stderr, "%s\n", terminal_text(line).c_str());
    }
    const std::string three = viewer_three_text(scene);
    auto data = viewer_page_data(scene, run, options, read_contact_events(dir / "summary.json"));
    // the model's units, when not SI (docs/model-format.md, "Units": the page's labels; the
    // same as ukdyn/viewer.py's scene_data)
    if (!model.unit_system.is_si()) {
      const UnitSystem& u = model.unit_system;
      data["unit_system"] = {
          {"length", u.length}, {"time", u.time}, {"force", u.force()}, {"energy", u.energy()}};
    }
    const std::string html = fill_viewer_template(kViewerTemplate, three, data);
    detail::write_whole_file(page.string(), "ukdyn run --viewer", html.data(), html.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: the viewer's page: %s: no animation.html\n",
                 terminal_text(e.what()).c_str());
    failed = true;
    return std::nullopt;
  }
  return page;
}

}  // namespace ukdyn::cli
