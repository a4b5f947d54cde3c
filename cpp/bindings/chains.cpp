// ChainEstimator classes of one extension module (algid._core, _core_v3 or _core_v4: the same
// sources built for each instruction set, see CMakeLists.txt): ChainEstimator{N} for every N
// in FixedSizes and ChainEstimatorDynamic for any other n.
#include "bind_estimators.hpp"

#include <string>
#include <utility>

namespace algid_bindings {

template <int... Ns>
void bind_chains(py::module_& m, bool local, std::integer_sequence<int, Ns...>) {
  (bind_chain<Ns>(m, ("ChainEstimator" + std::to_string(Ns)).c_str(), local), ...);
  bind_chain<algid::Dynamic>(m, "ChainEstimatorDynamic", local);
}

void bind_chain_classes(py::module_& m, bool local) { bind_chains(m, local, FixedSizes{}); }

py::tuple chain_sizes() { return sizes_tuple(FixedSizes{}); }

}  // namespace algid_bindings
