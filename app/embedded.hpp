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

/// python/ukdyn/plotting_reactions.py (the joint reactions figure), which kPlotScript imports:
/// written beside it, as plotting_reactions.py.
extern const char* const kPlotReactionsScript;

/// examples/models/*.yaml, sorted by name.
std::span<const EmbeddedFile> example_models();

}  // namespace ukdyn::cli
