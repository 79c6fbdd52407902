// SPDX-License-Identifier: BSD-3-Clause
// initial: project: {keep: [...]} (modelfile/initial_keep.cpp)
#pragma once

#include <string>
#include <vector>

#include "ukdyn/core/system.hpp"

namespace ukdyn::model_reader {

// Makes (q, q') consistent with the constraints of `sys` at t while the coordinates with
// keep_q[j] (velocities with keep_qd[j]) keep their values: Gauss–Newton over the other
// coordinates for the holonomic rows, each correction of least M_FF-norm (M restricted to the
// free coordinates), to the roundoff floor; then the same over the free velocities for the
// velocity-level rows (holonomic and nonholonomic). `kept_names` name the kept entries in the
// messages. Returns "" on success, else why there is no such state: the kept set
// over-determines the constraints (the rank of the rows over the free coordinates is lower than
// over all of them), or the iteration does not converge (50 steps). Cost per step: one
// evaluation of M and A, and a decomposition of the m × f rows, O(m f²).
std::string project_keeping(const System& sys, VectorXd& q, VectorXd& qd, double t,
                            const std::vector<unsigned char>& keep_q,
                            const std::vector<unsigned char>& keep_qd,
                            const std::vector<std::string>& kept_names);

}  // namespace ukdyn::model_reader
