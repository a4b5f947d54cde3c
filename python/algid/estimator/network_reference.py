"""Plain numpy reference of the algebraic estimator for any spring network (issue 39), whole
signal: the test oracle of networks, as :mod:`.reference` is the chain's (whose quadrature
and integration-by-parts moments it uses). The library never imports it.

DOF i's equation (:mod:`algid.model.network`) after the integration by parts of eqs. 2-4 is
eq. 4 with one column per unknown: its mass, its damping and one spring column per distinct
other end of its springs (``y_i - y_other``, the other end's acceleration 0 for ground), so
M = 2 + deg(i) unknowns (springs in parallel share a column). Row q (q = 0..R-1, R >= M) is
the q-fold integral of eq. 4 (eq. 6), exactly as the chain's rows 0..3:

    A[q, 0] = I^q(Delta^2 y - 4 I(Delta y) + 2 I^2 y),  A[q, 1] = I^(q+1)(Delta^2 y) - 2 I^(q+2)(Delta y),
    A[q, 1 + c] = I^(q+2)(Delta^2 (y_i - y_other)),       B[q] = I^q(Delta^2 u - 4 I(Delta u) + 2 I^2 u).

Time scaling as the chain's: ``S = diag(tau^-q) A diag(tau^-2, tau^-3, tau^-4, ..)``,
``b = tau^-2 diag(tau^-q) B``, ``S phi = b``, ``theta = [phi_1, phi_2 / tau, phi_3.. / tau^2]``.
R = M solves the square system (the chain's Cramer); R > M is least squares. Eq. 7 weights
every trusted sample by ``sqrt(det(A^T A))`` (``|det A|`` when square, the chain's weight).
"""

from __future__ import annotations

import numpy as np

from ..model.network import Network
from .reference import _cumtrapz2, equilibrated_hadamard, moments


def dof_system(network: Network, i: int, G: list[np.ndarray], Gu: np.ndarray, tau: np.ndarray, rows: int):
    """``S (T, R, M)``, ``b (T, R)`` of DOF ``i`` (1-based) from the moments ``G`` of every
    acceleration and ``Gu`` of its force (:func:`algid.estimator.reference.moments`)."""
    cols = network.columns(i)
    M, T = 2 + len(cols), tau.size
    if rows < M:
        raise ValueError(f"DOF {i} has {M} unknowns: it needs at least {M} rows, got {rows}")
    g = G[i - 1]
    A = np.zeros((T, rows, M))
    B = np.zeros((T, rows))
    for q in range(rows):
        A[:, q, 0] = g[2, q] - 4.0 * g[1, q + 1] + 2.0 * g[0, q + 2]
        A[:, q, 1] = g[2, q + 1] - 2.0 * g[1, q + 2]
        for c, (_, other) in enumerate(cols):
            A[:, q, 2 + c] = g[2, q + 2] - (G[other - 1][2, q + 2] if other else 0.0)
        B[:, q] = Gu[2, q] - 4.0 * Gu[1, q + 1] + 2.0 * Gu[0, q + 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(tau > 0, 1.0 / tau, 0.0)
    R = inv[:, None] ** np.arange(rows)[None, :]  # (T, R)
    C = inv[:, None] ** np.minimum(np.arange(2, M + 2), 4)[None, :]  # (T, M)
    return A * R[:, :, None] * C[:, None, :], B * R * (inv**2)[:, None]


#: Lowest moment order computed: the 12 rows of a DOF with 10 unknowns (the lattice's centre)
#: and two extra, so that one set of quadrature weights (slow to build, cached) serves them all.
MIN_ORDER = 13


def moments_of(y: np.ndarray, u: np.ndarray, dt: float, rows: int, points: int = 8):
    """Moments (:func:`algid.estimator.reference.moments`) of every acceleration and force up
    to the order ``rows + 1`` that R rows need (at least :data:`MIN_ORDER`), and ``tau`` (T,) [s]."""
    T = y.shape[0]
    tau = dt * np.arange(T)
    order = max(rows + 1, MIN_ORDER)
    Gy = [moments(y[:, i], tau, dt, points, order) for i in range(y.shape[1])]
    Gu = [moments(u[:, i], tau, dt, points, order) for i in range(u.shape[1])]
    return Gy, Gu, tau


def solve(S: np.ndarray, b: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``theta (T, M)`` of every sample (NaN at tau = 0) and ``log sqrt(det(A^T A))`` (T,), the
    log of eq. 7's weight (``-inf`` where singular)."""
    T, R, M = S.shape
    theta = np.full((T, M), np.nan)
    ok = tau > 0
    if R == M:
        theta[ok] = np.linalg.solve(S[ok], b[ok][..., None])[..., 0]
    else:  # least squares by Householder QR (no singular value truncated, unlike pinv)
        Q, Rf = np.linalg.qr(S[ok])
        theta[ok] = np.linalg.solve(Rf, np.einsum("trm,tr->tm", Q, b[ok])[..., None])[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = tau[:, None] ** -np.minimum(np.arange(M), 2)[None, :]
        theta *= scale
        # A = diag(tau^q) S diag(tau^c): sqrt(det(A^T A)) = prod |R_jj| (QR of diag(tau^q) S) prod tau^c
        logw = _log_volume(S * tau[:, None, None] ** np.arange(R)[None, :, None])
        logw = logw + np.sum(np.minimum(np.arange(2, M + 2), 4)) * np.log(tau)
    logw = np.where(ok & np.isfinite(logw), logw, -np.inf)
    return theta, logw


def _log_volume(S: np.ndarray) -> np.ndarray:
    """``log sqrt(det(S^T S))`` (T,) from the diagonal of a QR factor (no Gram matrix, whose
    condition is the square of S's)."""
    ok = np.all(np.isfinite(S), axis=(-2, -1))
    out = np.full(S.shape[0], -np.inf)
    Rf = np.linalg.qr(S[ok], mode="r")
    with np.errstate(divide="ignore"):
        out[ok] = np.sum(np.log(np.abs(np.diagonal(Rf, axis1=-2, axis2=-1))), axis=-1)
    return out


def hadamard(S: np.ndarray) -> np.ndarray:
    """Conditioning measure (T,), 1 for orthogonal columns, 0 when singular: a square S, the
    chain's doubly equilibrated Hadamard ratio (:func:`algid.estimator.reference.equilibrated_hadamard`);
    least squares, ``sqrt(det(Sc^T Sc))`` with every column of ``S`` scaled to unit norm."""
    if S.shape[-1] == S.shape[-2]:
        return equilibrated_hadamard(S)
    col = np.linalg.norm(S, axis=-2, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.exp(_log_volume(S / col))


def hadamard_threshold(min_hadamard: float, M: int) -> float:
    """The Hadamard ratio a system of M unknowns must reach: the chain's ``min_hadamard`` up to
    M = 4, beyond it the same per column (the ratio is about a product of M-1 column angles:
    ``min_hadamard^((M-1)/3)``)."""
    return min_hadamard ** (max(M - 1, 3) / 3)


def condition(S: np.ndarray) -> np.ndarray:
    """2-norm condition number (T,) of ``S`` after scaling every column to unit norm."""
    col = np.linalg.norm(S, axis=-2, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        Sc = S / col
    ok = np.all(np.isfinite(Sc), axis=(-2, -1))
    out = np.full(S.shape[0], np.inf)
    out[ok] = np.linalg.cond(Sc[ok])
    return out


def estimate(
    network: Network,
    y,
    u,
    dt: float,
    points: int = 8,
    extra_rows: int = 0,
    min_samples: int = 16,
    min_hadamard: float = 1e-9,
) -> dict:
    """Instantaneous (eq. 5) and ratio (eq. 7) estimates of every DOF of ``network``.

    Returns ``dof``: per DOF (1-based order) a dict with ``names`` (``m_i, c_i, k_s ..``,
    packed names), ``theta_inst`` and ``theta_ratio`` (T, M), ``hadamard`` (T,); ``tau`` (T,);
    and ``packed`` (T, 2n+S): every packed parameter, a spring seen by both its DOFs as the
    mean of their ratio estimates (NaN for springs with no column of their own).
    ``extra_rows``: rows beyond M per DOF (least squares). A sample is trusted as the chain's
    (:func:`algid.estimator.reference.estimate`): ``index + points - 1 >= min_samples``, a
    finite weight and a Hadamard measure of at least :func:`hadamard_threshold` (the chain's
    ``min_hadamard`` up to 4 unknowns).
    """
    y = np.atleast_2d(np.asarray(y, dtype=float))
    u = np.atleast_2d(np.asarray(u, dtype=float))
    if y.shape != u.shape or y.shape[1] != network.n:
        raise ValueError(f"accel and force must both be (T, {network.n}), got {y.shape} and {u.shape}")
    rows = 2 + max(len(network.columns(i)) for i in range(1, network.n + 1)) + extra_rows
    Gy, Gu, tau = moments_of(y, u, dt, rows, points)
    out = []
    for i in range(1, network.n + 1):
        M = 2 + len(network.columns(i))
        S, b = dof_system(network, i, Gy, Gu[i - 1], tau, M + extra_rows)
        theta, logw = solve(S, b, tau)
        had = hadamard(S)
        good = (
            np.isfinite(logw)
            & (had >= hadamard_threshold(min_hadamard, M))
            & (np.arange(tau.size) + points - 1 >= min_samples)
        )
        out.append(
            {
                "names": [f"m{i}", f"c{i}"] + [f"k{s}" for s, _ in network.columns(i)],
                "theta_inst": theta,
                "theta_ratio": ratio(theta, np.where(good, logw, -np.inf), dt),
                "hadamard": had,
            }
        )
    return {"dof": out, "tau": tau, "packed": packed(network, out)}


def ratio(theta: np.ndarray, logw: np.ndarray, dt: float) -> np.ndarray:
    """Eq. 7: the running double integral of ``w theta`` over that of ``w`` (w = exp(logw),
    shifted by its maximum so that it stays in range; the ratio does not see the shift)."""
    top = np.max(logw[np.isfinite(logw)]) if np.isfinite(logw).any() else 0.0
    w = np.exp(logw - top)
    den = _cumtrapz2(w, dt)
    out = np.full_like(theta, np.nan)
    for j in range(theta.shape[1]):
        num = _cumtrapz2(np.where(w > 0, w * np.nan_to_num(theta[:, j]), 0.0), dt)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[:, j] = np.where(den > 0, num / den, np.nan)
    return out


def packed(network: Network, dofs: list[dict]) -> np.ndarray:
    """(T, 2n+S) packed estimates from the per-DOF ratio estimates (a spring's two estimates averaged)."""
    names = network.parameter_names()
    T = dofs[0]["theta_ratio"].shape[0]
    acc = {name: [] for name in names}
    for d in dofs:
        for j, name in enumerate(d["names"]):
            acc[name].append(d["theta_ratio"][:, j])
    return np.stack([np.mean(acc[name], axis=0) if acc[name] else np.full(T, np.nan) for name in names], axis=1)
