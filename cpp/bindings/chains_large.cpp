// ChainEstimator<N> bindings for N = 12, 16, 20, 32, 50, 64 (one translation unit per group: parallel builds).
#include "bind_chain.hpp"

void bind_chains_large(pybind11::module_& m) {
  algid_bindings::bind_chains(m, std::integer_sequence<int, 12, 16, 20, 32, 50, 64>{});
}
