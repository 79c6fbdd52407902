// SPDX-License-Identifier: BSD-3-Clause
// A contact side by side with MuJoCo (issue #31 item 4; docs/contact.md, "Beside MuJoCo"): a block
// on a rough incline (alpha = 0.5, mu = 0.3, m = 2) launched down the slope at v0 = 1 and pulled
// along the normal by F = k t (k = 4), which slides with friction mu N until N = m g cos alpha − k
// t reaches zero at t* = 4.3045 s and then flies (the model of
// ContactFriction.BlockSlidesOnARoughInclineThenLiftsOff, where ukdyn's run meets the closed form
// to 1e-8). Both start from the same state:
//   * ukdyn: the model file below, a rigid unilateral contact with Coulomb friction;
//   * MuJoCo (Debian's 2.2.2): a sphere (r = 0.05, mass 2) on two slide joints (x, z) against a
//     plane turned by alpha about y, condim 3, elliptic cone, the force k t n̂ at each step's
//     midpoint, Euler at h, with solref (tc, 1) for tc = 0.02 (the default), 0.01, 0.005 and
//     the default solimp (0.9 0.95 0.001).
// Printed: the slide s along the slope at t = 1, 2, 3, 4 s and the normal offset n at t* + 1
// from each, their differences, the share of MuJoCo's steps with a contact before t*, and its
// last step with one. A measurement, not a benchmark of speed (bench/RESULTS.md, "A contact
// beside MuJoCo").
//
//   bench_contact_mujoco [h]      (default h = 1e-4)
#include <mujoco/mujoco.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace {

constexpr double kM = 2.0, kG = 9.81, kAlpha = 0.5, kMu = 0.3, kK = 4.0, kV0 = 1.0, kR = 0.05;
const double kTStar = kM * kG * std::cos(kAlpha) / kK;
const std::vector<double> kTimes = {1.0, 2.0, 3.0, 4.0};

constexpr const char* kIncline = R"(
parameters: {m: 2, g: 9.81, alpha: 0.5, mu: 0.3, k: 4, v0: 1}
coordinates: [x, y]
mass_matrix: [[m, 0], [0, m]]
forces: [k*t*sin(alpha), k*t*cos(alpha) - m*g]
constraints:
  - {name: plane, holonomic: x*sin(alpha) + y*cos(alpha), unilateral: true}
nonideal:
  - {friction: coulomb, constraint: plane, mu: mu}
initial:
  q: {x: 0, y: 0}
  q_dot: {x: v0*cos(alpha), y: -v0*sin(alpha)}
simulate: {t_end: 5.3045, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
)";

struct Run {
  std::vector<double> s;  // the slide at kTimes
  double n_after = NAN;   // the normal offset at t* + 1
  double contact_share = NAN, last_contact = NAN;
};

// ukdyn: the model file with samples at kTimes and t* + 1
Run run_ukdyn() {
  ukdyn::Model model = ukdyn::parse_model(kIncline);
  model.options.output_every = 0.0;
  model.options.output_at = kTimes;
  model.options.output_at.push_back(kTStar + 1.0);
  model.options.t_end = kTStar + 1.0;
  const ukdyn::Trajectory tr = ukdyn::simulate(model.system, model.q0, model.qd0, model.options);
  Run r;
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
Run run_mujoco(double tc, double h) {
  const double ca = std::cos(kAlpha), sa = std::sin(kAlpha);
  char xml[2000];
  std::snprintf(xml, sizeof xml,
                "<mujoco><compiler angle='radian'/>"
                "<option timestep='%.17g' gravity='0 0 -9.81' cone='elliptic'/><worldbody>"
                "<geom type='plane' size='100 100 0.1' euler='0 %.17g 0' friction='%.17g 0 0' "
                "solref='%.17g 1'/>"
                "<body pos='%.17g 0 %.17g'><joint type='slide' axis='1 0 0'/>"
                "<joint type='slide' axis='0 0 1'/><geom type='sphere' size='%.17g' "
                "mass='%.17g' friction='%.17g 0 0' condim='3' solref='%.17g 1'/></body>"
                "</worldbody></mujoco>",
                h, kAlpha, kMu, tc, kR * sa, kR * ca, kR, kM, kMu, tc);
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      ("ukdyn_contact_mujoco_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(file) << xml;
  char error[1000] = "";
  mjModel* m = mj_loadXML(file.string().c_str(), nullptr, error, int(sizeof error));
  std::filesystem::remove(file);
  Run r;
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
      ++next;
    }
    if (i == steps) r.n_after = n;
  }
  r.contact_share = double(in_contact) / double(before);
  mj_deleteData(d);
  mj_deleteModel(m);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const double h = argc > 1 ? std::atof(argv[1]) : 1e-4;
  const Run u = run_ukdyn();
  std::printf("ukdyn: t* = %.6f s; s(1, 2, 3, 4 s) =", kTStar);
  for (double s : u.s) std::printf(" %.6f", s);
  std::printf(" m; n(t* + 1) = %.6f m (closed form k/(6m) = %.6f)\n", u.n_after, kK / (6 * kM));
  std::printf("MuJoCo %d, Euler h = %g:\n", mj_version(), h);
  std::printf("%8s %12s %12s %12s %12s %14s %12s %12s\n", "solref", "ds(1)", "ds(2)", "ds(3)",
              "ds(4)", "dn(t*+1)", "in contact", "last one");
  for (double tc : {0.02, 0.01, 0.005}) {
    const Run r = run_mujoco(tc, h);
    if (r.s.size() != u.s.size()) return 1;
    std::printf("%8g", tc);
    for (std::size_t i = 0; i < u.s.size(); ++i) std::printf(" %12.3e", r.s[i] - u.s[i]);
    std::printf(" %14.3e %11.1f%% %12.4f\n", r.n_after - u.n_after, 100 * r.contact_share,
                r.last_contact);
  }
  return 0;
}
