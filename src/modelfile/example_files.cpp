// SPDX-License-Identifier: BSD-3-Clause
// The files a model file names (a robot's URDF, a table's data), relative to the model file; for
// the built-in examples, whose text is embedded in the program, looked up in the examples
// directories (modelfile/reader.hpp, model_relative_path).
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

namespace fs = std::filesystem;

fs::path model_relative_path(const std::string& model_file, const std::string& path) {
  const fs::path given(path);
  if (given.is_absolute()) return given;
  const fs::path beside = fs::path(model_file).parent_path() / given;
  // a built-in example is named "examples/models/NAME.yaml" (app/source.cpp, python's load)
  constexpr std::string_view kExamples = "examples/models/";
  if (model_file.rfind(kExamples, 0) != 0 ||
      model_file.find('/', kExamples.size()) != std::string::npos)
    return beside;
  std::error_code ec;
  if (fs::exists(beside, ec)) return beside;  // run from the source tree's root
  const char* env = std::getenv("UKDYN_EXAMPLES_DIR");
  for (const char* dir : {env, UKDYN_INSTALLED_EXAMPLES_DIR, UKDYN_SOURCE_EXAMPLES_DIR}) {
    if (dir == nullptr || *dir == '\0') continue;
    const fs::path candidate = fs::path(dir) / given;
    if (fs::exists(candidate, ec)) return candidate;
  }
  return beside;  // not found: the error names the path as the model file has it
}

}  // namespace ukdyn::model_reader
