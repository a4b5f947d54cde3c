#pragma once
/// @file robust.hpp
/// Allocation-free robust statistics on small fixed buffers (internals of ContinuousEstimator).

#include <algorithm>
#include <cmath>
#include <limits>

namespace algid {
namespace detail {

/// Median of `values[0..count)`, reordering them in place (nth_element; O(count)).
/// The mean of the two middle values for an even count; NaN for count = 0.
/// @realtime no allocation, no throw
template <class Scalar>
Scalar median_inplace(Scalar* values, int count) noexcept {
  if (count <= 0) return std::numeric_limits<Scalar>::quiet_NaN();
  const int mid = count / 2;
  std::nth_element(values, values + mid, values + count);
  const Scalar upper = values[mid];
  if (count % 2) return upper;
  const Scalar lower = *std::max_element(values, values + mid);
  return Scalar(0.5) * (lower + upper);
}

/// Median absolute deviation from `center` of `values[0..count)`, reordering them in place.
/// @realtime no allocation, no throw
template <class Scalar>
Scalar mad_inplace(Scalar* values, int count, Scalar center) noexcept {
  for (int i = 0; i < count; ++i) values[i] = std::abs(values[i] - center);
  return median_inplace(values, count);
}

/// Consistency factor of the MAD for a Gaussian: sigma ~ kMadToSigma * MAD.
template <class Scalar>
constexpr Scalar kMadToSigma = Scalar(1.482602218505602);

/// Standard deviation of the sample median relative to that of the mean, large-sample
/// Gaussian value sqrt(pi / 2).
template <class Scalar>
constexpr Scalar kMedianInefficiency = Scalar(1.2533141373155003);

}  // namespace detail
}  // namespace algid
