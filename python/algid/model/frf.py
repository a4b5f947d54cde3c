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

the multiple coherence of output ``e`` with the forces (1 where the forces explain the
output linearly and noise-free). Only where the forces excite: at every frequency ``G_uu`` and
``G_ua`` are restricted to the forces whose auto-spectrum reaches :data:`EXCITED` of its peak
(a multisine line's leakage lobe, at most :data:`LOBE` bins, counts once: its top bin, which
stands for the line's frequency, :func:`excitation`), and
solved only when those forces are separable there (``cond(G_uu) <=`` :data:`COND_MAX`; the
forces of a multisine that share their lines are not). The columns of forces that do not
excite a frequency are NaN there (unforced inputs, all-zero channels: NaN everywhere), and the
coherence is NaN where no force excites.

Resolution: a resonance of damping ratio ``zeta`` at ``f_n`` is ``2 zeta f_n`` wide at half
power; bins of width ``zeta f_n`` (:func:`resolution_hz`, half of the narrowest) resolve every
mode, as far as the record allows (:func:`segment_samples`).
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
#: A force excites a frequency where its auto-spectrum is at least this share of its peak (20 dB below).
EXCITED = 1e-2
#: A run of at most this many excited bins is one line's leakage lobe (Hann: a line is four bins wide).
LOBE = 4
#: Largest condition number of the excited forces' cross-spectral matrix that is solved.
COND_MAX = 1e3


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
    in the columns of forces that do not excite a frequency); coherence : (F, n) multiple
    coherence of every output with the exciting forces [-] (NaN where none excites);
    at_hz : (F, n) the frequency [Hz] column j's estimate in bin f stands for (the bin's, or
    a multisine line's within it), NaN where force j does not excite bin f; segments :
    Welch segments averaged; nperseg : samples per segment; output : the motion; units : the
    unit of H when the recording is not in SI.
    """

    f_hz: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    at_hz: np.ndarray
    segments: int
    nperseg: int
    output: str = "acceleration"
    units: str = ""  #: unit of H (``UNITS[output]`` when empty)

    @property
    def unit(self) -> str:
        """Unit label of ``H``: the recording's motion unit per its force unit."""
        return self.units or UNITS[self.output]

    @property
    def excited(self) -> np.ndarray:
        """(F, n) bool: force j excites bin f (and its column is solved there)."""
        return np.isfinite(self.at_hz)

    @property
    def resolution_hz(self) -> float:
        """Bin width [Hz]."""
        return float(self.f_hz[1] - self.f_hz[0])


def resolution_hz(chain: Chain) -> float:
    """Bin width [Hz] that resolves every underdamped mode of ``chain``: half the narrowest
    half-power bandwidth, ``min zeta f_n`` (NaN when the chain has no underdamped mode)."""
    modes = chain.modes()
    f, zeta = modes.frequencies_hz, modes.damping_ratios
    keep = (f > 0) & np.isfinite(zeta) & (zeta < 1)
    return float(np.min(zeta[keep] * f[keep])) if keep.any() else float("nan")


def segment_samples(T: int, dt: float, resolution: float | None = None, forces: int = 1) -> int:
    """Samples per Welch segment for bins of ``resolution`` [Hz] (``1 / (dt resolution)``),
    capped by the record: at most ``T / (forces + 1)``, at least ``2 forces + 1``
    half-overlapping segments, to average the ``forces`` inputs apart. Without a resolution,
    the power of two at most ``T /`` :data:`SEGMENTS`."""
    if resolution is None or not np.isfinite(resolution):
        return int(2 ** np.floor(np.log2(max(T // SEGMENTS, 16))))
    if resolution <= 0:
        raise ValueError(f"the resolution must be > 0 Hz, got {resolution:g}")
    wanted = int(np.ceil(1.0 / (dt * resolution)))
    return int(max(16, min(wanted, T // (forces + 1), T)))


def excitation(f_hz: np.ndarray, Guu_diag: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the forces excite, from their auto-spectra (F, q): ``(on, at_hz)``, (F, q) bool
    and the frequency [Hz] each excited bin stands for. A bin is excited at :data:`EXCITED`
    of the force's peak or above; a run of at most :data:`LOBE` such bins is one line's
    leakage lobe, kept at its top bin ``k`` and placed at the line's frequency
    ``f_k + delta df`` (Hann: ``delta = (2 r - 1) / (1 + r)`` towards the larger neighbour,
    ``r`` the ratio of its amplitude to the top's), where the bin's ``G_ua / G_uu`` belongs."""
    S = np.asarray(Guu_diag, dtype=float)
    df = float(f_hz[1] - f_hz[0])
    on = S >= EXCITED * S.max(axis=0, keepdims=True)
    on[0] = False  # the mean is removed from every segment: no FRF at 0 Hz
    at = np.where(on, f_hz[:, None], np.nan)
    for j in range(S.shape[1]):
        edges = np.diff(np.concatenate([[0], on[:, j].astype(int), [0]]))
        for start, stop in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]):
            if stop - start > LOBE:
                continue
            k = start + int(np.argmax(S[start:stop, j]))
            on[start:stop, j], at[start:stop, j] = False, np.nan
            side = 1 if k + 1 < S.shape[0] and (k == 0 or S[k + 1, j] >= S[k - 1, j]) else -1
            r = np.sqrt(S[k + side, j] / S[k, j]) if 0 <= k + side < S.shape[0] else 0.0
            on[k, j], at[k, j] = True, f_hz[k] + side * df * float(np.clip((2 * r - 1) / (1 + r), 0.0, 0.5))
    return on, at


def _solve_excited(Guu, Gua, excited):
    """``G_uu^-1 G_ua`` (F, q, e) per frequency over its excited forces (NaN rows elsewhere),
    and ``excited`` without the frequencies whose forces are not separable (cond > :data:`COND_MAX`)."""
    solved = np.full(Gua.shape, np.nan + 0j)
    excited = excited.copy()
    patterns, which = np.unique(excited, axis=0, return_inverse=True)
    for k, pattern in enumerate(patterns):
        rows = np.nonzero(which.ravel() == k)[0]
        if not pattern.any():
            continue
        G = Guu[np.ix_(rows, pattern, pattern)]
        separable = np.linalg.cond(G) <= COND_MAX
        excited[rows[~separable]] = False
        good = rows[separable]
        if good.size:
            solved[np.ix_(good, pattern)] = np.linalg.solve(G[separable], Gua[np.ix_(good, pattern)])
    return solved, excited


def h1_estimate(u: np.ndarray, y: np.ndarray, dt: float, nperseg: int | None = None, output="acceleration"):
    """H1 of outputs ``y`` (T, n) per forces ``u`` (T, n) [N] sampled every ``dt`` [s] where
    the forces excite them (module docstring); ``nperseg``: Welch segment length, default
    :func:`segment_samples` without a resolution."""
    from scipy.signal import csd

    u, y = np.atleast_2d(np.asarray(u, float).T).T, np.atleast_2d(np.asarray(y, float).T).T
    T, n = u.shape
    nperseg = min(int(nperseg or segment_samples(T, dt)), T)
    forced = np.nonzero(np.any(u != 0, axis=0))[0]
    if forced.size == 0:
        raise ValueError("no force: every force channel is zero, there is no FRF to estimate")
    q = forced.size
    X = np.column_stack([u[:, forced], y])
    f, S = csd(X[:, :, None], X[:, None, :], fs=1.0 / dt, nperseg=nperseg, axis=0)
    Guu, Gua, Gaa = S[:, :q, :q], S[:, :q, q:], np.einsum("fii->fi", S[:, q:, q:]).real
    on, at = excitation(f, np.einsum("fii->fi", Guu).real)
    solved, on = _solve_excited(Guu, Gua, on)
    with np.errstate(divide="ignore", invalid="ignore"):
        coherence = np.einsum("fie,fie->fe", np.where(on[:, :, None], Gua.conj(), 0), np.nan_to_num(solved)).real / Gaa
    coherence[~on.any(axis=1)] = np.nan
    H = np.full((f.size, y.shape[1], n), np.nan + 0j)
    H[:, :, forced] = np.swapaxes(solved, 1, 2)
    at_hz = np.full((f.size, n), np.nan)
    at_hz[:, forced] = np.where(on, at, np.nan)
    segments = 1 + max(0, (T - nperseg) // (nperseg // 2))
    return FrfEstimate(f, H, coherence, at_hz, segments, nperseg, output)


def recording_h1(rec, nperseg: int | None = None, resolution: float | None = None) -> FrfEstimate:
    """H1 of a :class:`algid.Recording`: accelerations when it has them, else velocities or
    displacements (the output is named in the estimate); labelled in the recording's units
    when it declares any (``Recording.units``, by role). Segments of ``nperseg`` samples, or
    for bins of ``resolution`` [Hz] as far as the record allows (:func:`segment_samples`)."""
    from dataclasses import replace

    from ..recording import motion

    kind, y = motion(rec)
    if nperseg is None:
        forces = int(np.sum(np.any(rec.u != 0, axis=0)))
        nperseg = segment_samples(rec.u.shape[0], rec.dt, resolution, max(forces, 1))
    est = h1_estimate(rec.u, y, rec.dt, nperseg, output=kind)
    labels = getattr(rec, "units", None) or {}  # a recording's declared units, by role (SI when absent)
    if labels.get(kind) or labels.get("force"):
        si = {"force": "N", "acceleration": "m/s^2", "velocity": "m/s", "displacement": "m"}
        est = replace(est, units=f"{labels.get(kind) or si[kind]}/{labels.get('force') or si['force']}")
    return est
