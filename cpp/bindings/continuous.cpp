// ContinuousEstimator of one extension module (see chains.cpp): the run-time sized
// ContinuousEstimatorDynamic serves every n. Its per-sample work is that of its weak-form
// windows, whose buffers are run-time sized for every N, so fixed-size instantiations would
// add compile time to every install and no speed (docs/performance.md).
#include "bind_estimators.hpp"

namespace algid_bindings {

void bind_continuous_classes(py::module_& m, bool local) {
  bind_continuous<algid::Dynamic>(m, "ContinuousEstimatorDynamic", local);
}

}  // namespace algid_bindings
