// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/ridders.cpp
/// Stage 3 of linearize(): Jacobians by Ridders' method — central differences at steps
/// h, h/c, h/c², … extrapolated to h → 0 in a Richardson (Neville) table, each entry of the
/// result taking the table element with the smallest estimated error (Ridders 1982; Numerical
/// Recipes, 3rd ed., §5.7, dfridr, applied to every component of a vector function at once).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "analysis/internal.hpp"

namespace ukdyn::analysis {

bool ridders_jacobian(const VectorFunction& F, const Eigen::Ref<const VectorXd>& z0,
                      const Eigen::Ref<const VectorXd>& h0, Index p, const RiddersOptions& o,
                      MatrixXd& J, MatrixXd& err, std::string& why) {
  const Index k = z0.size();
  const int ntab = o.table_size;
  const double c2 = o.step_ratio * o.step_ratio;
  const double eps = std::numeric_limits<double>::epsilon();
  J.setZero(p, k);
  err.setZero(p, k);
  // the table: a[i][j] (p each), row i the i-th extrapolation of column j (step h / c^j)
  const auto ntab_u = static_cast<std::size_t>(ntab);
  std::vector<std::vector<VectorXd>> a(ntab_u, std::vector<VectorXd>(ntab_u));
  VectorXd zp(k), zm(k), fp(p), fm(p), best_err(p), floor(p);
  std::vector<unsigned char> done(static_cast<std::size_t>(p));
  // central difference of column `col` at step hh into d; the roundoff floor 4 ε |F| / hh
  auto central = [&](Index col, double hh, VectorXd& d) {
    zp = z0;
    zm = z0;
    zp(col) += hh;
    zm(col) -= hh;
    if (!F(zp, fp) || !F(zm, fm)) return false;
    d = (fp - fm) / (2 * hh);
    floor = 4 * eps * fp.cwiseAbs().cwiseMax(fm.cwiseAbs()) / hh;
    return d.allFinite();
  };
  for (Index col = 0; col < k; ++col) {
    // the first level: quarter the step until both sides can be evaluated
    double hh = h0(col);
    bool started = false;
    for (int tries = 0; tries < 4 && !started; ++tries, hh /= 4)
      started = central(col, hh, a[0][0]);
    if (!started) {
      why = "the function cannot be evaluated near the point along entry " + std::to_string(col) +
            " (steps down to " + std::to_string(hh) + ")";
      return false;
    }
    hh *= 4;  // (undo the last quartering of the loop)
    J.col(col) = a[0][0];
    best_err.setConstant(std::numeric_limits<double>::infinity());
    std::fill(done.begin(), done.end(), 0);
    VectorXd floor_at_best = floor;
    for (int i = 1; i < ntab; ++i) {
      // a shorter step, then its extrapolations a[j][i] = (c^{2j} a[j−1][i] − a[j−1][i−1]) /
      // (c^{2j} − 1)
      hh /= o.step_ratio;
      if (!central(col, hh, a[0][i])) break;
      double fac = c2;
      for (int j = 1; j <= i; ++j) {
        a[j][i] = (a[j - 1][i] * fac - a[j - 1][i - 1]) / (fac - 1);
        fac *= c2;
        for (Index e = 0; e < p; ++e) {
          if (done[std::size_t(e)]) continue;
          const double errt = std::max(std::abs(a[j][i](e) - a[j - 1][i](e)),
                                       std::abs(a[j][i](e) - a[j - 1][i - 1](e)));
          if (errt <= best_err(e)) {
            best_err(e) = errt;
            J(e, col) = a[j][i](e);
            floor_at_best(e) = floor(e);
          }
        }
      }
      // an entry is finished once the higher orders move away by more than `safe` times its
      // best error (roundoff has taken over)
      bool all_done = true;
      for (Index e = 0; e < p; ++e) {
        if (!done[std::size_t(e)] &&
            std::abs(a[i][i](e) - a[i - 1][i - 1](e)) >= o.safe * best_err(e))
          done[std::size_t(e)] = 1;
        all_done = all_done && done[std::size_t(e)];
      }
      if (all_done) break;
    }
    // the estimate: the table's, at least the roundoff floor, plus 16 ε |J| (the evaluation's
    // own roundoff, a few ulps of q'' through the factorizations, carried into the result)
    for (Index e = 0; e < p; ++e)
      err(e, col) = std::max(best_err(e), floor_at_best(e)) + 16 * eps * std::abs(J(e, col));
  }
  return true;
}

}  // namespace ukdyn::analysis
