// SPDX-License-Identifier: BSD-3-Clause
// The largest margin of a split of the holding forces inside every friction cone (a small
// second-order cone programme), by a barrier method. See split_margin.hpp.
#include "simulation/split_margin.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/contact.hpp"

namespace ukdyn::detail {

namespace {

// (|y| <= kRadius scale: the barrier is bounded where the forces can grow without limit, a body
// squeezed between two walls; the cap s <= scale likewise)
constexpr double kRadius = 1e3;

// the barrier of the margin problem at z = (y, s) (scale units): its value's finiteness (false
// outside the domain), gradient and Hessian into w.G, w.H (w's other vectors: scratch)
bool barrier(const std::vector<SplitCone>& cones, SplitBarrier& w) {
  const Eigen::VectorXd& z = w.z;
  Eigen::VectorXd &G = w.G, &alpha = w.alpha, &grad = w.grad;
  Eigen::MatrixXd& H = w.H;
  const Index p = z.size(), nz = p - 1;
  const auto y = z.head(nz);
  const double s = z[nz];
  G.setZero(p);
  H.setZero(p, p);
  // −log l for l = λ·z + l0 > 0 (λ in alpha)
  auto linear = [&](double l) {
    if (!(l > 0.0)) return false;
    G -= alpha / l;
    H.noalias() += alpha * alpha.transpose() / (l * l);
    return true;
  };
  Index at = 0;
  for (std::size_t i = 0; i < cones.size(); ++i) {
    const SplitCone& cone = cones[i];
    const Index d = cone.F.rows();
    const double N = w.N0s[Index(i)] + cone.g.dot(y);
    // N >= s
    alpha.head(nz) = cone.g;
    alpha[nz] = -1.0;
    if (!linear(N - s)) return false;
    // |b| <= a, a = mu N − s, b = f0 + F y: −log(a² − |b|²)
    alpha.head(nz) = cone.mu * cone.g;
    const double a = cone.mu * N - s;
    if (d == 0) {
      if (!linear(a)) return false;
      continue;
    }
    // (b summed as f0 + (F y) for |b|², and F y accumulated onto f0 for Fᵀ b: the two ways
    // Eigen evaluated the expression f0 + F y there before it was kept in w, bit for bit)
    w.Fy.resize(d);
    w.Fy.noalias() = cone.F * y;
    w.b_sum.resize(d);
    w.b_sum = w.f0s.segment(at, d) + w.Fy;
    w.b = w.f0s.segment(at, d);
    w.b.noalias() += cone.F * y;
    at += d;
    const double D = a * a - w.b_sum.squaredNorm();
    if (!(a > 0.0) || !(D > 0.0)) return false;
    // ∇D = 2 a α − 2 Bᵀ b, ∇²D = 2 α αᵀ − 2 Bᵀ B (B = [F 0])
    grad = 2.0 * a * alpha;
    grad.head(nz).noalias() -= 2.0 * cone.F.transpose() * w.b;
    G -= grad / D;
    H.noalias() += grad * grad.transpose() / (D * D) - 2.0 * alpha * alpha.transpose() / D;
    w.FtF.noalias() = 2.0 * cone.F.transpose() * cone.F;
    H.topLeftCorner(nz, nz) += w.FtF / D;
  }
  // s <= 1, |y| <= kRadius
  alpha.setZero();
  alpha[nz] = 1.0;
  if (!linear(1.0 - s)) return false;
  const double room = kRadius * kRadius - y.squaredNorm();
  if (!(room > 0.0)) return false;
  grad.setZero();
  grad.head(nz) = -2.0 * y;
  G -= grad / room;
  H.noalias() += grad * grad.transpose() / (room * room);
  H.topLeftCorner(nz, nz).diagonal().array() += 2.0 / room;
  return true;
}

}  // namespace

bool split_space(const System& sys, Workspace& ws, const Eigen::VectorXd& Lambda,
                 const std::vector<std::size_t>& stuck, const std::vector<std::size_t>& fixed,
                 const Eigen::Ref<const Eigen::VectorXd>& q,
                 const Eigen::Ref<const Eigen::VectorXd>& qd, double t, SplitSpace& out,
                 bool push) {
  const auto& contacts = sys.friction_contacts();
  const Index m = Lambda.size(), n = sys.coordinate_count();
  Eigen::MatrixXd& rows_A = out.rows;
  Eigen::MatrixXd& null = out.null;
  Eigen::MatrixXd normals;
  Eigen::VectorXd part = Eigen::VectorXd::Zero(n);
  // the active rows, compact: their rows of A, and Λ there
  std::vector<Index>& row_of = out.row_of;
  row_of.clear();
  std::vector<Index> compact(std::size_t(m), -1);
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!ws.active[std::size_t(k)]) continue;
    for (Index r = 0; r < sys.constraint(k).rows(); ++r) {
      compact[std::size_t(sys.row_offset(k) + r)] = Index(row_of.size());
      row_of.push_back(sys.row_offset(k) + r);
    }
  }
  const Index ma = Index(row_of.size());
  rows_A.setZero(ma, n);
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!ws.active[std::size_t(k)] || sys.constraint(k).rows() == 0) continue;
    detail::copy_constraint_rows(
        sys, ws, k,
        rows_A.middleRows(compact[std::size_t(sys.row_offset(k))], sys.constraint(k).rows()));
  }
  Eigen::VectorXd lambda0(ma);
  for (Index i = 0; i < ma; ++i) lambda0[i] = Lambda[row_of[std::size_t(i)]];
  // Z: the left null space of the active rows, Z = D Z̃ with Z̃ that of D A C, the rows and then
  // the columns scaled to norms in [1, 2) by powers of two (exact): a model's rows in mm, g, ms
  // span 1 (a normal row's translation) to 1e6 (a stick row's κ times its lever arm in a
  // quaternion's column), and the null space of A itself carried ~1e-10 of roundoff (the
  // breakaway of a table on four legs located 1.8e-10 s late; 2e-12 in SI units)
  Eigen::VectorXd row_unit = Eigen::VectorXd::Ones(ma);
  Eigen::MatrixXd scaled = rows_A;
  auto unit = [](double norm) { return norm > 0.0 ? std::ldexp(1.0, -std::ilogb(norm)) : 1.0; };
  for (Index i = 0; i < ma; ++i) {
    row_unit[i] = unit(scaled.row(i).norm());
    scaled.row(i) *= row_unit[i];
  }
  for (Index j = 0; j < n; ++j) scaled.col(j) *= unit(scaled.col(j).norm());
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeFullU);
  const auto& sigma = svd.singularValues();
  Index rank = 0;
  while (rank < sigma.size() && sigma[rank] > 1e-10 * sigma[0]) ++rank;
  if (rank == ma) return false;
  null = row_unit.asDiagonal() * svd.matrixU().rightCols(ma - rank);
  // N_i = g·Λ of contact c (signed along a unilateral contact's push with `push`, else along Λ
  // at the evaluation: N is |·|) into g; false where N is not linear in Λ (a coordinate-path normal
  // constraint of several rows)
  auto normal_form = [&](std::size_t c, Eigen::VectorXd& g) {
    const FrictionContact& contact = contacts[c];
    const Index k = contact.normal_constraint, s = contact.stick_constraint;
    const Index rowsk = sys.constraint(k).rows(), rowss = sys.constraint(s).rows();
    const Index ok = compact[std::size_t(sys.row_offset(k))];
    g.setZero(ma);
    if (const ContactKinematics& kin = contact.kinematics) {
      // N = |w·A_kᵀ Λ_k| / |w|², w = J_Pᵀ n_W (contact_normal_force)
      detail::sliding_velocity(sys, ws, Index(c), q, qd, t, false);
      const auto& J = ws.contact_jacobian[c];
      const double ww = J.row(0).squaredNorm();
      for (Index r = 0; r < rowsk && ww > 0.0; ++r) {
        double wa = 0.0;
        for (std::size_t j = 0; j < kin.columns.size(); ++j)
          wa += J(0, Index(j)) * rows_A(ok + r, kin.columns[j]);
        g[ok + r] = wa / ww;
      }
    } else {
      // R = A_kᵀ Λ_k + A_sᵀ Λ_s (its rows while it sticks); N = |a·R| |a_p| / |a|² (one
      // normal row; p its normal coordinates, coordinate_normal_force)
      if (rowsk != 1) return false;
      const double aa = rows_A.row(ok).squaredNorm();
      if (!(aa > 0.0)) return false;
      // (|a_p| / |a|² is 1/|a| when p is all: the old expression, bit for bit)
      const bool all = contact.normal_coordinates.empty();
      const double root = std::sqrt(aa),
                   a_p = all ? root : detail::coordinate_normal_force(contact, rows_A.row(ok));
      const Index os = compact[std::size_t(sys.row_offset(s))];
      const bool sticks = os >= 0 && ws.active[std::size_t(s)];
      for (Index r = 0; r < rowsk + (sticks ? rowss : 0); ++r) {
        const Index i = r < rowsk ? ok + r : os + r - rowsk;
        g[i] = rows_A.row(ok).dot(rows_A.row(i)) / root * (all ? 1.0 : a_p / root);
      }
    }
    // N's sign: a unilateral contact's along its push (Λ_k > 0) with `push`, whatever Λ is at
    // the minimum-norm split, which depends on the units and on how the rows are written (a
    // ladder's wall bears nothing there, N ~ 1e-15 of either sign, and on a ladder stopped on a
    // rough wall and floor it pulled with −22.8 N in mm, g, ms where it pushed with 31 N in SI:
    // the cone taken from that sign pointed to a pull, and the wall slid or was released);
    // else, and for a bilateral contact, along Λ at the evaluation
    const bool along_push = push && sys.constraint(k).is_unilateral();
    if (along_push ? g[ok] < 0.0 : g.dot(lambda0) < 0.0) g = -g;
    return true;
  };
  // the sliding contacts' normal forces stay (their friction is μ N at the evaluation's N): Z
  // restricted to the y that leave each one's N unchanged
  {
    std::vector<Eigen::VectorXd> kept;
    Eigen::VectorXd g;
    for (std::size_t c : fixed) {
      if (compact[std::size_t(sys.row_offset(contacts[c].normal_constraint))] < 0) continue;
      if (!normal_form(c, g)) return false;
      kept.push_back(null.transpose() * g);
    }
    if (!kept.empty()) {
      Eigen::MatrixXd E(Index(kept.size()), null.cols());
      for (std::size_t i = 0; i < kept.size(); ++i) E.row(Index(i)) = kept[i].transpose();
      const Eigen::JacobiSVD<Eigen::MatrixXd> keep(E, Eigen::ComputeFullV);
      const auto& sv = keep.singularValues();
      const double top = sv.size() > 0 ? sv[0] : 0.0;
      Index used = 0;
      while (used < sv.size() && sv[used] > 1e-10 * std::max(top, 1e-300)) ++used;
      if (used == E.cols()) return false;
      null = (null * keep.matrixV().rightCols(E.cols() - used)).eval();
    }
  }
  // each contact's f_i = F_i Λ (d_i) and N_i = g_i·Λ on the compact rows, then on y
  std::vector<SplitCone>& cones = out.cones;
  cones.clear();
  double scale = 0.0;
  for (std::size_t c : stuck) {
    const FrictionContact& contact = contacts[c];
    const Index k = contact.normal_constraint, s = contact.stick_constraint;
    const Index rowsk = sys.constraint(k).rows(), rowss = sys.constraint(s).rows();
    const Index ok = compact[std::size_t(sys.row_offset(k))];
    const Index os = compact[std::size_t(sys.row_offset(s))];
    Eigen::MatrixXd F = Eigen::MatrixXd::Zero(0, ma), basis;
    Eigen::VectorXd g;
    if (!normal_form(c, g)) return false;
    if (const ContactKinematics& kin = contact.kinematics) {
      // f = kappa Λ_s
      if (normals.rows() != rowsk) normals.resize(rowsk, n);
      detail::copy_constraint_rows(sys, ws, k, normals);
      const double kappa = detail::normal_row_unit(normals, rowsk, part);
      F.setZero(kin.tangents, ma);
      for (Index j = 0; j < kin.tangents; ++j) F(j, os + j) = kappa;
      basis = Eigen::MatrixXd::Identity(kin.tangents, kin.tangents);
    } else {
      // f = P R in an orthonormal basis of its range, P = I − a aᵀ / |a|²
      const Eigen::VectorXd a = rows_A.row(ok).transpose();
      Eigen::MatrixXd H = rows_A.middleRows(os, rowss).transpose();  // (n × rowss)
      H -= a * (a.transpose() * H) / a.squaredNorm();
      const Eigen::JacobiSVD<Eigen::MatrixXd> range(H, Eigen::ComputeThinU);
      Index d = 0;
      const double top = range.singularValues().size() ? range.singularValues()[0] : 0.0;
      while (d < range.singularValues().size() && range.singularValues()[d] > 1e-10 * top) ++d;
      F.setZero(d, ma);
      F.middleCols(os, rowss) = range.matrixU().leftCols(d).transpose() * H;
      basis = range.matrixU().leftCols(d);
    }
    SplitCone cone;
    cone.basis = std::move(basis);
    cone.N0 = g.dot(lambda0);
    cone.f0 = F * lambda0;
    cone.F = F * null;  // (then on ỹ, below)
    cone.g = null.transpose() * g;
    cone.mu = contact.mu_static;
    scale = std::max({scale, cone.mu * cone.N0, cone.f0.norm()});
    cones.push_back(std::move(cone));
  }
  // the split sought in the contact forces, not in the multipliers: y = V S⁻¹ ỹ with
  // [F_i Z; g_iᵀ Z]_i = U S Vᵀ, so that every f_i and N_i moves by the orthonormal U ỹ. The
  // multipliers' own units depend on how each row is scaled (the stick rows are κ T, κ the
  // class of the normal rows: 100 in mm, g, ms, where the quaternion's rows carry lever arms of
  // 500 mm), and y's least norm there was no physical one: the tangent planes of three legs of a
  // table, nearly dependent in that metric, made the LCP's δ regularization miss the split (no
  // split found in mm, g, ms where SI finds one)
  Index rowsP = 0;
  for (const SplitCone& cone : cones) rowsP += cone.F.rows() + 1;
  rows_A.resize(rowsP, null.cols());
  for (Index i = 0; const SplitCone& cone : cones) {
    rows_A.middleRows(i, cone.F.rows()) = cone.F;
    rows_A.row(i + cone.F.rows()) = cone.g.transpose();
    i += cone.F.rows() + 1;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> forces(rows_A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sf = forces.singularValues();
  Index nz = 0;
  while (nz < sf.size() && sf[nz] > 1e-10 * sf[0]) ++nz;
  if (nz == 0) return false;
  null = (null * forces.matrixV().leftCols(nz) * sf.head(nz).cwiseInverse().asDiagonal()).eval();
  for (Index i = 0; SplitCone & cone : cones) {
    cone.F = forces.matrixU().block(i, 0, cone.F.rows(), nz);
    cone.g = forces.matrixU().row(i + cone.F.rows()).head(nz).transpose();
    i += cone.F.rows() + 1;
  }
  out.nz = nz;
  out.scale = scale;
  return true;
}

double max_split_margin(SplitSpace& space, Eigen::VectorXd* y_out, bool sign_only, bool optimum) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<SplitCone>& cones = space.cones;
  const Index nz = space.nz;
  const double scale = space.scale;
  if (!(scale > 0.0) || cones.empty()) return nan;
  SplitBarrier& w = space.barrier;
  // the data in units of the scale; the start y = 0, s below every margin there
  Index rows = 0;
  for (const SplitCone& cone : cones) rows += cone.f0.size();
  w.f0s.resize(rows);
  w.N0s.resize(Index(cones.size()));
  double s0 = 0.0;
  for (Index i = 0, at = 0; const SplitCone& cone : cones) {
    const Index d = cone.f0.size();
    w.f0s.segment(at, d) = cone.f0 / scale;
    at += d;
    w.N0s[i] = cone.N0 / scale;
    s0 = std::min({s0, w.N0s[i], cone.mu * w.N0s[i] - w.f0s.segment(at - d, d).norm()});
    ++i;
  }
  const Index p = nz + 1;
  Eigen::VectorXd& z = w.z;
  z.setZero(p);
  for (Eigen::VectorXd* v : {&w.G, &w.step, &w.alpha, &w.grad}) v->resize(p);
  w.H.resize(p, p);
  z[nz] = s0 - 1.0;
  // the barrier's parameter (2 per cone, 1 per linear term): the gap s* − s on the central path
  // is at most it over the weight τ
  const double theta = 3.0 * double(cones.size()) + 2.0;
  // (centred to λ² <= 1e-12 — or to λ <= 1/9 for the sign only, the gap bound's condition)
  const double centred = sign_only ? 1.0 / 81.0 : 1e-12, raise = sign_only ? 100.0 : 10.0;
  for (double tau = 1.0; tau <= 1e16; tau *= raise) {
    double decrement = std::numeric_limits<double>::infinity();
    for (int newton = 0; newton < 60 && decrement > centred; ++newton) {
      if (!barrier(cones, w)) return nan;
      w.G[nz] -= tau;  // (the objective −τ s)
      w.ldlt.compute(w.H);
      if (w.ldlt.info() != Eigen::Success) return nan;
      w.step = -w.ldlt.solve(w.G);
      decrement = -w.G.dot(w.step);  // λ², in the Hessian's norm
      if (!(decrement >= 0.0)) return nan;
      // (damped Newton: a step of 1/(1 + λ) stays inside a self-concordant barrier's domain)
      const double lambda = std::sqrt(decrement);
      z += (lambda > 0.25 ? 1.0 / (1.0 + lambda) : 1.0) * w.step;
      // (a point of the domain: its s is a lower bound of s*)
      if (sign_only && z[nz] > -kSplitTolerance) {
        if (!barrier(cones, w)) return nan;
        if (y_out) *y_out = z.head(nz) * scale;
        return z[nz];
      }
    }
    if (!barrier(cones, w)) return nan;
    // decided: a split with a margin above −kSplitTolerance (s <= s*), or none within the gap's
    // bound
    const double s = z[nz], gap = 2.0 * theta / tau;
    // (or, for the optimum, only the gap's bound)
    if ((!optimum && (s > -kSplitTolerance || s + gap < -kSplitTolerance)) || gap < 1e-14) break;
  }
  if (y_out) *y_out = z.head(nz) * scale;
  return z[nz];
}

}  // namespace ukdyn::detail
