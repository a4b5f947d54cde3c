// ChainEstimator<N> bindings for N = 6, 7, 8, 9, 10 (one translation unit per group: parallel builds).
#include "bind_chain.hpp"

void bind_chains_medium(pybind11::module_& m) {
  algid_bindings::bind_chains(m, std::integer_sequence<int, 6, 7, 8, 9, 10>{});
}
