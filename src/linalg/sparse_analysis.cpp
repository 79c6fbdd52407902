// SPDX-License-Identifier: BSD-3-Clause
// SparseDecomposition, the analysis (once per workspace): block structure of M, pattern of A and
// W, pattern of G = W Wᵀ and the program that assembles it, AMD ordering of G (CHOLMOD), and the
// elimination tree and column counts of its LDLᵀ factor. Everything here may allocate.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <cholmod.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

namespace {
// the fill-reducing ordering of the symmetric pattern `upper` (column j: rows i <= j) by
// CHOLMOD's analysis with AMD; perm[k] is the row eliminated k-th
std::vector<int> amd_ordering(int m, const std::vector<std::vector<int>>& upper) {
  std::vector<int> perm(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) perm[std::size_t(k)] = k;
  if (m <= 1) return perm;
  std::size_t nnz = 0;
  for (const auto& c : upper) nnz += c.size();
  cholmod_common common;
  cholmod_start(&common);
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_AMD;
  common.postorder = 1;
  common.supernodal = CHOLMOD_SIMPLICIAL;
  common.print = 0;
  cholmod_sparse* S =
      cholmod_allocate_sparse(std::size_t(m), std::size_t(m), nnz, 1, 1, 1, CHOLMOD_REAL, &common);
  if (S) {
    int* p = static_cast<int*>(S->p);
    int* i = static_cast<int*>(S->i);
    double* x = static_cast<double*>(S->x);
    std::size_t at = 0;
    for (int j = 0; j < m; ++j) {
      p[j] = int(at);
      for (int r : upper[std::size_t(j)]) {
        i[at] = r;
        x[at] = (r == j) ? double(m) : 1.0;
        ++at;
      }
    }
    p[m] = int(at);
    cholmod_factor* F = cholmod_analyze(S, &common);
    if (F && F->Perm) {
      const int* P = static_cast<const int*>(F->Perm);
      for (int k = 0; k < m; ++k) perm[std::size_t(k)] = P[k];
    }
    cholmod_free_factor(&F, &common);
    cholmod_free_sparse(&S, &common);
  }
  cholmod_finish(&common);
  return perm;
}
}  // namespace

SparseDecomposition::SparseDecomposition(const System& sys)
    : n_(sys.coordinate_count()), m_(sys.constraint_rows()) {
  if (!sys.mass_is_block_diagonal()) {
    throw std::invalid_argument(
        "ukdyn::SparseDecomposition: the mass matrix is not block-diagonal (give it with "
        "SystemBuilder::mass_block, or use SolverOptions::engine = Engine::kDense)");
  }
  // --- M: blocks and their storage
  const auto& blocks = sys.mass_blocks();
  const std::size_t nb = blocks.size();
  blk_off_.resize(nb + 1);
  blk_val_.resize(nb + 1);
  blk_const_.resize(nb);
  Index v = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    blk_off_[b] = blocks[b].offset;
    blk_val_[b] = v;
    blk_const_[b] = blocks[b].constant() ? 1 : 0;
    v += blocks[b].size * blocks[b].size;
  }
  blk_off_[nb] = n_;
  blk_val_[nb] = v;
  Mv_.assign(std::size_t(v), 0.0);
  Lv_.assign(std::size_t(v), 0.0);
  inv_ldiag_.assign(std::size_t(n_), 0.0);
  for (std::size_t b = 0; b < nb; ++b) {
    if (blocks[b].constant()) mass_block(Index(b)) = blocks[b].value;
  }
  std::vector<int> blk_of(static_cast<std::size_t>(n_));
  for (std::size_t b = 0; b < nb; ++b) {
    for (Index c = blk_off_[b]; c < blk_off_[b + 1]; ++c) blk_of[std::size_t(c)] = int(b);
  }

  // --- A: each row is the run of the whole blocks its constraint touches
  const Index K = sys.constraint_count();
  con_r0_.resize(std::size_t(K));
  con_rows_.resize(std::size_t(K));
  local_pos_.resize(std::size_t(K));
  row_ptr_.assign(1, 0);
  seg_ptr_.assign(1, 0);
  std::vector<int> touched, seg_start;
  for (Index k = 0; k < K; ++k) {
    const Constraint& c = sys.constraint(k);
    const Index r0 = sys.row_offset(k), rows = c.rows();
    if (r0 != Index(row_ptr_.size()) - 1) {
      throw std::logic_error("ukdyn::SparseDecomposition: constraint rows are not contiguous");
    }
    con_r0_[std::size_t(k)] = r0;
    con_rows_[std::size_t(k)] = rows;
    const std::vector<Index>& cols = c.model().columns();
    touched.clear();
    if (cols.empty()) {
      for (std::size_t b = 0; b < nb; ++b) touched.push_back(int(b));
    } else {
      for (Index col : cols) touched.push_back(blk_of[std::size_t(col)]);
      std::sort(touched.begin(), touched.end());
      touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    }
    // offset of each touched block in the row, and of each local column
    seg_start.assign(touched.size(), 0);
    int len = 0;
    for (std::size_t s = 0; s < touched.size(); ++s) {
      seg_start[s] = len;
      len += int(blk_off_[std::size_t(touched[s]) + 1] - blk_off_[std::size_t(touched[s])]);
    }
    auto& lp = local_pos_[std::size_t(k)];
    for (Index col : cols) {
      const int b = blk_of[std::size_t(col)];
      const std::size_t s =
          std::size_t(std::lower_bound(touched.begin(), touched.end(), b) - touched.begin());
      lp.push_back(seg_start[s] + int(col - blk_off_[std::size_t(b)]));
    }
    for (Index r = 0; r < rows; ++r) {
      const int base = row_ptr_.back();
      for (std::size_t s = 0; s < touched.size(); ++s) {
        const std::size_t b = std::size_t(touched[s]);
        seg_blk_.push_back(int(b));
        seg_pos_.push_back(base + seg_start[s]);
        for (Index col = blk_off_[b]; col < blk_off_[b + 1]; ++col) col_.push_back(int(col));
      }
      seg_ptr_.push_back(int(seg_blk_.size()));
      row_ptr_.push_back(base + len);
    }
  }
  Av_.assign(col_.size(), 0.0);
  Wv_.assign(col_.size(), 0.0);

  // --- G = W Wᵀ: rows i, j are coupled when they share a block
  const int m = int(m_);
  std::vector<std::vector<std::pair<int, int>>> rows_of_block(nb);  // (row, segment position)
  for (int i = 0; i < m; ++i) {
    for (int s = seg_ptr_[std::size_t(i)]; s < seg_ptr_[std::size_t(i) + 1]; ++s) {
      rows_of_block[std::size_t(seg_blk_[std::size_t(s)])].emplace_back(i,
                                                                        seg_pos_[std::size_t(s)]);
    }
  }
  std::vector<std::vector<int>> upper(
      static_cast<std::size_t>(m));  // original order, column j: rows i <= j
  for (int i = 0; i < m; ++i) upper[std::size_t(i)].push_back(i);
  for (const auto& rb : rows_of_block) {
    for (const auto& [i, pi] : rb) {
      for (const auto& [j, pj] : rb) {
        if (i < j) upper[std::size_t(j)].push_back(i);
      }
    }
  }
  for (auto& c : upper) {
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }
  // ordering, and G permuted: P G Pᵀ, upper triangle by columns
  perm_ = amd_ordering(m, upper);
  pinv_.assign(std::size_t(m), 0);
  for (int k = 0; k < m; ++k) pinv_[std::size_t(perm_[std::size_t(k)])] = k;
  std::vector<std::vector<int>> pcols(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) {
    for (int i : upper[std::size_t(j)]) {
      const int a = pinv_[std::size_t(i)], b = pinv_[std::size_t(j)];
      pcols[std::size_t(std::max(a, b))].push_back(std::min(a, b));
    }
  }
  Gp_.assign(std::size_t(m) + 1, 0);
  for (int j = 0; j < m; ++j) {
    auto& c = pcols[std::size_t(j)];
    std::sort(c.begin(), c.end());
    Gp_[std::size_t(j) + 1] = Gp_[std::size_t(j)] + int(c.size());
    Gi_.insert(Gi_.end(), c.begin(), c.end());
  }
  Gx_.assign(Gi_.size(), 0.0);
  Gdiag_.assign(std::size_t(m), 0);
  for (int j = 0; j < m; ++j) Gdiag_[std::size_t(j)] = Gp_[std::size_t(j) + 1] - 1;  // last row = j
  const auto index_of = [&](int i, int j) {
    const int a = pinv_[std::size_t(i)], b = pinv_[std::size_t(j)];
    const int col = std::max(a, b), row = std::min(a, b);
    const auto first = Gi_.begin() + Gp_[std::size_t(col)];
    const auto last = Gi_.begin() + Gp_[std::size_t(col) + 1];
    return int(std::lower_bound(first, last, row) - Gi_.begin());
  };
  // the assembly program: G_ij += w_ib · w_jb over the blocks b that rows i and j share
  for (std::size_t b = 0; b < nb; ++b) {
    const int len = int(blk_off_[b + 1] - blk_off_[b]);
    for (const auto& [i, pi] : rows_of_block[b]) {
      for (const auto& [j, pj] : rows_of_block[b]) {
        if (i <= j) program_.push_back(Product{index_of(i, j), pi, pj, len});
      }
    }
  }
  std::sort(program_.begin(), program_.end(),
            [](const Product& x, const Product& y) { return x.target < y.target; });
  // the first product of each entry assigns it (compute_constraints), the rest add to it (every
  // entry has one: a row's columns are whole blocks, and a row with no local columns is dense)
  {
    std::vector<Product> rest;
    int last = -1;
    for (const Product& pr : program_) {
      if (pr.target != last) {
        program_first_.push_back(pr);
        last = pr.target;
      } else {
        rest.push_back(pr);
      }
    }
    program_.swap(rest);
  }

  // --- symbolic LDLᵀ of P G Pᵀ: elimination tree and column counts; the rows whose pivot is
  // known to carry little roundoff (pivot_margin_, see factor_G): every row in the pattern of
  // row k has an empty pattern itself, so that L_G restricted to them is the identity and
  // d_k = G_kk − Σ_i G_ik² / G_ii with no earlier elimination in it
  parent_.assign(std::size_t(m), -1);
  flag_.assign(std::size_t(m), -1);
  Lnz_.assign(std::size_t(m), 0);
  pivot_margin_.assign(std::size_t(m), HUGE_VAL);
  std::vector<int> row_count(std::size_t(m), 0);
  for (int k = 0; k < m; ++k) {
    flag_[std::size_t(k)] = k;
    bool leaves_only = true;
    for (int p = Gp_[std::size_t(k)]; p < Gp_[std::size_t(k) + 1]; ++p) {
      for (int i = Gi_[std::size_t(p)]; i < k && flag_[std::size_t(i)] != k;
           i = parent_[std::size_t(i)]) {
        if (parent_[std::size_t(i)] == -1) parent_[std::size_t(i)] = k;
        ++Lnz_[std::size_t(i)];
        ++row_count[std::size_t(k)];
        if (row_count[std::size_t(i)] != 0) leaves_only = false;
        flag_[std::size_t(i)] = k;
      }
    }
    // the error of d_k: the products G_ik (n terms at most), the quotients and the sum —
    // (3p + 1) (n + 1) eps G_kk and (2p + 6) eps G_kk (p = row_count) — within this bound
    if (leaves_only) {
      pivot_margin_[std::size_t(k)] = 4.0 * double(row_count[std::size_t(k)] + 1) * double(n_ + 2) *
                                      std::numeric_limits<double>::epsilon();
    }
  }
  Lp_.assign(std::size_t(m) + 1, 0);
  for (int k = 0; k < m; ++k) Lp_[std::size_t(k) + 1] = Lp_[std::size_t(k)] + Lnz_[std::size_t(k)];
  Li_.assign(std::size_t(Lp_[std::size_t(m)]), 0);
  Lx_.assign(std::size_t(Lp_[std::size_t(m)]), 0.0);
  D_.assign(std::size_t(m), 0.0);
  Y_.assign(std::size_t(m), 0.0);
  // the pattern of each row k of L_G in the order factor_G eliminates it: the union of the
  // elimination-tree paths from the entries of column k of G, each path pushed in reverse (a
  // topological order). It is structural, so it is found here once and factor_G only reads it.
  // pattern_ holds the m + 1 starts (indices into pattern_), then the rows (nnz(L_G) entries)
  {
    const std::size_t ms = static_cast<std::size_t>(m);
    std::vector<int> mark(ms, -1), path(ms), row(ms);
    std::vector<int> starts(std::size_t(m) + 1, 0), rows;
    for (int k = 0; k < m; ++k) {
      mark[std::size_t(k)] = k;
      int top = m;
      for (int p = Gp_[std::size_t(k)]; p < Gp_[std::size_t(k) + 1]; ++p) {
        int len = 0;
        for (int i = Gi_[std::size_t(p)]; mark[std::size_t(i)] != k; i = parent_[std::size_t(i)]) {
          path[std::size_t(len++)] = i;
          mark[std::size_t(i)] = k;
        }
        while (len > 0) row[std::size_t(--top)] = path[std::size_t(--len)];
      }
      rows.insert(rows.end(), row.begin() + top, row.end());
      starts[std::size_t(k) + 1] = int(rows.size());
    }
    pattern_.assign(starts.begin(), starts.end());
    for (int& s : pattern_) s += m + 1;
    pattern_.insert(pattern_.end(), rows.begin(), rows.end());
  }
  dropped_.assign(std::size_t(m), 0);
  N_.setZero(m_, std::min<Index>(m_, kReservedNullity));
  null_rows_.assign(std::size_t(N_.cols()), 0);
  wm_.assign(std::size_t(m), 0.0);
  wm2_.assign(std::size_t(m), 0.0);
  wm3_.assign(std::size_t(m), 0.0);
  wm4_.assign(std::size_t(m), 0.0);
  row_scale_.assign(std::size_t(m), 1.0);
  wn_.assign(std::size_t(n_), 0.0);
  wn2_.assign(std::size_t(n_), 0.0);
  wn3_.assign(std::size_t(n_), 0.0);
  // rows local to one block (a single segment): the rows a singular block is augmented with;
  // blocks singular by construction (MassBlock::singular) take that path from the start
  blk_sing_.assign(nb, 0);
  blk_known_.assign(nb, 0);
  for (std::size_t b = 0; b < nb; ++b) {
    if (blocks[b].singular) blk_sing_[b] = blk_known_[b] = 1;
  }
  singular_blocks_ = Index(std::count(blk_sing_.begin(), blk_sing_.end(), 1));
  aug_g_.assign(std::size_t(m), 0.0);
  local_row_ptr_.assign(nb + 1, 0);
  for (int i = 0; i < m; ++i) {
    if (seg_ptr_[std::size_t(i) + 1] - seg_ptr_[std::size_t(i)] == 1) {
      ++local_row_ptr_[std::size_t(seg_blk_[std::size_t(seg_ptr_[std::size_t(i)])]) + 1];
    }
  }
  for (std::size_t b = 0; b < nb; ++b) local_row_ptr_[b + 1] += local_row_ptr_[b];
  local_rows_.assign(std::size_t(local_row_ptr_[nb]), 0);
  std::vector<int> fill(local_row_ptr_.begin(), local_row_ptr_.end() - 1);
  for (int i = 0; i < m; ++i) {
    if (seg_ptr_[std::size_t(i) + 1] - seg_ptr_[std::size_t(i)] == 1) {
      local_rows_[std::size_t(
          fill[std::size_t(seg_blk_[std::size_t(seg_ptr_[std::size_t(i)])])]++)] = i;
    }
  }
}

SparseDecomposition::~SparseDecomposition() = default;
SparseDecomposition::SparseDecomposition(SparseDecomposition&&) noexcept = default;
SparseDecomposition& SparseDecomposition::operator=(SparseDecomposition&&) noexcept = default;

SparseDecomposition& SparseDecomposition::set_threshold(double threshold) {
  if (!(threshold > 0.0 && threshold < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::SparseDecomposition::set_threshold: the relative rank threshold must lie in "
        "(0, 1), got " +
        format_number(threshold));
  }
  threshold_ = threshold;
  return *this;
}

}  // namespace ukdyn
