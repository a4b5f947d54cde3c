"""The Cramer-Rao bound of :mod:`algid.identification.crlb`: its sensitivities against finite differences of
independent simulations, the benchmark's own and ``algid.simulator``'s sampled mode (held
DAC, actuator lag), and the bound against the spread of an efficient estimator."""

from __future__ import annotations

import numpy as np
import pytest

from algid.identification import crlb as C  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402
from algid.simulator import simulate  # noqa: E402

N = TABLE1.n
COLUMNS = (1, N + 0, 2 * N + 2)  # m2, c1, k3


def _bench_accelerations(rec: C.Record, theta: np.ndarray) -> np.ndarray:
    """The benchmark's record re-simulated with parameters ``theta``, same forcing and state."""
    Af, Bf, Cf = C.force_filter(N, rec.band_hz)
    Phi, Gam = C._plant(theta, N, Af, Bf, Cf, rec.dt)
    z, a = rec.z0.copy(), np.empty_like(rec.a)
    nf = Af.shape[0]
    A, B = C.chain_blocks(theta[:N], theta[N : 2 * N], theta[2 * N :])
    for k in range(rec.t.size):
        a[k] = A[N:] @ z[nf:] + B[N:] @ (Cf @ z[:nf])
        z = Phi @ z + Gam @ rec.w[k]
    return a


@pytest.mark.slow  # 6 s: the fast tier stays within 6 minutes
def test_sensitivities_match_finite_differences_of_the_benchmark_simulation():
    rec = C.simulate(TABLE1, 0.4, seed=3, burn_in_s=0.5)
    J, idx = C.sensitivities(rec)
    theta = C.params_of(TABLE1)
    assert np.allclose(_bench_accelerations(rec, theta), rec.a, rtol=0, atol=1e-9 * np.abs(rec.a).max())
    for j in COLUMNS:
        e = np.zeros_like(theta)
        e[j] = 1e-5 * theta[j]
        fd = (_bench_accelerations(rec, theta + e) - _bench_accelerations(rec, theta - e)) / (2 * e[j])
        col = int(np.nonzero(idx == j)[0][0])
        assert np.max(np.abs(J[:, :, col] - fd)) < 1e-6 * np.max(np.abs(fd))


def _perturbed(j: int, step: float) -> Chain:
    theta = TABLE1.identifiable().copy()
    theta[j] += step
    return Chain(mass=theta[:N], damping=theta[N : 2 * N], stiffness=theta[2 * N :])


@pytest.mark.parametrize("lag_s", [0.0, 2e-3])
def test_rig_sensitivities_match_finite_differences_of_the_sampled_simulator(lag_s):
    """Held DAC (and lag): ``rig_drive`` recovers the applied force, and the sensitivities
    equal central differences of ``algid.simulator`` runs of perturbed chains."""
    T = 400
    force = np.random.default_rng(5).standard_normal((T, N))
    run = lambda chain: simulate(chain, force, T / 1000, mode="sampled", actuator_lag_s=lag_s)  # noqa: E731
    res = run(TABLE1)
    drive, u_samples = C.rig_drive(res, lag_s)
    if lag_s == 0:
        assert np.array_equal(drive.w[:-1], force[: T - 1])
    else:
        assert np.allclose(drive.w[:-1], force[: T - 1], atol=1e-9)
    theta = TABLE1.identifiable()
    J, idx = C.driven_sensitivities(TABLE1, theta, np.zeros(2 * N), drive, res.dt, u_samples)
    for j in COLUMNS:
        step = 1e-5 * theta[j]
        fd = (run(_perturbed(j, step)).a_true - run(_perturbed(j, -step)).a_true) / (2 * step)
        col = int(np.nonzero(idx == j)[0][0])
        assert np.max(np.abs(J[:, :, col] - fd)) < 1e-5 * np.max(np.abs(fd))


def test_bound_is_the_spread_of_least_squares_on_a_linear_model():
    """Linear in the parameters (a known design J), least squares is efficient: its spread
    over noise draws is the bound."""
    rng = np.random.default_rng(1)
    T, h = 2000, 1e-3
    J = rng.standard_normal((T, 2, 3))
    theta, sigma = np.array([2.0, -1.0, 0.5]), np.array([0.3, 0.1])
    rel = C.bound(J, np.arange(3), theta, sigma, h, [T * h])[T * h]
    X = (J / sigma[None, :, None]).reshape(-1, 3)
    draws = []
    for _ in range(400):
        y = (J @ theta + sigma * rng.standard_normal((T, 2))) / sigma
        draws.append(np.linalg.lstsq(X, y.reshape(-1), rcond=None)[0])
    spread = np.std(draws, axis=0) / np.abs(theta)
    assert np.allclose(spread, rel, rtol=0.15)
