#pragma once
/// @file one_force.hpp
/// The DOF without force of a ChainEstimator (chain_estimator.hpp, file comment, "One force"):
/// which DOF are forced since t0, the homogeneous system a DOF without force solves instead
/// of eq. 5 (its mass set to 1), and its scale carried along the springs from the nearest
/// forced DOF once eq. 7 has its ratios. The DOF sit in the owner's SIMD lanes (DOF i in lane
/// i % W of register i / W); every call below is per sample and O(n).

#include "algid/detail/lanes.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

namespace algid {
namespace detail {

/// The forced DOF of a chain of n DOF in registers of W lanes, and the scale of the others.
/// @tparam Scalar double or float. @tparam W lanes per register.
/// @tparam Registers registers of DOF, or Dynamic. @tparam Dofs DOF, or Dynamic.
template <class Scalar, int W, int Registers, int Dofs>
class OneForce {
 public:
  using L = Lanes<Scalar, W>;
  using Ops = LaneOps<Scalar, W>;

  /// Configure for n DOF and allocate (Dofs == Dynamic only).
  void configure(int n) {
    n_ = n;
    forced_.resize(registers());
    left_mass_.resize(n);
    left_reach_.resize(n);
    scaled_by_.resize(n);
    reset();
  }

  /// No force seen yet (a new t0). @realtime no allocation, no throw
  void reset() noexcept {
    // the lanes beyond the last DOF count as forced (they never join a DOF)
    forced_.fill(L::Zero());
    for (int i = n_; i < registers() * W; ++i) forced_[i / W](i % W) = Scalar(1);
    all_forced_ = false;
    for (int i = 0; i < n_; ++i) scaled_by_[i] = kUnscaled;
  }

  /// Whether every DOF is forced (then nothing below has anything to do).
  bool all_forced() const noexcept { return all_forced_; }
  /// Whether DOF i (0-based) has had a non-zero force since t0.
  bool forced(int i) const noexcept { return forced_[i / W](i % W) > Scalar(0); }

  /// Note the forces [N] of a sample (n values): a DOF is forced from its first non-zero force
  /// sample since t0 on (before it, every integral of its force is zero); its system then
  /// changes from the homogeneous one and its lane of eq. 7 restarts (`ratio[g].restart()`).
  /// @realtime no allocation, no throw
  template <class Ratios>
  void note(const Scalar* force, Ratios& ratio) noexcept {
    if (all_forced_) return;
    bool all = true;
    for (int g = 0; g < registers(); ++g) {
      L now = forced_[g];
      for (int k = 0, i = g * W; k < W && i < n_; ++k, ++i)
        if (force[i] != Scalar(0)) now(k) = Scalar(1);
      const L switched = now - forced_[g];
      if ((switched > Scalar(0)).any()) ratio[g].restart(switched);
      forced_[g] = now;
      all &= (now > Scalar(0)).all();
    }
    all_forced_ = all;
  }

  /// `if_forced` in the lanes of register g whose DOF is forced, `otherwise` elsewhere.
  /// @realtime no allocation, no throw
  L select(int g, const L& if_forced, const L& otherwise) const noexcept {
    return Ops::if_less(L::Zero(), forced_[g], if_forced, otherwise);
  }

  /// The homogeneous system of a DOF without force, in the 4x4 layout (column-major S, s) of
  /// register g; `reduced` is 1 in the lane of a 3x3 DOF. Its last row (row 3; row 2 for the
  /// 3x3 DOF of a free end, whose row 3 is the identity's) becomes m_i = 1 and its right-hand
  /// side is zero elsewhere, so Cramer's rule returns [1, c_i / m_i, k_i / m_i, k_{i+1} / m_i]
  /// from rows 0-2 (0-1), and |det S| is that of those rows and columns c_i, k_i, k_{i+1}
  /// (c_n, k_n). @realtime no allocation, no throw
  void homogeneous_rows(int g, const L& reduced, L* S, L* s) const noexcept {
    const L zero = L::Zero(), one = L::Ones();
    const L row3 = Ops::if_less(zero, forced_[g], zero, Ops::if_less(zero, reduced, zero, one));
    const L row2 = Ops::if_less(zero, forced_[g], zero, reduced);
    for (int q = 0; q < 4; ++q) s[q] = Ops::if_less(zero, forced_[g], s[q], zero);
    s[3] = Ops::if_less(zero, row3, one, s[3]);
    s[2] = Ops::if_less(zero, row2, one, s[2]);
    for (int c = 0; c < 4; ++c) {
      const L entry = c == 0 ? one : zero;
      S[c * 4 + 3] = Ops::if_less(zero, row3, entry, S[c * 4 + 3]);
      S[c * 4 + 2] = Ops::if_less(zero, row2, entry, S[c * 4 + 2]);
    }
  }

  /// The scale of the DOF without force, in the eq. 7 estimates `estimate[j]` (slot j of every
  /// DOF, in lanes), which hold [1, c_i / m_i, k_i / m_i, k_{i+1} / m_i] for them: a neighbour
  /// with a scale estimates the spring they share, and m_i = k_shared / (k_shared / m_i). Left
  /// to right, each DOF's mass from the nearest forced DOF on its left (through the springs
  /// between them), then right to left the same from the right; the nearer wins, equally near
  /// ones are averaged. Their lanes are then overwritten with m_i times the ratios; a DOF that
  /// no forced DOF reaches through valid estimates is NaN. @realtime no allocation, no throw
  template <class Estimates>
  void propagate(Estimates (&estimate)[4]) noexcept {
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    constexpr int far = std::numeric_limits<int>::max();
    Scalar carried = nan;  // the spring on the right of the last DOF, scaled
    int reach = far;       // DOF from that estimate to its forced DOF
    for (int i = 0; i < n_; ++i) {
      if (forced(i)) {
        left_mass_[i] = nan;
        left_reach_[i] = 0;
        carried = lane(estimate[3], i);
        reach = 0;
        continue;
      }
      const Scalar m = carried / lane(estimate[2], i);
      const bool ok = std::isfinite(m);
      left_mass_[i] = ok ? m : nan;
      left_reach_[i] = ok ? reach + 1 : far;
      carried = ok ? m * lane(estimate[3], i) : nan;
      reach = left_reach_[i];
    }
    carried = nan;  // the spring on the left of the last DOF, scaled
    reach = far;
    for (int i = n_ - 1; i >= 0; --i) {
      if (forced(i)) {
        scaled_by_[i] = kForced;
        carried = lane(estimate[2], i);
        reach = 0;
        continue;
      }
      const Scalar ratio[3] = {lane(estimate[1], i), lane(estimate[2], i), lane(estimate[3], i)};
      const Scalar right = carried / ratio[2];
      const int right_reach = std::isfinite(right) ? reach + 1 : far;
      const Scalar left = left_mass_[i];
      const int left_reach = left_reach_[i];
      Scalar m = nan;
      Scale by = kUnscaled;
      if (left_reach < right_reach) {
        m = left;
        by = kFromLeft;
      } else if (right_reach < left_reach) {
        m = right;
        by = kFromRight;
      } else if (left_reach < far) {
        m = Scalar(0.5) * (left + right);
        by = kFromBoth;
      }
      scaled_by_[i] = by;
      set_lane(estimate[0], i, m);
      for (int j = 0; j < 3; ++j) set_lane(estimate[j + 1], i, m * ratio[j]);
      carried = right_reach < far ? right * ratio[1] : nan;
      reach = right_reach;
    }
  }

  /// After propagate(): a fused spring k_j (`spring`, lane j) between a DOF and the neighbour
  /// that took its scale through it alone is not a mean: both estimates are the same number,
  /// the scaled side's. @realtime no allocation, no throw
  template <class Estimates>
  void carried_springs(const Estimates (&estimate)[4], Estimates& spring) const noexcept {
    for (int j = 1; j < n_; ++j) {
      if (scaled_by_[j] == kFromLeft) set_lane(spring, j, lane(estimate[3], j - 1));
      if (scaled_by_[j - 1] == kFromRight) set_lane(spring, j, lane(estimate[2], j));
    }
  }

 private:
  // How a DOF has its scale: its force, the spring on its left (k_i), on its right (k_{i+1}),
  // both (equally near forced DOF: the mean of the two masses), or none.
  enum Scale : std::int8_t { kForced, kFromLeft, kFromRight, kFromBoth, kUnscaled };

  int registers() const noexcept { return Registers == Dynamic ? (n_ + W - 1) / W : Registers; }
  template <class R>
  static Scalar lane(const R& registers, int i) noexcept {
    return registers[i / W](i % W);
  }
  template <class R>
  static void set_lane(R& registers, int i, Scalar value) noexcept {
    registers[i / W](i % W) = value;
  }

  int n_ = 0;
  // 1 in the lanes of a DOF whose force was non-zero at a sample since t0 (and in the lanes
  // beyond the last DOF), 0 where its system is homogeneous; whether all are 1.
  Storage<L, Registers> forced_{};
  bool all_forced_ = false;
  // propagate(): the masses from the left and their distance to the forced DOF [DOF], and how
  // each DOF has its scale (Scale).
  Storage<Scalar, Dofs> left_mass_{};
  Storage<int, Dofs> left_reach_{};
  Storage<std::int8_t, Dofs> scaled_by_{};
};

}  // namespace detail
}  // namespace algid
