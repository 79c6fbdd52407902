// SPDX-License-Identifier: BSD-3-Clause
/// @file dynamics/contact.hpp
/// Unilateral contacts (docs/contact.md): the linear complementarity problem (LCP) that decides
/// which contacts push, and the record of a run's contact events.
///
/// Glossary (docs/contact.md): g the gaps of the unilateral constraints (g >= 0), A_c their rows
/// of A, A_b the rows of the bilateral constraints, P = M⁻¹ − M⁻¹A_bᵀ (A_b M⁻¹ A_bᵀ)⁺ A_b M⁻¹ the
/// inverse mass with the bilateral rows eliminated, W = A_c P A_cᵀ the Delassus matrix.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

/// The linear complementarity problem w = W z + r, w >= 0, z >= 0, wᵀz = 0 (W k × k, r k), solved
/// by Siconos Numerics' lexicographic Lemke method (lcp_lexicolemke: a direct pivoting method
/// that terminates on degenerate problems too, exact for the few contacts of an event; see
/// docs/contact.md, "The LCP solver"). Lemke finds a solution whenever one exists for a
/// copositive-plus W (symmetric positive semi-definite: every uncontrolled Delassus matrix); for
/// other W (the controlled W̃ of a weighted or actuated law) it may end on a ray, and then, for
/// k <= kMaxEnumerated, Siconos's enumeration of the 2^k complementary bases (lcp_enum) decides:
/// false only when no solution exists. Shaped like an Eigen decomposition: constructed with the
/// largest size (its vectors and the enumeration's workspace reserved once; Siconos allocates its
/// own copy of W and its pivoting tableau in each solve: at events only, never in a step),
/// solve(), info(), solver(), z(), w(). The solvers see the problem scaled to diagonals of order
/// one (row_scale), so that any factor on a contact's row (docs/simulation.md, "Scales and
/// tolerances": 1e-170 to 1e8) gives the same solution.
class ContactLcp {
 public:
  /// Reserves the buffers of problems up to max_size × max_size. @throws std::invalid_argument
  /// when max_size < 0.
  explicit ContactLcp(Index max_size = 0);
  /// The largest k the enumeration is tried for (2^k bases of O(k³) each: 4096 for 12 contacts).
  static constexpr Index kMaxEnumerated = 12;
  /// Which method gave the last solve's answer (z = 0 when r >= 0 is reported as kLemke).
  enum class Solver : unsigned char {
    kLemke,        ///< lcp_lexicolemke
    kEnumeration,  ///< lcp_enum, after Lemke found no solution
  };
  ~ContactLcp();
  /// Moves the buffers, member by member (no allocation).
  ContactLcp(ContactLcp&&) noexcept;
  /// Moves the buffers, member by member (no allocation).
  ContactLcp& operator=(ContactLcp&&) noexcept;

  /// Solves the LCP of W (k × k, k <= max_size; copied) and r (k). Returns true when Siconos
  /// reports success and the solution satisfies w = W z + r, z >= 0, w >= 0, wᵀz = 0 to
  /// tolerance · (‖W̃‖ ‖z̃‖ + ‖r̃‖) in the scaled problem (row_scale); when Lemke's answer fails that,
  /// the enumeration's is taken (k <= kMaxEnumerated), so false means no solution exists (or k is
  /// larger). A solution with z = 0 (r >= 0) is found without Siconos. @throws
  /// std::invalid_argument on sizes that do not match or exceed max_size. Cost O(k³) per Lemke
  /// pivot sequence (at most 2^k pivots in theory, k to 2k in practice); where Lemke fails, up to
  /// 2^k LU solves of k × k (O(2^k k³)).
  bool solve(const Eigen::Ref<const MatrixXd>& W, const Eigen::Ref<const VectorXd>& r,
             double tolerance = 1e-9);
  /// Siconos's info of the last solve (0: success; the enumeration's when Lemke failed), or −1
  /// when a solution Siconos reported failed the check.
  int info() const { return info_; }
  /// The method of the last solve's answer (or of its last attempt when it failed).
  Solver solver() const { return solver_; }
  /// The multipliers z (size k) of the last solve.
  Eigen::Ref<const VectorXd> z() const { return z_.head(size_); }
  /// The slacks w = W z + r (size k) of the last solve.
  Eigen::Ref<const VectorXd> w() const { return w_.head(size_); }
  /// The factor d_i of row and column i in the scaled problem the solvers see, W̃ = D W D,
  /// r̃ = D r (z = D z̃, w = D⁻¹ w̃): a power of two near |W_ii|^(−1/2), 2^(−10 j) with j the
  /// whole number nearest to log2 |W_ii| / 20, so that |W_ii| d_i² lies in [2^−10, 2^10]; 1 for
  /// |W_ii| there (every model in SI units), and for W_ii zero or not finite. Exact in binary:
  /// the scaled problem is the same problem. Cost: a logarithm.
  static double row_scale(double W_ii);

 private:
  // true when z_, w_ (k) satisfy the LCP of W, r to tolerance (w_ recomputed as W z + r)
  bool check(const Eigen::Ref<const MatrixXd>& W, const Eigen::Ref<const VectorXd>& r,
             double tolerance);

  Index max_size_ = 0, size_ = 0;
  VectorXd r_, z_, w_;              // (max_size) r̃, z̃, w̃ handed to Siconos, then z, w
  VectorXd d_;                      // (max_size) the scale D of the last solve (row_scale)
  std::vector<double> enum_dwork_;  // (3 m + m², m = min(max_size, kMaxEnumerated)) lcp_enum's
  std::vector<int> enum_iwork_;     // (2 m) lcp_enum's pivots and basis flags
  int info_ = 0;
  Solver solver_ = Solver::kLemke;
};

/// What happened at a contact during a run (RunStatistics::contact_events): an impact, release
/// or rest of a unilateral contact, or a stick or slip of a Coulomb contact (docs/contact.md,
/// "In a run"; docs/friction.md, "Stick and slip, as events").
struct ContactEvent {
  /// The kind of event.
  enum class Kind : unsigned char {
    kImpact,   ///< the gap closed with approaching speed: a velocity jump
    kRelease,  ///< a closed contact's multiplier would pull: it opens
    kRest,     ///< an impact below the rest speed closed the contact (an accumulation point)
    kStick,    ///< a sliding Coulomb contact stopped, and friction holds it: it sticks
    kSlip,     ///< a sticking Coulomb contact starts to slide (its holding force reached
               ///< mu_s N, an impact set it sliding, or its contact opened)
  };
  double t = 0.0;  ///< time of the event
  /// the unilateral constraint (System::constraint index); for a stick or slip, the constraint
  /// whose reaction gives the Coulomb contact's N (its normal constraint)
  Index constraint = -1;
  Kind kind = Kind::kImpact;  ///< impact, release, rest, stick or slip
  /// g' just before (impacts: < 0, approaching; a rest that held a contact closed before it:
  /// 0); stick, slip: the sliding speed |v_rel| just before (a stick: the stop's v_stop =
  /// 100 eps)
  double speed_before = 0.0;
  double speed_after = 0.0;  ///< g' just after; stick, slip: |v_rel| just after
  /// the contact's impulse Λ >= 0 (impacts); a rest's may pull, Λ < 0, by 1e-6 of its
  /// sequence's impulses: a contact held at rest with another that came to rest (a rocking
  /// block's lifting corner, docs/contact.md "Rest")
  double impulse = 0.0;
  /// the kinetic energy the event changed, T⁺ − T⁻ (<= 0: an impact never creates energy)
  double energy_change = 0.0;
  /// release: the contact's whole multiplier lambda + lambda_nonideal just before, with the
  /// contacts closed as they were (about 0 at a located release, whose criterion it is; the
  /// force it carried when an impact elsewhere lifts it off); NaN for the other kinds
  double force_before = std::numeric_limits<double>::quiet_NaN();
  /// stick, slip: the Coulomb contact's name (its friction force's, System::nonideal_name);
  /// empty for the other kinds
  std::string friction;
  /// slip: |the force that held the contact| just before, which reached friction_limit (its
  /// split of the reaction, docs/friction.md); NaN for a slip an impact or the contact's opening
  /// caused, and for the other kinds
  double holding_force = std::numeric_limits<double>::quiet_NaN();
  /// slip: mu_s N just before (NaN as holding_force)
  double friction_limit = std::numeric_limits<double>::quiet_NaN();
};

/// "impact", "release", "rest", "stick" or "slip". Cost O(1).
const char* to_string(ContactEvent::Kind kind);

}  // namespace ukdyn
