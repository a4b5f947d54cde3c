"""Exact simulation of a linear chain under broadband forcing, and its Cramer-Rao lower bound.

The benchmarks need 60 s at 1 kHz, many times over, with parameters that step or drift, so it
uses its own simulator instead of the general one in ``algid.simulator`` (a Runge-Kutta step
per sample in Python). For a linear chain the exact discretisation is cheap:

* Forcing: each DOF's force is the output of a 4th-order Butterworth low-pass (cut-off
  ``band_hz``) driven by white noise held constant over each sample (ZOH). The force is
  therefore a smooth (C^3) continuous-time signal known exactly between samples, and the
  chain plus the force filters form one LTI system driven by a piecewise-constant input.
* Discretisation: ``Phi = expm(A h)``, ``Gamma = int_0^h expm(A s) ds B`` (one augmented
  ``expm``), exact to rounding. Forces and accelerations are sampled simultaneously.
* Parameter changes: the chain matrices are swapped at a sample instant (a step is exact; a
  linear drift is applied as a staircase updated every ``drift_update`` samples, 10 ms by
  default: 1.7e-5 of relative change per stair on the benchmark's 10 %/60 s drift).
* The record starts after ``burn_in_s`` of forcing, so the chain is in a stationary random
  state at t = 0 (the estimators do not know it; the Cramer-Rao bound treats it as unknown).

Cramer-Rao bound (``crlb``): accelerations observed with independent white Gaussian noise of
standard deviation ``sigma_i = rms(a_i) 10^(-snr/20)`` per channel, the force known exactly.
The Fisher information of the 3n+1 parameters (m, c, k; n + n + n+1, or n + n + n with a free
end) and the 2n unknown initial positions and velocities is

    F(t) = sum_{t_k <= t} J_k^T diag(sigma^-2) J_k,   J_k = d a(t_k) / d (theta, x0, v0),

with the sensitivities from the forward sensitivity equations, integrated exactly with the
plant (one block-triangular LTI system: filters, chain, and one chain copy per parameter).
The bound on parameter j is sqrt((F^-1)_jj); the initial state is marginalised out.

A spring network (:class:`~algid.model.network.NetworkModel`) goes through the same steps
with its own stiffness matrix ``K = D^T diag(k) D`` and parameters ``m, c, k_1..k_S``.

The benchmarks judge the estimators against this bound (``bench/continuous.py``,
``bench/identify.py``, ``bench/soak.py``); ``python bench/crlb.py`` prints it for Table 1,
``--network NAME`` for one of the example networks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm
from scipy.signal import butter

from ..model.chain import Chain
from ..model.network import Network, NetworkModel

# ---------------------------------------------------------------------------------------------
# model


def chain_blocks(m: np.ndarray, c: np.ndarray, k: np.ndarray, network: Network | None = None):
    """Continuous dynamics y' = A y + B u with y = [x; v] (2n) of the chain (springs
    ``k_1..k_{n+1}``) or of ``network`` (springs ``k_1..k_S``)."""
    n = m.size
    K = (Network.chain(n) if network is None else network).stiffness_matrix(k)
    Minv = np.diag(1.0 / m)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -Minv @ K
    A[n:, n:] = -Minv @ np.diag(c)
    B = np.zeros((2 * n, n))
    B[n:] = Minv
    return A, B


def force_filter(n: int, band_hz: float, order: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block-diagonal Butterworth low-passes, one per DOF: z' = Af z + Bf w, u = Cf z."""
    b, a = butter(order, 2 * np.pi * band_hz, analog=True)
    # controllable canonical form of b / a (strictly proper: b is a constant)
    a = a / a[0]
    Ac = np.zeros((order, order))
    Ac[:-1, 1:] = np.eye(order - 1)
    Ac[-1] = -a[1:][::-1]
    Bc = np.zeros((order, 1))
    Bc[-1, 0] = 1.0
    Cc = np.zeros((1, order))
    Cc[0, 0] = b[-1]
    Af = np.kron(np.eye(n), Ac)
    Bf = np.kron(np.eye(n), Bc)
    Cf = np.kron(np.eye(n), Cc)
    return Af, Bf, Cf


def discretise(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH discretisation: (expm(A h), int_0^h expm(A s) ds B)."""
    nx, nu = B.shape
    big = np.zeros((nx + nu, nx + nu))
    big[:nx, :nx] = A
    big[:nx, nx:] = B
    E = expm(big * h)
    return E[:nx, :nx], E[:nx, nx:]


# ---------------------------------------------------------------------------------------------
# simulation


@dataclass
class Record:
    """A simulated record sampled at t_k = k h, k = 0 .. T-1."""

    t: np.ndarray  #: (T,) sample times [s]
    a: np.ndarray  #: (T, n) clean accelerations [m/s^2]
    u: np.ndarray  #: (T, n) clean forces [N]
    truth: np.ndarray  #: (T, 3n+1) true parameters m, c, k_1..k_{n+1} (a network's k_1..k_S) at each sample
    y0: np.ndarray  #: (2n,) chain state at t = 0
    z0: np.ndarray  #: full simulator state at t = 0 (filters then chain)
    w: np.ndarray  #: (T, n) ZOH white-noise input of the force filters
    chain: Chain | NetworkModel = field(repr=False, default=None)
    band_hz: float = 20.0

    @property
    def n(self) -> int:
        return self.a.shape[1]

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    def noisy(self, snr_db: float | None, on: tuple[str, ...], seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations and forces with white noise of RMS ``rms(channel) 10^(-snr/20)``
        added to the channels in ``on`` (``"accel"``, ``"force"``)."""
        a, u = self.a.copy(), self.u.copy()
        if snr_db is None:
            return a, u
        ratio = 10.0 ** (-snr_db / 20.0)
        ss = np.random.SeedSequence([seed, 0x5EED])
        ga, gu = (np.random.default_rng(s) for s in ss.spawn(2))
        if "accel" in on:
            a += ga.standard_normal(a.shape) * ratio * rms(self.a)
        if "force" in on:
            u += gu.standard_normal(u.shape) * ratio * rms(self.u)
        return a, u


def rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(x**2, axis=0))


def params_of(chain: Chain | NetworkModel) -> np.ndarray:
    return np.concatenate([chain.mass, chain.damping, chain.stiffness])


def topology(model: Chain | NetworkModel) -> Network:
    """The springs of the packed parameters: a chain's all n+1 (a free end's k_{n+1} = 0
    included), a network model's own."""
    return model.network if isinstance(model, NetworkModel) else Network.chain(model.n)


def _plant(p: np.ndarray, n: int, Af, Bf, Cf, h: float, network: Network | None = None):
    """Exact discretisation of (force filters -> chain or ``network``) with parameters p = (m, c, k)."""
    nf = Af.shape[0]
    A, B = chain_blocks(p[:n], p[n : 2 * n], p[2 * n :], network)
    nz = nf + 2 * n
    Az = np.zeros((nz, nz))
    Az[:nf, :nf] = Af
    Az[nf:, nf:] = A
    Az[nf:, :nf] = B @ Cf
    Bz = np.zeros((nz, n))
    Bz[:nf] = Bf
    return discretise(Az, Bz, h)


def _filter_gain(band_hz: float, h: float, force_rms: float) -> float:
    """Input scale giving a stationary force RMS of ``force_rms`` [N] for unit ZOH noise."""
    Af, Bf, Cf = force_filter(1, band_hz)
    Phi, Gam = discretise(Af, Bf, h)
    P = np.zeros_like(Phi)
    for _ in range(100000):
        P_next = Phi @ P @ Phi.T + Gam @ Gam.T
        done = np.allclose(P_next, P, rtol=1e-13, atol=0)
        P = P_next
        if done:
            break
    return force_rms / float(np.sqrt((Cf @ P @ Cf.T)[0, 0]))


def simulate(
    chain: Chain | NetworkModel,
    duration_s: float,
    fs_hz: float = 1000.0,
    *,
    seed: int = 0,
    band_hz: float = 20.0,
    force_rms: float = 10.0,
    burn_in_s: float = 3.0,
    schedule=None,
    drift_update: int = 10,
    forced=None,
) -> Record:
    """Simulate ``chain`` under broadband random forcing, exactly (see the module docstring).

    ``forced``: the 0-based DOFs that carry a force (default: every DOF; the others' forces are
    zero, and the bound of :func:`crlb` is that of this one-shaker record).

    ``schedule(t) -> (3n+1,)`` gives time-varying parameters (m, c, k) at time t [s] (t >= 0);
    it is evaluated at every ``drift_update``-th sample and applied from that sample on (a
    step placed on such a sample, e.g. at 30 s, is exact).
    """
    n = chain.n
    h = 1.0 / fs_hz
    T = int(round(duration_s * fs_hz))
    B0 = int(round(burn_in_s * fs_hz))
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xF0C3]))
    Af, Bf, Cf = force_filter(n, band_hz)
    nf = Af.shape[0]
    w = rng.standard_normal((B0 + T, n)) * _filter_gain(band_hz, h, force_rms)
    if forced is not None:
        w[:, np.setdiff1d(np.arange(n), forced)] = 0.0
    p = params_of(chain)
    net = topology(chain)
    Phi, Gam = _plant(p, n, Af, Bf, Cf, h, net)
    z = np.zeros(nf + 2 * n)
    for k in range(B0):
        z = Phi @ z + Gam @ w[k]
    z0 = z.copy()
    truth = np.empty((T, p.size))
    Z = np.empty((T, z.size))
    for k in range(T):
        if schedule is not None and k % drift_update == 0:
            p_new = np.asarray(schedule(k * h), dtype=float)
            if not np.array_equal(p_new, p):
                p = p_new
                Phi, Gam = _plant(p, n, Af, Bf, Cf, h, net)
        truth[k] = p
        Z[k] = z
        z = Phi @ z + Gam @ w[B0 + k]
    u = Z[:, :nf] @ Cf.T
    x, v = Z[:, nf : nf + n], Z[:, nf + n :]
    m, c, kk = truth[:, :n], truth[:, n : 2 * n], truth[:, 2 * n :]
    D = net.deformation_matrix()
    a = (u - c * v - (kk * (x @ D.T)) @ D) / m  # spring forces k_s d_s on both ends
    return Record(
        t=np.arange(T) * h,
        a=a,
        u=u,
        truth=truth,
        y0=Z[0, nf:].copy(),
        z0=z0,
        w=w[B0:].copy(),
        chain=chain,
        band_hz=band_hz,
    )


# ---------------------------------------------------------------------------------------------
# Cramer-Rao bound


def identified_mask(chain: Chain | NetworkModel) -> np.ndarray:
    """Which of (m, c, k_1..k_{n+1}) are unknown: all, except k_{n+1} = 0 with a free end; a
    network model's (m, c, k_1..k_S): all, and none for springs in parallel (only their sum)."""
    if isinstance(chain, NetworkModel):
        reasons = chain.network.identifiability()
        if reasons:
            raise ValueError(f"no per-parameter bound: {'; '.join(sorted(set(reasons.values())))}")
        return np.ones(2 * chain.n + chain.network.size, dtype=bool)
    mask = np.ones(3 * chain.n + 1, dtype=bool)
    if chain.boundary == "free":
        mask[-1] = False
    if chain.n == 1 and chain.boundary == "fixed":
        raise ValueError("n = 1 with walls identifies only k1 + k2; no per-spring bound")
    return mask


@dataclass
class Drive:
    """What drives the chain: a piecewise-constant input ``w`` (held over each sample) through
    a linear input stage ``z' = Af z + Bf w``, the force on the masses ``u = Cf z + Df w``
    (Butterworth: ``Df = 0``; a first-order actuator lag; a DAC holding the force: no stage,
    ``Df = I``)."""

    Af: np.ndarray
    Bf: np.ndarray
    Cf: np.ndarray
    Df: np.ndarray
    z0: np.ndarray  #: input stage state at t = 0
    w: np.ndarray  #: (T, n) the held input of each sample interval


def sensitivities(rec: Record) -> tuple[np.ndarray, np.ndarray]:
    """``J[k, i, j] = d a_i(t_k) / d col_j`` for the identified parameters (columns
    ``0..p-1``, indices into (m, c, k) returned as the second value) then the 2n initial
    positions and velocities, by the forward sensitivity equations integrated exactly."""
    theta = rec.truth[0]
    if not np.allclose(rec.truth, theta):
        raise ValueError("crlb() needs a record with constant parameters")
    Af, Bf, Cf = force_filter(rec.n, rec.band_hz)
    nf = Af.shape[0]
    drive = Drive(Af, Bf, Cf, np.zeros((rec.n, rec.n)), rec.z0[:nf], rec.w)
    return driven_sensitivities(rec.chain, theta, rec.y0, drive, rec.dt)


def _parameter_derivatives(theta: np.ndarray, idx: np.ndarray, n: int, network: Network) -> tuple[list, list]:
    """d A / d theta_j and d B / d theta_j of the chain or network, by central differences:
    exact for c and k (A is linear in them), O(eps^2) for m."""
    dA, dB = [], []
    for j in idx:
        e = np.zeros_like(theta)
        e[j] = 1e-6 * theta[j]
        Ap, Bp = chain_blocks(*np.split(theta + e, [n, 2 * n]), network)
        Am, Bm = chain_blocks(*np.split(theta - e, [n, 2 * n]), network)
        dA.append((Ap - Am) / (2 * e[j]))
        dB.append((Bp - Bm) / (2 * e[j]))
    return dA, dB


def driven_sensitivities(
    chain: Chain | NetworkModel,
    theta: np.ndarray,
    y0: np.ndarray,
    drive: Drive,
    h: float,
    u_samples: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sensitivities` of ``chain`` (parameters ``theta``, state ``y0`` at t = 0) under
    ``drive``: one block-triangular LTI system (input stage, chain, one chain copy per
    column), discretised exactly for the held input. ``u_samples`` (T, n): the force at the
    sample instants where it jumps there (the mean of its one-sided limits, as the
    accelerometers see it); default ``Cf z``, continuous."""
    n, T = chain.n, drive.w.shape[0]
    idx = np.nonzero(identified_mask(chain))[0]
    p = idx.size
    net = topology(chain)
    A, B = chain_blocks(theta[:n], theta[n : 2 * n], theta[2 * n :], net)
    dA, dB = _parameter_derivatives(theta, idx, n, net)
    Af, Bf, Cf, Df = drive.Af, drive.Bf, drive.Cf, drive.Df
    nf, ny = Af.shape[0], 2 * n
    q = p + ny  # sensitivity columns: parameters, then the initial state
    dim = nf + ny + ny * q
    Abig = np.zeros((dim, dim))
    Bbig = np.zeros((dim, n))
    Abig[:nf, :nf], Bbig[:nf] = Af, Bf
    Abig[nf : nf + ny, nf : nf + ny] = A
    Abig[nf : nf + ny, :nf], Bbig[nf : nf + ny] = B @ Cf, B @ Df
    for j in range(q):
        r = nf + ny + j * ny
        Abig[r : r + ny, r : r + ny] = A
        if j < p:
            Abig[r : r + ny, nf : nf + ny] = dA[j]
            Abig[r : r + ny, :nf], Bbig[r : r + ny] = dB[j] @ Cf, dB[j] @ Df
    Phi, Gam = discretise(Abig, Bbig, h)
    Zs = np.zeros(dim)
    Zs[:nf] = drive.z0
    Zs[nf : nf + ny] = y0
    for j in range(ny):  # d y / d y0 = I at t = 0
        Zs[nf + ny + (p + j) * ny + j] = 1.0
    states = np.empty((T, dim))
    for k in range(T):
        states[k] = Zs
        Zs = Phi @ Zs + Gam @ drive.w[k]
    uu = states[:, :nf] @ Cf.T if u_samples is None else u_samples
    y = states[:, nf : nf + ny]
    S = states[:, nf + ny :].reshape(T, q, ny)  # S[k, j] = d y / d col_j
    low = slice(n, 2 * n)
    # J[k, i, j] = d a_i(t_k) / d col_j
    J = np.einsum("ab,kjb->kaj", A[low], S)
    for j in range(p):
        J[:, :, j] += y @ dA[j][low].T + uu @ dB[j][low].T
    return J, idx


def bound(J: np.ndarray, idx: np.ndarray, theta: np.ndarray, sigma: np.ndarray, h: float, times_s) -> dict:
    """Relative bound ``sqrt((F^-1)_jj) / theta_j`` from the samples in [0, t] for each t in
    ``times_s`` (white noise ``sigma`` (n,) on the accelerations; NaN where not identified)."""
    Jw = J / sigma[None, :, None]
    p, out = idx.size, {}
    for t in times_s:
        K = min(J.shape[0], int(round(t / h)))
        F = np.einsum("kaj,kal->jl", Jw[:K], Jw[:K])
        cov = np.linalg.inv(F)
        rel = np.full(theta.size, np.nan)
        rel[idx] = np.sqrt(np.diag(cov)[:p]) / np.abs(theta[idx])
        out[float(t)] = rel
    return out


def crlb(rec: Record, snr_db: float, times_s=(1.0, 10.0, 60.0)) -> dict[float, np.ndarray]:
    """Relative Cramer-Rao bound sqrt((F^-1)_jj) / theta_j on every parameter (m, c, k order,
    NaN where not identified) from the accelerations in [0, t] for each t in ``times_s``,
    white noise of ``rms(a_i) 10^(-snr/20)`` on each acceleration, the force known, the
    initial chain state unknown. The record must have constant parameters."""
    J, idx = sensitivities(rec)
    sigma = rms(rec.a) * 10.0 ** (-snr_db / 20.0)
    return bound(J, idx, rec.truth[0], sigma, rec.dt, times_s)


def rig_drive(res, actuator_lag_s: float) -> tuple[Drive, np.ndarray | None]:
    """The :class:`Drive` of a sampled-mode run of :func:`algid.simulator.simulate` (a DAC
    holding each command, through a first-order lag of ``actuator_lag_s`` [s] or none), from
    the forces it applied, and the force at the samples the accelerometers saw (None: no
    jumps). The held commands are recovered from the lag's exact step
    ``w_{k+1} = c_k + (w_k - c_k) exp(-h / tau)``."""
    n, h = res.n, res.dt
    w_app = res.limits["u_applied_plus"]
    if actuator_lag_s > 0:
        E = np.exp(-h / actuator_lag_s)
        cmd = np.empty_like(w_app)
        cmd[:-1] = (w_app[1:] - E * w_app[:-1]) / (1.0 - E)
        cmd[-1] = cmd[-2]  # the last interval is not simulated
        eye = np.eye(n)
        return Drive(-eye / actuator_lag_s, eye / actuator_lag_s, eye, np.zeros((n, n)), w_app[0].copy(), cmd), None
    none = np.zeros((0, 0))
    return Drive(none, np.zeros((0, n)), np.zeros((n, 0)), np.eye(n), np.zeros(0), w_app), res.u_applied


def loop_crlb(res, actuator_lag_s: float, times_s) -> dict[float, np.ndarray]:
    """Relative Cramer-Rao bound (as :func:`crlb`) of a noisy sampled-mode run of
    :func:`algid.simulator.simulate`, open or closed loop: the accelerometers' white noise of
    the run's own RMS (``res.noise_rms["accel"]``), the applied force known, the initial
    state unknown. In closed loop the force depends on past noise; the likelihood still
    factors sample by sample, so the information is that of the realised force."""
    drive, u_samples = rig_drive(res, actuator_lag_s)
    theta = params_of(res.chain)
    y0 = np.concatenate([res.x[0], res.v[0]])
    J, idx = driven_sensitivities(res.chain, theta, y0, drive, res.dt, u_samples)
    return bound(J, idx, theta, np.asarray(res.noise_rms["accel"], dtype=float), res.dt, times_s)
