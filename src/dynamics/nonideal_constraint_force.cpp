// SPDX-License-Identifier: BSD-3-Clause
// Stage 4: non-ideal constraints (eqs. 7, 9, 12). C is summed from the system's forces, which may
// read the ideal force (it does not depend on C) and the reactions (which do: iterated to a
// fixed point), then projected:
//   Qc_nonideal = L (I − W⁺W) L⁻¹ C,   q'' += L⁻ᵀ (I − W⁺W) L⁻¹ C.
#include <algorithm>
#include <cmath>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {
namespace {
// evaluations of C that apply_nonideal allows for the reactions to settle
constexpr int kMaxReactionIterations = 50;
// the plain rounds go on while each shrinks the reactions' move to at most this fraction of the
// move before (they then settle at 1e-13 within about 45 rounds); past it, the rounds are
// Anderson-accelerated (docs/friction.md §1)
constexpr double kSlowContraction = 0.5;

// the record of an evaluation at t whose fixed point did not settle: its last round moved
// constraint k's reaction by `change`, the largest reaction being `size`
void record_unsettled(Workspace& ws, double t, Index k, double change, double size) {
  ++ws.counters.nonideal_unsettled;
  UnsettledReactions& u = ws.unsettled;
  const double residual = size > 0.0 ? change / size : change;
  if (std::isnan(u.first_t)) u.first_t = t;
  u.last_t = t;
  if (std::isnan(u.worst_t) || residual > u.worst_residual) {
    u.worst_t = t;
    u.worst_residual = residual;
    u.worst_constraint = k;
  }
}
}  // namespace

Status apply_nonideal(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::apply_nonideal");
  detail::require_state_size(sys, q, &qd, "ukdyn::apply_nonideal");
  if (sys.nonideal_count() == 0) {
    // ideal constraints: Qc = Qc_ideal (C, Qc_nonideal and lambda_nonideal are zero since the
    // workspace was made, and stay so)
    ws.Qc = ws.Qc_ideal;
    return Status::kOk;
  }
  ws.C.setZero();
  // v_rel of each Coulomb contact whose friction acts (its constraint's rows are assembled)
  const auto& contacts = sys.friction_contacts();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (ws.nonideal_enabled[std::size_t(contacts[c].force)]) {
      detail::sliding_velocity(sys, ws, Index(c), q, qd, t, true);
    }
  }
  // C = Σ C_i(q, q', t, reactions), then its projection. A force that reads a reaction (a
  // friction's normal force) sees the ideal shares first, then the whole reactions
  // A_kᵀ (lambda_k + lambda_nonideal,k) of the last C, until they settle: C is a fixed point of
  // C ↦ C(reactions(C)), iterated on x = lambda_read ↦ g(x) = lambda_nonideal(C(reactions(x)))
  // (no iteration when no force reads a reaction). For a sliding contact the map is affine, with
  // the rate mu / mu_c of Painlevé's critical mu_c: plain rounds while they contract fast, then
  // Anderson's extrapolation from the rounds so far, which settles an affine map in a few
  // rounds at any rate below 1 (docs/friction.md §1)
  ws.reactions = ws.shares;
  ws.lambda_read.setZero();
  ws.reaction_acceleration.reset();
  bool accelerated = false;
  double last_change = 0.0;
  for (int iteration = 0;; ++iteration) {
    const IdealForceInfo ideal(sys, ws);
    ws.C.setZero();
    ++ws.counters.nonideal_rounds;
    for (Index i = 0; i < sys.nonideal_count(); ++i) {
      if (!ws.nonideal_enabled[std::size_t(i)]) continue;
      ws.C_term.setZero();
      sys.nonideal(i)(q, qd, t, ideal, ws.C_term);
      if (!detail::all_finite(ws.C_term))
        return detail::fail(ws, Status::kNonFiniteInput, "C", i, t);
      ws.C += ws.C_term;
    }
    // Qc_nonideal, lambda_nonideal and dq = L⁻ᵀ (I − W⁺W) L⁻¹ C
    ws.engine->project_nonideal(ws);
    if (!ideal.read_reactions()) break;
    // reactions_k = share_k + A_kᵀ lambda_nonideal,k; settled when none moves by more than
    // 1e-13 of the largest reaction
    double change = 0.0, size = 0.0;
    Index moved = 0;
    for (Index k = 0; k < sys.constraint_count(); ++k) {
      auto next = ws.reactions_next.col(k);
      detail::constraint_share(sys, ws, k, ws.lambda_nonideal, next);
      next += ws.shares.col(k);
      const double change_k = (next - ws.reactions.col(k)).lpNorm<Eigen::Infinity>();
      if (change_k > change) {
        change = change_k;
        moved = k;
      }
      size = std::max(size, next.lpNorm<Eigen::Infinity>());
    }
    if (!(change > 1e-13 * size)) break;
    if (iteration == kMaxReactionIterations) {
      record_unsettled(ws, t, moved, change, size);
      break;
    }
    // the round's iterate and image (x, g(x)); plain rounds until one shrinks the move by less
    // than kSlowContraction, accelerated from then on (restarted from the round whose move grew)
    const bool slow = iteration > 0 && change > kSlowContraction * last_change;
    if (accelerated && change > last_change) ws.reaction_acceleration.reset();
    last_change = change;
    ws.reaction_acceleration.update(ws.lambda_read, ws.lambda_nonideal);
    if (!accelerated && !slow) {
      // x ← g(x)
      ws.lambda_read = ws.lambda_nonideal;
      ws.reactions.swap(ws.reactions_next);
      continue;
    }
    accelerated = true;
    // x ← g(x) − ΔG γ, and its reactions share_k + A_kᵀ x_k
    ws.reaction_acceleration.extrapolate(ws.lambda_read);
    for (Index k = 0; k < sys.constraint_count(); ++k) {
      auto reaction = ws.reactions.col(k);
      detail::constraint_share(sys, ws, k, ws.lambda_read, reaction);
      reaction += ws.shares.col(k);
    }
  }
  // q'' += dq;  Qc = Qc_ideal + Qc_nonideal
  ws.qdd += ws.dqdd;
  ws.Qc = ws.Qc_ideal + ws.Qc_nonideal;
  return Status::kOk;
}

}  // namespace ukdyn
