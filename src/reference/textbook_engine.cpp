// SPDX-License-Identifier: BSD-3-Clause
// The textbook engine: the dense engine (dynamics/dense_engine.hpp) on TextbookDecomposition,
// eqs. (9)–(12) as printed (M^{±1/2} by eigendecomposition, B⁺ by SVD). Algorithm::kTextbook;
// a reference, not a production path (it allocates on every evaluation). It lives in the
// reference library (target ukdyn::reference), not in the core: linking that library
// registers it with the core (dynamics/engine.hpp, TextbookProvider) before main.
#include "dynamics/dense_engine.hpp"
#include "ukdyn/reference/reference.hpp"

namespace ukdyn::detail {

template <>
TextbookDecomposition& decomposition_of<TextbookDecomposition>(Workspace& ws) {
  return *ws.textbook;
}

namespace {

TextbookDecomposition* make_textbook(Index n, Index m, double rank_threshold) {
  auto d = std::make_unique<TextbookDecomposition>(n, m);
  d->set_threshold(rank_threshold);
  return d.release();
}

void destroy_textbook(TextbookDecomposition* d) { delete d; }

const DenseEngine<TextbookDecomposition> kTextbookEngine;
const TextbookProvider kProvider{&make_textbook, &destroy_textbook, &kTextbookEngine};

// registers the engine when this object file is linked (ukdyn::reference is an OBJECT
// library, so its objects are always linked into the programs that name it)
[[maybe_unused]] const bool kRegistered = (register_textbook_provider(&kProvider), true);

}  // namespace
}  // namespace ukdyn::detail
