#pragma once
/// @file histories.hpp
/// Where ChainEstimator::record() and ContinuousEstimator::record() write the estimates after
/// the samples of a record: the histories a batch caller keeps (the Python `run()` returns them
/// as numpy arrays).

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

/// Caller-owned, row-major histories of a ContinuousEstimator's record of T samples: the
/// status of every sample, and every `stride`-th sample's estimates (rows = ceil(T / stride)).
/// Every pointer must be valid for its rows; nothing is allocated or freed.
template <class Scalar>
struct ContinuousHistories {
  std::int8_t* status = nullptr;   ///< T: the Status of each sample, as an integer
  Scalar* estimate = nullptr;      ///< rows x (3n+1): estimate() after samples 0, stride, 2 stride, ...
  Scalar* sigma = nullptr;         ///< rows x (3n+1): sigma() after the same samples
  std::int64_t* sample = nullptr;  ///< rows: the index of each row's sample (samples() - 1 after it)
  long stride = 1;                 ///< samples per row, >= 1
};

}  // namespace algid
