"""Frequency responses of a chain: the state-space model, its FRF, and the H1 estimate of the
FRF from a recording.

Model (eq. 1 in the frequency domain, ``w = 2 pi f`` [rad/s]): the receptance
``G(w) = (K - w^2 M + i w C)^-1`` [m/N] maps forces to displacements; the mobility is
``i w G`` [(m/s)/N], the accelerance ``-w^2 G`` [(m/s^2)/N]. ``H[f, e, j]`` is the response of
mass ``e`` to a force on mass ``j`` (0-based).

State space ``s = [x; v]``, ``s' = A s + B u``, ``y = C s + D u`` with ``B = [0; M^-1]`` and
``C, D`` = ``[I, 0], 0`` (displacement), ``[0, I], 0`` (velocity) or
``[-M^-1 K, -M^-1 C], M^-1`` (acceleration).

H1 from a recording: Welch cross-spectral matrices ``G_uu[f, i, j] = E[conj(U_i) U_j]`` and
``G_ua[f, i, e] = E[conj(U_i) A_e]`` (Hann windows, half overlap), then

    H1(f) = (G_uu^-1 G_ua)^T,     gamma_e^2(f) = G_ua[:, e]^H G_uu^-1 G_ua[:, e] / G_aa[e, e],

the multiple coherence of output ``e`` with all the forces (1 where the forces explain the
output linearly and noise-free). Unforced inputs (an all-zero force channel) have no column:
NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chain import Chain
from .modal import state_matrix

OUTPUTS = ("displacement", "velocity", "acceleration")
#: Units of the FRF of each output, forces in N.
UNITS = {"displacement": "m/N", "velocity": "(m/s)/N", "acceleration": "(m/s^2)/N"}
#: Record length / segment length of the H1 estimate when none is asked for (about 15 half-overlapping segments).
SEGMENTS = 8


def _check_output(output: str) -> None:
    if output not in OUTPUTS:
        raise ValueError(f"output must be one of {', '.join(OUTPUTS)}, got {output!r}")


def state_matrices(chain: Chain, output: str = "acceleration") -> tuple[np.ndarray, ...]:
    """``(A, B, C, D)`` of the chain with the forces [N] as inputs and ``output`` of every mass."""
    _check_output(output)
    n = chain.n
    M, Cd, K = chain.matrices()
    A = state_matrix(chain)
    Minv = np.diag(1.0 / chain.mass)
    B = np.vstack([np.zeros((n, n)), Minv])
    if output == "displacement":
        C, D = np.hstack([np.eye(n), np.zeros((n, n))]), np.zeros((n, n))
    elif output == "velocity":
        C, D = np.hstack([np.zeros((n, n)), np.eye(n)]), np.zeros((n, n))
    else:
        C, D = A[n:].copy(), Minv
    return A, B, C, D


def state_space(chain: Chain, output: str = "acceleration"):
    """``scipy.signal.StateSpace`` of :func:`state_matrices`."""
    from scipy.signal import StateSpace

    return StateSpace(*state_matrices(chain, output))


def to_control(chain: Chain, output: str = "acceleration"):
    """``control.StateSpace`` of :func:`state_matrices`; a one-line ``ImportError`` without python-control."""
    try:
        import control
    except ImportError:
        raise ImportError("Chain.to_control needs python-control: pip install control (or algid[control])") from None
    n = chain.n
    return control.ss(
        *state_matrices(chain, output),
        inputs=[f"u{i + 1}" for i in range(n)],
        outputs=[f"{output[0]}{i + 1}" for i in range(n)],
    )


def frf(chain: Chain, f_hz, output: str = "acceleration") -> np.ndarray:
    """``H`` (F, n, n) complex: the ``output`` of every mass per force on every mass at ``f_hz`` (F,) [Hz]."""
    _check_output(output)
    w = 2 * np.pi * np.atleast_1d(np.asarray(f_hz, dtype=float))
    M, C, K = chain.matrices()
    G = np.linalg.inv(K[None] - w[:, None, None] ** 2 * M[None] + 1j * w[:, None, None] * C[None])
    power = OUTPUTS.index(output)
    return (1j * w[:, None, None]) ** power * G


@dataclass(frozen=True)
class FrfEstimate:
    """H1 estimate of a recording's FRF.

    f_hz : (F,) frequencies [Hz]; H : (F, n, n) response of mass e per force on mass j (NaN
    columns for unforced masses); coherence : (F, n) multiple coherence of every output [-];
    segments : Welch segments averaged; nperseg : samples per segment; output : the motion;
    units : the unit of H when the recording is not in SI.
    """

    f_hz: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    segments: int
    nperseg: int
    output: str = "acceleration"
    units: str = ""  #: unit of H (``UNITS[output]`` when empty)

    @property
    def unit(self) -> str:
        """Unit label of ``H``: the recording's motion unit per its force unit."""
        return self.units or UNITS[self.output]


def h1_estimate(u: np.ndarray, y: np.ndarray, dt: float, nperseg: int | None = None, output="acceleration"):
    """H1 of outputs ``y`` (T, n) per forces ``u`` (T, n) [N] sampled every ``dt`` [s]
    (``nperseg``: Welch segment length, default the power of two at most T / :data:`SEGMENTS`)."""
    from scipy.signal import csd

    u, y = np.atleast_2d(np.asarray(u, float).T).T, np.atleast_2d(np.asarray(y, float).T).T
    T, n = u.shape
    if nperseg is None:
        nperseg = int(2 ** np.floor(np.log2(max(T // SEGMENTS, 16))))
    nperseg = min(int(nperseg), T)
    forced = np.nonzero(np.any(u != 0, axis=0))[0]
    if forced.size == 0:
        raise ValueError("no force: every force channel is zero, there is no FRF to estimate")
    q = forced.size
    X = np.column_stack([u[:, forced], y])
    f, S = csd(X[:, :, None], X[:, None, :], fs=1.0 / dt, nperseg=nperseg, axis=0)
    Guu, Gua, Gaa = S[:, :q, :q], S[:, :q, q:], np.einsum("fii->fi", S[:, q:, q:]).real
    with np.errstate(divide="ignore", invalid="ignore"):
        solved = np.linalg.pinv(Guu) @ Gua  # (F, q, n_out)
        coherence = np.einsum("fie,fie->fe", Gua.conj(), solved).real / Gaa
    H = np.full((f.size, y.shape[1], n), np.nan + 0j)
    H[:, :, forced] = np.swapaxes(solved, 1, 2)
    segments = 1 + max(0, (T - nperseg) // (nperseg // 2))
    return FrfEstimate(f, H, coherence, segments, nperseg, output)


def recording_h1(rec, nperseg: int | None = None) -> FrfEstimate:
    """H1 of a :class:`algid.Recording`: accelerations when it has them, else velocities or
    displacements (the output is named in the estimate); labelled in the recording's units
    when it declares any (``Recording.units``, by role)."""
    from dataclasses import replace

    from .recording import motion

    kind, y = motion(rec)
    est = h1_estimate(rec.u, y, rec.dt, nperseg, output=kind)
    labels = getattr(rec, "units", None) or {}  # a recording's declared units, by role (SI when absent)
    if labels.get(kind) or labels.get("force"):
        si = {"force": "N", "acceleration": "m/s^2", "velocity": "m/s", "displacement": "m"}
        est = replace(est, units=f"{labels.get(kind) or si[kind]}/{labels.get('force') or si['force']}")
    return est
