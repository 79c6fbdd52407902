// SPDX-License-Identifier: BSD-3-Clause
// MuJoCo on the shared benchmark problems P1 (double pendulum), P2 (crank-rocker four-bar) and P3
// (closed chain, N = 8, 32, 128) of bench/data/README.md, on this machine, so that ukdyn's figures
// (bench_multibody_problems) have a same-machine, same-run comparison (issue #15 item 3). MuJoCo
// is the library Debian ships (libmujoco-dev, 2.2.2), the version of the README's published row
// "MuJoCo 2.2.2, RK4, default soft constraints".
//
// Each problem of problems.json becomes an MJCF model, built as a string and loaded from MuJoCo's
// virtual file system (a chain deeper than kBodiesPerFile continues in <include>d files):
//   * link k is a body whose frame sits at its proximal hinge with x along the link; it is the
//     child of its parent link's body (of the world body for parent −1) at joint_in_parent, turned
//     by phi0 − phi0(parent): the model is defined in the initial pose, qpos0 = 0, which is where
//     MuJoCo computes a connect constraint's second anchor;
//   * one hinge joint about z at the body's origin, without damping, armature, stiffness or
//     friction loss; the link angle is phi0 + the hinge angles from the root down;
//   * an <inertial> element with the link's mass at (com_x, 0, 0) and diaginertia I_com (about the
//     link's own axis, then the transverse ones; P1: 1 kg point masses at the tips, 1e-9);
//   * no geoms, so nothing can collide (no contacts, no collision detection work);
//   * each loop closure an equality <connect> constraint (anchor p1 in body b1; b2 = −1: the
//     world) with MuJoCo's default soft-constraint settings (solref, solimp) and default solver;
//   * <option integrator="RK4" timestep="0.001" gravity="0 -9.81 0">.
//
//   bench_mujoco [google-benchmark flags]   per problem, one whole run of T seconds (mj_step
//                                           loop) per iteration; the counters carry the accuracy
//                                           figures of a separate run
//   bench_mujoco --json=PATH                the README's protocol (one warm-up, five timed runs,
//                                           median; a separate run checked at every step) written
//                                           as a JSON array of records
//   bench_mujoco --once=ID                  one run of the loop (ID: P1, P2, P3_N8, ...) and
//                                           nothing else, printing the steps and the coordinate
//                                           at T, for instruction counts: valgrind
//                                           --tool=callgrind --toggle-collect='run_mujoco*'
//                                           (instructions per step = Ir / steps)
//   bench_mujoco --print-mjcf=ID            the MJCF of one problem
//   --problems=PATH                         problems.json (default: bench/data/ in the repository)
//   --no-contact                            <flag contact="disable"/>: no collision detection
//   --solref=A,B --solimp=A,B,C[,D,E]       the connect constraints' soft settings instead of
//                                           MuJoCo's defaults (0.02,1 and 0.9,0.95,0.001,0.5,2),
//                                           to see how far the results depend on them
//
// Counters: ms_per_sim_s (wall milliseconds per simulated second), max_violation and
// final_violation (distance between the two connect points, from the body poses xpos, xmat that
// mj_forward computes on a copy of the state; 0 for P1), coord_final and coord_error (reported
// coordinate at T and its difference from the reference, rad), rel_drift_max (|E − E0| / |E0|,
// energy measured from V_eq, MuJoCo's potential and kinetic energy), steps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "shared_problems.hpp"

/// One run of the stepping loop: `steps` calls of mj_step from the state in d. Not inlined and
/// outside any namespace, so that `valgrind --tool=callgrind --toggle-collect='run_mujoco*'`
/// counts exactly the loop. Cost: steps × (4 evaluations of MuJoCo's forward dynamics).
__attribute__((noinline)) void run_mujoco(const mjModel* m, mjData* d, long steps) {
  for (long i = 0; i < steps; ++i) mj_step(m, d);
}

namespace {

constexpr double kStep = 1e-3;

using shared_problems::Closure;
using shared_problems::Link;
using shared_problems::Problem;

std::vector<Problem> load(const std::string& path) {
  return shared_problems::load(path, "bench_mujoco");
}

// --- the MJCF --------------------------------------------------------------------------------

// --solref=, --solimp=: the connect constraints' soft settings, MJCF text ("": MuJoCo's defaults,
// which the measurements use; other values only to see how the results depend on them)
std::string g_solref, g_solimp;
// --no-contact: <flag contact="disable"/> in <option> (MuJoCo's harness MJCF of the shared
// problems; without geoms nothing collides, but collision detection still runs: ~2 % of P1)
bool g_no_contact = false;

// shortest text that reads back as the same double
std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// MJCF files: the model first, then the files it includes
struct File {
  std::string name, text;
};

// bodies nested at most this deep in one file: Debian's tinyxml2 (9.0) refuses elements nested
// more than 100 deep, so a longer chain (P3 N = 128) continues in an <include>d file, which is
// parsed on its own and then spliced into the body that includes it
constexpr int kBodiesPerFile = 40;

// link k's body and, nested inside, its children's; depth counts the bodies above it in this file
void write_body(std::ostringstream& x, std::vector<File>& files, const Problem& p, std::size_t k,
                int depth) {
  const Link& l = p.links[k];
  const double turn = l.phi0 - (l.parent < 0 ? 0.0 : p.links[std::size_t(l.parent)].phi0);
  const std::string pad(std::size_t(2 * depth + 4), ' ');
  x << pad << "<body name=\"" << l.name << "\" pos=\"" << num(l.joint[0]) << ' ' << num(l.joint[1])
    << " 0\" quat=\"" << num(std::cos(0.5 * turn)) << " 0 0 " << num(std::sin(0.5 * turn))
    << "\">\n"
    << pad << "  <joint name=\"J" << k << "\" type=\"hinge\" pos=\"0 0 0\" axis=\"0 0 1\"/>\n"
    << pad << "  <inertial pos=\"" << num(l.com_x) << " 0 0\" mass=\"" << num(l.mass)
    << "\" diaginertia=\"" << num(l.I_com[0]) << ' ' << num(l.I_com[1]) << ' ' << num(l.I_com[2])
    << "\"/>\n";
  for (std::size_t c = 0; c < p.links.size(); ++c) {
    if (p.links[c].parent != int(k)) continue;
    if (depth + 1 < kBodiesPerFile) {
      write_body(x, files, p, c, depth + 1);
    } else {
      // the child's subtree in a file of its own
      const std::size_t slot = files.size();
      files.push_back({p.id + "_" + p.links[c].name + ".xml", ""});
      std::ostringstream y;
      y << "<mujoco>\n";
      write_body(y, files, p, c, -1);
      y << "</mujoco>\n";
      files[slot].text = y.str();
      x << pad << "  <include file=\"" << files[slot].name << "\"/>\n";
    }
  }
  x << pad << "</body>\n";
}

std::vector<File> mjcf(const Problem& p) {
  std::vector<File> files = {{p.id + ".xml", ""}};
  std::ostringstream x;
  x << "<mujoco model=\"" << p.id << "\">\n"
    << "  <option integrator=\"RK4\" timestep=\"" << num(kStep) << "\" gravity=\"0 -9.81 0\""
    << (g_no_contact ? ">\n    <flag contact=\"disable\"/>\n  </option>\n" : "/>\n")
    << "  <worldbody>\n";
  for (std::size_t k = 0; k < p.links.size(); ++k) {
    if (p.links[k].parent < 0) write_body(x, files, p, k, 0);
  }
  x << "  </worldbody>\n";
  if (!p.closures.empty()) {
    x << "  <equality>\n";
    for (std::size_t c = 0; c < p.closures.size(); ++c) {
      const Closure& cl = p.closures[c];
      x << "    <connect name=\"closure" << c << "\" body1=\"" << p.links[std::size_t(cl.b1)].name
        << '"';
      if (cl.b2 >= 0) x << " body2=\"" << p.links[std::size_t(cl.b2)].name << '"';
      x << " anchor=\"" << num(cl.p1[0]) << ' ' << num(cl.p1[1]) << " 0\"";
      if (!g_solref.empty()) x << " solref=\"" << g_solref << '"';
      if (!g_solimp.empty()) x << " solimp=\"" << g_solimp << '"';
      x << "/>\n";
    }
    x << "  </equality>\n";
  }
  x << "</mujoco>\n";
  files[0].text = x.str();
  return files;
}

// --- the model -------------------------------------------------------------------------------

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

// compiles the MJCF of p from a virtual file; checks what the compiler made of it: one hinge per
// link, the closures' second anchors equal to p2 (MuJoCo computes them from the initial pose)
ModelPtr compile(const Problem& p) {
  const std::vector<File> files = mjcf(p);
  auto vfs = std::make_unique<mjVFS>();  // 2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  for (const File& f : files) {
    if (mj_makeEmptyFileVFS(vfs.get(), f.name.c_str(), int(f.text.size())) != 0) {
      mj_deleteVFS(vfs.get());
      throw std::runtime_error("bench_mujoco: cannot make the virtual file " + f.name);
    }
    const int i = mj_findFileVFS(vfs.get(), f.name.c_str());
    std::memcpy(vfs->filedata[i], f.text.data(), f.text.size());
  }
  char error[1000] = "";
  ModelPtr m(mj_loadXML(files[0].name.c_str(), vfs.get(), error, int(sizeof error)));
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error("bench_mujoco: " + p.id + ": MuJoCo: " + error);
  if (m->nq != int(p.links.size()) || m->nv != m->nq || m->neq != int(p.closures.size()) ||
      m->ngeom != 0) {
    throw std::runtime_error("bench_mujoco: " + p.id + ": unexpected model sizes");
  }
  if (p.links[0].parent >= 0 || m->jnt_qposadr[mj_name2id(m.get(), mjOBJ_JOINT, "J0")] != 0) {
    throw std::runtime_error("bench_mujoco: " + p.id + ": link 0's hinge is not qpos[0]");
  }
  for (std::size_t c = 0; c < p.closures.size(); ++c) {
    const mjtNum* data = m->eq_data + c * mjNEQDATA;
    const Closure& cl = p.closures[c];
    const double gap = std::hypot(data[3] - cl.p2[0], data[4] - cl.p2[1]) + std::abs(data[5]);
    if (gap > 1e-12) {
      throw std::runtime_error("bench_mujoco: " + p.id + ": closure " + std::to_string(c) +
                               ": MuJoCo's second anchor is " + num(gap) + " m from p2");
    }
  }
  return m;
}

// the reported coordinate: the angle of the first link (P2: the crank), a root link, phi0 + its
// hinge angle (the first joint in the XML: qpos[0])
double coordinate(const Problem& p, const mjData* d) { return p.links[0].phi0 + d->qpos[0]; }

// steps of one run: T / h
long step_count(const Problem& p) { return std::lround(p.T / kStep); }

// one run from the initial state (qpos0 = 0: the model is defined in it; at rest)
void run(const Problem& p, const mjModel* m, mjData* d) {
  mj_resetData(m, d);
  run_mujoco(m, d, step_count(p));
}

// --- the checking run: after every step, the closure gaps and the energy ------------------------

struct Accuracy {
  double max_violation = 0, final_violation = 0;
  double E0 = 0, E_final = 0, rel_drift_final = 0, rel_drift_max = 0;
  double coord_t1 = NAN, coord_final = 0, coord_error = 0;
  long steps = 0;
  bool finite = true;
};

// s, data of e (a copy of the model with MuJoCo's energy computation enabled: 2.2.2's
// mj_energyPos and mj_energyVel do nothing without it), takes the state of d (qpos, qvel); its
// poses and energy are computed there, so the stepping data d is not touched and the checking run
// steps exactly as the timed runs
struct Check {
  double gap = 0, E = 0;
};
Check check(const Problem& p, const mjModel* e, const mjData* d, mjData* s) {
  std::copy(d->qpos, d->qpos + e->nq, s->qpos);
  std::copy(d->qvel, d->qvel + e->nv, s->qvel);
  mj_forward(e, s);
  Check c;
  c.E = s->energy[0] + s->energy[1] - p.V_eq;
  // world point of a point (x, y) of link b's frame: xpos + xmat (x, y, 0)
  const auto world = [&](int b, const Eigen::Vector2d& q, double(&w)[3]) {
    if (b < 0) {
      w[0] = q[0], w[1] = q[1], w[2] = 0.0;
      return;
    }
    // MuJoCo numbers the bodies depth first through the XML: look link b's body up by name
    const int body = mj_name2id(e, mjOBJ_BODY, p.links[std::size_t(b)].name.c_str());
    const mjtNum* x = s->xpos + 3 * body;
    const mjtNum* R = s->xmat + 9 * body;
    for (int r = 0; r < 3; ++r) w[r] = x[r] + R[3 * r] * q[0] + R[3 * r + 1] * q[1];
  };
  for (const Closure& cl : p.closures) {
    double w1[3], w2[3];
    world(cl.b1, cl.p1, w1);
    world(cl.b2, cl.p2, w2);
    c.gap = std::max(
        c.gap, std::sqrt((w1[0] - w2[0]) * (w1[0] - w2[0]) + (w1[1] - w2[1]) * (w1[1] - w2[1]) +
                         (w1[2] - w2[2]) * (w1[2] - w2[2])));
  }
  return c;
}

Accuracy measure_accuracy(const Problem& p, const mjModel* m) {
  const ModelPtr e(mj_copyModel(nullptr, m));
  e->opt.enableflags |= mjENBL_ENERGY;
  DataPtr d(mj_makeData(m)), s(mj_makeData(e.get()));
  mj_resetData(m, d.get());
  Accuracy a;
  a.E0 = check(p, e.get(), d.get(), s.get()).E;
  const long N = step_count(p);
  for (long i = 1; i <= N; ++i) {
    run_mujoco(m, d.get(), 1);
    const Check c = check(p, e.get(), d.get(), s.get());
    a.max_violation = std::max(a.max_violation, c.gap);
    a.rel_drift_max = std::max(a.rel_drift_max, std::abs(c.E - a.E0) / std::abs(a.E0));
    if (i == std::lround(1.0 / kStep)) a.coord_t1 = coordinate(p, d.get());
    if (i == N) {
      a.final_violation = c.gap;
      a.E_final = c.E;
    }
    a.finite = a.finite && std::isfinite(c.E) && std::isfinite(d->qpos[0]);
  }
  a.coord_final = coordinate(p, d.get());
  a.coord_error = a.coord_final - p.reference;
  a.rel_drift_final = (a.E_final - a.E0) / std::abs(a.E0);
  a.steps = N;
  return a;
}

// MuJoCo's warnings of a run (the solver's, the integrator's): "" when there were none
std::string warnings(const mjData* d) {
  std::string w;
  for (int i = 0; i < mjNWARNING; ++i) {
    if (d->warning[i].number > 0) {
      w += (w.empty() ? "" : "; ") + std::string("MuJoCo warning ") + std::to_string(i) + " ×" +
           std::to_string(d->warning[i].number);
    }
  }
  return w;
}

// --- Google Benchmark: the timed loop is one whole run ---------------------------------------

void BM_Problem(benchmark::State& state, const Problem& p) {
  const ModelPtr m = compile(p);
  const DataPtr d(mj_makeData(m.get()));
  double wall = 0.0;  // seconds spent in the runs, summed over the iterations
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    run(p, m.get(), d.get());
    benchmark::DoNotOptimize(d->qpos);
    benchmark::ClobberMemory();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // wall milliseconds per simulated second (each iteration simulates T seconds)
  state.counters["ms_per_sim_s"] = 1e3 * wall / (double(state.iterations()) * p.T);
  const Accuracy a = measure_accuracy(p, m.get());
  state.counters["max_violation"] = a.max_violation;
  state.counters["final_violation"] = a.final_violation;
  state.counters["coord_final"] = a.coord_final;
  state.counters["coord_error"] = a.coord_error;
  state.counters["rel_drift_max"] = a.rel_drift_max;
  state.counters["steps"] = double(a.steps);
  if (!a.finite) state.SkipWithError("the run left the finite numbers");
}

// --- --json=PATH: the record format of bench/data/README.md ----------------------------------

nlohmann::ordered_json record(const Problem& p) {
  const ModelPtr m = compile(p);
  const DataPtr d(mj_makeData(m.get()));

  // one warm-up run, then five timed runs of the stepping loop; median wall time
  std::vector<double> wall, q_first;
  bool deterministic = true;
  for (int r = 0; r < 6; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run(p, m.get(), d.get());
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<double> q_end(d->qpos, d->qpos + m->nq);
    if (r == 0) {
      q_first = q_end;
    } else {
      deterministic = deterministic && q_end == q_first;
      wall.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
  }
  const std::string warned = warnings(d.get());
  std::vector<double> sorted = wall;
  std::sort(sorted.begin(), sorted.end());
  const Accuracy a = measure_accuracy(p, m.get());

  nlohmann::ordered_json r;
  r["engine"] = "MuJoCo " + std::string(mj_versionString());
  r["config"] =
      "Debian's libmujoco 2.2.2; one body per link, hinge joints about z (minimal coordinates), "
      "loop closures as equality connect constraints with default soft settings, no geoms, "
      "RK4";
  r["problem"] = p.id;
  r["integrator"] = "RK4";
  r["h"] = kStep;
  r["T"] = p.T;
  r["nq"] = m->nq;
  r["n_closure_eqs"] = 3 * m->neq;
  r["wall_runs"] = wall;
  r["wall_per_sim_s"] = sorted[sorted.size() / 2] / p.T;
  r["max_violation"] = a.max_violation;
  r["final_violation"] = a.final_violation;
  r["E0"] = a.E0;
  r["E_final"] = a.E_final;
  r["rel_drift_final"] = a.rel_drift_final;
  r["rel_drift_max"] = a.rel_drift_max;
  r["coord_name"] = p.coord_name;
  r["coord_t1"] = a.coord_t1;
  r["coord_final"] = a.coord_final;
  r["steps"] = a.steps;
  r["deterministic"] = deterministic;
  r["extra"] = {
      {"coord_reference", p.reference},
      {"coord_error", a.coord_error},
      {"violation_measure", p.closures.empty()
                                ? "no loop closure (0)"
                                : "distance between the two connect points, from xpos and xmat of "
                                  "the body poses"},
      {"energy", "MuJoCo's energy[0] + energy[1] (mjENBL_ENERGY) - V_eq"},
      {"wall_per_sim_s_min", sorted.front() / p.T},
      {"warnings", warned}};
  // the connect constraints' soft settings (the defaults; none without closures)
  const auto soft = [&](const mjtNum* v, int n) {
    return m->neq > 0 ? nlohmann::json(std::vector<double>(v, v + n)) : nlohmann::json();
  };
  r["settings"] = {{"timestep", m->opt.timestep},
                   {"solver", m->opt.solver == mjSOL_NEWTON ? "Newton"
                              : m->opt.solver == mjSOL_CG   ? "CG"
                                                            : "PGS"},
                   {"iterations", m->opt.iterations},
                   {"tolerance", m->opt.tolerance},
                   {"jacobian", m->opt.jacobian == mjJAC_DENSE    ? "dense"
                                : m->opt.jacobian == mjJAC_SPARSE ? "sparse"
                                                                  : "auto"},
                   {"eq_solref", soft(m->eq_solref, mjNREF)},
                   {"eq_solimp", soft(m->eq_solimp, mjNIMP)},
                   {"samples_timed_runs", "final state only"},
                   {"samples_accuracy_run", "every step"}};
  r["error"] = a.finite ? nlohmann::json() : nlohmann::json("the run left the finite numbers");
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::string json_path, once, print;
  std::string problems = UKDYN_PROBLEMS_JSON;  // bench/data/problems.json of the source tree
  // our flags; the rest goes to Google Benchmark
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--json=", 7) == 0) {
      json_path = argv[i] + 7;
    } else if (std::strncmp(argv[i], "--problems=", 11) == 0) {
      problems = argv[i] + 11;
    } else if (std::strncmp(argv[i], "--once=", 7) == 0) {
      once = argv[i] + 7;
    } else if (std::strncmp(argv[i], "--solref=", 9) == 0) {
      g_solref = argv[i] + 9;
      std::replace(g_solref.begin(), g_solref.end(), ',', ' ');
    } else if (std::strncmp(argv[i], "--solimp=", 9) == 0) {
      g_solimp = argv[i] + 9;
      std::replace(g_solimp.begin(), g_solimp.end(), ',', ' ');
    } else if (std::strcmp(argv[i], "--no-contact") == 0) {
      g_no_contact = true;
    } else if (std::strncmp(argv[i], "--print-mjcf=", 13) == 0) {
      print = argv[i] + 13;
    } else {
      rest.push_back(argv[i]);
    }
  }
  std::vector<Problem> all;
  try {
    all = load(problems);
    if (!once.empty() || !print.empty()) {
      const std::string& id = once.empty() ? print : once;
      const auto p =
          std::find_if(all.begin(), all.end(), [&](const Problem& q) { return q.id == id; });
      if (p == all.end()) {
        std::cerr << "bench_mujoco: no such problem '" << id
                  << "' (P1, P2, P3_N8, P3_N32, P3_N128)\n";
        return 2;
      }
      if (!print.empty()) {
        for (const File& f : mjcf(*p)) std::cout << "<!-- " << f.name << " -->\n" << f.text;
        return 0;
      }
      const ModelPtr m = compile(*p);
      const DataPtr d(mj_makeData(m.get()));
      run(*p, m.get(), d.get());
      std::cout.precision(10);
      std::cout << p->id << ": " << step_count(*p) << " steps, coordinate at T "
                << coordinate(*p, d.get()) << "\n";
      return std::isfinite(d->qpos[0]) ? 0 : 1;
    }
    if (!json_path.empty()) {
      nlohmann::ordered_json records = nlohmann::ordered_json::array();
      for (const Problem& p : all) {
        records.push_back(record(p));
        std::cout << records.back().dump() << std::endl;
      }
      return shared_problems::write_records(json_path, records, "bench_mujoco");
    }
    // compile every model once before timing anything, so that a bad one stops the program
    for (const Problem& p : all) compile(p);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  for (const Problem& p : all) {
    benchmark::RegisterBenchmark((p.id + "/mujoco_rk4").c_str(),
                                 [&p](benchmark::State& s) { BM_Problem(s, p); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinTime(1.0);
  }
  int rest_argc = int(rest.size());
  benchmark::Initialize(&rest_argc, rest.data());
  if (benchmark::ReportUnrecognizedArguments(rest_argc, rest.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
