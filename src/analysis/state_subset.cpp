// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/state_subset.cpp
/// Stage 5 of linearize(): the linear model restricted to the states named in
/// LinearizeOptions::states, after checking that the dropped states do not act on the kept
/// ones (docs/linearize.md, "Keeping a subsystem").
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/internal.hpp"

namespace ukdyn::analysis {
namespace {

// rows `r`, columns `c` of M (either list empty: all of that dimension kept as is)
MatrixXd pick(const MatrixXd& M, const std::vector<Index>* r, const std::vector<Index>* c) {
  const Index nr = r ? Index(r->size()) : M.rows(), nc = c ? Index(c->size()) : M.cols();
  MatrixXd out(nr, nc);
  for (Index i = 0; i < nr; ++i)
    for (Index j = 0; j < nc; ++j)
      out(i, j) = M(r ? (*r)[std::size_t(i)] : i, c ? (*c)[std::size_t(j)] : j);
  return out;
}

}  // namespace

void keep_states(LinearModel& lm, const std::vector<std::string>& names, const char* who) {
  const auto& all = lm.state_names;
  std::vector<Index> keep;
  for (const std::string& name : names) {
    const auto it = std::find(all.begin(), all.end(), name);
    if (it == all.end()) {
      std::string list;
      for (const auto& s : all) list += (list.empty() ? "" : ", ") + s;
      throw std::invalid_argument(std::string(who) + ": states: '" + name +
                                  "' is not a state of the linear model; its states are " + list +
                                  " (choose them with the independent coordinates)");
    }
    const Index k = Index(it - all.begin());
    if (std::find(keep.begin(), keep.end(), k) != keep.end())
      throw std::invalid_argument(std::string(who) + ": states: '" + name + "' is named twice");
    keep.push_back(k);
  }
  // the dropped states must not act on the kept rows: |A_kd| within its error estimate (and
  // 1e-9 of A's largest entry, for entries whose estimate is 0)
  const Index s = lm.A.rows();
  const double scale = std::max(1.0, lm.A.cwiseAbs().maxCoeff());
  for (Index i : keep)
    for (Index j = 0; j < s; ++j) {
      if (std::find(keep.begin(), keep.end(), j) != keep.end()) continue;
      const double a = lm.A(i, j), e = lm.A_error(i, j);
      if (std::abs(a) <= 10 * e + 1e-9 * scale) continue;
      std::ostringstream msg;
      msg << who << ": states: the dropped state '" << all[std::size_t(j)]
          << "' acts on the kept state '" << all[std::size_t(i)] << "' (A = " << a << " ± " << e
          << "): the kept states are not a subsystem of their own; keep '" << all[std::size_t(j)]
          << "' too, or drop only states the others do not depend on (cyclic coordinates)";
      throw std::invalid_argument(msg.str());
    }
  // nor on an output: its C column within its error estimate, or the output would be silently
  // wrong without it (a bicycle's heading, its contact point)
  const double c_scale = std::max(1.0, lm.C.size() > 0 ? lm.C.cwiseAbs().maxCoeff() : 0.0);
  for (Index o = 0; o < lm.C.rows(); ++o)
    for (Index j = 0; j < s; ++j) {
      if (std::find(keep.begin(), keep.end(), j) != keep.end()) continue;
      const double c = lm.C(o, j), e = lm.C_error.size() > 0 ? lm.C_error(o, j) : 0.0;
      if (std::abs(c) <= 10 * e + 1e-9 * c_scale) continue;
      std::ostringstream msg;
      msg << who << ": states: the output '"
          << (std::size_t(o) < lm.output_names.size() ? lm.output_names[std::size_t(o)] : "?")
          << "' depends on the dropped state '" << all[std::size_t(j)] << "' (C = " << c << " ± "
          << e << "); keep '" << all[std::size_t(j)] << "' too, or leave that output out";
      throw std::invalid_argument(msg.str());
    }
  // A, B rows and columns; C columns; x0, f0, names
  lm.A = pick(lm.A, &keep, &keep);
  lm.A_error = pick(lm.A_error, &keep, &keep);
  lm.B = pick(lm.B, &keep, nullptr);
  lm.B_error = pick(lm.B_error, &keep, nullptr);
  lm.C = pick(lm.C, nullptr, &keep);
  lm.C_error = pick(lm.C_error, nullptr, &keep);
  lm.x0 = pick(lm.x0, &keep, nullptr);
  lm.f0 = pick(lm.f0, &keep, nullptr);
  std::vector<std::string> kept;
  for (Index k : keep) kept.push_back(all[std::size_t(k)]);
  lm.state_names = kept;
}

}  // namespace ukdyn::analysis
