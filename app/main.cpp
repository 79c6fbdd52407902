// SPDX-License-Identifier: BSD-3-Clause
// ukdyn: the command-line front end. Argument parsing and dispatch only; the subcommands live in
// run.cpp, check.cpp and source.cpp, the physics in the library.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include <ukdyn/io/provenance.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/options.hpp>

#include "commands.hpp"
#include "stop_signals.hpp"
#include "suggest.hpp"
#include "terminal_text.hpp"

namespace {

constexpr const char* kExitCodes = R"(Exit codes:
  0  ok; also when a plot or the viewer cannot be made on this machine (no python, a python
     without matplotlib or NumPy, a program built without three.js): one warning line on
     stderr, and every other file written (--no-plots, --no-viewer: no warning)
  1  the run failed numerically (status not ok; "control failed" when a controlled run's
     controller failed); the trajectory up to the failure is still written (also: the output
     files could not be written)
  2  bad command line (also --set of a parameter the model does not declare, an unknown
     --example)
  3  bad model file (printed as FILE:LINE:COLUMN: error: MESSAGE (hint: ...)), including a
     setting of the file a run cannot use, and a model that cannot be started (inconsistent
     initial state: at initial:, or at the constraints that contradict each other)
  4  check found problems
  5  the run reached its end, but its energy balance residual exceeds the tolerance (status
     energy_balance): energy was gained or lost that no work channel accounts for
  6  the output directory is in use by another ukdyn run (its pid is named); nothing was run
  129, 130, 143  interrupted by SIGHUP (the terminal or ssh session closed), SIGINT (Ctrl-C)
     or SIGTERM (128 + the signal's number): the run stopped at its next step and the
     trajectory up to there, summary.json (status interrupted, t_reached) and the plots are
     written; a second signal ends it at once. SIGPIPE and SIGXFSZ are ignored: a console
     that went away costs only the console lines, and a file-size limit is an error of the
     file it stopped (exit 1)

Output files are written under a temporary name and renamed when complete; the directory is
locked for the run (DIR/.ukdyn.lock), and a run removes the previous run's files from it just
before writing its own. An output name (or the lock) that exists and is not a regular file (a
symbolic link, a FIFO, a directory) is refused before anything runs. Names from a model file
are printed with control characters escaped.)";

// the options shared by run and check: MODEL.yaml or --example NAME, and --set
void add_source_options(CLI::App* cmd, ukdyn::cli::ModelSource& source) {
  auto* path = cmd->add_option("model", source.path, "the model file (YAML)");
  cmd->add_option("--example", source.example,
                  "a built-in example instead of a file (ukdyn examples lists them)")
      ->excludes(path);
  cmd->add_option("--set", source.set, "override a parameter: --set name=value (repeatable)")
      ->type_name("NAME=VALUE")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

// the whole number a flag was given, >= min: a text such as -3, 2.5 or 1e3 is refused with the flag
// named (CLI11 would wrap -3 of an unsigned option to 2^64 - 3)
// the most threads `ukdyn sweep --jobs` takes
constexpr std::uint64_t kMaxJobs = 1024;

std::uint64_t whole_number_of(const std::string& flag, const std::string& text, std::uint64_t min) {
  std::uint64_t value = 0;
  bool ok = !text.empty() && text.size() <= 20;
  for (const char c : text) {
    if (!ok) break;
    const auto digit = static_cast<std::uint64_t>(c - '0');
    ok = c >= '0' && c <= '9' && value <= (std::numeric_limits<std::uint64_t>::max() - digit) / 10;
    if (ok) value = value * 10 + digit;
  }
  if (!ok || value < min) {
    throw ukdyn::cli::UsageError(flag + " " + text +
                                 ": must be a whole number >= " + std::to_string(min));
  }
  return value;
}

// A flag (--name, --name=value, -x or -xVALUE) that `cmd` does not have is refused here, before
// CLI11 parses: CLI11 would leave it aside and read its value as the model file ("model excludes
// --example" for `run --example pendulum --t-edn 3` or `-Z 3`). The nearest long flag is
// suggested (a short one has no near neighbour: any other letter is one edit away). Values of
// the flags that take one are skipped, so `--set name=--x` is not read as a flag, and a
// negative number (-3, -.5) is a value, not a flag.
void check_flags(const CLI::App& cmd, int first, int argc, char** argv) {
  std::vector<std::string> known;
  for (const CLI::Option* opt : cmd.get_options()) {
    for (const std::string& name : opt->get_lnames()) known.push_back("--" + name);
  }
  const std::string command = cmd.get_parent() == nullptr ? "ukdyn" : "ukdyn " + cmd.get_name();
  for (int i = first; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") return;  // the rest are positional
    const bool is_long = arg.size() >= 3 && arg.compare(0, 2, "--") == 0;
    const bool is_short = arg.size() >= 2 && arg[0] == '-' && arg[1] != '-' && arg[1] != '.' &&
                          (arg[1] < '0' || arg[1] > '9');
    if (!is_long && !is_short) continue;
    // --name[=value], or -x[VALUE]
    const std::string name = is_long ? arg.substr(0, arg.find('=')) : arg.substr(0, 2);
    const CLI::Option* opt = cmd.get_option_no_throw(name);
    if (opt == nullptr) {
      throw ukdyn::cli::UsageError("unknown option '" + name + "' for " + command +
                                   (is_long ? ukdyn::cli::did_you_mean(name, known) : ""));
    }
    // a flag that takes a value and was not given one with it: its value is the next argument
    if (opt->get_type_size() != 0 && name.size() == arg.size()) ++i;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ukdyn::cli;
  ignore_output_signals();
  CLI::App app(
      "ukdyn: explicit equations of motion of constrained mechanical systems "
      "(Udwadia-Kalaba). Runs and checks model files (YAML).",
      "ukdyn");
  app.footer(kExitCodes);
  app.set_version_flag("--version", std::string("ukdyn ") + ukdyn::version(),
                       "print the version and exit");
  app.require_subcommand(1);

  RunArguments run;
  bool no_plots = false;
  bool viewer = false, no_viewer = false;
  CLI::App* run_cmd = app.add_subcommand(
      "run",
      "simulate a model; write DIR/trajectory.csv, DIR/summary.json, the plots and "
      "animation.html");
  add_source_options(run_cmd, run.source);
  run_cmd
      ->add_option("-o,--output", run.out_dir,
                   "output directory (default: ukdyn-<model name>; created if missing)")
      ->type_name("DIR");
  // one flag per simulation option of the table (simulation/options.hpp), replacing simulate: NAME;
  // a boolean option also has --no-NAME
  std::map<std::string, std::string> texts;
  std::map<std::string, bool> negated;
  std::vector<std::pair<const ukdyn::OptionInfo*, CLI::Option*>> flags, no_flags;
  const ukdyn::SimulationOptions defaults;
  for (const ukdyn::OptionInfo& info : ukdyn::option_table()) {
    std::string names = ukdyn::option_flag(info);
    for (const std::string& alias : info.aliases) {
      ukdyn::OptionInfo a;
      a.name = alias;
      names += "," + ukdyn::option_flag(a);
    }
    const char* type = info.type == ukdyn::OptionType::kNumber    ? "X"
                       : info.type == ukdyn::OptionType::kInteger ? "N"
                       : info.type == ukdyn::OptionType::kChoice  ? "NAME"
                       : info.type == ukdyn::OptionType::kBool    ? "BOOL"
                                                                  : "T1,T2,...";
    const std::string help = info.doc + ": " + ukdyn::option_rule(info) + " (default " +
                             ukdyn::option_text(info.get(defaults)) +
                             "), instead of simulate: " + info.name;
    flags.emplace_back(&info, run_cmd->add_option(names, texts[info.name], help)->type_name(type));
    if (info.type == ukdyn::OptionType::kBool) {
      const std::string no = "--no-" + ukdyn::option_flag(info).substr(2);
      no_flags.emplace_back(&info,
                            run_cmd->add_flag(no, negated[info.name],
                                              "the same as " + ukdyn::option_flag(info) +
                                                  " false (simulate: " + info.name + ": false)"));
    }
  }
  run_cmd
      ->add_option("--format", run.formats,
                   "the trajectory's files: csv (trajectory.csv), hdf5 (trajectory.h5, the same "
                   "columns with summary.json as attributes), or csv,hdf5 (default csv)")
      ->delimiter(',')
      ->type_name("LIST");
  run_cmd
      ->add_option("--from-summary", run.from_summary,
                   "make an earlier run again from its summary.json (or its trajectory.h5, or "
                   "Python's Result.to_hdf5 file): the same model (checked unchanged), parameter "
                   "overrides, settings and --format; --set and flags apply on top")
      ->type_name("FILE");
  run_cmd
      ->add_option("--plot-format", run.plot_formats,
                   "the plots' file formats: png, pdf, svg or a list (--plot-format png,pdf; "
                   "default png, or pdf with --plot-style paper)")
      ->delimiter(',')
      ->type_name("LIST");
  run_cmd
      ->add_option("--plot-style", run.plot_style,
                   "the plots' style: screen (default) or paper (a journal's single column: "
                   "3.5 in wide, 8 pt text, legends inside the panels)")
      ->type_name("STYLE");
  run_cmd->add_flag("--no-plots", no_plots,
                    "write no plots (plots need /usr/bin/python3 "
                    "with matplotlib, or $UKDYN_PYTHON)");
  run_cmd->add_flag("--viewer", viewer,
                    "write animation.html, the run in a browser (the default for models with "
                    "bodies or a visual: section; needs /usr/bin/python3 or $UKDYN_PYTHON)");
  run_cmd->add_flag("--no-viewer", no_viewer, "write no animation.html")->excludes("--viewer");

  // sweep: a design over the model's parameters, initial values and options (docs/ensembles.md)
  SweepArguments sweep;
  bool sweep_no_plots = false;
  std::map<std::string, std::string> sweep_texts;
  std::vector<std::pair<const ukdyn::OptionInfo*, CLI::Option*>> sweep_flags;
  CLI::App* sweep_cmd = app.add_subcommand(
      "sweep",
      "run a model over a grid of parameters and/or random draws on every core; write "
      "DIR/ensemble.csv (one row per sample), summary.json and sweep.png");
  add_source_options(sweep_cmd, sweep.source);
  sweep_cmd
      ->add_option("--grid", sweep.grid, "a grid axis: NAME=START:STOP:COUNT or NAME=V1,V2,...")
      ->type_name("AXIS")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  sweep_cmd
      ->add_option("--random", sweep.random,
                   "a random variable: NAME~uniform(A,B), NAME~normal(MEAN,SD) or "
                   "NAME~loguniform(A,B)")
      ->type_name("VAR")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  // read as text and converted below, so that a negative number is refused by name
  std::string samples_text, seed_text;
  CLI::Option* samples_opt =
      sweep_cmd->add_option("--samples", samples_text, "random draws (per grid point)")
          ->type_name("N");
  CLI::Option* seed_opt =
      sweep_cmd->add_option("--seed", seed_text, "the random draws' seed (default 0)")
          ->type_name("S");
  sweep_cmd->add_flag("--lhs", sweep.lhs, "Latin hypercube draws");
  sweep_cmd
      ->add_option("--at", sweep.at,
                   "record the state and outputs at these times "
                   "(default: the run's end)")
      ->type_name("T1,T2,...");
  sweep_cmd
      ->add_option("--record", sweep.outputs,
                   "a column of trajectory.csv to record (repeatable; default the model's output "
                   "expressions)")
      ->type_name("NAME")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  std::string jobs_text;
  CLI::Option* jobs_opt =
      sweep_cmd->add_option("-j,--jobs", jobs_text, "threads, 1 to 1024 (default 0: every core)")
          ->type_name("N");
  sweep_cmd
      ->add_option("-o,--output", sweep.out_dir, "output directory (default ukdyn-sweep-<model>)")
      ->type_name("DIR");
  sweep_cmd->add_option("--format", sweep.formats, "csv, hdf5 or csv,hdf5 (default csv)")
      ->delimiter(',')
      ->type_name("LIST");
  sweep_cmd->add_flag("--no-plots", sweep_no_plots, "write no plot");
  sweep_cmd
      ->add_option("--plot-format", sweep.plot_formats,
                   "the summary plot's file formats: png, pdf, svg or a list (--plot-format "
                   "png,pdf; default png)")
      ->delimiter(',')
      ->type_name("LIST");
  for (const ukdyn::OptionInfo& info : ukdyn::option_table()) {
    sweep_flags.emplace_back(&info,
                             sweep_cmd
                                 ->add_option(ukdyn::option_flag(info), sweep_texts[info.name],
                                              info.doc + " (every sample)")
                                 ->type_name("VALUE"));
  }

  ModelSource check;
  CLI::App* check_cmd =
      app.add_subcommand("check",
                         "report coordinates, constraint rank, degrees of freedom, redundant "
                         "constraints, initial consistency, M and the control (requirements "
                         "that cannot be met, a controller that fails) at the initial state "
                         "only: the control as the run's first sample evaluates it, with the "
                         "contacts the run closes there; what happens later in the run is not "
                         "checked");
  add_source_options(check_cmd, check);

  LinearizeArguments lin;
  CLI::App* lin_cmd = app.add_subcommand(
      "linearize",
      "the linear model x' = A x + B u, y = C x + D u in minimal coordinates of the constraint "
      "manifold, with eigenvalues and modes (docs/linearize.md)");
  add_source_options(lin_cmd, lin.source);
  lin_cmd
      ->add_option("--at", lin.at,
                   "the state: NAME=VALUE,… (coordinates, NAME_dot, t; "
                   "default the model's initial state)")
      ->delimiter(',');
  lin_cmd->add_option("--independent", lin.independent, "independent positions by name")
      ->delimiter(',');
  lin_cmd
      ->add_option("--independent-velocities", lin.independent_velocities,
                   "independent velocities by name")
      ->delimiter(',');
  lin_cmd
      ->add_option("--inputs", lin.inputs,
                   "inputs: coordinates (a generalized force) or parameters")
      ->delimiter(',');
  lin_cmd
      ->add_option("--outputs", lin.outputs,
                   "outputs: coordinates, NAME_dot or the model's output expressions")
      ->delimiter(',');
  lin_cmd
      ->add_option("--states", lin.states,
                   "keep only these states (a subsystem the others do not act on)")
      ->delimiter(',');
  lin_cmd->add_flag("--along", lin.along,
                    "linearize along the model's own run, at every output sample (JSON)");
  lin_cmd->add_flag("--project", lin.project,
                    "first move the state onto the constraints (least M-weighted correction; "
                    "an open contact keeps its gap)");
  lin_cmd
      ->add_option("--initial-step", lin.initial_step,
                   "Ridders' first step, relative to each variable's scale (default 0.1; "
                   "docs/linearize.md, \"Steps in the model's own scale\")")
      ->check(
          [](const std::string& text) {
            char* end = nullptr;
            const double v = std::strtod(text.c_str(), &end);
            return end != text.c_str() && *end == '\0' && v > 0 && std::isfinite(v)
                       ? std::string()
                       : "must be a number > 0 (Ridders' first step relative to each "
                         "variable's scale; default 0.1)";
          },
          "> 0");
  lin_cmd->add_flag("--equilibrium", lin.equilibrium,
                    "first find an equilibrium (or steady motion) from the --at state");
  lin_cmd
      ->add_option("--unknowns", lin.unknowns,
                   "the equilibrium's unknowns (default: the independent positions)")
      ->delimiter(',');
  lin_cmd->add_option("--format", lin.format, "json (default) or csv");

  std::string example_name;
  CLI::App* examples_cmd = app.add_subcommand(
      "examples", "list the built-in examples; with NAME, print that example's model file");
  examples_cmd->add_option("name", example_name, "an example's name: print its model file");

  // an unknown subcommand is named, with the nearest one (CLI11 would say only "A subcommand is
  // required"); a flag the subcommand does not have is refused before parsing
  if (argc > 1 && argv[1][0] != '-') {
    const std::string first = argv[1];
    const CLI::App* chosen = nullptr;
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({})) {
      names.push_back(sub->get_name());
      if (sub->check_name(first)) chosen = sub;
    }
    if (chosen == nullptr) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      std::fprintf(stderr,
                   "error: unknown subcommand '%s'%s (the subcommands are %s)\n"
                   "Run with --help for more information.\n",
                   terminal_text(first, false).c_str(),
                   terminal_text(did_you_mean(first, names), false).c_str(), list.c_str());
      return kExitUsage;
    }
    try {
      check_flags(*chosen, 2, argc, argv);
    } catch (const UsageError& e) {
      std::fprintf(stderr, "error: %s\nRun with ukdyn %s --help for more information.\n",
                   terminal_text(e.what()).c_str(), chosen->get_name().c_str());
      return kExitUsage;
    }
  } else if (argc > 1) {
    // a flag before any subcommand: --help or --version, or named with the nearest (`ukdyn
    // --verison`: CLI11 would say only "A subcommand is required")
    try {
      check_flags(app, 1, 2, argv);
    } catch (const UsageError& e) {
      std::fprintf(stderr, "error: %s\nRun with --help for more information.\n",
                   terminal_text(e.what()).c_str());
      return kExitUsage;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints and exits 0; everything else is a bad command line
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }

  try {
    if (run_cmd->parsed()) {
      for (const auto& [info, opt] : flags) {
        if (opt->count() > 0) {
          run.settings.push_back({info->name, opt->get_name(), texts[info->name]});
        }
        for (const auto& [no_info, no_opt] : no_flags) {
          if (no_info == info && no_opt->count() > 0) {
            run.settings.push_back({info->name, no_opt->get_name(), "false"});
          }
        }
      }
      run.plots = !no_plots;
      if (viewer || no_viewer) run.viewer = viewer;
      run.arguments.assign(argv, argv + argc);
      return run_command(run);
    }
    if (sweep_cmd->parsed()) {
      for (const auto& [info, opt] : sweep_flags) {
        if (opt->count() > 0) {
          sweep.settings.push_back({info->name, opt->get_name(), sweep_texts[info->name]});
        }
      }
      if (samples_opt->count() > 0) sweep.samples = whole_number_of("--samples", samples_text, 1);
      if (seed_opt->count() > 0) sweep.seed = whole_number_of("--seed", seed_text, 0);
      if (jobs_opt->count() > 0) {
        // (a thread per sample at most; more than 1024 is a typo, not a machine)
        const std::uint64_t jobs = whole_number_of("--jobs", jobs_text, 0);
        if (jobs > kMaxJobs) {
          throw UsageError("--jobs " + jobs_text + ": at most " + std::to_string(kMaxJobs) +
                           " threads (0: one per core, " +
                           std::to_string(std::max(1u, std::thread::hardware_concurrency())) +
                           " here)");
        }
        sweep.jobs = unsigned(jobs);
      }
      sweep.plots = !sweep_no_plots;
      sweep.arguments.assign(argv, argv + argc);
      return sweep_command(sweep);
    }
    if (check_cmd->parsed()) return check_command(check);
    if (lin_cmd->parsed()) return linearize_command(lin);
    return examples_command(example_name);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "error: %s\nRun with --help for more information.\n",
                 terminal_text(e.what()).c_str());
    return kExitUsage;
  } catch (const ukdyn::ModelError& e) {
    std::fprintf(stderr, "%s\n", terminal_text(e.what()).c_str());
    return kExitModel;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", terminal_text(e.what()).c_str());
    return kExitRunFailed;
  }
}
