// Firmware-style use of the estimator: a 3-DOF chain (Table 1 of the paper) sampled by a 1 kHz
// "interrupt" that pushes accelerations and forces into a lock-free ring buffer; the main loop
// drains the buffer and feeds a statically allocated algid::ChainEstimator<3> sample by sample.
//
// No heap anywhere (no std::vector, no new), no exceptions, no RTTI: the test suite builds this
// file with -fno-exceptions -fno-rtti -Wall -Wextra -Wconversion -Wshadow -Werror and runs it.
// The configuration is checked with the non-throwing validate() before construction.
//
// Check: every estimate (m_1..3, c_1..3, k_1..4) within 1 % of the truth at every sample from
// t0 + 0.1 s to the end of the run (0.5 s), for the double estimator and for a float one (the
// single-precision FPU case). Prints the estimates and "firmware_loop: N passed, N failed";
// exits 0 on success.
#include <algid/algid.hpp>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>

namespace {

// ---- The plant (stands in for the hardware) -------------------------------------------------

constexpr int kDofs = 3;
constexpr double kMass[kDofs] = {2.0, 2.5, 3.0};              // [kg]
constexpr double kDamping[kDofs] = {5.5, 5.0, 4.5};           // [N s/m]
constexpr double kStiffness[kDofs + 1] = {1000, 900, 900, 700};  // [N/m], walls at both ends
constexpr double kSamplePeriod = 1e-3;                        // [s], 1 kHz
constexpr double kPi = 3.14159265358979323846;

// Actuator force [N] on DOF i: a multisine, three tones per DOF between 1.3 and 17 Hz.
double actuator_force(int i, double t) {
  const double di = static_cast<double>(i);
  const double freq[3] = {1.3 + 0.7 * di, 5.1 + 1.9 * di, 11.0 + 3.1 * di};  // [Hz]
  const double amp[3] = {10.0, 6.0, 4.0};                                    // [N]
  double u = 0;
  for (int q = 0; q < 3; ++q) u += amp[q] * std::sin(2 * kPi * freq[q] * t + 0.9 * q + 0.4 * di);
  return u;
}

// Eq. 1: accelerations [m/s^2] from positions [m], velocities [m/s] and time [s].
void plant_accel(const double* x, const double* v, double t, double* a) {
  for (int i = 0; i < kDofs; ++i) {
    const double left = i > 0 ? x[i - 1] : 0.0;
    const double right = i + 1 < kDofs ? x[i + 1] : 0.0;
    a[i] = (actuator_force(i, t) - kDamping[i] * v[i] - kStiffness[i] * (x[i] - left) -
            kStiffness[i + 1] * (x[i] - right)) /
           kMass[i];
  }
}

// The plant state, advanced by classical RK4 with 16 substeps per sample period (accurate to
// ~1e-12 relative, so the check below measures the estimator, not the simulation).
struct Plant {
  double x[kDofs] = {0, 0, 0};  // [m], starts at rest
  double v[kDofs] = {0, 0, 0};  // [m/s]
  double t = 0;                 // [s]

  void advance(double period) {
    constexpr int kSub = 16;
    const double h = period / kSub;
    for (int s = 0; s < kSub; ++s) {
      double kx[4][kDofs], kv[4][kDofs], xt[kDofs], vt[kDofs];
      const double stage_t[4] = {t, t + 0.5 * h, t + 0.5 * h, t + h};
      const double stage_w[4] = {0.0, 0.5, 0.5, 1.0};
      for (int st = 0; st < 4; ++st) {
        for (int i = 0; i < kDofs; ++i) {
          xt[i] = st ? x[i] + stage_w[st] * h * kx[st - 1][i] : x[i];
          vt[i] = st ? v[i] + stage_w[st] * h * kv[st - 1][i] : v[i];
          kx[st][i] = vt[i];
        }
        plant_accel(xt, vt, stage_t[st], kv[st]);
      }
      for (int i = 0; i < kDofs; ++i) {
        x[i] += h / 6 * (kx[0][i] + 2 * kx[1][i] + 2 * kx[2][i] + kx[3][i]);
        v[i] += h / 6 * (kv[0][i] + 2 * kv[1][i] + 2 * kv[2][i] + kv[3][i]);
      }
      t += h;
    }
  }
};

// ---- The firmware ------------------------------------------------------------------------------

/// One simultaneous sample of the sensors: accelerations [m/s^2] and actuator forces [N].
struct Sample {
  double accel[kDofs];
  double force[kDofs];
};

/// Single-producer (interrupt) / single-consumer (main loop) ring buffer, statically sized.
/// @tparam Capacity number of slots, a power of two; holds Capacity - 1 samples.
template <unsigned Capacity>
class SampleRing {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "capacity must be a power of two");

 public:
  /// Interrupt side. Returns false (and drops the sample) when the main loop has fallen behind.
  bool push(const Sample& s) {
    const unsigned head = head_.load(std::memory_order_relaxed);
    const unsigned next = (head + 1) & (Capacity - 1);
    if (next == tail_.load(std::memory_order_acquire)) return false;
    slots_[head] = s;
    head_.store(next, std::memory_order_release);
    return true;
  }
  /// Main-loop side. Returns false when empty.
  bool pop(Sample& s) {
    const unsigned tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    s = slots_[tail];
    tail_.store((tail + 1) & (Capacity - 1), std::memory_order_release);
    return true;
  }

 private:
  std::array<Sample, Capacity> slots_{};
  std::atomic<unsigned> head_{0};
  std::atomic<unsigned> tail_{0};
};

Plant g_plant;                // the hardware
SampleRing<16> g_ring;        // 16 slots: 15 ms of slack for the main loop at 1 kHz
unsigned g_dropped = 0;       // samples lost to a full ring (must stay 0)

/// The 1 kHz sampling interrupt: read the accelerometers and the force sensors of the current
/// instant, queue them, and let the world move on by one sample period.
void sampling_isr() {
  Sample s;
  plant_accel(g_plant.x, g_plant.v, g_plant.t, s.accel);
  for (int i = 0; i < kDofs; ++i) s.force[i] = actuator_force(i, g_plant.t);
  if (!g_ring.push(s)) ++g_dropped;
  g_plant.advance(kSamplePeriod);
}

int g_passed = 0;
int g_failed = 0;

void check(bool ok, const char* what) {
  if (ok) {
    ++g_passed;
  } else {
    ++g_failed;
    std::printf("FAIL: %s\n", what);
  }
}

/// The estimator task for one scalar type: drains the ring after every "tick" burst.
template <class Scalar>
void run_task(const char* label) {
  using Estimator = algid::ChainEstimator<kDofs, Scalar>;
  typename Estimator::Config config;
  config.dt = static_cast<Scalar>(kSamplePeriod);
  config.boundary = algid::Boundary::kFixed;
  // Firmware: validate instead of relying on the constructor's error path.
  if (Estimator::validate(config) != algid::ConfigError::kNone) {
    check(false, "configuration rejected");
    return;
  }
  static Estimator estimator(config);  // static storage: no heap, constructed once

  g_plant = Plant{};
  const double truth[10] = {kMass[0],    kMass[1],      kMass[2],      kDamping[0],   kDamping[1],
                            kDamping[2], kStiffness[0], kStiffness[1], kStiffness[2], kStiffness[3]};
  constexpr int kSamples = 501;       // t = 0 .. 0.5 s
  constexpr int kCheckFrom = 100;     // t0 + 0.1 s
  int consumed = 0;
  int tick = 0;
  double worst = 0;        // worst relative error over [0.1 s, 0.5 s], all 10 parameters
  bool all_valid = true;
  while (consumed < kSamples) {
    // The timer fires 1 to 3 times between two passes of the main loop (jitter in the loop).
    const int burst = 1 + (tick++ % 3);
    for (int b = 0; b < burst && consumed + b < kSamples; ++b) sampling_isr();
    Sample s;
    while (g_ring.pop(s)) {
      Scalar a[kDofs], u[kDofs];
      for (int i = 0; i < kDofs; ++i) {
        a[i] = static_cast<Scalar>(s.accel[i]);
        u[i] = static_cast<Scalar>(s.force[i]);
      }
      const algid::Status status = estimator.update(a, u);  // noexcept, no allocation
      if (consumed >= kCheckFrom) {
        all_valid = all_valid && status == algid::Status::kOk && estimator.all_valid();
        double est[10];
        for (int i = 0; i < kDofs; ++i) {
          est[i] = static_cast<double>(estimator.mass()(i));
          est[3 + i] = static_cast<double>(estimator.damping()(i));
        }
        for (int j = 0; j <= kDofs; ++j) est[6 + j] = static_cast<double>(estimator.stiffness()(j));
        for (int j = 0; j < 10; ++j) {
          const double e = std::abs(est[j] / truth[j] - 1);
          worst = std::isnan(e) ? INFINITY : (e > worst ? e : worst);
        }
      }
      ++consumed;
    }
  }
  std::printf("%s estimator after %.3f s (window %.3f s):\n", label, g_plant.t - kSamplePeriod,
              static_cast<double>(estimator.window()));
  for (int i = 0; i < kDofs; ++i)
    std::printf("  m%d = %8.4f kg (true %.2f)   c%d = %7.4f N s/m (true %.2f)\n", i + 1,
                static_cast<double>(estimator.mass()(i)), kMass[i], i + 1, static_cast<double>(estimator.damping()(i)),
                kDamping[i]);
  for (int j = 0; j <= kDofs; ++j)
    std::printf("  k%d = %9.3f N/m (true %.0f)\n", j + 1, static_cast<double>(estimator.stiffness()(j)), kStiffness[j]);
  std::printf("  worst relative error over t0 + [0.1, 0.5] s: %.2e\n", worst);
  check(all_valid, "estimates valid from t0 + 0.1 s on");
  check(worst < 0.01, "every estimate within 1 % from t0 + 0.1 s on");
  check(g_dropped == 0, "no sample dropped by the ring buffer");
}

}  // namespace

int main() {
  run_task<double>("double");
  run_task<float>("float");
  std::printf("firmware_loop: %d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}
