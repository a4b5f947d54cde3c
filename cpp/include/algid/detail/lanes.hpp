#pragma once
/// @file lanes.hpp
/// SIMD lanes: W values of one quantity side by side, one per DOF (or per signal) of a chain,
/// as an Eigen array of W scalars, and the few lane operations Eigen 3.4's arrays lack in
/// vectorised form: selects on comparisons, fused multiply-add, and moving every value one
/// lane up or down (a DOF's neighbours). Each has a plain scalar fallback, taken for lane
/// types that are not whole SIMD registers and for scalar types without packets (the
/// flop-counting scalar of the benchmarks), so the results do not depend on the path taken
/// except through fused multiply-adds.

#include <Eigen/Core>

#include <cstddef>
#include <type_traits>
#include <utility>

// The lane moves use the compilers' vector shuffles where the packets are plain vector types
// (x86 SSE / AVX / AVX-512 with GCC or Clang); elsewhere they move scalars.
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__SSE2__) || defined(__AVX__))
#define ALGID_LANE_SHUFFLE 1
#else
#define ALGID_LANE_SHUFFLE 0
#endif

namespace algid {
namespace detail {

/// f(std::integral_constant<int, i>) for i = Begin .. End - 1, unrolled at compile time.
template <int Begin, int End, class F>
inline void static_for(F&& f) {
  if constexpr (Begin < End) {
    f(std::integral_constant<int, Begin>{});
    static_for<Begin + 1, End>(f);
  }
}

/// W lanes of Scalar.
template <class Scalar, int W>
using Lanes = Eigen::Array<Scalar, W, 1>;

/// Lane width for a chain of N DOF: the SIMD register of Scalar in this build (Eigen's packet:
/// 2 doubles with SSE2, 4 with AVX), at most 256 bits wide, halved while a narrower register
/// still holds all N DOF. 256 bits also with AVX-512, as GCC prefers for its own vectorisation
/// there: 512-bit instructions lower the clock of many Intel CPUs and are split in two on AMD
/// Zen 4, where 8 lanes of double measured no faster than 4 (n = 50) and slower at n = 10
/// (16 lanes for 10 DOF).
template <int N, class Scalar>
constexpr int lane_width() noexcept {
  constexpr int packet = Eigen::internal::packet_traits<Scalar>::size;
  constexpr int widest = packet < int(32 / sizeof(Scalar)) ? packet : int(32 / sizeof(Scalar));
  int w = 1;
  while (w < N && w < widest) w *= 2;
  return w;
}

/// Lane operations on Lanes<Scalar, W>.
template <class Scalar, int W>
struct LaneOps {
  using L = Lanes<Scalar, W>;
  /// The SIMD register type that holds PW lanes (W is a multiple of PW when vectorised).
  using Packet = typename Eigen::internal::find_best_packet<Scalar, W>::type;
  static constexpr int PW = Eigen::internal::unpacket_traits<Packet>::size;
  static constexpr bool kVector = PW > 1 && W % PW == 0 &&
                                  static_cast<bool>(Eigen::internal::packet_traits<Scalar>::Vectorizable);

  /// a * b + c, fused where the build has FMA (one rounding), else multiply then add.
  static L madd(const L& a, const L& b, const L& c) noexcept {
    if constexpr (kVector) {
      using namespace Eigen::internal;
      L out;
      for (int k = 0; k < W; k += PW)
        pstoreu(out.data() + k,
                pmadd(ploadu<Packet>(a.data() + k), ploadu<Packet>(b.data() + k), ploadu<Packet>(c.data() + k)));
      return out;
    } else {
      return a * b + c;
    }
  }

// (a OP b) ? x : y, lane by lane; comparisons with NaN are false.
#define ALGID_LANE_SELECT(NAME, PCMP, OP)                                                                   \
  static L NAME(const L& a, const L& b, const L& x, const L& y) noexcept {                                  \
    L out;                                                                                                  \
    if constexpr (kVector) {                                                                                \
      using namespace Eigen::internal;                                                                      \
      for (int k = 0; k < W; k += PW) {                                                                     \
        const Packet mask = PCMP(ploadu<Packet>(a.data() + k), ploadu<Packet>(b.data() + k));               \
        pstoreu(out.data() + k, pselect(mask, ploadu<Packet>(x.data() + k), ploadu<Packet>(y.data() + k))); \
      }                                                                                                     \
    } else {                                                                                                \
      for (int k = 0; k < W; ++k) out(k) = a(k) OP b(k) ? x(k) : y(k);                                      \
    }                                                                                                       \
    return out;                                                                                             \
  }
  /// (a < b) ? x : y, lane by lane (false where either is NaN).
  ALGID_LANE_SELECT(if_less, pcmp_lt, <)
  /// (a <= b) ? x : y, lane by lane (false where either is NaN).
  ALGID_LANE_SELECT(if_less_equal, pcmp_le, <=)
  /// (a == b) ? x : y, lane by lane (false where either is NaN).
  ALGID_LANE_SELECT(if_equal, pcmp_eq, ==)
#undef ALGID_LANE_SELECT

  /// Every value one lane up: out(k) = x(k - 1), out(0) = below(W - 1). With the lanes of
  /// consecutive DOF, the value of the previous DOF (`below`: the register before x).
  static L from_previous(const L& x, const L& below) noexcept {
#if ALGID_LANE_SHUFFLE
    if constexpr (kVector && PW == W) {
      return shuffled<true>(x, below, std::make_index_sequence<W>());
    }
#endif
    L out;
    out(0) = below(W - 1);
    for (int k = 1; k < W; ++k) out(k) = x(k - 1);
    return out;
  }

  /// Every value one lane down: out(k) = x(k + 1), out(W - 1) = above(0): the value of the next
  /// DOF (`above`: the register after x).
  static L from_next(const L& x, const L& above) noexcept {
#if ALGID_LANE_SHUFFLE
    if constexpr (kVector && PW == W) {
      return shuffled<false>(x, above, std::make_index_sequence<W>());
    }
#endif
    L out;
    for (int k = 0; k + 1 < W; ++k) out(k) = x(k + 1);
    out(W - 1) = above(0);
    return out;
  }

 private:
#if ALGID_LANE_SHUFFLE
  // Lane k of the result: from_previous (Up) or from_next, as indices into (x, y).
  static constexpr int source(bool up, int k) noexcept {
    return up ? (k == 0 ? 2 * W - 1 : k - 1) : (k == W - 1 ? W : k + 1);
  }
  // Lanes of the concatenation (x, y) picked by source(), in registers.
  template <bool Up, std::size_t... K>
  static L shuffled(const L& x, const L& y, std::index_sequence<K...>) noexcept {
    using namespace Eigen::internal;
    const Packet px = ploadu<Packet>(x.data()), py = ploadu<Packet>(y.data());
#if defined(__clang__) || __GNUC__ >= 12
    const Packet r = __builtin_shufflevector(px, py, source(Up, static_cast<int>(K))...);
#else
    using Int = std::conditional_t<sizeof(Scalar) == 8, long long, int>;
    typedef Int Mask __attribute__((vector_size(sizeof(Packet))));
    const Mask mask = {source(Up, static_cast<int>(K))...};
    const Packet r = __builtin_shuffle(px, py, mask);
#endif
    L out;
    pstoreu(out.data(), r);
    return out;
  }
#endif
};

}  // namespace detail
}  // namespace algid
