// SPDX-License-Identifier: BSD-3-Clause
// The slider-crank of the multibody validation (issue #5): crank r turning at the prescribed
// rate w, rod l, slider on the x axis; closed-form kinematics and the energy by hand, for the
// C++ test (multibody/test_multibody.cpp) and the model-file test
// (modelfile/test_model_multibody.cpp).
#pragma once

#include <cmath>
#include <numbers>

#include <Eigen/Core>

namespace ukdyn::test {

struct SliderCrank {
  double r = 0.3, l = 1.0, mc = 1.0, mr = 2.0, ms = 0.5, g = 9.81, w = 2 * std::numbers::pi,
         th0 = 0.3;
  double Ic() const { return mc * r * r / 12; }  ///< crank, about its centre
  double Ir() const { return mr * l * l / 12; }  ///< rod, about its centre
  /// crank angle, piston position, rod angle and their rates
  struct State {
    double th, x, phi, xd, phid;
  };
  /// the state at t (closed-form kinematics)
  State at(double t) const {
    const double th = th0 + w * t, s = std::sin(th), c = std::cos(th);
    const double root = std::sqrt(l * l - r * r * s * s);
    const double x = r * c + root, xd = (-r * s - r * r * s * c / root) * w;
    const double phi = std::asin(-r * s / l), phid = -r * c * w / (l * std::cos(phi));
    return {th, x, phi, xd, phid};
  }
  /// E = T + V by hand: crank about its pin, rod (centre velocity the mean of its ends), slider
  double energy(double t) const {
    const State z = at(t);
    const Eigen::Vector3d Bd = r * w * Eigen::Vector3d(-std::sin(z.th), std::cos(z.th), 0);
    const Eigen::Vector3d Gd = 0.5 * (Bd + Eigen::Vector3d(z.xd, 0, 0));
    const double T = 0.5 * (Ic() + mc * r * r / 4) * w * w + 0.5 * mr * Gd.squaredNorm() +
                     0.5 * Ir() * z.phid * z.phid + 0.5 * ms * z.xd * z.xd;
    const double V = (mc + mr) * g * 0.5 * r * std::sin(z.th);
    return T + V;
  }
};

}  // namespace ukdyn::test
