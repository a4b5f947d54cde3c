// ContinuousEstimator classes of one extension module (see chains.cpp):
// ContinuousEstimator{N} for every N in FixedSizes and ContinuousEstimatorDynamic.
#include "bind_estimators.hpp"

#include <string>
#include <utility>

namespace algid_bindings {

template <int... Ns>
void bind_continuous_sizes(py::module_& m, bool local, std::integer_sequence<int, Ns...>) {
  (bind_continuous<Ns>(m, ("ContinuousEstimator" + std::to_string(Ns)).c_str(), local), ...);
  bind_continuous<algid::Dynamic>(m, "ContinuousEstimatorDynamic", local);
}

void bind_continuous_classes(py::module_& m, bool local) { bind_continuous_sizes(m, local, FixedSizes{}); }

}  // namespace algid_bindings
