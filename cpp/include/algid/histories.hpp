#pragma once
/// @file histories.hpp
/// Where ChainEstimator::record() writes the estimates after every sample of a record: the
/// histories a batch caller keeps (the Python `run()` returns them as numpy arrays).

#include "algid/types.hpp"

#include <cstdint>

namespace algid {

/// Caller-owned, row-major histories of a record of T samples: row t holds what the accessors
/// of the same name return after sample t (NaN where not valid). Every pointer must be valid
/// for its T rows; nothing is allocated or freed.
template <class Scalar>
struct Histories {
  std::int8_t* status = nullptr;  ///< T: the Status of each sample, as an integer
  Scalar* mass = nullptr;         ///< T x N: m_i [kg]
  Scalar* damping = nullptr;      ///< T x N: c_i [N s/m]
  Scalar* stiffness = nullptr;    ///< T x (N + 1): k_1 .. k_{N+1} [N/m]
  bool* valid = nullptr;          ///< T x N: validity of DOF i's estimates
};

}  // namespace algid
