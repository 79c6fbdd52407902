// SPDX-License-Identifier: BSD-3-Clause
// Model files, the generalized plant (modelfile/reader.hpp): kinetic_energy, potential_energy,
// mass_matrix and forces: → M(q, t), Q(q, q', t) and the external power, by symbolic derivatives:
//   Lagrangian      M = ∂²T/∂q̇∂q̇,  Q = ∂L/∂q − D(∂T/∂q̇) − ∂V/∂q … (L = T − V) + forces
// (D: total time derivative without q̈). Every error names file:line:column and gives a hint.
#include "ukdyn/modelfile/model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/options.hpp"

#include "modelfile/initial_keep.hpp"
#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

void Reader::read_dynamics(const YAML::Node& root, SystemBuilder& builder) {
  const Index n = Index(coordinates_.size());
  const YAML::Node T = root["kinetic_energy"], V = root["potential_energy"],
                   Mnode = root["mass_matrix"], F = root["forces"];
  if (T && Mnode) fail(Mnode, "give either kinetic_energy or mass_matrix, not both");
  if (!T && !Mnode) {
    throw ModelError(
        file_, 1, 1, "no dynamics: neither 'kinetic_energy' nor 'mass_matrix'",
        "add kinetic_energy: 0.5*m*x_dot^2 (and potential_energy), or mass_matrix and forces");
  }
  // M by its entries that are not the number 0 (row i, column j, entry), in row-major order:
  // a large M is mostly zeros, which are neither stored, differentiated nor compiled
  struct Entry {
    Index i, j;
    Expr e;
  };
  std::vector<Entry> M;
  std::vector<Expr> Q(static_cast<std::size_t>(n));
  const Expr zero = set_->constant(0.0);
  std::fill(Q.begin(), Q.end(), zero);
  const Expr Ve = V ? expression(V, "potential_energy") : zero;
  if (V) {
    if (const std::string* v = velocity_in(*set_, Ve, velocities_))
      fail(V, "potential_energy depends on the velocity '" + *v + "'");
  }
  // the external power P_ext (System::external_power): the rate of E = ½ q̇ᵀ M q̇ + V that V
  // does not account for, q̇ᵀ F + P_time (the forces F beside the energies, the explicit time
  // dependence); for a Lagrangian P_time = ∂V/∂t − ∂T/∂t + D T0, T0 = T(q̇ = 0), which is
  // T − q̇ · ∂T/∂q̇ + ½ q̇ᵀ M q̇; for a mass matrix P_time = ½ q̇ᵀ D(M) q̇ + ∂V/∂t
  std::vector<Expr> qdot;
  for (const auto& v : velocities_) qdot.push_back(set_->parse(v));
  Expr P_time = V ? set_->diff(Ve, "t") : zero;
  if (T) {
    // M = ∂²T/∂q̇∂q̇;  Q = ∂T/∂q − D(∂T/∂q̇) − ∂V/∂q (the q̈ part of D is M q̈)
    const Expr Te = expression(T, "kinetic_energy");
    // T0 = T − Σ q̇_i ∂T/∂q̇_i + Σ ½ q̇_i M_ij q̇_j, summed at once (the same expression as
    // term by term); only the velocities T holds give derivatives that are not 0
    std::vector<Expr> T0{Te};
    const std::vector<Index> in_T = set_->inputs_of(Te);
    for (Index i = 0; i < n; ++i) {
      const bool has_i = std::binary_search(in_T.begin(), in_T.end(), n + i);
      // ∂T/∂q̇_i = 0 when T does not hold q̇_i: then row i of M is 0
      const Expr dT = has_i ? set_->diff(Te, velocities_[std::size_t(i)]) : zero;
      if (has_i) T0.push_back(set_->negate(set_->multiply(qdot[std::size_t(i)], dT)));
      for (const Index k : has_i ? set_->inputs_of(dT) : std::vector<Index>()) {
        if (k < n || k >= 2 * n) continue;
        const Index j = k - n;
        const Expr e = set_->diff(dT, velocities_[std::size_t(j)]);
        // T must be quadratic in the velocities: M = ∂²T/∂q̇∂q̇ may not depend on them
        if (const std::string* v = velocity_in(*set_, e, velocities_)) {
          fail(T,
               "kinetic_energy is not quadratic in the velocities: its mass matrix depends "
               "on '" +
                   *v + "'",
               "T = ½ q̇ᵀ M(q, t) q̇ + (terms linear in q̇) + T0(q, t)");
        }
        if (!set_->is_literal_zero(e)) M.push_back({i, j, e});
      }
      // ∂T/∂q_i is 0 when T does not hold q_i (not differentiated)
      const Expr dTq = std::binary_search(in_T.begin(), in_T.end(), i)
                           ? set_->diff(Te, coordinates_[std::size_t(i)])
                           : zero;
      Q[std::size_t(i)] = set_->subtract(dTq, time_derivative(dT));
    }
    const Expr half = set_->constant(0.5);
    for (const Entry& m : M) {
      T0.push_back(set_->multiply(
          half,
          set_->multiply(qdot[std::size_t(m.i)], set_->multiply(m.e, qdot[std::size_t(m.j)]))));
    }
    P_time = set_->add(set_->subtract(P_time, set_->diff(Te, "t")),
                       set_->total_derivative(set_->sum(T0), "t", chain_));
  } else {
    if (!Mnode.IsSequence() || Index(Mnode.size()) != n) {
      fail(Mnode, "mass_matrix must be a list of " + format_number(n) + " rows",
           "one row per coordinate: [[m, 0], [0, m]]");
    }
    for (Index i = 0; i < n; ++i) {
      const YAML::Node row = Mnode[std::size_t(i)];
      if (!row.IsSequence() || Index(row.size()) != n) {
        fail(row, "row " + format_number(i + 1) + " of mass_matrix must have " + format_number(n) +
                      " entries");
      }
      for (Index j = 0; j < n; ++j) {
        const Expr e = expression(row[std::size_t(j)], "mass_matrix");
        if (const std::string* v = velocity_in(*set_, e, velocities_))
          fail(row[std::size_t(j)], "mass_matrix depends on the velocity '" + *v + "'");
        if (!set_->is_literal_zero(e)) M.push_back({i, j, e});
      }
    }
    // P_time + Σ ½ q̇_i D(M_ij) q̇_j, summed at once (the same expression as term by term)
    std::vector<Expr> terms{P_time};
    for (const Entry& m : M) {
      const Expr De = time_derivative(m.e);
      if (set_->is_literal_zero(De)) continue;
      terms.push_back(set_->multiply(
          set_->constant(0.5),
          set_->multiply(qdot[std::size_t(m.i)], set_->multiply(De, qdot[std::size_t(m.j)]))));
    }
    P_time = set_->sum(terms);
  }
  // − ∂V/∂q (0 for the q_i that V does not hold: not differentiated), and non-conservative
  // forces
  const std::vector<Index> in_V = V ? set_->inputs_of(Ve) : std::vector<Index>();
  for (Index i = 0; i < n; ++i) {
    if (V)
      Q[std::size_t(i)] =
          set_->subtract(Q[std::size_t(i)], std::binary_search(in_V.begin(), in_V.end(), i)
                                                ? set_->diff(Ve, coordinates_[std::size_t(i)])
                                                : zero);
  }
  if (F) {
    const auto rows = rows_of(F, "forces");
    if (Index(rows.size()) != n)
      fail(F, "forces must have " + format_number(n) + " entries, one per coordinate",
           cut_flow_list_hint(F, "forces"));
    // P = P_time + Σ q̇_i F_i, summed at once (the same expression as term by term, which was
    // O(n²) for n forces: each add copied the growing sum)
    std::vector<Expr> P{P_time};
    for (Index i = 0; i < n; ++i) {
      const Expr f = expression(rows[std::size_t(i)], "forces");
      Q[std::size_t(i)] = set_->add(Q[std::size_t(i)], f);
      P.push_back(set_->multiply(qdot[std::size_t(i)], f));
    }
    P_time = set_->sum(P);
  }
  const Expr P_ext = P_time;

  // M: a constant matrix when it depends on nothing (factorized once per workspace)
  bool constant = true;
  std::vector<Expr> entries;
  auto at = std::make_shared<std::vector<std::pair<Index, Index>>>();  // (i, j) of entries[k]
  for (const Entry& m : M) {
    constant = constant && set_->inputs_of(m.e).empty();
    entries.push_back(m.e);
    at->emplace_back(m.i, m.j);
  }
  const InputLayout layout = layout_;
  const YAML::Node dynamics = T ? T : Mnode;
  note_switches(entries);
  note_switches(Q);
  const Program Mp = compile(entries, dynamics,
                             T ? "the derivatives of kinetic_energy" : "mass_matrix"),
                Qp = compile(Q, dynamics, "the generalized forces");
  if (constant) {
    std::vector<double> in(std::size_t(layout.size()), 0.0), out(entries.size()),
        scratch(std::size_t(Mp.scratch_size()));
    Mp.evaluate(in.data(), out.data(), scratch.data());
    // a large block-diagonal M (uncoupled coordinates or groups of them) is given by its blocks,
    // which the sparse engine factorizes one by one (a dense M of 10⁴ coordinates is 800 MB):
    // the blocks start where no entry of the rows before reaches
    std::vector<Index> reach(
        static_cast<std::size_t>(n));  // the last row or column an entry of row i reaches
    for (Index i = 0; i < n; ++i) reach[std::size_t(i)] = i;
    for (const auto& [i, j] : *at) {
      Index& r = reach[std::size_t(std::min(i, j))];
      r = std::max(r, std::max(i, j));
    }
    std::vector<Index> starts{0};
    for (Index i = 0, end = 0; i + 1 < n; ++i) {
      end = std::max(end, reach[std::size_t(i)]);
      if (end == i) starts.push_back(i + 1);
    }
    std::vector<MatrixXd> blocks;
    if (n >= SolverOptions().sparse_threshold && starts.size() > 1) {
      starts.push_back(n);
      for (std::size_t k = 0; k + 1 < starts.size(); ++k) {
        const Index size = starts[k + 1] - starts[k];
        blocks.push_back(MatrixXd::Zero(size, size));
      }
      for (std::size_t k = 0; k < out.size(); ++k) {
        const auto [i, j] = (*at)[k];
        const std::size_t b =
            std::size_t(std::upper_bound(starts.begin(), starts.end(), i) - starts.begin()) - 1;
        blocks[b](i - starts[b], j - starts[b]) = out[k];
      }
      // only a symmetric positive definite M (else the checks of the dense M report it)
      for (const MatrixXd& B : blocks) {
        if (!B.allFinite() || B != B.transpose() ||
            Eigen::LLT<MatrixXd>(B).info() != Eigen::Success) {
          blocks.clear();
          break;
        }
      }
    }
    if (!blocks.empty()) {
      for (std::size_t b = 0; b < blocks.size(); ++b) builder.mass_block(starts[b], blocks[b]);
    } else {
      MatrixXd Mc = MatrixXd::Zero(n, n);
      for (std::size_t k = 0; k < out.size(); ++k) Mc((*at)[k].first, (*at)[k].second) = out[k];
      builder.mass_matrix(Mc);
    }
  } else {
    sizes_->fit(layout.size(), Mp);
    builder.mass_matrix([Mp, at, n](const Eigen::Ref<const VectorXd>& q, double t,
                                    CallableScratch* s, Eigen::Ref<MatrixXd> Mout) {
      ModelBuffers& b = model_buffers(s);
      std::copy(q.data(), q.data() + n, b.in.begin());
      b.in[std::size_t(2 * n)] = t;
      Mp.evaluate(b.in.data(), b.out.data(), b.scratch.data());
      Mout.setZero();
      for (std::size_t k = 0; k < at->size(); ++k) Mout((*at)[k].first, (*at)[k].second) = b.out[k];
    });
  }
  // the callables' buffers: one ModelBuffers per workspace, sized for every program of the model
  builder.scratch(BufferSizes::factory(sizes_));
  sizes_->fit(layout.size(), Qp);
  builder.forces([Qp, layout](const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s,
                              Eigen::Ref<VectorXd> Qout) {
    ModelBuffers& b = model_buffers(s);
    layout.fill(b.in, q, qd, t);
    Qp.evaluate(b.in.data(), Qout.data(), b.scratch.data());
  });
  // V and P_ext account for every force's work (the run's energy balance is checked)
  builder.accounts_for_energy();
  if (!set_->is_zero(P_ext)) {
    const Program Pp = compile({P_ext}, dynamics, "the external power");
    sizes_->fit(layout.size(), Pp);
    builder.external_power([Pp, layout](const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& qd, double t,
                                        CallableScratch* s) {
      ModelBuffers& b = model_buffers(s);
      layout.fill(b.in, q, qd, t);
      double p = 0.0;
      Pp.evaluate(b.in.data(), &p, b.scratch.data());
      return p;
    });
  }
  if (V) {
    const Program Vp = compile({Ve}, V, "potential_energy");
    sizes_->fit(layout.size(), Vp);
    builder.potential_energy(
        [Vp, layout](const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s) {
          ModelBuffers& b = model_buffers(s);
          std::copy(q.data(), q.data() + layout.n, b.in.begin());
          b.in[std::size_t(2 * layout.n)] = t;
          double v = 0.0;
          Vp.evaluate(b.in.data(), &v, b.scratch.data());
          return v;
        });
  }
}

}  // namespace ukdyn::model_reader
