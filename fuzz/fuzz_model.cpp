// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target for the model reader: the input bytes are a model file's text. Every input
// must either load or be refused with a ukdyn::ModelError naming file:line:column; anything
// else escaping (another exception), a crash, a hang or a sanitizer report is a bug. A model
// that loads is also checked (check_model), its output expressions evaluated, and integrated
// for a few fixed RK4 steps, so that the compiled expressions run on real states.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace {

constexpr const char* kFile = "<fuzz>";

// an expected outcome that breaks its promise is a bug too: report it as a crash
[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "fuzz_model: %s\n", what.c_str());
  std::abort();
}

// A ModelError must say where: "<fuzz>:LINE:COLUMN: error: MESSAGE", LINE within the text
// (without overrides, every error of parse_model has a position).
void check_error(const ukdyn::ModelError& e, const std::string& text) {
  const std::string what = e.what();
  if (e.file() != kFile || what.rfind(kFile, 0) != 0) bug("ModelError without the file: " + what);
  if (e.message().empty()) bug("ModelError without a message: " + what);
  if (what.find(": error: ") == std::string::npos) bug("ModelError in another format: " + what);
  long breaks = 0;  // an upper bound of the lines YAML sees (\n, \r, NEL, U+2028/9)
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    breaks += u == '\n' || u == '\r' || u == 0x85 || u == 0xE2;
  }
  if (e.line() < 1 || e.line() > breaks + 1 || e.column() < 1)
    bug("ModelError without a position in the text: " + what);
}

// A few RK4 steps from the initial state: enough to run M, Q, the constraints and C on real
// states, never long (the model's own t_end, integrator and output settings are replaced).
void run_briefly(const ukdyn::Model& model) {
  ukdyn::SimulationOptions o = model.options;
  if (!std::isfinite(o.t_start) || std::fabs(o.t_start) > 1e6) return;
  o.integrator = ukdyn::Integrator::kRK4;
  o.step = 1e-3;
  o.t_end = o.t_start + 4 * o.step;
  o.max_steps = 8;
  o.output_every = 0.0;
  o.output_at.clear();
  o.progress = nullptr;
  try {
    // as `ukdyn run` does: under the controller of a control: section, with the bodies' and
    // the output expressions' columns
    const ukdyn::ModelRun run = ukdyn::run_model(model, o);
    (void)run.columns();
  } catch (const std::invalid_argument&) {
    // documented misuse: inconsistent initial conditions without `project: true`, bad tolerances
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const ukdyn::Model model = ukdyn::parse_model(text, kFile);
    (void)ukdyn::check_model(model);
    run_briefly(model);
  } catch (const ukdyn::ModelError& e) {
    check_error(e, text);  // the expected way to refuse a model
  }
  // any other exception escapes: libFuzzer reports the abort (uncaught exception) as a crash
  return 0;
}
