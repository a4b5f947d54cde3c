// ChainEstimator<N> bindings for N = 1, 2, 3, 4, 5 (one translation unit per group: parallel builds).
#include "bind_chain.hpp"

void bind_chains_small(pybind11::module_& m) {
  algid_bindings::bind_chains(m, std::integer_sequence<int, 1, 2, 3, 4, 5>{});
}
