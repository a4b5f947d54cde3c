"""The chain's m, c, k from measured FRFs (``algid identify frf.uff``): :func:`identify_frf`.

Model (eq. 1 in frequency, :mod:`algid.model.frf`): the receptance ``G(w) = Z(w)^-1`` with the
dynamic stiffness ``Z(w) = K - w^2 M + i w C``. Every parameter enters ``Z`` as a rank-one
term, ``Z = sum_p theta_p s_p(w) u_p u_p^T`` with ``s_p = -w^2`` and ``u_p = e_i`` for mass
``i``, ``s_p = i w``, ``u_p = e_i`` for damper ``i`` and ``s_p = 1``, ``u_p = d_j`` (its row
of the deformation matrix) for spring ``j``. Parameters fixed by the topology (a free right
end's spring, the second spring of one DOF between walls: :func:`algid.model.modal.known_parameters`)
are not estimated. Stages, each entered once:

1. **Lines.** Every measured column (a force on DOF ``j``) as a receptance ``X`` (accelerance
   and mobility divided by ``-w^2`` and ``i w``; 0 Hz dropped), with a noise scale per line
   and response: ``|X| sqrt((1 - gamma^2) / gamma^2)`` from the coherence ``gamma^2`` where the
   file has one (the random error of an H1 estimate, up to the number of averages), else
   ``|X|`` (the same relative error on every line).
2. **Equation error** (linear in the parameters): ``Z(w) X(w) = e_j`` for every column, DOF
   row and line, real and imaginary parts as two equations, stacked and solved jointly. One
   column is enough: the rows of the unforced DOF are homogeneous, the forced row sets the
   scale and the springs carry it along the chain. The first pass weights each row by its
   regressor's norm (over the noise scale of its DOF), the second by the noise the first
   pass's ``Z`` puts in it (``sqrt(sum_l |Z_el|^2 scale_l^2)``).
3. **Output error**: Gauss-Newton (with step halving) on ``(G(theta) e_j - X) / scale`` over
   every line, response and column, from the equation-error estimate. This removes the bias
   noise in the regressors leaves in stage 2. Standard deviations: ``s^2 (J^T J)^-1`` with
   ``s^2`` the weighted residual's variance (a misfit inflates them).
4. **Fit check.** The noise of the data is read off the FRFs themselves, without the model:
   the second differences over neighbouring lines (noise adds up, a smooth FRF cancels) in
   units of the noise scale, robustly (the median of ``|d|^2 / 6`` over ``ln 2``, a complex
   Gaussian's). Eq. 1 explains the FRFs when the output-error residual is at most
   :data:`MISFIT` times that noise. It assumes lines dense against the resonances' half-power
   bandwidths (otherwise the FRF's own curvature counts as noise and the check is lenient)
   and independent errors on neighbouring lines (analyser smoothing makes it strict).
5. **Verdicts** (:func:`frf_verdicts`): each parameter against the largest term of the
   equations it enters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..model.chain import deformation_matrix, parameter_names
from ..model.modal import known_parameters
from ..recording.frf_file import QUANTITIES, FrfData, load_frf
from .verdicts import NEGLIGIBLE, RELATIVE, UNDETERMINED, ZERO_BOUND, Verdict

#: Output-error residual over the FRFs' own noise above which eq. 1 does not explain them.
MISFIT = 1.5
#: Most Gauss-Newton iterations of the output-error fit.
ITERATIONS = 50
#: Coherence is clipped to at most this (a noise-free line would get an infinite weight).
COHERENCE_MAX = 1.0 - 1e-9
MISFIT_REASON = "eq. 1 does not explain these FRFs to their noise"


@dataclass(frozen=True)
class Lines:
    """The measured columns as receptances: ``w`` (F,) [rad/s], ``X`` (F, n, Q) [m/N]
    (responses in DOF order), ``forced`` (Q,) 0-based DOF of each column, ``relative`` (F, n,
    Q) the noise relative to ``|X|`` (from the coherence, else 1) and ``scale`` (F, n, Q) the
    noise scale of every value (stage 1)."""

    w: np.ndarray
    X: np.ndarray
    forced: np.ndarray
    relative: np.ndarray
    scale: np.ndarray

    def rescaled(self, magnitude: np.ndarray) -> Lines:
        """These lines with the noise scale ``relative * magnitude`` (F, n, Q) [m/N]."""
        floor = 1e-12 * np.max(magnitude)  # a line exactly at an antiresonance keeps a finite weight
        return replace(self, scale=np.maximum(magnitude, floor) * self.relative)


def measured_lines(data: FrfData) -> Lines:
    """Stage 1 (module docstring); a one-line ``ValueError`` unless every DOF 1..n has a response."""
    n = data.n
    missing = sorted(set(range(1, n + 1)) - set(data.response_dof.tolist()))
    if missing:
        raise ValueError(
            f"the FRFs need a response at every DOF 1..{n} for eq. 1: none at DOF {', '.join(map(str, missing))}"
        )
    keep = data.frequency_hz > 0
    order = np.argsort(data.response_dof)
    X = np.moveaxis(data.receptance()[order][:, :, keep], 2, 0)
    if data.coherence is None:
        rel = np.ones(X.shape)
    else:
        g2 = np.clip(np.moveaxis(data.coherence[order][:, :, keep], 2, 0), 1e-12, COHERENCE_MAX)
        rel = np.sqrt((1.0 - g2) / g2)
    return Lines(2 * np.pi * data.frequency_hz[keep], X, data.force_dof - 1, rel, rel).rescaled(np.abs(X))


def rank_one_terms(n: int, boundary: str, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(free, U, S)``: the estimated packed parameters (3n+1,) bool, their vectors ``u_p``
    (n, P) and factors ``s_p(w)`` (F, P) (module docstring)."""
    free = ~known_parameters(n, boundary)
    U = np.hstack([np.eye(n), np.eye(n), deformation_matrix(n).T])[:, free]
    family = np.array(list("m" * n + "c" * n + "k" * (n + 1)))[free]
    S = np.ones((w.size, U.shape[1]), complex)
    S[:, family == "m"] = -(w**2)[:, None]
    S[:, family == "c"] = 1j * w[:, None]
    return free, U, S


def dynamic_stiffness(p: np.ndarray, U: np.ndarray, S: np.ndarray) -> np.ndarray:
    """``Z(w)`` (F, n, n) of the estimated parameters ``p`` (P,)."""
    n = U.shape[0]
    return ((S * p) @ (U[:, None, :] * U[None, :, :]).reshape(n * n, -1).T).reshape(-1, n, n)


def scaled_lstsq(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least squares of the real system ``A x = b`` (tall), columns scaled to unit norm, by its
    normal equations (a fraction of QR's time on these tall systems; the output-error
    iterations make up for their squared condition number)."""
    col = np.linalg.norm(A, axis=0)
    col[col == 0] = 1.0
    As = A / col
    return np.linalg.lstsq(As.T @ As, As.T @ b, rcond=None)[0] / col


def _weighted_solve(A: np.ndarray, b: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Least squares of complex rows ``A p = b`` (real ``p``), each row times ``weight``."""
    A, b = A * weight[:, None], b * weight
    return scaled_lstsq(np.vstack([A.real, A.imag]), np.concatenate([b.real, b.imag]))


def equation_error_fit(lines: Lines, U: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Stage 2: the estimated parameters (P,) from ``Z(w) X(w) = e_j``, two weighted passes."""
    F, n, Q = lines.X.shape
    UX = np.einsum("ep,feq->fpq", U, lines.X)
    A = S[:, None, None, :] * U[None, :, None, :] * np.swapaxes(UX, 1, 2)[:, None]  # (line, DOF, column, parameter)
    b = np.zeros((F, n, Q), complex)
    b[:, lines.forced, np.arange(Q)] = 1.0
    col = np.linalg.norm(A.reshape(-1, A.shape[-1]), axis=0)
    row = np.linalg.norm(A / np.where(col > 0, col, 1.0), axis=-1) * np.median(lines.relative, axis=0)
    A, b = A.reshape(-1, A.shape[-1]), b.reshape(-1)
    p = _weighted_solve(A, b, 1.0 / np.maximum(row.reshape(-1), 1e-300))
    Z2 = np.abs(dynamic_stiffness(p, U, S)) ** 2
    noise = np.sqrt(np.einsum("fel,flq->feq", Z2, lines.scale**2)).reshape(-1)
    return _weighted_solve(A, b, 1.0 / np.maximum(noise, 1e-300 + 1e-12 * noise.max()))


def _output_residual(p, lines: Lines, U, S) -> tuple[np.ndarray, np.ndarray]:
    """``(G, r)``: the model receptance (F, n, n) and the weighted residual (F, n, Q)."""
    G = np.linalg.inv(dynamic_stiffness(p, U, S))
    return G, (G[:, :, lines.forced] - lines.X) / lines.scale


def _jacobian(G, lines: Lines, U, S) -> np.ndarray:
    """d r / d p (F, n, Q, P): ``dG = -s_p (G u_p)(u_p^T G)`` for a rank-one term."""
    GU = np.einsum("fij,jp->fip", G, U)
    UG = np.einsum("ip,fiq->fpq", U, G[:, :, lines.forced])
    return -(S[:, None, None, :] * GU[:, :, None, :] * np.swapaxes(UG, 1, 2)[:, None]) / lines.scale[..., None]


def _real(z: np.ndarray) -> np.ndarray:
    return np.concatenate([z.real.reshape(-1, *z.shape[3:]), z.imag.reshape(-1, *z.shape[3:])])


def output_error_fit(p: np.ndarray, lines: Lines, U, S) -> tuple[np.ndarray, np.ndarray, int]:
    """Stage 3: ``(p, covariance (P, P), iterations)`` of the output-error fit from ``p``."""
    G, r = _output_residual(p, lines, U, S)
    cost, iterations = float(np.sum(np.abs(r) ** 2)), 0
    while iterations < ITERATIONS:
        iterations += 1
        J = _real(_jacobian(G, lines, U, S))
        step = scaled_lstsq(J, -_real(r))
        for _ in range(30):  # halve the step until the cost goes down
            G_new, r_new = _output_residual(p + step, lines, U, S)
            new = float(np.sum(np.abs(r_new) ** 2))
            if new <= cost:
                break
            step = step / 2
        else:
            break
        converged = np.all(np.abs(step) <= 1e-13 * np.abs(p)) or new >= cost * (1 - 1e-14)
        p, G, r, cost = p + step, G_new, r_new, new
        if converged:
            break
    J = _real(_jacobian(G, lines, U, S))
    dof = max(J.shape[0] - J.shape[1], 1)
    return p, (cost / dof) * np.linalg.pinv(J.T @ J), iterations


def frf_noise(lines: Lines) -> float:
    """Stage 4: the FRFs' own noise in units of their noise scale (rms of the complex
    error), from second differences over neighbouring lines, robustly."""
    d = (lines.X[:-2] - 2 * lines.X[1:-1] + lines.X[2:]) / lines.scale[1:-1]
    return float(np.sqrt(np.median(np.abs(d) ** 2) / 6.0 / math.log(2.0)))


def fit_check(lines: Lines, p: np.ndarray, U, S) -> dict:
    """``residual`` (the output-error residual's rms, per complex value, corrected for the
    parameters fitted), ``noise`` (:func:`frf_noise`), their ``ratio`` and ``explains_data``
    (ratio at most :data:`MISFIT`, or a residual at rounding level)."""
    _, r = _output_residual(p, lines, U, S)
    residual = math.sqrt(float(np.sum(np.abs(r) ** 2)) / max(r.size - p.size / 2, 1))
    noise = frf_noise(lines)
    ratio = residual / noise if noise > 0 else (0.0 if residual == 0 else math.inf)
    return {
        "residual": residual,
        "noise": noise,
        "ratio": ratio,
        "threshold": MISFIT,
        "explains_data": bool(ratio <= MISFIT or residual <= 1e-9),
        "rule": "output-error residual over the noise read off second differences of neighbouring lines, "
        "both relative to the noise scale (coherence, else |H|)",
    }


def force_shares(theta: np.ndarray, lines: Lines, U, S) -> np.ndarray:
    """(P,) ``||s_p u_p u_p^T X||`` over the largest term (a parameter's or the unit force)
    of each DOF equation it enters, the largest over those equations (norms over lines and
    columns): the share of the estimated parameter ``p`` is ``|theta_p|`` times this."""
    UX = np.einsum("ep,feq->fpq", U, lines.X)
    reg = np.sqrt(np.einsum("fp,ep,fpq->ep", np.abs(S) ** 2, U**2, np.abs(UX) ** 2))  # (n, P)
    force = np.zeros(U.shape[0])
    np.add.at(force, lines.forced, lines.X.shape[0])  # |e_j|^2 over every line of its column
    scale = np.maximum(np.max(np.abs(theta) * reg, axis=1), np.sqrt(force))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nanmax(np.where(reg > 0, reg / scale[:, None], np.nan), axis=0)


def frf_verdicts(theta, sigma, ratio, n: int, boundary: str, misfit: str = "") -> list[Verdict]:
    """One :class:`~.verdicts.Verdict` per packed parameter (3n+1): ``known`` /
    ``not_separable`` where the topology fixes it; ``not_identifiable`` without a finite
    estimate, for a mass not above zero by three sigma or with a relative uncertainty above
    :data:`~.verdicts.RELATIVE`, for a damping or spring whose three sigma stand for more
    than :data:`~.verdicts.UNDETERMINED` of its equation's largest term, or that is
    consistent with zero beyond :data:`~.verdicts.ZERO_BOUND`; ``negligible`` for a damping
    or spring consistent with zero within it or under :data:`~.verdicts.NEGLIGIBLE` (three
    sigma included); ``inadmissible`` below zero by three sigma; ``model_misfit`` when the fit
    check fails (``misfit``); else ``ok``. ``ratio`` (3n+1,): :func:`force_shares`."""
    out = []
    for p, name in enumerate(parameter_names(n)):
        th, sg, share, ss = theta[p], sigma[p], abs(theta[p]) * ratio[p], sigma[p] * ratio[p]
        fam, what = name[0], {"m": "mass", "c": "damping", "k": "stiffness"}[name[0]]
        if name == f"k{n + 1}" and boundary == "free":
            status, reason = "known", f"free right end: k{n + 1} = 0"
        elif name == "k2" and n == 1:
            status, reason = "not_separable", "one DOF between walls: only k1 + k2 is identifiable, reported as k1"
        elif not (np.isfinite(th) and np.isfinite(sg)):
            status, reason = "not_identifiable", f"{what} not identifiable: the fit has no finite estimate"
        elif th < -3 * sg and share + 3 * ss > NEGLIGIBLE:
            status, reason = "inadmissible", f"negative {what}: {MISFIT_REASON}"
        elif fam == "m" and (th <= 3 * sg or sg > RELATIVE * abs(th)):
            status, reason = "not_identifiable", f"mass not identifiable: {name} = {th:.3g} +- {sg:.2g}"
        elif fam != "m" and ss > UNDETERMINED:
            status = "not_identifiable"
            reason = f"{what} not identifiable: its uncertainty is {100 * ss:.2g} % of its equation's largest term"
        elif fam != "m" and (abs(th) <= 3 * sg or share + 3 * ss <= NEGLIGIBLE):
            small = 3 * ss <= ZERO_BOUND or share + 3 * ss <= NEGLIGIBLE
            status = "negligible" if small else "not_identifiable"
            reason = f"{what} consistent with zero: {100 * (share + 3 * ss):.2g} % of its equation's largest term"
        else:
            status, reason = "ok", ""
        if misfit and status in ("ok", "negligible", "inadmissible"):
            status, reason = "model_misfit", f"{what} biased: {misfit}"
        out.append(Verdict(name, status, reason, float(share), float(ss)))
    return out


def fit_frf(data: FrfData, boundary: str = "fixed") -> dict:
    """Stages 1-4: ``theta``, ``sigma``, ``covariance`` (packed, 3n+1), ``equation_error``
    (the stage-2 estimate), ``iterations``, ``model_fit`` and ``shares`` (:func:`force_shares`)."""
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    n = data.n
    lines = measured_lines(data)
    free, U, S = rank_one_terms(n, boundary, lines.w)
    if lines.X.shape[0] * 2 * lines.X.shape[2] < 2 * U.shape[1]:
        raise ValueError(f"{lines.X.shape[0]} frequency lines are too few for {U.shape[1]} parameters")
    p0 = equation_error_fit(lines, U, S)
    p, _, first = output_error_fit(p0, lines, U, S)
    # weights from the measured |X| favour lines the noise made smaller: once more with the model's
    lines = lines.rescaled(np.abs(_output_residual(p, lines, U, S)[0][:, :, lines.forced]))
    p, cov, iterations = output_error_fit(p, lines, U, S)
    iterations += first
    theta, sigma = np.full(3 * n + 1, np.nan), np.full(3 * n + 1, np.nan)
    theta[free], sigma[free] = p, np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if boundary == "free":
        theta[-1], sigma[-1] = 0.0, 0.0
    shares, covariance = np.full(3 * n + 1, np.nan), np.zeros((3 * n + 1, 3 * n + 1))
    shares[free] = force_shares(p, lines, U, S)
    covariance[np.ix_(free, free)] = cov
    eq = np.full(3 * n + 1, np.nan)
    eq[free] = p0
    return {
        "theta": theta,
        "sigma": sigma,
        "covariance": covariance,
        "equation_error": eq,
        "iterations": iterations,
        "model_fit": fit_check(lines, p, U, S),
        "shares": shares,
    }


def identify_frf(source, boundary: str = "fixed"):
    """Identify the chain of measured FRFs (an FRF ``.npz``, a UFF file with function type 4,
    a mapping or :class:`~algid.recording.frf_file.FrfData`; :func:`load_frf`): estimates,
    standard deviations and verdicts (module docstring) as an
    :class:`~.frf_result.FrfIdentification`, which prints and writes JSON as
    :class:`~.result.Identification` does."""
    from .frf_result import FrfIdentification

    data = load_frf(source)
    fit = fit_frf(data, boundary)
    misfit = "" if fit["model_fit"]["explains_data"] else MISFIT_REASON
    verdicts = frf_verdicts(fit["theta"], fit["sigma"], fit["shares"], data.n, boundary, misfit)
    return FrfIdentification(n=data.n, boundary=boundary, data=data, verdicts=verdicts, **fit)


def model_frf(theta: np.ndarray, data: FrfData, boundary: str = "fixed") -> np.ndarray:
    """The FRFs (R, Q, F) of packed parameters ``theta`` (3n+1,) at the lines, responses and
    forces of ``data``, in its quantity (receptance times ``(i w)^p``); any finite values,
    admissible or not."""
    f = data.frequency_hz
    free, U, S = rank_one_terms(data.n, boundary, 2 * np.pi * f)
    with np.errstate(divide="ignore", invalid="ignore"):
        G = np.linalg.inv(dynamic_stiffness(theta[free], U, S))
    G = G[:, data.response_dof - 1][:, :, data.force_dof - 1]
    return np.moveaxis(G * (2j * np.pi * f[:, None, None]) ** QUANTITIES[data.quantity][1], 0, 2)
