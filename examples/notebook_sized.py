"""Notebook-sized tour: identify the Table 1 chain from simulated accelerations and forces, once
sample by sample (as a control loop would call it) and once in a single batch call, and see
what each costs.

    python examples/notebook_sized.py

The per-sample ``update()`` pays the Python call and the numpy conversions every sample
(a few microseconds); ``run()`` crosses into C++ once for the whole record and releases the
GIL, so it costs about what the C++ core costs (bench/per_sample.py measures both).
"""

from __future__ import annotations

import time

import numpy as np

import algid
from algid.simulator import simulate

chain = algid.TABLE1  # m = 2, 2.5, 3 kg; c = 5.5, 5, 4.5 N s/m; k = 1000, 900, 900, 700 N/m


def multisine(t: float) -> np.ndarray:
    """Force [N] on each DOF: three tones between 1.3 and 17 Hz, distinct per DOF."""
    i = np.arange(3)
    freq = np.stack([1.3 + 0.7 * i, 5.1 + 1.9 * i, 11.0 + 3.1 * i])  # [Hz], (tone, dof)
    amp = np.array([10.0, 6.0, 4.0])[:, None]  # [N]
    phase = 0.9 * np.arange(3)[:, None] + 0.4 * i
    return np.sum(amp * np.sin(2 * np.pi * freq * t + phase), axis=0)


rec = simulate(chain, multisine, duration_s=1.0, fs_hz=1000.0)  # noise-free, from rest
T = rec.a.shape[0]

# 1. Sample by sample.
est = algid.ChainEstimator(3, rec.dt)
at_100ms = None
t0 = time.perf_counter()
for k in range(T):
    est.update(rec.a[k], rec.u[k])
    if k == 100:  # newest sample at t0 + 0.1 s
        at_100ms = np.concatenate([est.mass, est.damping, est.stiffness])
per_sample_s = time.perf_counter() - t0
final = np.concatenate([est.mass, est.damping, est.stiffness])

# 2. One batch call over the same record.
t0 = time.perf_counter()
out = algid.ChainEstimator(3, rec.dt).run(rec.a, rec.u)
batch_s = time.perf_counter() - t0
batch_final = np.concatenate([out["mass"][-1], out["damping"][-1], out["stiffness"][-1]])
assert np.array_equal(batch_final, final), "batch and per-sample paths run the same C++ code"

truth = np.concatenate([chain.mass, chain.damping, chain.stiffness])
names = ["m1", "m2", "m3", "c1", "c2", "c3", "k1", "k2", "k3", "k4"]
print(f"{'':4s} {'truth':>9s} {'t0+0.1 s':>11s} {'rel. err':>9s} {'t0+1 s':>11s} {'rel. err':>9s}")
for name, x, a, b in zip(names, truth, at_100ms, final):
    print(f"{name:4s} {x:9.2f} {a:11.5f} {abs(a / x - 1):9.1e} {b:11.5f} {abs(b / x - 1):9.1e}")
print(f"\nper-sample update(): {per_sample_s / T * 1e6:6.2f} us per sample")
print(
    f"batch run():         {batch_s / T * 1e6:6.2f} us per sample "
    f"({per_sample_s / batch_s:.0f}x faster, identical estimates)"
)

# 3. A noisy 10 s record as a rig would log it (40 dB on forces and accelerations), through the
#    whole-record entry point: the estimator, its settings and one standard deviation per
#    estimate come from the recording itself.
noisy = simulate(chain, multisine, duration_s=10.0, fs_hz=1000.0, noise_db=40, noise_on=("accel", "force"), seed=1)
res = algid.identify(algid.Recording(t=noisy.t, u=noisy.u, a=noisy.a))
print("\n" + res.summary())
for name, x, est_, sd in zip(names, truth, res.theta, res.sigma):
    print(f"{name:4s} truth {x:8.2f}  estimate {est_:9.4f} +- {sd:.2g}  ({(est_ - x) / sd:+.1f} sigma)")
