// SPDX-License-Identifier: BSD-3-Clause
// ukdyn on the shared benchmark problems P1 (double pendulum), P2 (crank-rocker four-bar) and P3
// (closed chain, N = 8, 32, 128) of bench/data/README.md, each built with the
// multibody layer (multibody/multibody.hpp): one planar body (x, y, theta of its centre of mass)
// per link of problems.json, one revolute joint per hinge and per loop closure, gravity (0, −9.81).
// P1's point masses are planar bodies with the stated inertia 1e-9 about their centre (the tip).
// Fixed step h = 1e-3 with RK4 and with RK5 (Dormand–Prince's 5th-order formula at a fixed
// step), projection drift control, the sparse engine (--engine=dense for the dense one).
//
//   bench_multibody_problems [google-benchmark flags]   timing by Google Benchmark; the counters
//                                                       carry the accuracy figures of a
//                                                       separate run
//   bench_multibody_problems --json=PATH                the README's protocol (one warm-up, five
//                                                       timed runs, median; a separate run
//                                                       sampled at every step) written as a JSON
//                                                       array of records
//   --engine=dense|sparse|auto                          the engine (default sparse; auto:
//                                                       Engine::kAuto, what a user gets)
//   --projection-tolerance=TOL                          drift projection tolerance (default
//                                                       1e-10: a tenth of the closure target)
//   --problems=PATH                                     problems.json (default:
//                                                       bench/data/ in the repository)
//   --once=ID/rk4|rk5                                   one run of the timed loop (e.g. P1/rk4)
//                                                       and nothing else, for instruction
//                                                       counts: valgrind --tool=callgrind
//                                                       --toggle-collect='ukdyn::simulate(*'
//                                                       (instructions per step = Ir / steps)
//
// Counters: ms_per_sim_s (wall milliseconds per simulated second), max_violation and
// final_violation (distance between the two loop-closure points from the body poses,
// world_point; 0 for P1, which has no loop), max_joint_gap (the same for every joint),
// coord_final and coord_error (reported coordinate at T and its difference from the reference,
// rad), rel_drift_max (|E − E0| / E0, energy measured from V_eq), steps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "shared_problems.hpp"
#include "shared_protocol.hpp"

#include <ukdyn/multibody/multibody.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

namespace mb = ukdyn::mb;
using Eigen::Vector3d;
using ukdyn::Index;
using ukdyn::VectorXd;

constexpr double kStep = 1e-3;

using shared_problems::Closure;
using shared_problems::Link;
using shared_problems::Problem;

// the shared problems, and P1 a second time, its point masses as particles (x, y, z) held by
// distance joints (the massless rods) instead of planar bodies with inertia 1e-9 and revolute
// joints
std::vector<Problem> load(const std::string& path) {
  std::vector<Problem> out;
  for (Problem& r : shared_problems::load(path, "bench_multibody_problems")) {
    out.push_back(r);
    if (r.id == "P1") {
      r.particles = true;
      out.push_back(r);
    }
  }
  return out;
}

// a point given in link k's frame (origin at the proximal hinge, x along the link), as a point
// of its body (origin at the centre of mass, same axes)
Vector3d body_point(const Link& k, const Eigen::Vector2d& p) { return {p.x() - k.com_x, p.y(), 0}; }

// P1 with particles: the point mass of link k (at its tip, com_x = length) is particle k, tied
// to the previous one (the ground pivot for link 0) by a distance joint "J<k>" of the link's length
mb::MultibodyModel build_particles(const Problem& p) {
  mb::Multibody b;
  b.set_gravity({0.0, -9.81, 0.0});
  Eigen::Vector2d tip(0.0, 0.0);
  for (std::size_t k = 0; k < p.links.size(); ++k) {
    const Link& l = p.links[k];
    if (l.com_x != l.length || l.parent != int(k) - 1 ||
        (l.parent >= 0 && l.joint.x() != p.links[k - 1].length)) {
      throw std::invalid_argument(
          "bench_multibody_problems: particles need a chain of point "
          "masses at the links' tips (P1)");
    }
    const Eigen::Vector2d hinge = l.parent < 0 ? l.joint : tip;
    tip = hinge + l.length * Eigen::Vector2d(std::cos(l.phi0), std::sin(l.phi0));
    b.add_particle(l.name, l.mass, Vector3d(tip.x(), tip.y(), 0.0));
    b.add_joint(mb::distance("J" + std::to_string(k), l.parent < 0 ? mb::kGround : l.parent,
                             Vector3d(hinge.x(), hinge.y(), 0.0) * (l.parent < 0 ? 1.0 : 0.0),
                             Index(k), Vector3d::Zero(), l.length));
  }
  return b.build();
}

// the model: link k is body k, posed from the link angles (each hinge placed from its parent's),
// at rest; joints "J<k>" at the hinges and "closure<c>" at the loop closures
mb::MultibodyModel build(const Problem& p) {
  mb::Multibody b;
  b.set_gravity({0.0, -9.81, 0.0});
  std::vector<Eigen::Vector2d> hinge(p.links.size());  // proximal hinge of each link (world)
  if (p.particles) return build_particles(p);
  for (std::size_t k = 0; k < p.links.size(); ++k) {
    const Link& l = p.links[k];
    const Eigen::Vector2d u(std::cos(l.phi0), std::sin(l.phi0));
    if (l.parent < 0) {
      hinge[k] = l.joint;
    } else {
      const Link& P = p.links[std::size_t(l.parent)];
      const Eigen::Vector2d up(std::cos(P.phi0), std::sin(P.phi0)), vp(-up.y(), up.x());
      hinge[k] = hinge[std::size_t(l.parent)] + l.joint.x() * up + l.joint.y() * vp;
    }
    const Eigen::Vector2d com = hinge[k] + l.com_x * u;
    b.add_planar_body(l.name, l.mass, l.I_com.z(), Vector3d(com.x(), com.y(), l.phi0));
  }
  for (std::size_t k = 0; k < p.links.size(); ++k) {
    const Link& l = p.links[k];
    const mb::Frame child = mb::Frame::planar(-l.com_x, 0.0);
    if (l.parent < 0) {
      b.add_joint(mb::revolute("J" + std::to_string(k), mb::kGround,
                               mb::Frame::planar(l.joint.x(), l.joint.y()), Index(k), child));
    } else {
      const Vector3d s = body_point(p.links[std::size_t(l.parent)], l.joint);
      b.add_joint(mb::revolute("J" + std::to_string(k), Index(l.parent),
                               mb::Frame::planar(s.x(), s.y()), Index(k), child));
    }
  }
  for (std::size_t c = 0; c < p.closures.size(); ++c) {
    const Closure& cl = p.closures[c];
    const Vector3d s1 = body_point(p.links[std::size_t(cl.b1)], cl.p1);
    const mb::Frame f2 = cl.b2 < 0 ? mb::Frame::planar(cl.p2.x(), cl.p2.y()) : [&] {
      const Vector3d s2 = body_point(p.links[std::size_t(cl.b2)], cl.p2);
      return mb::Frame::planar(s2.x(), s2.y());
    }();
    b.add_joint(mb::revolute("closure" + std::to_string(c), cl.b2 < 0 ? mb::kGround : cl.b2, f2,
                             cl.b1, mb::Frame::planar(s1.x(), s1.y())));
  }
  return b.build();
}

// a body point in the world (the ground: the point itself)
Vector3d world(const mb::MultibodyModel& m, const Eigen::Ref<const VectorXd>& q, mb::BodyId b,
               const Vector3d& p) {
  return b == mb::kGround ? p : mb::world_point(m, q, b, p);
}

// the largest distance between the two closure points, from the body poses (0 without loops)
double closure_gap(const Problem& p, const mb::MultibodyModel& m,
                   const Eigen::Ref<const VectorXd>& q) {
  double gap = 0.0;
  for (const Closure& c : p.closures) {
    const Vector3d x1 = world(m, q, c.b1, body_point(p.links[std::size_t(c.b1)], c.p1));
    const Vector3d x2 = c.b2 < 0 ? Vector3d(c.p2.x(), c.p2.y(), 0.0)
                                 : world(m, q, c.b2, body_point(p.links[std::size_t(c.b2)], c.p2));
    gap = std::max(gap, (x1 - x2).norm());
  }
  return gap;
}

// the largest distance between the two frames of any revolute joint (hinges and closures), or
// for particles the largest error of a rod's length, | |x_k − x_hinge| − L_k |
double joint_gap(const Problem& p, const mb::MultibodyModel& m,
                 const Eigen::Ref<const VectorXd>& q) {
  double gap = 0.0;
  for (std::size_t k = 0; k < m.joints.size(); ++k) {
    const mb::JointInfo& j = m.joints[k];
    const double d =
        (world(m, q, j.parent, j.frame_parent.p) - world(m, q, j.child, j.frame_child.p)).norm();
    gap = std::max(gap, p.particles ? std::abs(d - p.links[k].length) : d);
  }
  return gap;
}

// the reported coordinate: the angle of link 1 (P2: the crank), theta of its body, or for
// particles the direction from the ground pivot to the first particle
double coordinate(const Problem& p, const mb::MultibodyModel& m,
                  const Eigen::Ref<const VectorXd>& q) {
  const Index o = m.bodies[0].offset;
  if (!p.particles) return q[o + 2];
  return std::atan2(q[o + 1] - p.links[0].joint.y(), q[o] - p.links[0].joint.x());
}

// --- runs -----------------------------------------------------------------------------------

struct Config {
  ukdyn::Integrator integrator = ukdyn::Integrator::kRK4;
};

// --engine=dense|sparse (default sparse: block-diagonal M and joints with local columns; it is
// the faster one here even for P1 and P2, n = 6 and 9, where Engine::kAuto would pick the dense
// one: RK4, ms per simulated second, sparse against dense, P1 3.1 / 3.7, P2 5.6 / 8.7,
// P3 N = 8 14.8 / 34.2)
std::string g_engine = "sparse";
double g_projection_tolerance =
    1e-10;  // --projection-tolerance= (joints held to 1e-10 m, under the 1e-9 target)

ukdyn::Engine engine_for(const mb::MultibodyModel&) {
  if (g_engine == "auto") return ukdyn::Engine::kAuto;
  return g_engine == "dense" ? ukdyn::Engine::kDense : ukdyn::Engine::kSparse;
}

// fixed step h = 1e-3 over T, projection drift control; samples every `every` s (0: 0 and T)
ukdyn::SimulationOptions options(const mb::MultibodyModel& m, ukdyn::Integrator method, double T,
                                 double every) {
  ukdyn::SimulationOptions o;
  o.t_end = T;
  o.integrator = method;
  o.step = kStep;
  o.output_every = every;
  o.drift = ukdyn::DriftControl::kProjection;
  o.solver.engine = engine_for(m);
  o.projection.tolerance = g_projection_tolerance;
  return o;
}

// the accuracy figures of one run sampled at every step
struct Accuracy {
  double max_violation = 0, final_violation = 0, max_joint_gap = 0;
  double E0 = 0, E_final = 0, rel_drift_final = 0, rel_drift_max = 0;
  double coord_t1 = NAN, coord_final = 0, coord_error = 0;
  double max_phi = 0;  // largest constraint residual of any joint (simulate's own measure)
  long steps = 0, evaluations = 0, projections = 0;
  std::string error;    // "" when the run finished
  std::string warning;  // the energy-balance warning of a finished run (Status::kEnergyBalance)
};

Accuracy measure_accuracy(const Problem& p, const mb::MultibodyModel& m, ukdyn::Integrator method) {
  const ukdyn::Trajectory tr =
      ukdyn::simulate(m.system, m.q0, m.qd0, options(m, method, p.T, kStep));
  Accuracy a;
  const Index n = tr.n, N = tr.samples();
  a.E0 = tr.energy.front() - p.V_eq;
  for (Index i = 0; i < N; ++i) {
    const VectorXd q = Eigen::Map<const VectorXd>(tr.q.data() + i * n, n);
    const double gap = closure_gap(p, m, q);
    a.max_violation = std::max(a.max_violation, gap);
    if (i == N - 1) a.final_violation = gap;
    a.max_joint_gap = std::max(a.max_joint_gap, joint_gap(p, m, q));
    const double E = tr.energy[std::size_t(i)] - p.V_eq;
    a.rel_drift_max = std::max(a.rel_drift_max, std::abs(E - a.E0) / std::abs(a.E0));
    if (std::abs(tr.t[std::size_t(i)] - 1.0) < 0.5 * kStep) a.coord_t1 = coordinate(p, m, q);
    if (i == N - 1) a.coord_final = coordinate(p, m, q);
  }
  a.E_final = tr.energy.back() - p.V_eq;
  a.rel_drift_final = (a.E_final - a.E0) / std::abs(a.E0);
  a.coord_error = a.coord_final - p.reference;
  a.max_phi = tr.stats.max_position_violation;
  a.steps = tr.stats.steps;
  a.evaluations = tr.stats.evaluations;
  a.projections = tr.stats.projections;
  // a finished run may warn that its energy balance exceeds the tolerance (energy gained or lost
  // that no work channel accounts for: the integration error of the fixed step): kept as a
  // warning, not an error
  if (tr.stats.status == ukdyn::Status::kEnergyBalance) a.warning = tr.stats.message;
  if ((tr.stats.status != ukdyn::Status::kOk && tr.stats.status != ukdyn::Status::kEnergyBalance) ||
      std::abs(tr.t.back() - p.T) > 1e-9) {
    a.error = tr.stats.message.empty() ? "run stopped at t = " + std::to_string(tr.t.back())
                                       : tr.stats.message;
  }
  return a;
}

// --- Google Benchmark: the timed loop is one whole run with samples at t = 0 and T only --------

void BM_Problem(benchmark::State& state, const Problem& p, ukdyn::Integrator method) {
  const mb::MultibodyModel m = build(p);
  const ukdyn::SimulationOptions opt = options(m, method, p.T, 0.0);
  double wall = 0.0;  // seconds spent in simulate(), summed over the iterations
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    ukdyn::Trajectory tr = ukdyn::simulate(m.system, m.q0, m.qd0, opt);
    benchmark::DoNotOptimize(tr.q.data());
    benchmark::ClobberMemory();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // wall milliseconds per simulated second (each iteration simulates T seconds)
  state.counters["ms_per_sim_s"] = 1e3 * wall / (double(state.iterations()) * p.T);
  const Accuracy a = measure_accuracy(p, m, method);
  state.counters["max_violation"] = a.max_violation;
  state.counters["final_violation"] = a.final_violation;
  state.counters["max_joint_gap"] = a.max_joint_gap;
  state.counters["coord_final"] = a.coord_final;
  state.counters["coord_error"] = a.coord_error;
  state.counters["rel_drift_max"] = a.rel_drift_max;
  state.counters["steps"] = double(a.steps);
  state.counters["energy_balance_warning"] = a.warning.empty() ? 0.0 : 1.0;
  if (!a.error.empty()) state.SkipWithError(a.error.c_str());
}

// --- --json=PATH: the record format of bench/data/README.md ----------------------------------

nlohmann::ordered_json record(const Problem& p, ukdyn::Integrator method) {
  const mb::MultibodyModel m = build(p);
  const ukdyn::SimulationOptions opt = options(m, method, p.T, 0.0);

  // one warm-up run, then five timed runs of the stepping loop; median wall time
  const ukdyn::bench::TimedRuns timed = ukdyn::bench::time_runs(m.system, m.q0, m.qd0, opt);
  const std::vector<double>& wall = timed.wall;
  const bool deterministic = timed.deterministic;
  const Accuracy a = measure_accuracy(p, m, method);

  const bool sparse = ukdyn::Workspace(m.system, opt.solver).is_sparse();  // (kAuto decides)
  const std::string integrator = ukdyn::to_string(method);
  const auto number = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  };
  nlohmann::ordered_json r;
  r["engine"] = "ukdyn";
  r["config"] =
      std::string(
          p.particles
              ? "multibody/multibody.hpp: particles (x, y, z) and distance joints (the massless "
                "rods), "
              : "multibody/multibody.hpp: planar bodies (x, y, theta) and revolute joints, ") +
      (sparse ? "sparse engine (block Cholesky of M, rank-revealing sparse LDL' of A M^-1 A')"
              : "dense engine (Cholesky of M + complete orthogonal decomposition)") +
      ", projection drift control, " +
      (method == ukdyn::Integrator::kRK4
           ? "RK4"
           : "RK5 (Dormand-Prince 5th-order formula at a fixed step)");
  r["problem"] = p.id;
  r["integrator"] = integrator;
  r["h"] = kStep;
  r["T"] = p.T;
  r["nq"] = m.system.coordinate_count();
  r["n_closure_eqs"] = m.system.constraint_rows();
  r["wall_runs"] = wall;
  r["wall_per_sim_s"] = timed.median() / p.T;
  r["max_violation"] = a.max_violation;
  r["final_violation"] = a.final_violation;
  r["E0"] = a.E0;
  r["E_final"] = a.E_final;
  r["rel_drift_final"] = a.rel_drift_final;
  r["rel_drift_max"] = a.rel_drift_max;
  r["coord_name"] = p.coord_name;
  r["coord_t1"] = number(a.coord_t1);
  r["coord_final"] = a.coord_final;
  r["steps"] = a.steps;
  r["deterministic"] = deterministic;
  r["extra"] = {
      {"coord_reference", p.reference},
      {"coord_error", a.coord_error},
      {"max_joint_gap", a.max_joint_gap},
      {"max_constraint_violation", a.max_phi},
      {"violation_measure",
       p.particles ? "no loop closure (0); max_joint_gap: largest error of a rod's length, "
                     "from the particles' positions"
       : p.closures.empty()
           ? "no loop closure (0); max_joint_gap: largest distance between the two frames of "
             "any revolute joint, from world_point of the body poses"
           : "distance between the two closure points, world_point of the body poses"},
      {"bodies", m.bodies.size()},
      {"point_masses", p.id != "P1"  ? "none"
                       : p.particles ? "particles"
                                     : "planar bodies with the stated inertia 1e-9 kg m^2 "
                                       "about the tip"},
      {"evaluations", a.evaluations},
      {"projections", a.projections},
      {"wall_per_sim_s_min", *std::min_element(wall.begin(), wall.end()) / p.T},
      {"warnings", a.warning}};
  r["settings"] = {{"drift", "projection"},
                   {"projection_tolerance", opt.projection.tolerance},
                   {"projection_max_iterations", opt.projection.max_iterations},
                   {"engine", sparse ? "sparse" : "dense"},
                   {"rank_threshold", opt.solver.rank_threshold},
                   {"samples_timed_runs", "t = 0 and T only"},
                   {"samples_accuracy_run", "every step"}};
  r["error"] = a.error.empty() ? nlohmann::json() : nlohmann::json(a.error);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::string json_path, once;
  std::string problems =
      (std::filesystem::path(__FILE__).parent_path() / "data/problems.json").string();
  // our flags; the rest goes to Google Benchmark
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--json=", 7) == 0) {
      json_path = argv[i] + 7;
    } else if (std::strncmp(argv[i], "--engine=", 9) == 0) {
      g_engine = argv[i] + 9;
      if (g_engine != "dense" && g_engine != "sparse" && g_engine != "auto") {
        std::cerr << "bench_multibody_problems: --engine=dense, sparse or auto\n";
        return 2;
      }
    } else if (std::strncmp(argv[i], "--projection-tolerance=", 23) == 0) {
      g_projection_tolerance = std::atof(argv[i] + 23);
    } else if (std::strncmp(argv[i], "--problems=", 11) == 0) {
      problems = argv[i] + 11;
    } else if (std::strncmp(argv[i], "--once=", 7) == 0) {
      once = argv[i] + 7;
    } else {
      rest.push_back(argv[i]);
    }
  }
  std::vector<Problem> all;
  try {
    all = load(problems);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  const ukdyn::Integrator methods[] = {ukdyn::Integrator::kRK4, ukdyn::Integrator::kRK5};
  if (!once.empty()) {
    for (const Problem& p : all) {
      for (ukdyn::Integrator method : methods) {
        const std::string id = p.id + (p.particles ? "_particles" : "") +
                               (method == ukdyn::Integrator::kRK4 ? "/rk4" : "/rk5");
        if (id != once) continue;
        const mb::MultibodyModel m = build(p);
        const ukdyn::Trajectory tr =
            ukdyn::simulate(m.system, m.q0, m.qd0, options(m, method, p.T, 0.0));
        std::cout << id << ": " << tr.stats.steps << " steps, " << tr.stats.evaluations
                  << " evaluations, " << tr.stats.projections << " projections, coordinate at T "
                  << coordinate(
                         p, m,
                         Eigen::Map<const VectorXd>(tr.q.data() + (tr.samples() - 1) * tr.n, tr.n))
                  << "\n";
        return tr.stats.status == ukdyn::Status::kOk ||
                       tr.stats.status == ukdyn::Status::kEnergyBalance
                   ? 0
                   : 1;
      }
    }
    std::cerr << "bench_multibody_problems: --once=" << once
              << ": no such problem (P1, P1_particles, P2, P3_N8, ... with /rk4 or /rk5)\n";
    return 2;
  }
  if (!json_path.empty()) {
    nlohmann::ordered_json records = nlohmann::ordered_json::array();
    for (const Problem& p : all) {
      for (ukdyn::Integrator method : methods) {
        records.push_back(record(p, method));
        std::cout << records.back().dump() << std::endl;
      }
    }
    return shared_problems::write_records(json_path, records, "bench_multibody_problems");
  }
  for (const Problem& p : all) {
    for (ukdyn::Integrator method : methods) {
      const std::string name =
          p.id + (p.particles ? "_particles/" : "/") + ukdyn::to_string(method);
      benchmark::RegisterBenchmark(name.c_str(),
                                   [&p, method](benchmark::State& s) { BM_Problem(s, p, method); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(1.0);
    }
  }
  int rest_argc = int(rest.size());
  benchmark::Initialize(&rest_argc, rest.data());
  if (benchmark::ReportUnrecognizedArguments(rest_argc, rest.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
