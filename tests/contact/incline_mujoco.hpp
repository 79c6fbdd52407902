// SPDX-License-Identifier: BSD-3-Clause
// The rough incline run by ukdyn and by MuJoCo from the same state (issue #31 item 4;
// docs/contact.md, "Beside MuJoCo"), shared by tests/contact/test_contact_mujoco.cpp and
// bench/bench_contact_mujoco.cpp: a block (m = 2) on an incline (alpha = 0.5, mu = 0.3) launched
// down the slope at v0 = 1 and pulled along the normal by F = k t (k = 4), which slides with
// friction mu N until N = m g cos alpha − k t reaches zero at t* = 4.3045 s and then flies.
//   * ukdyn: the model file below, a rigid unilateral contact with Coulomb friction;
//   * MuJoCo 2.x: a sphere (r = 0.05, mass 2) on two slide joints (x, z) against a plane turned by
//     alpha about y, condim 3, elliptic cone, the force k t n̂ at each step's midpoint, at step h
//     with the integrator named, solref (tc, 1) and the default solimp (0.9 0.95 0.001).
#pragma once

#include <mujoco/mujoco.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "contact/incline_model.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::incline_mujoco {

constexpr double kM = 2.0, kG = 9.81, kAlpha = 0.5, kMu = 0.3, kK = 4.0, kV0 = 1.0, kR = 0.05;
inline const double kTStar = kM * kG * std::cos(kAlpha) / kK;
inline const std::vector<double> kTimes = {1.0, 2.0, 3.0, 4.0};

inline const std::string kIncline =
    std::string(incline::kModel) +
    "simulate: {t_end: 5.3045, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n";

struct InclineRun {
  std::vector<double> s;  // the slide at kTimes
  std::vector<double> n;  // the normal offset at kTimes
  double n_after = NAN;   // the normal offset at t* + 1
  double contact_share = NAN, last_contact = NAN;
};

// ukdyn: the model file with samples at kTimes and t* + 1
inline InclineRun run_ukdyn() {
  ukdyn::Model model = ukdyn::parse_model(kIncline);
  model.options.output_every = 0.0;
  model.options.output_at = kTimes;
  model.options.output_at.push_back(kTStar + 1.0);
  model.options.t_end = kTStar + 1.0;
  const ukdyn::Trajectory tr = ukdyn::simulate(model.system, model.q0, model.qd0, model.options);
  InclineRun r;
  const double ca = std::cos(kAlpha), sa = std::sin(kAlpha);
  for (double t : kTimes) {
    for (std::size_t i = 0; i < tr.t.size(); ++i)
      if (std::abs(tr.t[i] - t) < 1e-12) r.s.push_back(tr.q[2 * i] * ca - tr.q[2 * i + 1] * sa);
  }
  const std::size_t last = tr.t.size() - 1;
  r.n_after = tr.q[2 * last] * sa + tr.q[2 * last + 1] * ca;
  return r;
}

// MuJoCo with solref (tc, 1) at step h
inline InclineRun run_mujoco(double tc, double h, const char* integrator) {
  const double ca = std::cos(kAlpha), sa = std::sin(kAlpha);
  char xml[2000];
  std::snprintf(xml, sizeof xml,
                "<mujoco><compiler angle='radian'/>"
                "<option timestep='%.17g' gravity='0 0 -9.81' cone='elliptic' integrator='%s'/>"
                "<worldbody>"
                "<geom type='plane' size='100 100 0.1' euler='0 %.17g 0' friction='%.17g 0 0' "
                "solref='%.17g 1'/>"
                "<body pos='%.17g 0 %.17g'><joint type='slide' axis='1 0 0'/>"
                "<joint type='slide' axis='0 0 1'/><geom type='sphere' size='%.17g' "
                "mass='%.17g' friction='%.17g 0 0' condim='3' solref='%.17g 1'/></body>"
                "</worldbody></mujoco>",
                h, integrator, kAlpha, kMu, tc, kR * sa, kR * ca, kR, kM, kMu, tc);
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      ("ukdyn_contact_mujoco_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(file) << xml;
  char error[1000] = "";
  mjModel* m = mj_loadXML(file.string().c_str(), nullptr, error, int(sizeof error));
  std::filesystem::remove(file);
  InclineRun r;
  if (!m) {
    std::fprintf(stderr, "MuJoCo: %s\n", error);
    return r;
  }
  mjData* d = mj_makeData(m);
  d->qvel[0] = kV0 * ca;
  d->qvel[1] = -kV0 * sa;
  const long steps = std::lround((kTStar + 1.0) / h);
  long in_contact = 0, before = 0;
  std::size_t next = 0;
  for (long i = 1; i <= steps; ++i) {
    // the pull at the step's midpoint, on the block (body 1)
    const double t = d->time + 0.5 * h;
    d->xfrc_applied[6 + 0] = kK * t * sa;
    d->xfrc_applied[6 + 2] = kK * t * ca;
    mj_step(m, d);
    const double s = d->qpos[0] * ca - d->qpos[1] * sa, n = d->qpos[0] * sa + d->qpos[1] * ca;
    if (d->ncon > 0) r.last_contact = d->time;
    if (d->time <= kTStar) {
      ++before;
      in_contact += d->ncon > 0 ? 1 : 0;
    }
    if (next < kTimes.size() && std::abs(d->time - kTimes[next]) < 0.5 * h) {
      r.s.push_back(s);
      r.n.push_back(n);
      ++next;
    }
    if (i == steps) r.n_after = n;
  }
  r.contact_share = double(in_contact) / double(before);
  mj_deleteData(d);
  mj_deleteModel(m);
  return r;
}

}  // namespace ukdyn::incline_mujoco
