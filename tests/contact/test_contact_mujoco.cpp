// SPDX-License-Identifier: BSD-3-Clause
// A rough contact beside MuJoCo's soft one (issue #31 item 4; docs/contact.md, "Beside MuJoCo"):
// the incline of contact/incline_mujoco.hpp, run by ukdyn (rigid contact, Coulomb friction) and
// by MuJoCo (a sphere against a tilted plane, elliptic cone, RK4 at h = 1e-4) from the same state.
//
// While the block slides down, both apply the same gravity and pull and differ in the normal
// force only, and each applies friction mu times its own normal force against the same sliding
// direction. Across the slope ukdyn's block stays on the plane (n ≡ 0) and MuJoCo's moves by
// m n'' = N_MuJoCo − N; along it m Δs'' = −mu (N_MuJoCo − N) = −mu m n''. From the same state:
//     Δs(t) = −mu n_MuJoCo(t)     at every instant, whatever solref and solimp make of N_MuJoCo,
// so the whole difference of the slides is mu times how far MuJoCo's soft contact lets the block
// off the plane — the difference that solref and solimp allow. RK4 keeps the identity to its
// truncation error (2e-9 m measured); Euler, MuJoCo's default, breaks it by 0.66 h m (its O(h)
// error, bench/RESULTS.md). The offset itself: its contact holds the block within 1e-3 m of the
// plane while it slides (8e-4 measured at t = 4 s, tc = 0.005), neither sinking nor flying.
#include <gtest/gtest.h>

#include <cmath>

#include "contact/incline_mujoco.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using namespace incline_mujoco;

TEST(ContactMujoco, SlidesDifferByMuTimesMujocosNormalOffset) {
  const InclineRun u = run_ukdyn();
  ASSERT_EQ(u.s.size(), kTimes.size());
  // ukdyn's slide: s = v0 t + ½ g (sin α − μ cos α) t² + μ k t³/(6m) (the closed form)
  const double a0 = kG * (std::sin(kAlpha) - kMu * std::cos(kAlpha)), j = kMu * kK / kM;
  for (std::size_t i = 0; i < kTimes.size(); ++i) {
    const double t = kTimes[i];
    EXPECT_NEAR(u.s[i], kV0 * t + 0.5 * a0 * t * t + j * t * t * t / 6.0, 1e-8) << t;
  }
  for (const double tc : {0.02, 0.005}) {
    const InclineRun r = run_mujoco(tc, 1e-4, "RK4");
    ASSERT_EQ(r.s.size(), kTimes.size()) << tc;
    for (std::size_t i = 0; i < kTimes.size(); ++i) {
      EXPECT_NEAR(r.s[i] - u.s[i], -kMu * r.n[i], 1e-8) << "tc " << tc << ", t " << kTimes[i];
      EXPECT_NEAR(r.n[i], 0.0, 1e-3) << "tc " << tc << ", t " << kTimes[i];
    }
    // and it is off the plane: a soft contact, not a rigid one (n > 1e-7 m by t = 3 s)
    EXPECT_GT(std::abs(r.n[2]), 1e-7) << tc;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
