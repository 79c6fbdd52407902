// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn run`: load a model, simulate it, write trajectory.csv (the library's columns and the
// model's output expressions), summary.json and the plots.
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <csignal>

#include <unistd.h>

#include <ukdyn/core/format.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/options.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "commands.hpp"
#include "embedded.hpp"
#include "modelfile/contact_start.hpp"
#include "output_dir.hpp"
#include "progress.hpp"
#include "python_process.hpp"
#include "stop_signals.hpp"
#include "terminal_text.hpp"
#include "viewer.hpp"

namespace ukdyn::cli {
namespace fs = std::filesystem;
namespace {

// the exit code plotting.py uses when matplotlib cannot be imported
constexpr int kPlotNoMatplotlib = 3;

// warns about an output expression named like a standard column (the CSV then has two)
void warn_duplicate_columns(const ModelRun& run) {
  const auto standard = csv_columns(run.trajectory);
  for (const CsvColumn& c : run.extra_columns) {
    if (std::find(standard.begin(), standard.end(), c.name) != standard.end()) {
      std::fprintf(stderr,
                   "warning: the output column '%s' has the name of a standard "
                   "column; the CSV holds two columns of that name\n",
                   terminal_text(c.name, false).c_str());
    }
  }
}

// the plots of a run: python/ukdyn/plotting.py (embedded) and the modules it imports in a
// private temporary directory (mkdtemp: mode 0700), run by /usr/bin/python3 (or $UKDYN_PYTHON),
// started before the simulation (start_plots) so that its imports overlap the run, and told to
// go on when the run's files are written (finish_plots); destroyed without that, the script
// leaves without drawing (the end of its input), and the directory is removed
struct PlotJob {
  std::string scripts;                    // the temporary directory
  std::optional<StartedProgram> program;  // the script, waiting for its go-ahead

  ~PlotJob() {
    program.reset();  // (waited for before its files are removed)
    std::error_code ignored;
    fs::remove_all(scripts, ignored);
  }
};

// starts the plot script on the run's files-to-be; nullptr (with a warning) when python is
// missing or the script cannot be written
std::unique_ptr<PlotJob> start_plots(const fs::path& csv, const fs::path& dir,
                                     const std::vector<std::string>& formats,
                                     const std::string& style) {
  const std::string python = python_interpreter();
  if (!is_executable(python)) {
    std::fprintf(stderr,
                 "warning: %s not found: no plots (set UKDYN_PYTHON to a python with "
                 "matplotlib, or pass --no-plots)\n",
                 python.c_str());
    return nullptr;
  }
  std::string scripts = (fs::temp_directory_path() / "ukdyn-plot-XXXXXX").string();
  if (::mkdtemp(scripts.data()) == nullptr) {
    std::fprintf(stderr,
                 "warning: cannot create a temporary directory for the plot script: no plots\n");
    return nullptr;
  }
  auto job = std::make_unique<PlotJob>();
  job->scripts = scripts;
  const fs::path script = fs::path(scripts) / "plotting.py";
  bool written = true;
  std::vector<EmbeddedFile> sources = {{"plotting", kPlotScript}};
  sources.insert(sources.end(), plot_modules().begin(), plot_modules().end());
  for (const EmbeddedFile& f : sources) {
    const std::string_view text(f.text);
    std::ofstream out(fs::path(scripts) / (std::string(f.name) + ".py"), std::ios::binary);
    out.write(text.data(), std::streamsize(text.size()));
    written = written && out.flush().good();
  }
  if (written) {
    // --wait: the script imports what it needs, then waits for "go" on its input
    job->program.emplace(std::vector<std::string>{python, script.string(), "--wait", csv.string(),
                                                  dir.string(), join(formats, ","), style});
  }
  return job;
}

// lets the started plot script draw the run's files and waits for it; returns the files
// written; a missing matplotlib is a warning, a script that ran and failed (a full disk) an
// error: `failed` is set
std::vector<fs::path> finish_plots(PlotJob& job, const fs::path& dir,
                                   const std::vector<std::string>& formats, bool& failed) {
  const int code = job.program ? job.program->finish("go") : -1;
  if (code == kPlotNoMatplotlib) {
    std::fprintf(stderr,
                 "warning: %s has no matplotlib: no plots (install python3-matplotlib, "
                 "or pass --no-plots)\n",
                 python_interpreter().c_str());
    return {};
  }
  if (code != 0) {
    std::fprintf(stderr, "error: the plot script failed (exit %d): no plots\n", code);
    failed = true;
    return {};
  }
  std::vector<fs::path> files;
  for (const std::string& f : formats) {
    for (const char* name : kRunOutputs) {
      if (fs::path(name).extension() == "." + f && fs::exists(dir / name)) {
        files.push_back(dir / name);
      }
    }
  }
  return files;
}

// the default output directory: ukdyn-<file stem or example name>
std::string default_out_dir(const ModelSource& source) {
  const std::string stem =
      source.example.empty() ? fs::path(source.path).stem().string() : source.example;
  return "ukdyn-" + stem;
}

// the option flags replace the model's simulate: settings, each through the table's setter
// (simulation/options.hpp): a bad value is a UsageError naming the flag, its text and the rule
void apply_option_flags(const RunArguments& args, SimulationOptions& options) {
  for (const FlagSetting& f : args.settings) {
    try {
      set_option_text(options, f.name, f.text);
    } catch (const OptionError& e) {
      throw UsageError(f.flag + " " + f.text + ": " + e.what());
    }
  }
}

// the settings with the command line's flags, as the run checks them (check_run_settings, the
// check the model reader made of the file's own): those were accepted when the model was read, so
// a setting at fault here is due to a flag (named, with its value: a UsageError, exit 2)
void check_flags(const RunArguments& args, const Model& model, const SimulationOptions& options) {
  try {
    check_run_settings(model, options);
  } catch (const SettingError& e) {
    const std::string message = user_message(e);
    // the flags given, the one of the setting first
    std::string flags;
    for (const FlagSetting& f : args.settings) {
      const std::string given = f.flag + " " + f.text;
      flags = f.name == e.setting() ? given + (flags.empty() ? "" : ", " + flags)
                                    : flags + (flags.empty() ? "" : ", ") + given;
    }
    throw UsageError((flags.empty() ? std::string() : flags + ": ") + message);
  }
}

// the progress display's interval: the mode's default, or $UKDYN_PROGRESS_INTERVAL seconds
// (for tests, which cannot wait 5 s for a log line)
ProgressBar::Clock::duration progress_interval() {
  const char* env = std::getenv("UKDYN_PROGRESS_INTERVAL");
  double seconds = -1.0;
  if (env && *env) std::from_chars(env, env + std::strlen(env), seconds);
  if (!(seconds >= 0.0) || !std::isfinite(seconds)) return ProgressBar::Clock::duration(-1);
  return std::chrono::duration_cast<ProgressBar::Clock::duration>(
      std::chrono::duration<double>(seconds));
}

}  // namespace

int run_command(const RunArguments& given) {
  RunArguments args = given;
  if (!args.from_summary.empty()) apply_summary(args);
  const TableFormats formats = parse_formats(args.formats);
  const bool want_csv = formats.csv, want_hdf5 = formats.hdf5;
  check_plot_style(args.plot_style);
  if (args.plot_formats.empty()) args.plot_formats = {args.plot_style == "paper" ? "pdf" : "png"};
  check_plot_formats(args.plot_formats);
  Model model = load_source(args.source);
  const RunProvenance provenance = provenance_of(args.source, model, args.arguments);

  // the model's settings, with the command line's
  SimulationOptions options = model.options;
  options.project_initial = model.project_initial;
  for (const FlagSetting& f : args.settings) {
    // --t-end: a finite time after the model's t_start (said before the table's rule)
    double t_end = 0.0;
    if (f.name == "t_end" && std::sscanf(f.text.c_str(), "%lf", &t_end) == 1 &&
        (!(t_end > options.t_start) || !std::isfinite(t_end))) {
      char text[96];
      std::snprintf(text, sizeof text,
                    "--t-end %g must be a finite time after the model's t_start = %g", t_end,
                    options.t_start);
      throw UsageError(text);
    }
  }
  apply_option_flags(args, options);
  check_flags(args, model, options);
  const fs::path dir = args.out_dir.empty() ? default_out_dir(args.source) : args.out_dir;

  // the directory, held for the run: a second run into it is refused now, before it computes
  // anything, and this one's files are never mixed with another's
  std::optional<OutputDirectory> out;
  if (const int status = hold_output_directory(dir, kRunOutputs, out); status != 0) {
    return status;
  }

  // (every unit printed is the model's: UnitSystem, docs/model-format.md "Units")
  const UnitSystem& units = model.unit_system;
  const char* tu = units.time.c_str();
  std::printf("ukdyn run: %s (%s), t = %g … %g %s\n", terminal_text(model.name, false).c_str(),
              terminal_text(model.file, false).c_str(), options.t_start, options.t_end, tu);
  std::fflush(stdout);

  // SIGINT, SIGTERM, SIGHUP: the run stops at its next step and what it computed is written; a
  // second signal ends the program at once. A trajectory.csv that cannot be written (a full
  // disk, a file-size limit) stops the run too: nothing more of it could be kept
  StopSignals signals;
  std::string csv_error;  // the write error of trajectory.csv ("": none)
  options.should_stop = [&csv_error] { return StopSignals::received() != 0 || !csv_error.empty(); };

  // trajectory.csv streams to its temporary while the run goes (memory does not grow with
  // the run's length): created with the first samples — a run that cannot start leaves the
  // previous run's files — after removing the previous run's files (each directory holds one
  // run's files); renamed when the run has ended, however it ended. trajectory.h5 (--format
  // hdf5) gathers the same columns in memory and is written after the run.
  const fs::path csv_path = dir / kRunOutputs[0], summary_path = dir / kRunOutputs[1];
  const fs::path hdf5_path = dir / "trajectory.h5";
  std::vector<fs::path> files;
  std::optional<CsvWriter> csv;
  std::vector<CsvColumn> table;
  Index rows = 0;
  bool started = false;
  auto start = [&](const ModelRun& first) {
    out->remove_previous_outputs();
    warn_duplicate_columns(first);
    if (want_csv) csv.emplace(csv_path.string());
    started = true;
  };
  auto write_rows = [&](const ModelRun& chunk) {
    if (!started) start(chunk);
    if (csv && csv_error.empty()) {
      try {
        csv->append(chunk.trajectory, chunk.extra_columns);
      } catch (const std::runtime_error& e) {
        csv_error = e.what();
      }
    }
    if (want_hdf5) {
      std::vector<CsvColumn> part = csv_table(chunk.trajectory);
      part.insert(part.end(), chunk.extra_columns.begin(), chunk.extra_columns.end());
      if (table.empty()) {
        table = std::move(part);
      } else {
        for (std::size_t c = 0; c < table.size() && c < part.size(); ++c) {
          table[c].values.insert(table[c].values.end(), part[c].values.begin(),
                                 part[c].values.end());
        }
      }
    }
    rows += chunk.trajectory.samples();
  };

  // the plot script, started now: its imports overlap the simulation
  std::unique_ptr<PlotJob> plots;
  if (args.plots && want_csv) {
    plots = start_plots(csv_path, dir, args.plot_formats, args.plot_style);
  }

  // simulate, with a progress bar on a terminal
  ModelRun run;
  {
    ProgressBar bar(options.t_start, options.t_end, ProgressBar::mode_for(stderr), stderr,
                    progress_interval(), progress_interval());
    bar.set_time_unit(units.time);
    options.progress = [&bar](const ProgressReport& p) { bar.update(p); };
    try {
      run = run_model(model, options, write_rows);
    } catch (const InconsistentInitialState& e) {
      // at the initial: section or the constraint's entry (no hint to project when the
      // constraints contradict each other: it cannot help)
      bar.finish();
      std::fprintf(stderr, "%s\n", terminal_text(locate_run_error(model, e).what()).c_str());
      return kExitModel;
    } catch (const SettingError& e) {
      // (checked before the run: the file's settings when it was read, the flags' above)
      bar.finish();
      std::fprintf(stderr, "%s\n", terminal_text(locate_run_error(model, e).what()).c_str());
      return kExitModel;
    } catch (const ukdyn::detail::ContactStartError& e) {
      // the contacts at the start cannot be solved (Painlevé): at the friction's or contact's entry
      bar.finish();
      std::fprintf(stderr, "%s\n",
                   terminal_text(ukdyn::detail::locate_contact_start(model, e).what()).c_str());
      return kExitModel;
    } catch (const std::invalid_argument& e) {
      // the model cannot be started
      bar.finish();
      std::fprintf(stderr, "%s: error: %s\n", terminal_text(model.file, false).c_str(),
                   terminal_text(user_message(e)).c_str());
      return kExitModel;
    }
  }
  options.progress = nullptr;
  options.should_stop = nullptr;
  const int received = StopSignals::received();
  RunStatistics& stats = run.trajectory.stats;
  if (stats.status == Status::kInterrupted && csv_error.empty()) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "interrupted by %s at t = %g %s: the samples computed up to there are written",
                  StopSignals::name(received), stats.t_reached, tu);
    stats.message = text;
    std::fprintf(stderr, "interrupted by %s at t = %g %s; writing what was computed\n",
                 StopSignals::name(received), stats.t_reached, tu);
  }

  // files: each is written under a temporary name and renamed when complete, trajectory.csv
  // first (just its header when the run recorded no sample), summary.json second (its
  // presence says that trajectory.csv is complete), the plots last
  if (!started) write_rows(run);
  if (csv && csv_error.empty()) {
    try {
      csv->commit();
      files.push_back(csv_path);
    } catch (const std::runtime_error& e) {
      csv_error = e.what();
    }
  }
  if (!csv_error.empty()) {
    // the rows that reached the file are kept under its own name, said to be incomplete; the
    // summary says why (if it can still be written)
    const bool kept = csv->keep_partial();
    std::fprintf(stderr, "error: %s\n", terminal_text(csv_error).c_str());
    char text[200];
    std::snprintf(text, sizeof text, "the run stopped at t = %g %s: %s", stats.t_reached, tu,
                  kept ? "trajectory.csv holds the rows written before the failure (incomplete)"
                       : "no trajectory.csv");
    std::fprintf(stderr, "%s\n", text);
    stats.status = Status::kInterrupted;  // (summary.json's status: the files are not whole)
    stats.message = "trajectory.csv could not be written (" + csv_error + "); " + text;
    try {
      write_summary_json(run.trajectory, options, summary_path.string(), provenance,
                         run.controlled ? &run.control : nullptr);
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "error: %s\n", terminal_text(e.what()).c_str());
    }
    return kExitRunFailed;
  }
  const ControlStatistics* control = run.controlled ? &run.control : nullptr;
  if (want_hdf5) {
    write_table_hdf5(hdf5_path.string(), table,
                     summary_json(run.trajectory, options, &provenance, control));
    files.push_back(hdf5_path);
  }
  write_summary_json(run.trajectory, options, summary_path.string(), provenance, control);
  files.push_back(summary_path);
  // (a plot or page whose generator ran and failed is a missing output: exit 1)
  bool output_failed = false;
  if (plots && csv) {
    for (const auto& f : finish_plots(*plots, dir, args.plot_formats, output_failed)) {
      files.push_back(f);
    }
  }
  if (args.viewer.value_or(viewer_by_default(model)) && csv) {
    if (const auto page = write_viewer(model, csv_path, dir, output_failed)) files.push_back(*page);
  }

  // what happened
  const RunStatistics& s = run.trajectory.stats;
  std::printf("  %lld samples to t = %g %s: %ld steps (%ld rejected), %ld evaluations, %.3g s\n",
              static_cast<long long>(rows), s.t_reached, tu, s.steps, s.rejected_steps,
              s.evaluations, s.wall_time);
  if (s.stiff_switches > 0) {
    std::printf("  stiff from t = %g %s: %s switched to bdf %ld time%s (%ld of the steps by bdf)\n",
                s.stiff_switch_time, tu, to_string(options.integrator), s.stiff_switches,
                s.stiff_switches == 1 ? "" : "s", s.stiff_steps);
  }
  if (s.least_squares > 0) {
    std::printf(
        "  redundant constraints: %ld evaluations off the constraints took the "
        "least-squares acceleration\n",
        s.least_squares);
  }
  std::printf("  max violation %.3g (position), %.3g (velocity)\n", s.max_position_violation,
              s.max_velocity_violation);
  if (s.energy_balance_checked) {
    std::printf("  energy balance %.3g relative (energy exchanged %.3g %s; tolerance %.3g)\n",
                s.energy_balance, s.energy_exchanged, units.energy().c_str(),
                options.energy_balance_tolerance);
  } else {
    std::printf("  energy balance %.3g relative (energy exchanged %.3g %s; not checked)\n",
                s.energy_balance, s.energy_exchanged, units.energy().c_str());
  }
  // the contact events by kind (summary.json's contact_events lists each)
  long kinds[5] = {0, 0, 0, 0, 0};  // impact, release, rest, stick, slip
  for (const ContactEvent& e : s.contact_events) ++kinds[int(e.kind)];
  if (kinds[0] + kinds[1] + kinds[2] > 0) {
    std::printf("  contacts: %ld impacts, %ld rests, %ld releases (summary.json: contact_events)\n",
                kinds[0], kinds[2], kinds[1]);
  }
  if (s.events > 0 || s.stick_refusals > 0) {
    std::printf(
        "  friction: %ld sticks, %ld slips (summary.json: contact_events), %ld located "
        "events, %ld stops where sticking was refused\n",
        kinds[3], kinds[4], s.events, s.stick_refusals);
  }
  if (s.switch_events > 0) {
    std::printf("  switches: %ld sign changes of non-smooth functions located\n", s.switch_events);
  }
  for (std::size_t i = 0; i < s.notes.size() && i < 3; ++i) {
    std::printf("  note: %s\n", terminal_text(s.notes[i]).c_str());
  }
  if (s.notes.size() > 3) {
    std::printf("  (%zu more notes in summary.json)\n", s.notes.size() - 3);
  }
  if (run.controlled) {
    const ControlStatistics& c = run.control;
    std::printf("  control: %ld evaluations", c.evaluations);
    if (c.max_kappa > 0) std::printf(", largest robust gain %.3g", c.max_kappa);
    std::printf("\n");
    for (const std::string& w : control_warnings(c, tu)) {
      std::fprintf(stderr, "warning: %s\n", terminal_text(w).c_str());
    }
  }
  for (const auto& f : files) std::printf("  wrote %s\n", terminal_text(f.string(), false).c_str());
  if (s.status == Status::kEnergyBalance) {
    std::fprintf(stderr, "warning: %s\n", terminal_text(s.message).c_str());
    std::printf("  status: energy_balance\n");
    return kExitEnergyBalance;
  }
  if (s.status == Status::kInterrupted) {
    std::printf("  status: interrupted\n");
    return kExitInterruptedBase + (received != 0 ? received : SIGINT);
  }
  if (s.status != Status::kOk) {
    std::fprintf(stderr, "error: the run failed at t = %g %s: %s\n", s.t_reached, tu,
                 s.message.empty() ? to_string(s.status) : terminal_text(s.message).c_str());
    return kExitRunFailed;
  }
  if (output_failed) {
    std::printf("  status: ok, but an output file could not be written\n");
    return kExitRunFailed;
  }
  std::printf("  status: ok\n");
  return kExitOk;
}

}  // namespace ukdyn::cli
