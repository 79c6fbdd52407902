// SPDX-License-Identifier: BSD-3-Clause
// Nothing lost, nothing hanging, untrusted names harmless (issue #29, items 6 and 7; reproducers
// 2026-11-28): the command under SIGHUP, a console that went away (SIGPIPE) and a file-size
// limit (SIGXFSZ); symbolic links and FIFOs planted among its outputs; --format checked before a
// sweep runs; a viewer page that cannot be written; names with escape sequences; and the
// library's writers (io/atomic_file.hpp, io/hdf5.cpp) under the same conditions.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "support/cli_process.hpp"

namespace ukdyn::test {
namespace UKDYN_TEST_FILE {

fs::path scratch(const std::string& name) { return scratch_directory("ukdyn_outputs_", name); }

// the names in a directory, sorted (hidden ones included)
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Runs `ukdyn ARGS` in a child process whose stdout and stderr go to `out` (a descriptor), after
// `setup` ran in the child; returns the exit code, or 128 + the signal that ended it.
template <class Setup>
int run_ukdyn(const std::vector<std::string>& args, int out, Setup&& setup) {
  std::vector<std::string> argv_s = {UKDYN_CLI};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out, 1);
    ::dup2(out, 2);
    for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ}) std::signal(sig, SIG_DFL);
    setup();
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// `ukdyn ARGS` with stdout and stderr to the file `log`; the exit code
int run_logged(const std::vector<std::string>& args, const fs::path& log) {
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int code = run_ukdyn(args, fd, [] {});
  ::close(fd);
  return code;
}

nlohmann::json summary_of(const fs::path& dir) {
  return nlohmann::json::parse(read_text(dir / "summary.json"));
}

// --- signals ------------------------------------------------------------------------------------

// sighup_loses_run.sh: SIGHUP (a closed terminal or ssh session) ended the run at once, with
// nothing written; now it stops the run as SIGTERM does, and the files are written
TEST(CommandSignals, SighupStopsARunAndItsFilesAreWritten) {
  const fs::path dir = scratch("sighup_run");
  Command run({"run", "--example", "pendulum", "--t-end", "100000", "--no-plots", "-o",
               (dir / "out").string()},
              dir / "stdout.txt");
  ASSERT_TRUE(run.wait_for("ukdyn: t = ", 120)) << run.stderr_text();
  ::kill(run.pid(), SIGHUP);
  EXPECT_EQ(run.wait(), 128 + SIGHUP) << run.stderr_text();
  EXPECT_NE(run.stderr_text().find("interrupted by SIGHUP"), std::string::npos);
  const nlohmann::json s = summary_of(dir / "out");
  EXPECT_EQ(s["status"], "interrupted");
  const double t = s["t_reached"].get<double>();
  EXPECT_GT(t, 0.0);
  EXPECT_LT(t, 100000.0);
  const std::string csv = read_text(dir / "out" / "trajectory.csv");
  EXPECT_GT(std::count(csv.begin(), csv.end(), '\n'), 2);
}

TEST(CommandSignals, SighupStopsASweepAndTheFinishedSamplesAreWritten) {
  const fs::path dir = scratch("sighup_sweep");
  Command sweep({"sweep", "--example", "pendulum", "--grid", "L=1:2:3000", "--t-end", "5", "--jobs",
                 "1", "--no-plots", "-o", (dir / "out").string()},
                dir / "stdout.txt");
  ASSERT_TRUE(sweep.wait_for(" of 3000 samples", 120)) << sweep.stderr_text();
  ::kill(sweep.pid(), SIGHUP);
  EXPECT_EQ(sweep.wait(), 128 + SIGHUP) << sweep.stderr_text();
  const auto summary = summary_of(dir / "out");
  EXPECT_TRUE(summary["interrupted"].get<bool>());
  // the samples stopped or never started are counted apart, not as failed (repro u14/11: "3000
  // samples: 2 ok, 2998 failed")
  const auto ok = summary["ok"].get<std::size_t>();
  const auto interrupted = summary["samples_interrupted"].get<std::size_t>();
  const auto not_run = summary["not_run"].get<std::size_t>();
  EXPECT_EQ(summary["failed"].get<std::size_t>(), 0u);
  EXPECT_EQ(ok + interrupted + not_run, 3000u);
  EXPECT_LE(interrupted, 1u);
  EXPECT_GT(not_run, 2000u);
  EXPECT_NE(read_text(dir / "stdout.txt").find(", 0 failed, "), std::string::npos)
      << read_text(dir / "stdout.txt");
  EXPECT_NE(read_text(dir / "stdout.txt").find(" not run; "), std::string::npos)
      << read_text(dir / "stdout.txt");
  // one row per sample (those not run say so) below the header
  const std::string csv = read_text(dir / "out" / "ensemble.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3001);
  EXPECT_NE(csv.find(",not run,"), std::string::npos);
}

// ctrl_c_with_tee.sh: `ukdyn run … 2>&1 | head -1` died of SIGPIPE at its next console line,
// before any file was renamed into place; now the console lines are lost, the files are not
TEST(CommandSignals, AConsoleThatWentAwayCostsNoFile) {
  const fs::path dir = scratch("sigpipe");
  int fds[2];
  ASSERT_EQ(::pipe2(fds, O_CLOEXEC), 0);
  ::close(fds[0]);  // no reader: every write gets EPIPE (and SIGPIPE unless ignored)
  const int code = run_ukdyn(
      {"run", "--example", "pendulum", "--t-end", "2", "--no-plots", "-o", (dir / "out").string()},
      fds[1], [] {});
  ::close(fds[1]);
  EXPECT_EQ(code, 0);
  EXPECT_EQ(summary_of(dir / "out")["status"], "ok");
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "trajectory.csv"));
  // a sweep the same
  int more[2];
  ASSERT_EQ(::pipe2(more, O_CLOEXEC), 0);
  ::close(more[0]);
  EXPECT_EQ(run_ukdyn({"sweep", "--example", "pendulum", "--grid", "L=1,2", "--t-end", "0.1",
                       "--no-plots", "-o", (dir / "sweep").string()},
                      more[1], [] {}),
            0);
  ::close(more[1]);
  EXPECT_TRUE(fs::is_regular_file(dir / "sweep" / "ensemble.csv"));
}

// limits_signals.sh: under `ulimit -f` the run died of SIGXFSZ leaving a hidden temporary; now
// the write that met the limit fails with the usual message and exit code 1, the run stops, and
// the rows that reached the file are kept under its own name, said to be incomplete
TEST(CommandSignals, AFileSizeLimitIsAWriteErrorNotASignal) {
  const fs::path dir = scratch("sigxfsz");
  const fs::path log = dir / "log.txt";
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int code = run_ukdyn({"run", "--example", "pendulum", "--t-end", "2000", "--no-plots", "-o",
                              (dir / "out").string()},
                             fd, [] {
                               rlimit limit{};
                               ::getrlimit(RLIMIT_FSIZE, &limit);
                               limit.rlim_cur = 256 * 1024;
                               ::setrlimit(RLIMIT_FSIZE, &limit);
                             });
  ::close(fd);
  const std::string text = read_text(log);
  EXPECT_EQ(code, 1) << text;
  EXPECT_NE(
      text.find("cannot write '" + (dir / "out" / "trajectory.csv").string() + "': File too large"),
      std::string::npos)
      << text;
  const fs::path csv = dir / "out" / "trajectory.csv";
  ASSERT_TRUE(fs::is_regular_file(csv));
  EXPECT_EQ(fs::file_size(csv), 256u * 1024u);
  EXPECT_EQ(read_text(csv).rfind("t,", 0), 0u);
  const nlohmann::json s = summary_of(dir / "out");
  EXPECT_EQ(s["status"], "interrupted");
  EXPECT_NE(s["message"].get<std::string>().find("trajectory.csv could not be written"),
            std::string::npos);
  EXPECT_EQ(listing(dir / "out"),
            (std::vector<std::string>{".ukdyn.lock", "summary.json", "trajectory.csv"}));
}

// --- planted files
// --------------------------------------------------------------------------------

// lock_symlink.sh: a symbolic link planted as DIR/.ukdyn.lock had its target truncated and
// given the pid; now it is refused before anything runs, and the target is left as it was
TEST(OutputDirectory, ALinkPlantedAsTheLockIsRefused) {
  const fs::path dir = scratch("lock_link");
  const fs::path victim = dir / "victim.txt";
  std::ofstream(victim) << "precious data\n";
  for (const std::string command : {"run", "sweep"}) {
    SCOPED_TRACE(command);
    const fs::path out = dir / command;
    fs::create_directories(out);
    fs::create_symlink(victim, out / ".ukdyn.lock");
    std::vector<std::string> args = {command, "--example",  "pendulum", "--t-end",
                                     "0.1",   "--no-plots", "-o",       out.string()};
    if (command == "sweep") args.insert(args.end(), {"--grid", "L=1,2"});
    const int code = run_logged(args, dir / "log.txt");
    const std::string text = read_text(dir / "log.txt");
    EXPECT_EQ(code, 1) << text;
    EXPECT_NE(text.find("error: '" + (out / ".ukdyn.lock").string() +
                        "' is a symbolic link, not a regular file"),
              std::string::npos)
        << text;
    EXPECT_EQ(read_text(victim), "precious data\n");
    EXPECT_EQ(listing(out), std::vector<std::string>{".ukdyn.lock"});
  }
}

// lock_symlink.sh, sweep_fifo_hang.sh: links named ensemble.csv or sweep.png had their targets
// replaced; a FIFO named ensemble.csv hung the sweep after every sample was computed. Now each
// is refused before the sweep runs (no progress line), and nothing is written through it.
TEST(OutputDirectory, ASweepRefusesLinksAndFifosAmongItsOutputsBeforeRunning) {
  const fs::path dir = scratch("sweep_planted");
  const fs::path victim = dir / "victim.txt";
  std::ofstream(victim) << "precious data\n";
  struct Case {
    const char* name;
    bool fifo;
    const char* kind;
  };
  for (const Case c :
       {Case{"ensemble.csv", false, "a symbolic link"}, Case{"sweep.png", false, "a symbolic link"},
        Case{"summary.json", false, "a symbolic link"}, Case{"ensemble.csv", true, "a FIFO"}}) {
    SCOPED_TRACE(std::string(c.name) + " " + c.kind);
    const fs::path out = dir / (std::string(c.fifo ? "fifo_" : "link_") + c.name);
    fs::create_directories(out);
    if (c.fifo) {
      ASSERT_EQ(::mkfifo((out / c.name).c_str(), 0644), 0);
    } else {
      fs::create_symlink(victim, out / c.name);
    }
    Command sweep(
        {"sweep", "--example", "pendulum", "--grid", "L=1,2", "--t-end", "0.1", "-o", out.string()},
        dir / "stdout.txt");
    EXPECT_EQ(sweep.wait(), 1) << sweep.stderr_text();
    EXPECT_NE(sweep.stderr_text().find("error: '" + (out / c.name).string() + "' is " + c.kind +
                                       ", not a regular file"),
              std::string::npos)
        << sweep.stderr_text();
    EXPECT_EQ(sweep.stderr_text().find("samples ("), std::string::npos) << "it ran";
    EXPECT_EQ(read_text(victim), "precious data\n");
  }
}

// --- formats
// --------------------------------------------------------------------------------------

// sweep_format_typo.sh: `sweep --format json` ran every sample, wrote no table and exited 0;
// now refused before anything runs (exit 2; the directory is not even created)
TEST(CommandFormats, ASweepFormatTypoIsRefusedBeforeRunning) {
  const fs::path dir = scratch("format_typo");
  for (const std::string format : {"json", "CSV", "csv,hdf"}) {
    SCOPED_TRACE(format);
    const int code =
        run_logged({"sweep", "--example", "pendulum", "--grid", "L=1,2", "--t-end", "0.1",
                    "--no-plots", "--format", format, "-o", (dir / "out").string()},
                   dir / "log.txt");
    const std::string text = read_text(dir / "log.txt");
    EXPECT_EQ(code, 2) << text;
    const std::string bad = format == "csv,hdf" ? "hdf" : format;
    EXPECT_NE(text.find("error: --format " + bad + ": the formats are csv and hdf5"),
              std::string::npos)
        << text;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
}

// ...and a sweep into an old sweep's directory leaves none of the old sweep's files
TEST(CommandFormats, ASweepOverAnOldSweepLeavesNoStaleTable) {
  const fs::path dir = scratch("stale_table");
  const fs::path out = dir / "out";
  ASSERT_EQ(run_logged({"sweep", "--example", "pendulum", "--grid", "L=1,2,3", "--t-end", "0.1",
                        "--no-plots", "-o", out.string()},
                       dir / "log.txt"),
            0);
  ASSERT_TRUE(fs::exists(out / "ensemble.csv"));
  ASSERT_EQ(run_logged({"sweep", "--example", "pendulum", "--grid", "L=5,6", "--t-end", "0.1",
                        "--no-plots", "--format", "hdf5", "-o", out.string()},
                       dir / "log.txt"),
            0)
      << read_text(dir / "log.txt");
  EXPECT_EQ(listing(out), (std::vector<std::string>{".ukdyn.lock", "ensemble.h5", "summary.json"}));
  EXPECT_EQ(summary_of(out)["samples"].get<int>(), 2);
}

// --- a missing output
// -----------------------------------------------------------------------------

// disk_full_page.sh (the viewer's page not written on a full disk: exit 1, as --help says) is
// python/tests/test_viewer_page.py::test_a_page_that_cannot_be_written_is_exit_1, under a
// file-size limit: the command writes the page itself now, with no Python process to fail

// --- names on the terminal
// ------------------------------------------------------------------------

// terminal_escapes.sh: a model's name printed its escape sequences (retitle the window, colour);
// now every control character is printed as an escape
TEST(CommandText, ControlCharactersInNamesAreEscaped) {
  const fs::path dir = scratch("escapes");
  std::ofstream(dir / "e.yaml") << "name: \"\\x1b]0;owned\\x07\\x1b[31mRED\\u202e\\x9b2J\"\n"
                                   "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\n";
  const int code = run_logged({"run", (dir / "e.yaml").string(), "--t-end", "0.1", "--no-plots",
                               "-o", (dir / "out").string()},
                              dir / "log.txt");
  const std::string text = read_text(dir / "log.txt");
  EXPECT_EQ(code, 0) << text;
  EXPECT_NE(text.find("ukdyn run: \\x1b]0;owned\\x07\\x1b[31mRED\\u202e\\u009b2J ("),
            std::string::npos)
      << text;
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    EXPECT_FALSE(b < 0x20 && c != '\n' && c != '\t') << "control byte " << int(b) << " printed";
  }
}

// --- the library's writers
// ------------------------------------------------------------------------

Trajectory short_run(double t_end) {
  const auto ex = gallery::make("pendulum");
  SimulationOptions o;
  o.t_end = t_end;
  return simulate(ex.system, ex.q0, ex.qd0, o);
}

// A temporary is never at a name known in advance (the old `.NAME.tmp-PID-0`): a link planted
// there is neither followed nor replaced
TEST(AtomicFile, ALinkAtAPredictableTemporaryNameIsNotFollowed) {
  const fs::path dir = scratch("predictable");
  const fs::path victim = dir / "victim.txt";
  std::ofstream(victim) << "precious data\n";
  for (int k = 0; k < 4; ++k) {
    fs::create_symlink(
        victim, dir / (".t.csv.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(k)));
  }
  const Trajectory tr = short_run(0.5);
  write_csv(tr, (dir / "t.csv").string());
  write_hdf5(tr, (dir / "t.h5").string());
  EXPECT_EQ(read_text(victim), "precious data\n");
  const std::string csv = read_text(dir / "t.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), tr.samples() + 1);
  // the temporaries' mode is an ordinary file's (0666 less the umask), not mkstemp's 0600
  const mode_t mask = ::umask(022);
  ::umask(mask);
  EXPECT_EQ(fs::status(dir / "t.csv").permissions(),
            fs::perms(0666 & ~unsigned(mask)) & fs::perms::all);
}

// sweep_fifo_hang.sh, in the library: a FIFO that no process reads is an error, not a hang
TEST(AtomicFile, AFifoWithoutAReaderIsAnErrorNotAHang) {
  const fs::path dir = scratch("fifo");
  const fs::path fifo = dir / "t.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  try {
    write_csv(short_run(0.1), fifo.string());
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open '" + fifo.string() +
                                         "': No such device or address"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::is_fifo(fifo));
}

// hdf5_disk_full.sh: a disk that filled while trajectory.h5 was written crashed in H5Fclose
// (SIGSEGV, the Python interpreter too). In a child process (a crash must not take the test
// program with it), under a file-size limit: the write fails with the system's reason, the
// previous file is kept, and no temporary is left.
TEST(Hdf5Writer, AFullDiskIsAnErrorNotACrash) {
  const fs::path dir = scratch("hdf5_full");
  const fs::path h5 = dir / "t.h5", table = dir / "table.h5";
  for (const fs::path& p : {h5, table}) std::ofstream(p) << "previous\n";
  const Trajectory tr = short_run(200.0);  // about 1.5 MB of HDF5
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit{};
    ::getrlimit(RLIMIT_FSIZE, &limit);
    limit.rlim_cur = 100 * 1024;
    ::setrlimit(RLIMIT_FSIZE, &limit);
    int failures = 0;
    try {
      write_hdf5(tr, h5.string());
    } catch (const std::runtime_error& e) {
      failures += std::string(e.what()).find("cannot write '" + h5.string() +
                                             "': File too large") != std::string::npos;
    }
    try {
      write_table_hdf5(table.string(), csv_table(tr), "{\"status\": \"ok\"}");
    } catch (const std::runtime_error& e) {
      failures += std::string(e.what()).find("File too large") != std::string::npos;
    }
    ::_exit(failures == 2 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the errors did not name the file and the reason";
  for (const fs::path& p : {h5, table}) EXPECT_EQ(read_text(p), "previous\n");
  EXPECT_EQ(listing(dir), (std::vector<std::string>{"t.h5", "table.h5"}));
  // without the limit, the file reads back
  write_hdf5(tr, h5.string());
  EXPECT_EQ(read_hdf5_field(h5.string(), "t"), tr.t);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::test
