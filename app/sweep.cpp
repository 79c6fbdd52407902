// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn sweep`: a parameter sweep or Monte Carlo study of a model (run_ensemble,
// simulation/ensemble.hpp) on a pool of threads: DIR/ensemble.csv (and ensemble.h5), summary.json
// and a summary plot of the recorded outputs over the swept parameters (docs/ensembles.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <ukdyn/core/format.hpp>
#include <ukdyn/io/provenance.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/ensemble.hpp>
#include <ukdyn/simulation/options.hpp>

#include "commands.hpp"
#include "io/atomic_file.hpp"
#include "output_dir.hpp"
#include "progress.hpp"
#include "python_process.hpp"
#include "stop_signals.hpp"
#include "terminal_text.hpp"

namespace ukdyn::cli {
namespace fs = std::filesystem;
namespace {

// The summary plot: each recorded output (at the last recording time) over the swept names — a
// line over one grid axis, a map over two (the others' first values), a scatter over random
// variables. Failed samples are marked. Exit 3 when matplotlib is missing, 4 when there is
// nothing to plot.
constexpr const char* kSweepPlot = R"PY(
import csv, math, sys
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit(3)
table, out, grid, rand, outputs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]
plot_format = sys.argv[7]
# the model's units (name=unit, tab-separated): a column's axis is labelled "name [unit]"
units = dict(u.split("=", 1) for u in sys.argv[6].split("\t") if "=" in u)
def label(column):
    unit = units.get(column.split("@", 1)[0], "")
    return f"{column} [{unit}]" if unit else column
grid = [g for g in grid.split(",") if g]
rand = [r for r in rand.split(",") if r]
outputs = [o for o in outputs.split(",") if o]
with open(table, newline="") as f:
    rows = list(csv.DictReader(f))
def num(row, name):
    try:
        return float(row[name])
    except (KeyError, ValueError):
        return math.nan
swept = grid + rand
if not rows or not swept or not outputs:
    sys.exit(4)  # nothing to plot: no sweep.png
fig, axes = plt.subplots(len(outputs), 1, figsize=(7, 3.2 * len(outputs)), squeeze=False)
for ax, name in zip(axes[:, 0], outputs):
    ok = [r for r in rows if r["ok"] == "1"]
    bad = [r for r in rows if r["ok"] != "1"]
    if len(grid) >= 2 and not rand:
        xs = sorted({num(r, grid[1]) for r in rows})
        ys = sorted({num(r, grid[0]) for r in rows})
        first = {g: num(rows[0], g) for g in grid[2:]}
        z = [[math.nan] * len(xs) for _ in ys]
        for r in ok:
            if all(num(r, g) == v for g, v in first.items()):
                z[ys.index(num(r, grid[0]))][xs.index(num(r, grid[1]))] = num(r, name)
        mesh = ax.pcolormesh(xs, ys, z, shading="nearest")
        fig.colorbar(mesh, ax=ax, label=label(name))
        ax.set_xlabel(label(grid[1]))
        ax.set_ylabel(label(grid[0]))
        for r in bad:
            ax.plot(num(r, grid[1]), num(r, grid[0]), "rx")
    else:
        x = swept[0]
        ax.plot([num(r, x) for r in ok], [num(r, name) for r in ok],
                "-o" if grid and not rand else ".", ms=3)
        ax.plot([num(r, x) for r in bad], [0.0 for r in bad], "rx", label="failed")
        ax.set_xlabel(label(x))
        ax.set_ylabel(label(name))
    ax.set_title(f"{name} over {', '.join(swept)} ({len(ok)} ok, {len(bad)} failed)")
    ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(out, dpi=110, format=plot_format)
)PY";

// The ensemble's progress on one line: redrawn in place on a terminal, a log line every few
// seconds otherwise.
class EnsembleLine {
 public:
  explicit EnsembleLine(std::size_t total)
      : total_(total),
        bar_(ProgressBar::mode_for(stderr) == ProgressBar::Mode::kBar),
        start_(Clock::now()),
        next_(start_ + (bar_ ? std::chrono::milliseconds(500) : interval())) {}
  ~EnsembleLine() { finish(); }
  void update(const EnsembleProgress& p) {
    const auto now = Clock::now();
    if (now < next_ && p.done < p.total) return;
    next_ = now + (bar_ ? std::chrono::milliseconds(100) : interval());
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double eta = p.done > 0 ? elapsed * double(p.total - p.done) / double(p.done) : -1.0;
    std::fprintf(stderr, "%sukdyn sweep: %zu of %zu samples (%zu failed), %s elapsed, ETA %s%s",
                 bar_ ? "\r" : "", p.done, total_, p.failed,
                 ProgressBar::duration_text(elapsed).c_str(),
                 ProgressBar::duration_text(eta).c_str(), bar_ ? "   " : "\n");
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_ && bar_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  using Clock = std::chrono::steady_clock;
  // $UKDYN_PROGRESS_INTERVAL seconds (tests), else 5 s
  static Clock::duration interval() {
    const char* env = std::getenv("UKDYN_PROGRESS_INTERVAL");
    const double s = env && *env ? std::atof(env) : 5.0;
    return std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(s >= 0 && std::isfinite(s) ? s : 5.0));
  }
  std::size_t total_;
  bool bar_;
  Clock::time_point start_, next_;
  bool drawn_ = false;
};

// `text` without its leading `prefix` (the C++ function's name)
std::string without_prefix(std::string_view text, std::string_view prefix) {
  if (text.substr(0, prefix.size()) == prefix) text.remove_prefix(prefix.size());
  return std::string(text);
}

// "0.5,1" → {0.5, 1}
std::vector<double> times_of(const std::string& text) {
  std::vector<double> out;
  if (text.empty()) return out;
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = text.find(',', from);
    const std::string piece =
        text.substr(from, comma == std::string::npos ? text.npos : comma - from);
    char* end = nullptr;
    const double v = std::strtod(piece.c_str(), &end);
    if (piece.empty() || *end != '\0' || !std::isfinite(v)) {
      throw UsageError("--at " + text + ": '" + piece + "' is not a finite time");
    }
    out.push_back(v);
    if (comma == std::string::npos) break;
    from = comma + 1;
  }
  return out;
}

}  // namespace

int sweep_command(const SweepArguments& args) {
  // the table's formats, checked before anything runs (a typo must not cost the sweep)
  const TableFormats formats = parse_formats(args.formats);
  const bool want_csv = formats.csv, want_hdf5 = formats.hdf5;
  check_plot_formats(args.plot_formats);

  // the design, from the command line's text
  Design design;
  for (const std::string& g : args.grid) {
    try {
      design.grid.push_back(parse_grid_axis(g));
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--grid ") + e.what());
    }
  }
  for (const std::string& r : args.random) {
    try {
      design.random.push_back(parse_random_variable(r));
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--random ") + e.what());
    }
  }
  if (design.grid.empty() && design.random.empty()) {
    throw UsageError("give what to sweep: --grid NAME=START:STOP:COUNT or --random NAME~LAW(A,B)");
  }
  if (!design.random.empty() && args.samples == 0) {
    throw UsageError("--random needs --samples N (the number of draws)");
  }
  if (design.random.empty() && args.samples != 0) {
    throw UsageError("--samples " + std::to_string(args.samples) +
                     ": there is no --random variable to draw");
  }
  design.draws = args.samples;
  design.seed = args.seed;
  design.latin_hypercube = args.lhs;
  DesignTable table;
  try {
    table = make_design(design);
  } catch (const std::invalid_argument& e) {
    throw UsageError(without_prefix(e.what(), "ukdyn::make_design: "));
  }

  // the model: read once here (its errors are the file's, exit 3), then again per sample
  const Model base = load_source(args.source);
  EnsembleModel model;
  model.text = source_text(args.source);
  model.file = args.source.example.empty() ? args.source.path
                                           : "examples/models/" + args.source.example + ".yaml";
  model.overrides = parse_overrides(args.source.set);
  for (const FlagSetting& f : args.settings) {
    SimulationOptions o;
    try {
      set_option_text(o, f.name, f.text);
    } catch (const OptionError& e) {
      throw UsageError(f.flag + " " + f.text + ": " + e.what());
    }
    model.settings[f.name] = get_option(o, f.name);
  }
  std::vector<EnsembleSample> samples;
  try {
    samples = samples_of_design(base, table);
  } catch (const std::invalid_argument& e) {
    throw UsageError(without_prefix(e.what(), "ukdyn::samples_of_design: "));
  }
  EnsembleOptions options;
  options.threads = args.jobs;
  options.at = times_of(args.at);
  options.outputs = args.outputs;

  const fs::path dir =
      args.out_dir.empty()
          ? fs::path("ukdyn-sweep-" + (args.source.example.empty()
                                           ? fs::path(args.source.path).stem().string()
                                           : args.source.example))
          : fs::path(args.out_dir);
  std::optional<OutputDirectory> out;
  if (const int status = hold_output_directory(dir, kSweepOutputs, out); status != 0) {
    return status;
  }
  const unsigned threads =
      args.jobs != 0 ? args.jobs : std::max(1u, std::thread::hardware_concurrency());
  std::printf("ukdyn sweep: %s (%s), %zu samples on %u thread%s\n",
              terminal_text(base.name, false).c_str(), terminal_text(model.file, false).c_str(),
              samples.size(), threads, threads == 1 ? "" : "s");
  std::fflush(stdout);

  // SIGINT, SIGTERM: the runs under way stop at their next step, the rest are not started, and
  // what was computed is written
  StopSignals signals;
  options.should_stop = [] { return StopSignals::received() != 0; };
  EnsembleResult result;
  const auto start = std::chrono::steady_clock::now();
  {
    EnsembleLine line(samples.size());
    options.progress = [&line](const EnsembleProgress& p) { line.update(p); };
    try {
      result = run_ensemble(model, samples, options);
    } catch (const std::invalid_argument& e) {
      line.finish();
      throw UsageError(without_prefix(e.what(), "ukdyn::run_ensemble: "));
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // the files: the table (CSV, HDF5), summary.json, the plot — after removing a previous
  // sweep's (the directory then holds this sweep's files only: no old table beside a new
  // summary)
  const EnsembleTable t = ensemble_table(result, samples, table.names);
  out->remove_previous_outputs();
  nlohmann::json summary;
  summary["model"] = base.name;
  summary["file"] = model.file;
  summary["model_sha256"] = sha256_hex(model.text);
  summary["overrides"] = model.overrides;
  summary["command_line"] = args.arguments;
  summary["ukdyn_version"] = version();
  summary["ukdyn_commit"] = commit();
  summary["grid"] = args.grid;
  summary["random"] = args.random;
  summary["samples_per_grid_point"] = args.samples;
  summary["seed"] = args.seed;
  summary["latin_hypercube"] = args.lhs;
  summary["at"] = options.at;
  summary["samples"] = samples.size();
  // (ok + failed + samples_interrupted + not_run = samples: a sample stopped by a signal, or
  // never started, is not a failure)
  summary["ok"] = result.ok();
  summary["failed"] = result.failed();
  summary["interrupted"] = result.interrupted;
  summary["samples_interrupted"] = result.interrupted_samples();
  summary["not_run"] = result.not_run();
  summary["threads"] = threads;
  summary["wall_time"] = wall;
  const fs::path csv_path = dir / "ensemble.csv";
  if (want_csv) write_ensemble_csv(t, csv_path.string());
  if (want_hdf5) write_ensemble_hdf5(t, (dir / "ensemble.h5").string(), summary.dump());
  write_text_file((dir / "summary.json").string(), summary.dump(2) + "\n");
  bool output_failed = false;  // an output that should exist is missing (exit 1)
  if (args.plots && want_csv) {
    const std::string python = python_interpreter();
    std::string grid, rand, outs;
    for (const auto& g : design.grid) grid += (grid.empty() ? "" : ",") + g.name;
    for (const auto& r : design.random) rand += (rand.empty() ? "" : ",") + r.name;
    const std::vector<std::string> plotted =
        options.outputs.empty()
            ? (base.output_names.empty() ? base.system.coordinate_names() : base.output_names)
            : options.outputs;
    for (const auto& o : plotted) {
      outs += (outs.empty() ? "" : ",") + o + "@" +
              (options.at.empty() ? std::string("end") : format_number(options.at.back()));
    }
    // the units of the coordinates (their velocities: per the model's time unit), of the output
    // expressions and of the times (UnitSystem)
    std::string units;
    auto add_unit = [&units](const std::string& name, const std::string& unit) {
      if (!unit.empty()) units += (units.empty() ? "" : "\t") + name + "=" + unit;
    };
    const auto& coords = base.system.coordinate_names();
    for (std::size_t i = 0; i < coords.size() && i < base.coordinate_units.size(); ++i) {
      const std::string& u = base.coordinate_units[i];
      add_unit(coords[i], u);
      if (!u.empty()) add_unit(coords[i] + "_dot", base.unit_system.rate(u));
    }
    for (std::size_t i = 0; i < base.output_names.size() && i < base.output_units.size(); ++i) {
      add_unit(base.output_names[i], base.output_units[i]);
    }
    for (const char* time : {"t_start", "t_end", "t_reached"})
      add_unit(time, base.unit_system.time);
    // sweep.png (and .pdf, .svg: --plot-format): written by the script into a temporary made
    // here (mkostemp), renamed when the script has succeeded
    if (!is_executable(python)) {
      std::fprintf(stderr, "warning: %s not found: no summary plot\n", python.c_str());
    } else {
      for (const std::string& format : args.plot_formats) {
        const std::string name = "sweep." + format;
        detail::AtomicFile plot((dir / name).string(), "ukdyn sweep");
        plot.release_descriptor();
        const int code = run_program({python, "-c", kSweepPlot, csv_path.string(),
                                      plot.write_path(), grid, rand, outs, units, format});
        if (code == 0) {
          plot.commit();
        } else if (code == 4) {
          break;  // nothing to plot
        } else if (code == 3) {
          std::fprintf(stderr, "warning: %s has no matplotlib: no summary plot\n", python.c_str());
          break;
        } else {
          std::fprintf(stderr, "error: the summary plot script failed (exit %d): no %s\n", code,
                       name.c_str());
          output_failed = true;
        }
      }
    }
  }

  // (an interrupted sweep's samples: those stopped and those never started apart)
  std::string stopped;
  if (const std::size_t k = result.interrupted_samples(); k > 0)
    stopped += ", " + format_number(k) + " interrupted";
  if (const std::size_t k = result.not_run(); k > 0)
    stopped += ", " + format_number(k) + " not run";
  std::printf("  %zu samples: %zu ok, %zu failed%s; %.3g s (%.3g samples/s)\n", samples.size(),
              result.ok(), result.failed(), stopped.c_str(), wall,
              double(samples.size()) / std::max(wall, 1e-9));
  for (std::size_t i = 0, shown = 0; i < t.status.size() && shown < 3; ++i) {
    if (!result.samples[i].ok() && result.samples[i].outcome != SampleOutcome::kNotRun) {
      std::printf("  sample %zu: %s: %s\n", i, t.status[i].c_str(),
                  terminal_text(t.message[i]).c_str());
      ++shown;
    }
  }
  std::printf("  written: %s\n", terminal_text(dir.string(), false).c_str());
  if (result.interrupted && StopSignals::received() != 0) {
    std::fprintf(stderr, "interrupted by %s: the finished samples are written\n",
                 StopSignals::name(StopSignals::received()));
    return kExitInterruptedBase + StopSignals::received();
  }
  return result.ok() < samples.size() || output_failed ? kExitRunFailed : kExitOk;
}

}  // namespace ukdyn::cli
