// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn run --viewer`: the embedded page generator, run with the system's python (app/viewer.hpp).
#include "viewer.hpp"

#include "python_process.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/visual.hpp>

namespace ukdyn::cli {
namespace fs = std::filesystem;
namespace {

bool write_text(const fs::path& path, const char* text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return bool(out);
}

}  // namespace

bool viewer_by_default(const Model& model) {
  return model.multibody || !model.visual.points.empty();
}

std::optional<fs::path> write_viewer(const Model& model, const fs::path& csv, const fs::path& dir,
                                     bool& failed) {
  // as Python's Result.show(): a page with only the grid is not written
  if (!model.multibody && model.visual.points.empty() && model.visual.frames.empty() &&
      !model.controller) {
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
  const std::string python = python_interpreter();
  if (!is_executable(python)) {
    std::fprintf(stderr,
                 "warning: %s not found: no animation.html (set UKDYN_PYTHON, or pass "
                 "--no-viewer)\n",
                 python.c_str());
    return std::nullopt;
  }
  // the generator, its assets and the scene go to a private temporary directory
  std::string temp = (fs::temp_directory_path() / "ukdyn-viewer-XXXXXX").string();
  if (::mkdtemp(temp.data()) == nullptr) {
    std::fprintf(stderr, "error: cannot create a temporary directory: no animation.html\n");
    failed = true;
    return std::nullopt;
  }
  const fs::path work(temp), page = dir / "animation.html";
  const bool written = write_text(work / "viewer.py", kViewerScript) &&
                       write_text(work / "viewer_template.html", kViewerTemplate) &&
                       write_text(work / "three.min.js", kThreeJs) &&
                       write_text(work / "OrbitControls.js", kOrbitControlsJs) &&
                       write_text(work / "scene.json", viewer_scene_json(model).c_str());
  const int code = written ? run_program({python, (work / "viewer.py").string(), csv.string(),
                                          (work / "scene.json").string(), page.string()})
                           : -1;
  std::error_code ec;
  fs::remove_all(work, ec);
  if (code != 0) {
    std::fprintf(stderr, "error: the viewer's page generator failed (exit %d): no animation.html\n",
                 code);
    failed = true;
    return std::nullopt;
  }
  return page;
}

}  // namespace ukdyn::cli
