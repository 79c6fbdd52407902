// SPDX-License-Identifier: BSD-3-Clause
// Files embedded in the ukdyn binary at build time (embed.cmake writes embedded.cpp in the build
// tree), so that the program needs nothing from the source tree when it runs.
#pragma once

#include <span>

namespace ukdyn::cli {

/// An embedded text file.
struct EmbeddedFile {
  const char* name;  ///< the file's stem ("pendulum" for examples/models/pendulum.yaml)
  const char* text;  ///< its contents
};

/// python/ukdyn/plotting.py (the Python module's plotting, run by `ukdyn run` as a script).
extern const char* const kPlotScript;

/// python/ukdyn/plotting_*.py (the control and joint reactions figures), which kPlotScript
/// imports: each written beside it as <name>.py; sorted by name.
std::span<const EmbeddedFile> plot_modules();

/// examples/models/*.yaml, sorted by name.
std::span<const EmbeddedFile> example_models();

}  // namespace ukdyn::cli
