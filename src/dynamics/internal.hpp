// SPDX-License-Identifier: BSD-3-Clause
// Internal helpers shared by the stages (not installed).
#pragma once

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "dynamics/engine.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {
struct SimulationOptions;
struct Trajectory;
}  // namespace ukdyn

namespace ukdyn::detail {

// simulate(), with `finished` called with the run's workspace when the run ends (it returns or
// throws): a caller reads there what the system's callables recorded in their per-workspace
// scratch — the controlled plant's control statistics (control/controlled_plant.hpp).
Trajectory simulate_observed(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                             const Eigen::Ref<const VectorXd>& qd0,
                             const SimulationOptions& options,
                             const std::function<void(const Workspace&)>& finished);

// Index of the first non-finite of the n entries at p, or −1. Cost O(n). (A branch-free
// finiteness test, Σ x·0 in four sums, ran more instructions on the short vectors of an
// evaluation: measured on P1/rk4, 287.4 M against 285.6 M.)
inline Index first_non_finite(const double* p, Index n) {
  for (Index i = 0; i < n; ++i) {
    if (!std::isfinite(p[i])) return i;
  }
  return -1;
}
inline Index first_non_finite(const Eigen::Ref<const VectorXd>& v) {
  return first_non_finite(v.data(), v.size());
}
inline bool all_finite(const double* p, Index n) { return first_non_finite(p, n) < 0; }

// Whether every entry of x is finite: a vector, or a column-major matrix or block (unit inner
// stride). The checks of every evaluation use it: on these short vectors and small blocks it
// costs a fraction of Eigen's allFinite() (P1/rk4: 15 M of 305 M instructions before). Cost
// O(rows · cols).
template <class Derived>
inline bool all_finite(const Eigen::DenseBase<Derived>& x) {
  static_assert(Derived::IsVectorAtCompileTime || !(Derived::Flags & Eigen::RowMajorBit),
                "all_finite: column-major storage");
  static_assert(Derived::InnerStrideAtCompileTime == 1, "all_finite: unit inner stride");
  const Derived& d = x.derived();
  const Index rows = d.rows(), stride = d.outerStride();
  if (Derived::IsVectorAtCompileTime || d.cols() == 1 || stride == rows) {
    return all_finite(d.data(), d.size());
  }
  for (Index j = 0; j < d.cols(); ++j) {
    if (!all_finite(d.data() + j * stride, rows)) return false;
  }
  return true;
}

// Records a failing status in the workspace (tier 3) and returns it.
inline Status fail(Workspace& ws, Status s, const char* quantity, Index index, double t) {
  ws.status = s;
  ws.failed_quantity = quantity;
  ws.failed_index = index;
  ws.failed_time = t;
  ++ws.counters.failures;
  return s;
}

// The errors of require_same_system and require_state_size (out of line: the checks that pass,
// once per stage of every evaluation, stay a compare or two).
[[noreturn]] void throw_other_system(const Workspace& ws, const char* who);
[[noreturn]] void throw_state_size(Index n, Index q_size, Index qd_size, const char* who);

// Tier 1: refuses a workspace made for another system, or a moved-from one (system_id() 0,
// which no System has): one compare when the workspace is right.
inline void require_same_system(const System& sys, const Workspace& ws, const char* who) {
  if (sys.id() != ws.system_id()) [[unlikely]]
    throw_other_system(ws, who);
}

// Tier 1: q (and q', when given) have n entries.
inline void require_state_size(const System& sys, const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>* qd, const char* who) {
  const Index n = sys.coordinate_count();
  if (q.size() != n || (qd && qd->size() != n)) [[unlikely]]
    throw_state_size(n, q.size(), qd ? qd->size() : n, who);
}

// M(q,t), its checks and its factorization into the workspace's decomposition (stage 1 without
// Q; shared with the projections).
// A singular, positive semi-definite M sets ws.mass_singular and is factorized later by
// complete_singular_mass.
inline Status evaluate_mass(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                            double t) {
  return ws.engine->evaluate_mass(sys, ws, q, t);
}

// For a singular M (ws.mass_singular), with A (and b) assembled: factorizes the auxiliary
// M_A = M + Aᵀ G A, G = diag(s / ‖a_i‖²), s the largest diagonal of M (the sparse engine: each
// singular block with the rows local to it); with `forces`, a = M_A⁻¹ (Q + Aᵀ G b). When M_A is
// not positive definite ([M; A] rank deficient): kMotionUndetermined, or with `regularize` (a
// projection's metric) M_A + 1e-8 s I. Cost O(nnz(A)·(row nnz) + n³/3) dense.
inline Status complete_singular_mass(Workspace& ws, double t, bool forces, bool regularize) {
  return ws.engine->complete_singular_mass(ws, t, forces, regularize);
}

// Writes constraint k's rows of A (dense matrix or the sparse engine's pattern) and b from its
// acceleration form at (q, q', t); with `check`, kNonFiniteInput (recorded) when A is not
// finite.
inline Status write_constraint_rows(const System& sys, Workspace& ws, Index k,
                                    const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double t,
                                    bool check = true) {
  return ws.engine->write_constraint_rows(sys, ws, k, q, qd, t, check);
}
// Zeroes constraint k's rows of A and b.
inline void zero_constraint_rows(const System& sys, Workspace& ws, Index k) {
  ws.b.segment(sys.row_offset(k), sys.constraint(k).rows()).setZero();
  ws.engine->zero_constraint_rows(sys, ws, k);
}

// Copies constraint k's rows of A (as last assembled) into out (rows × n), either engine.
inline void copy_constraint_rows(const System& sys, const Workspace& ws, Index k,
                                 Eigen::Ref<MatrixXd> out) {
  ws.engine->copy_constraint_rows(sys, ws, k, out);
}
// The stick constraint of a Coulomb contact: psi = P (q'_c − u(q, t)) on `coordinates`, P the
// tangential projector of the normal constraint `normal` (sliding_velocity; P = I when normal is
// null), nonholonomic, local columns, inactive until the simulation switches it on
// (core/coulomb_contact.cpp). The stuck contact thus moves with the normal motion that a
// rheonomic normal constraint imposes.
Constraint stick_constraint(const std::string& name, const std::vector<Index>& coordinates,
                            const SurfaceVelocityFn& surface, const Constraint* normal);
// Contact c's sliding velocity relative to its constraint, v_rel = P (v − u) (see
// CoulombFriction), into ws.sliding.col(c).head(|coordinates|). With rows_assembled, N_k is read
// from the rows of A that the workspace last assembled at (q, t); else constraint k is evaluated
// here. Returns the number B of independent normals: ws.contact_basis.topRows(B) then holds
// them, orthonormal, for projecting other vectors. No allocation; O(rows_k · n + rows_k² ·
// |coordinates|).
Index sliding_velocity(const System& sys, Workspace& ws, Index c,
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, bool rows_assembled);

// The stick constraint of a Coulomb contact on the contact-point path: T q' = 0, T the
// kinematics' tangential rows (ContactKinematics), nonholonomic, on its columns
// (core/coulomb_contact.cpp).
Constraint point_stick_constraint(const std::string& name, const ContactKinematics& kinematics,
                                  const Constraint* normal);
// kappa = class(max_i ‖n_i‖) / 10 over the first `rows` rows n_i of rows_n (the unit of a
// contact's normal rows, in which its stick rows are stated; `row` (n) a buffer): 1 in SI units.
double normal_row_unit(const Eigen::Ref<const MatrixXd>& rows_n, Index rows, VectorXd& row);
// R_N = the part of a reaction R (n) along the normal rows (rows × n) of a contact on the
// coordinate path, into out (n): a (a·R)/(a·a) for one row a, the least-squares projection onto
// their span for several (allocates then). The holding force is R − R_N. O(rows · n).
void normal_part(const Eigen::Ref<const MatrixXd>& normals, const Eigen::Ref<const VectorXd>& R,
                 VectorXd& out);
// Contact c's physical normal force on the contact-point path from a reaction R (n) of its
// normal constraint: N = |w·R| / |w|², w = J_Pᵀ n_W the row 0 of ws.contact_jacobian[c] (as
// sliding_velocity last evaluated it). O(|columns|), no allocation.
double contact_normal_force(const System& sys, const Workspace& ws, Index c,
                            const Eigen::Ref<const VectorXd>& reaction);
// Contact c's normal force on the coordinate path from a vector R (n) along its normal rows —
// its normal constraint's reaction, or the normal part of a stuck contact's: N = |R_p| over the
// contact's normal_coordinates p (all n when empty; docs/friction.md §1), = |lambda| |a_p| for
// R = lambda a. With R a normal row a itself: N per unit multiplier, |a_p|. Any vector
// expression (a row of a matrix too). O(|p|) (O(n) when p is all), no allocation.
template <class Vector>
double coordinate_normal_force(const FrictionContact& contact, const Vector& R) {
  if (contact.normal_coordinates.empty()) return R.norm();
  double s = 0.0;
  for (const Index i : contact.normal_coordinates) s += R[i] * R[i];
  return std::sqrt(s);
}
// C += scale · Tᵀ f on the contact-point path: f (d) the tangential force components, T the
// tangential rows of ws.contact_jacobian[c]. O(d · |columns|), no allocation.
void add_contact_force(const System& sys, const Workspace& ws, Index c, double scale,
                       const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> C);
// v −= Σ_j (v·e_j) e_j over the first `basis` rows e_j of ws.contact_basis (orthonormal, from
// sliding_velocity): the part of v (|coordinates|) tangent to the contact's constraint.
void remove_normals(const Workspace& ws, Index basis, Eigen::Ref<VectorXd> v);

// out = A_kᵀ lambda_k (n) for any multipliers lambda (m) with the rows of A last assembled,
// either engine: constraint k's share of the force Aᵀ lambda. O(rows_k · n).
inline void constraint_share(const System& sys, const Workspace& ws, Index k,
                             const VectorXd& lambda, Eigen::Ref<VectorXd> out) {
  ws.engine->constraint_share(sys, ws, k, lambda, out);
}

// Kinetic energy ½ q'ᵀ M q' with the M of the last evaluation, either engine.
inline double kinetic_energy(const Workspace& ws, const VectorXd& qd) {
  return ws.engine->kinetic_energy(ws, qd);
}

// Whether constraint k acts at t, honouring ws.activity_override.
inline bool is_active(const System& sys, const Workspace& ws, Index k, double t) {
  const signed char forced = ws.activity_override[std::size_t(k)];
  return forced < 0 ? sys.constraint(k).is_active(t) : forced > 0;
}

}  // namespace ukdyn::detail
