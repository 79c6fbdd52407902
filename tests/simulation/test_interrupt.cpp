// SPDX-License-Identifier: BSD-3-Clause
// Interrupts and outputs (issue #14, items 1 and 2; docs/simulation.md, "Interrupts and
// outputs"):
//  1. SimulationOptions::should_stop stops a run within a step with every integrator, plain and
//     controlled, and keeps the samples so far — each as the uninterrupted run has it, the last
//     one at RunStatistics::t_reached;
//  2. the writers (CSV, JSON, HDF5) write whole files or none: a write that fails leaves the
//     previous file and no temporary;
//  3. the command: SIGINT and SIGTERM during `ukdyn run` write the trajectory so far and a
//     summary that says interrupted, with exit code 128 + the signal; SIGKILL while writing
//     leaves no truncated file under a final name; a second run into a directory in use is
//     refused naming the directory and the pid of the first.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "support/cli_process.hpp"

extern char** environ;

namespace ukdyn {
namespace UKDYN_TEST_FILE {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// a fresh, empty scratch directory for one test
fs::path scratch(const std::string& name) {
  return test::scratch_directory("ukdyn_interrupt_", name);
}

using test::Command;
using test::read_text;

// the names of the files in dir (hidden ones too)
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

bool has_temporary(const fs::path& dir) {
  for (const auto& name : listing(dir)) {
    if (name.find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

// |a - b| <= tol (1 + |b|), a two-sided comparison that reads well in a failure message
::testing::AssertionResult near(double a, double b, double tol) {
  if (std::abs(a - b) <= tol * (1.0 + std::abs(b))) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << a << " vs " << b << " (difference " << a - b << ", tolerance " << tol << " (1 + |b|))";
}

// --- 1. the library: should_stop ----------------------------------------------------------------

// a should_stop that says yes from its `after`-th call on, and counts the calls after that
struct StopAfter {
  long after;
  std::shared_ptr<long> calls = std::make_shared<long>(0);
  std::shared_ptr<long> calls_after_yes = std::make_shared<long>(0);
  std::function<bool()> fn() const {
    return [after = after, calls = calls, late = calls_after_yes] {
      if (*calls >= after) ++*late;
      return ++*calls >= after;
    };
  }
};

// every sample of the interrupted run `part` is the uninterrupted run's (`full`, run to
// part's t_reached): same times, same states to `tol`
void expect_prefix_of(const Trajectory& part, const Trajectory& full, double tol) {
  ASSERT_EQ(part.samples(), full.samples());
  const Index n = part.n;
  for (Index i = 0; i < part.samples(); ++i) {
    ASSERT_DOUBLE_EQ(part.t[std::size_t(i)], full.t[std::size_t(i)]) << "sample " << i;
    for (Index j = 0; j < n; ++j) {
      const std::size_t k = std::size_t(i * n + j);
      EXPECT_TRUE(near(part.q[k], full.q[k], tol))
          << "q of sample " << i << " at t = " << part.t[std::size_t(i)];
      EXPECT_TRUE(near(part.qd[k], full.qd[k], tol)) << "q' of sample " << i;
    }
  }
}

void expect_interrupted_run(const Trajectory& tr, double t_start, double t_end) {
  EXPECT_EQ(tr.stats.status, Status::kInterrupted);
  EXPECT_STREQ(to_string(tr.stats.status), "interrupted");
  EXPECT_NE(tr.stats.message.find("interrupted at t = "), std::string::npos) << tr.stats.message;
  ASSERT_GE(tr.samples(), 2);
  // the last sample is at t_reached, inside the run; times strictly increase
  EXPECT_DOUBLE_EQ(tr.t.back(), tr.stats.t_reached);
  EXPECT_GT(tr.stats.t_reached, t_start);
  EXPECT_LT(tr.stats.t_reached, t_end);
  for (std::size_t i = 1; i < tr.t.size(); ++i) ASSERT_LT(tr.t[i - 1], tr.t[i]) << "sample " << i;
  tr.check_consistent("test");
}

}  // namespace UKDYN_TEST_FILE

// (test names and ctest lines show the method, not its bytes)
void PrintTo(Integrator i, std::ostream* os) { *os << to_string(i); }

namespace UKDYN_TEST_FILE {

class EveryIntegrator : public ::testing::TestWithParam<Integrator> {};

TEST_P(EveryIntegrator, StopsOnRequestAndKeepsTheSamplesOfTheUninterruptedRun) {
  const auto ex = gallery::make("pendulum");
  SimulationOptions o;
  o.integrator = GetParam();
  o.t_end = 50.0;
  o.output_every = 0.05;
  if (o.integrator == Integrator::kRK4 || o.integrator == Integrator::kRK5) o.step = 2e-3;
  const StopAfter stop{400};
  o.should_stop = stop.fn();
  const Trajectory part = simulate(ex.system, ex.q0, ex.qd0, o);
  expect_interrupted_run(part, o.t_start, o.t_end);
  // asked until it said yes, never after
  EXPECT_EQ(*stop.calls, stop.after);
  EXPECT_EQ(*stop.calls_after_yes, 0);
  // the run stopped within a step of the request: 400 calls are one per step and sample, so
  // fewer than 400 steps were taken
  EXPECT_GE(part.stats.steps, 1);
  EXPECT_LE(part.stats.steps, stop.after);

  // the same run to t_reached, uninterrupted: the same samples (the fixed-step methods divide
  // [0, t_reached] into other steps: their error, 1e-9 here, separates the two)
  o.should_stop = nullptr;
  o.t_end = part.stats.t_reached;
  const Trajectory full = simulate(ex.system, ex.q0, ex.qd0, o);
  EXPECT_EQ(full.stats.status, Status::kOk) << full.stats.message;
  expect_prefix_of(part, full, o.integrator == Integrator::kRK4 ? 1e-6 : 1e-8);
  // the run is consistent up to its last sample: on the rod, energy kept (E = 0)
  EXPECT_NEAR(std::hypot(part.q[part.q.size() - 2], part.q.back()), 1.0, 1e-9);
  EXPECT_NEAR(part.energy.back(), 0.0, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Interrupt, EveryIntegrator,
                         ::testing::Values(Integrator::kRK4, Integrator::kRK5, Integrator::kDopri5,
                                           Integrator::kRKF78, Integrator::kBDF),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(Interrupt, AStopRequestedBeforeTheFirstStepKeepsTheInitialSample) {
  const auto ex = gallery::make("pendulum");
  SimulationOptions o;
  o.t_end = 5.0;
  o.should_stop = [] { return true; };
  const Trajectory tr = simulate(ex.system, ex.q0, ex.qd0, o);
  EXPECT_EQ(tr.stats.status, Status::kInterrupted);
  ASSERT_EQ(tr.samples(), 1);
  EXPECT_DOUBLE_EQ(tr.t[0], 0.0);
  EXPECT_DOUBLE_EQ(tr.stats.t_reached, 0.0);
  EXPECT_DOUBLE_EQ(tr.q[0], ex.q0[0]);
  EXPECT_DOUBLE_EQ(tr.q[1], ex.q0[1]);
}

TEST(Interrupt, WithoutSamplesBetweenItStopsAtTheStepAndRecordsIt) {
  // output_every = 0: only t_start and t_end are samples; the interrupted run still keeps the
  // state it reached, as its second sample
  const auto ex = gallery::make("pendulum");
  SimulationOptions o;
  o.t_end = 1000.0;
  o.output_every = 0.0;
  const StopAfter stop{300};
  o.should_stop = stop.fn();
  const Trajectory part = simulate(ex.system, ex.q0, ex.qd0, o);
  expect_interrupted_run(part, o.t_start, o.t_end);
  ASSERT_EQ(part.samples(), 2);
  o.should_stop = nullptr;
  o.t_end = part.stats.t_reached;
  expect_prefix_of(part, simulate(ex.system, ex.q0, ex.qd0, o), 1e-8);
}

TEST(Interrupt, ControlledAndFrictionModelsStopTheSameWay) {
  // a controlled model (simulate_controlled under run_model) and one with Coulomb friction
  // (stick/slip events): the columns of every part, control and outputs included, have one
  // value per sample, and they are the uninterrupted run's
  for (const char* name : {"control_duffing", "four_bar_friction"}) {
    SCOPED_TRACE(name);
    const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml");
    SimulationOptions o = model.options;
    o.t_end = 1e4;
    const StopAfter stop{500};
    o.should_stop = stop.fn();
    const ModelRun part = run_model(model, o);
    expect_interrupted_run(part.trajectory, o.t_start, o.t_end);
    const auto cols = part.columns();
    for (const auto& c : cols)
      EXPECT_EQ(Index(c.values.size()), part.trajectory.samples()) << c.name;

    o.should_stop = nullptr;
    o.t_end = part.trajectory.stats.t_reached;
    const ModelRun full = run_model(model, o);
    EXPECT_EQ(full.trajectory.stats.status, Status::kOk) << full.trajectory.stats.message;
    expect_prefix_of(part.trajectory, full.trajectory, 1e-7);
    const auto full_cols = full.columns();
    ASSERT_EQ(cols.size(), full_cols.size());
    for (std::size_t c = 0; c < cols.size(); ++c) {
      ASSERT_EQ(cols[c].values.size(), full_cols[c].values.size()) << cols[c].name;
      for (std::size_t i = 0; i < cols[c].values.size(); ++i) {
        EXPECT_TRUE(near(cols[c].values[i], full_cols[c].values[i], 1e-6))
            << cols[c].name << " at sample " << i;
      }
    }
  }
}

// --- 2. the writers: whole files or none --------------------------------------------------------

Trajectory short_run() {
  const auto ex = gallery::make("pendulum");
  SimulationOptions o;
  o.t_end = 2.0;
  return simulate(ex.system, ex.q0, ex.qd0, o);
}

// RLIMIT_FSIZE lowered for its lifetime: a write past `bytes` fails (EFBIG; SIGXFSZ ignored)
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previous_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lower = saved_;
    lower.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &lower);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_);
  }

 private:
  rlimit saved_{};
  void (*previous_)(int) = nullptr;
};

TEST(AtomicOutput, AWriterReplacesTheFileWholeAndLeavesNoTemporary) {
  const fs::path dir = scratch("replace");
  const Trajectory tr = short_run();
  const fs::path csv = dir / "trajectory.csv", json = dir / "summary.json", h5 = dir / "run.h5";
  for (const fs::path& p : {csv, json, h5}) std::ofstream(p) << "previous contents\n";
  write_csv(tr, csv.string());
  write_summary_json(tr, SimulationOptions{}, json.string());
  write_hdf5(tr, h5.string());
  EXPECT_EQ(listing(dir), (std::vector<std::string>{"run.h5", "summary.json", "trajectory.csv"}));
  // the new contents, whole: a header and one line per sample; the summary parses
  const std::string text = read_text(csv);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), tr.samples() + 1);
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(nlohmann::json::parse(read_text(json))["samples"].get<long>(), tr.samples());
  EXPECT_EQ(read_hdf5_field(h5.string(), "t").size(), tr.t.size());
}

TEST(AtomicOutput, AWriteThatFailsLeavesThePreviousFileAndNoTemporary) {
  const fs::path dir = scratch("failed_write");
  const Trajectory tr = short_run();
  const fs::path csv = dir / "trajectory.csv", json = dir / "summary.json", h5 = dir / "run.h5";
  const std::string previous = "previous contents of a complete run\n";
  for (const fs::path& p : {csv, json, h5}) std::ofstream(p) << previous;
  {
    // every writer fails after 64 bytes (the CSV holds 200 lines of ~400 bytes)
    FileSizeLimit limit(64);
    auto expect_fails = [&](const std::function<void()>& write, const fs::path& path) {
      try {
        write();
        ADD_FAILURE() << "no error writing " << path;
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("'" + path.string() + "'"), std::string::npos)
            << e.what();
      }
    };
    expect_fails([&] { write_csv(tr, csv.string()); }, csv);
    expect_fails([&] { write_summary_json(tr, SimulationOptions{}, json.string()); }, json);
    expect_fails([&] { write_hdf5(tr, h5.string()); }, h5);
  }
  for (const fs::path& p : {csv, json, h5}) EXPECT_EQ(read_text(p), previous) << p;
  EXPECT_EQ(listing(dir), (std::vector<std::string>{"run.h5", "summary.json", "trajectory.csv"}));
}

TEST(AtomicOutput, AFileThatIsNotRegularIsWrittenInPlace) {
  // /dev/null cannot be replaced by a rename (and must not be): written in place, as before
  const Trajectory tr = short_run();
  EXPECT_NO_THROW(write_csv(tr, "/dev/null"));
  EXPECT_NO_THROW(write_summary_json(tr, SimulationOptions{}, "/dev/null"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  // a missing directory is named, as before
  try {
    write_csv(tr, "/nonexistent-ukdyn-dir/t.csv");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open '/nonexistent-ukdyn-dir/t.csv': No such "
                                         "file or directory"),
              std::string::npos)
        << e.what();
  }
}

// --- 3. the command
// -------------------------------------------------------------------------------

// trajectory.csv: the header and the rows, each checked to have the header's width
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  std::size_t column(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error("no column " + name);
    return std::size_t(it - header.begin());
  }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string field; std::getline(ss, field, ',');) out.push_back(field);
  return out;
}

// parses the whole file; a malformed line (wrong width, not a number, no final newline) fails
// the test that calls it
Csv read_csv(const fs::path& path) {
  Csv csv;
  const std::string text = read_text(path);
  EXPECT_FALSE(text.empty()) << path;
  if (text.empty()) return csv;
  EXPECT_EQ(text.back(), '\n') << path << " does not end with a newline (truncated?)";
  std::stringstream in(text);
  std::string line;
  std::getline(in, line);
  csv.header = split(line);
  while (std::getline(in, line)) {
    const auto fields = split(line);
    EXPECT_EQ(fields.size(), csv.header.size()) << "row " << csv.rows.size() + 1 << ": " << line;
    if (fields.size() != csv.header.size()) continue;
    std::vector<double> row;
    for (const auto& f : fields) {
      char* end = nullptr;
      row.push_back(std::strtod(f.c_str(), &end));
      EXPECT_EQ(*end, '\0') << "not a number: '" << f << "' in row " << csv.rows.size() + 1;
    }
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

nlohmann::json read_summary(const fs::path& path) { return nlohmann::json::parse(read_text(path)); }

const std::string kLongModel = std::string(UKDYN_TEST_DATA_DIR) + "/interrupt_pendulum.yaml";

struct SignalCase {
  int signal;
  const char* name;
  bool plots;
};
void PrintTo(const SignalCase& c, std::ostream* os) { *os << c.name; }

class RunSignal : public ::testing::TestWithParam<SignalCase> {};

TEST_P(RunSignal, WritesTheTrajectorySoFarAndASummaryThatSaysInterrupted) {
  const SignalCase c = GetParam();
  const fs::path dir = scratch(std::string("signal_") + c.name), out = dir / "out";
  std::vector<std::string> args = {"run", kLongModel, "-o", out.string()};
  if (!c.plots) args.push_back("--no-plots");
  Command run(args, dir / "stdout.txt");
  // the run is under way: it logged its progress, and has been going a while
  ASSERT_TRUE(run.wait_for("ukdyn: t = ", 60.0)) << run.stderr_text();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(::kill(run.pid(), c.signal), 0);
  const auto sent = Clock::now();
  const int code = run.wait();
  const double seconds = std::chrono::duration<double>(Clock::now() - sent).count();
  const std::string out_text = read_text(dir / "stdout.txt");

  // exit code 128 + the signal; what happened, said
  EXPECT_EQ(code, 128 + c.signal) << run.stderr_text() << out_text;
  EXPECT_NE(run.stderr_text().find(std::string("interrupted by ") + c.name + " at t = "),
            std::string::npos)
      << run.stderr_text();
  EXPECT_NE(out_text.find("status: interrupted"), std::string::npos) << out_text;
  // (writing a few thousand rows, and with plots running matplotlib: seconds, not minutes; a run
  // that never stops fails by CTest's TIMEOUT, not by a wall-clock assertion)
  std::printf("  %s: exited %.3f s after the signal\n", c.name, seconds);

  // the summary: interrupted, with the time reached
  const nlohmann::json summary = read_summary(out / "summary.json");
  EXPECT_EQ(summary["status"], "interrupted");
  EXPECT_NE(summary["message"].get<std::string>().find(std::string("interrupted by ") + c.name),
            std::string::npos);
  const double t_reached = summary["t_reached"].get<double>();
  EXPECT_GT(t_reached, 1.0);
  EXPECT_LT(t_reached, 5e4);

  // the trajectory: complete, times increasing, the last at t_reached, every row on the rod
  const Csv csv = read_csv(out / "trajectory.csv");
  ASSERT_GE(csv.rows.size(), 3u);
  EXPECT_EQ(long(csv.rows.size()), summary["samples"].get<long>());
  const std::size_t t = csv.column("t"), r = csv.column("r"), x = csv.column("x");
  for (std::size_t i = 1; i < csv.rows.size(); ++i) {
    ASSERT_LT(csv.rows[i - 1][t], csv.rows[i][t]) << "row " << i;
  }
  EXPECT_DOUBLE_EQ(csv.rows.back()[t], t_reached);
  for (const auto& row : csv.rows) EXPECT_NEAR(row[r], 1.0, 1e-8);
  EXPECT_DOUBLE_EQ(summary["final_state"]["q"]["x"].get<double>(), csv.rows.back()[x]);
  // the plots too (unless the machine has no matplotlib: the command then says "no plots")
  if (c.plots && run.stderr_text().find("no plots") == std::string::npos) {
    for (const char* png : {"coordinates.png", "energy.png"}) {
      ASSERT_TRUE(fs::exists(out / png)) << png << "\n" << run.stderr_text();
      EXPECT_GT(fs::file_size(out / png), 1000u) << png;
    }
  }
  EXPECT_FALSE(has_temporary(out));

  // the same model run to t_reached without interruption: the same rows
  char t_end[40];
  std::snprintf(t_end, sizeof t_end, "%.17g", t_reached);
  Command reference(
      {"run", kLongModel, "-o", (dir / "reference").string(), "--no-plots", "--t-end", t_end},
      dir / "reference.txt");
  ASSERT_EQ(reference.wait(), 0) << reference.stderr_text();
  const Csv full = read_csv(dir / "reference" / "trajectory.csv");
  ASSERT_EQ(full.rows.size(), csv.rows.size());
  ASSERT_EQ(full.header, csv.header);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    ASSERT_DOUBLE_EQ(csv.rows[i][t], full.rows[i][t]) << "row " << i;
    for (std::size_t k = 0; k < csv.header.size(); ++k) {
      EXPECT_TRUE(near(csv.rows[i][k], full.rows[i][k], 1e-7))
          << csv.header[k] << " at t = " << csv.rows[i][t];
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Cli, RunSignal,
                         ::testing::Values(SignalCase{SIGINT, "SIGINT", true},
                                           SignalCase{SIGTERM, "SIGTERM", false}),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(Cli, ARunKilledWhileWritingLeavesNoTruncatedFileUnderAFinalName) {
  const fs::path dir = scratch("sigkill"), out = dir / "out";
  // a complete run first: its files are the "previous run" of the next one
  {
    Command first({"run", "--example", "pendulum", "-o", out.string(), "--no-plots"},
                  dir / "first.txt");
    ASSERT_EQ(first.wait(), 0) << first.stderr_text();
    ASSERT_TRUE(fs::exists(out / "summary.json"));
  }
  // the same model over 3000 s (300001 rows, some 80 MB of CSV), killed as soon as its CSV's
  // temporary appears
  Command run({"run", "--example", "pendulum", "-o", out.string(), "--no-plots", "--t-end", "3000"},
              dir / "second.txt");
  bool seen = false;
  const auto deadline = Clock::now() + std::chrono::seconds(120);
  while (!seen && Clock::now() < deadline) {
    for (const auto& name : listing(out)) seen = seen || name.rfind(".trajectory.csv.tmp-", 0) == 0;
    if (!seen) std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  ASSERT_TRUE(seen) << "the CSV's temporary never appeared";
  ASSERT_EQ(::kill(run.pid(), SIGKILL), 0);
  EXPECT_EQ(run.wait(), 128 + SIGKILL);

  // killed while writing: the previous run's files are gone (removed before writing), the new
  // CSV is not under its final name, and nothing else is
  EXPECT_FALSE(fs::exists(out / "trajectory.csv"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  EXPECT_TRUE(has_temporary(out));

  // the next run into the directory removes the dead run's temporary and writes its own files
  Command next({"run", "--example", "pendulum", "-o", out.string(), "--no-plots"},
               dir / "next.txt");
  ASSERT_EQ(next.wait(), 0) << next.stderr_text();
  EXPECT_FALSE(has_temporary(out));
  const Csv csv = read_csv(out / "trajectory.csv");
  EXPECT_EQ(long(csv.rows.size()), read_summary(out / "summary.json")["samples"].get<long>());
  // (the pendulum draws itself: its viewer page, written whole like the rest, comes last)
  EXPECT_EQ(listing(out), (std::vector<std::string>{".ukdyn.lock", "animation.html", "summary.json",
                                                    "trajectory.csv"}));
  fs::remove_all(dir);  // (the dead run's 80 MB are gone already; the rest is small)
}

TEST(Cli, ASecondRunIntoADirectoryInUseIsRefusedNamingItAndTheFirstRunsPid) {
  const fs::path dir = scratch("concurrent"), out = dir / "out";
  Command first({"run", kLongModel, "-o", out.string(), "--no-plots"}, dir / "first.txt");
  ASSERT_TRUE(first.wait_for("ukdyn: t = ", 60.0)) << first.stderr_text();

  // the second, with another rod length, is refused at once: exit 6, nothing computed or written
  // (no step taken: its output is empty)
  Command second({"run", kLongModel, "-o", out.string(), "--no-plots", "--set", "L=2"},
                 dir / "second.txt");
  EXPECT_EQ(second.wait(), 6);
  const std::string expected = "error: the output directory '" + out.string() +
                               "' is in use by another ukdyn run (pid " +
                               std::to_string(first.pid()) + ")";
  EXPECT_NE(second.stderr_text().find(expected), std::string::npos) << second.stderr_text();
  EXPECT_EQ(read_text(dir / "second.txt"), "");
  EXPECT_EQ(listing(out), std::vector<std::string>{".ukdyn.lock"});

  // the first goes on, and its files are its own: every row has its rod length, 1
  ASSERT_EQ(::kill(first.pid(), SIGINT), 0);
  EXPECT_EQ(first.wait(), 130) << first.stderr_text();
  const Csv csv = read_csv(out / "trajectory.csv");
  ASSERT_GE(csv.rows.size(), 2u);
  const nlohmann::json summary = read_summary(out / "summary.json");
  EXPECT_EQ(long(csv.rows.size()), summary["samples"].get<long>());
  const std::size_t r = csv.column("r");
  for (const auto& row : csv.rows) EXPECT_NEAR(row[r], 1.0, 1e-8);

  // and once it has ended, the directory is free again
  Command third(
      {"run", kLongModel, "-o", out.string(), "--no-plots", "--set", "L=2", "--t-end", "3"},
      dir / "third.txt");
  EXPECT_EQ(third.wait(), 0) << third.stderr_text();
  const Csv after = read_csv(out / "trajectory.csv");
  ASSERT_EQ(after.rows.size(), 7u);  // t = 0, 0.5, ..., 3
  for (const auto& row : after.rows) EXPECT_NEAR(row[r], 2.0, 1e-8);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
