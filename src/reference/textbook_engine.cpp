// The textbook engine: the dense engine (dynamics/dense_engine.hpp) on TextbookDecomposition,
// eqs. (9)–(12) as printed (M^{±1/2} by eigendecomposition, B⁺ by SVD). Algorithm::kTextbook;
// a reference, not a production path (it allocates on every evaluation).
#include "dynamics/dense_engine.hpp"
#include "ukdyn/reference/reference.hpp"

namespace ukdyn::detail {

template <>
TextbookDecomposition& decomposition_of<TextbookDecomposition>(Workspace& ws) {
  return *ws.textbook;
}

const EngineOps& textbook_engine() {
  static const DenseEngine<TextbookDecomposition> engine;
  return engine;
}

}  // namespace ukdyn::detail
