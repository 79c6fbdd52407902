// SPDX-License-Identifier: BSD-3-Clause
// A contact side by side with MuJoCo (issue #31 item 4; docs/contact.md, "Beside MuJoCo"): the
// rough incline of tests/contact/incline_mujoco.hpp (the model of
// ContactFriction.BlockSlidesOnARoughInclineThenLiftsOff, where ukdyn's run meets the closed form
// to 1e-8) in ukdyn and in MuJoCo from the same state, MuJoCo with solref (tc, 1) for tc = 0.02
// (the default), 0.01 and 0.005 at step h.
// Printed: the slide s along the slope at t = 1, 2, 3, 4 s and the normal offset n at t* + 1
// from each, their differences, the largest |Δs + mu n_MuJoCo| over those times (0 when MuJoCo's
// friction is mu times its normal force at every step: m Δs'' = −mu m n'' while it slides), the
// share of MuJoCo's steps with a contact before t*, and its last step with one. A measurement, not
// a benchmark of speed (bench/RESULTS.md, "A contact beside MuJoCo").
//
//   bench_contact_mujoco [h [Euler|RK4]]      (default 1e-4 Euler)
#include <cstdio>
#include <cstdlib>

#include "contact/incline_mujoco.hpp"

using namespace ukdyn::incline_mujoco;

int main(int argc, char** argv) {
  const double h = argc > 1 ? std::atof(argv[1]) : 1e-4;
  const char* integrator = argc > 2 ? argv[2] : "Euler";
  const InclineRun u = run_ukdyn();
  std::printf("ukdyn: t* = %.6f s; s(1, 2, 3, 4 s) =", kTStar);
  for (double s : u.s) std::printf(" %.6f", s);
  std::printf(" m; n(t* + 1) = %.6f m (closed form k/(6m) = %.6f)\n", u.n_after, kK / (6 * kM));
  std::printf("MuJoCo %d, %s h = %g:\n", mj_version(), integrator, h);
  std::printf("%8s %12s %12s %12s %12s %14s %12s %12s %14s\n", "solref", "ds(1)", "ds(2)", "ds(3)",
              "ds(4)", "dn(t*+1)", "in contact", "last one", "max|ds+mu n|");
  for (double tc : {0.02, 0.01, 0.005}) {
    const InclineRun r = run_mujoco(tc, h, integrator);
    if (r.s.size() != u.s.size()) return 1;
    std::printf("%8g", tc);
    for (std::size_t i = 0; i < u.s.size(); ++i) std::printf(" %12.3e", r.s[i] - u.s[i]);
    // sliding, m Δs'' = −mu (N_mujoco − N) = −mu m n'': Δs = −mu n when MuJoCo's friction is
    // mu N_mujoco at every step
    double identity = 0.0;
    for (std::size_t i = 0; i < u.s.size(); ++i)
      identity = std::max(identity, std::abs(r.s[i] - u.s[i] + kMu * r.n[i]));
    std::printf(" %14.3e %11.1f%% %12.4f %14.3e\n", r.n_after - u.n_after, 100 * r.contact_share,
                r.last_contact, identity);
  }
  return 0;
}
