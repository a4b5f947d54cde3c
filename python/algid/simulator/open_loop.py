"""The open-loop driver: the force is known beforehand, so its contribution to every
step is computed for the whole record at once and the state is stepped sample by sample."""

from __future__ import annotations

import numpy as np

from .pieces import peval, recorded_pieces
from .result import LIMIT_NAMES, Samples
from .run import Run
from .state_space import Propagator

__all__ = ["run_open_loop"]


def run_open_loop(run: Run) -> Samples:
    """Integrate an open loop from its initial state; the noise-free samples."""
    inp, J = run.inputs, run.schedule.J
    s = run.initial_state()
    rec = recorded_pieces(inp)
    app = run.routing.applied_pieces(rec)
    Wf, Wh, W2 = _input_terms(run.stepper.P, app, run.plant.nonlinear)
    app_r = app[:, 0, 0]
    app_l = np.empty((inp.T, inp.n))
    app_l[0] = app_r[0]
    app_l[1:] = peval(app[:-1, J - 1], run.schedule.lengths_s[-1])
    if run.layout.n_lp:
        _settle_lowpass(run, s, app_r[0])
    S = _integrate(run, s, app, Wf, Wh, W2)
    return _samples(run, S, rec, app_l, app_r)


def _input_terms(P: list[Propagator], app: np.ndarray, nonlinear: bool) -> tuple[np.ndarray, ...]:
    """Exact contributions ``(Wf, Wh, W2)`` (T, J, m) of the applied pieces over every
    sub-interval, its first half and its second half (the last two only for ETDRK4)."""
    T, J = app.shape[:2]
    m = P[0].E.shape[0]
    Wf = np.empty((T, J, m))
    for q in range(J):
        Wf[:, q] = np.einsum("jmn,kjn->km", P[q].G, app[:, q])
    if not nonlinear:
        return Wf, None, None
    Wh = np.empty((T, J, m))
    W2 = np.empty((T, J, m))
    for q in range(J):
        Wh[:, q] = np.einsum("jmn,kjn->km", P[q].Gh, app[:, q])
        W2[:, q] = Wf[:, q] - Wh[:, q] @ P[q].E2.T
    return Wf, Wh, W2


def _settle_lowpass(run: Run, s: np.ndarray, u0: np.ndarray) -> None:
    """Start the low-pass accelerometers settled on ``a(0+)`` (``u0``: the applied force at 0+);
    the high-pass ones at ``z = 0`` (settled on the structure at rest before the record: they
    read ``a(0+)``)."""
    n, lay, plant = run.inputs.n, run.layout, run.plant
    f0 = (s[lay.o_w : lay.o_z] if lay.n_w else u0) - plant.c * s[n : 2 * n] - plant.K @ s[:n]
    if plant.nonlinear:
        f0 = f0 + plant.effect_force(0.0, s[:n], s[n : 2 * n])
    s[lay.o_lp : lay.o_w] = np.where(lay.lp_high, 0.0, (f0 * plant.minv)[lay.lp_idx])


def _integrate(
    run: Run, s: np.ndarray, app: np.ndarray, Wf: np.ndarray, Wh: np.ndarray | None, W2: np.ndarray | None
) -> np.ndarray:
    """States (T, m) at the sample instants."""
    inp, P, lens = run.inputs, run.stepper.P, run.schedule.lengths_s
    T, J = inp.T, run.schedule.J
    nonlinear = run.plant.nonlinear
    N_open = run.plant.state_force  # N(t, s) = effect forces, entering as Bg @ N
    S = np.empty((T, s.size))
    Es = [p.E for p in P]
    for k in range(T):
        S[k] = s
        if k == T - 1:
            break
        run.report(k)
        if nonlinear:
            tq = inp.t[k]
            for q in range(J):
                s = run.stepper.step(q, s, tq, app[k, q], Wf[k, q], Wh[k, q], W2[k, q], N_open)
                tq += lens[q]
        else:
            for q in range(J):
                s = Es[q] @ s + Wf[k, q]
        if k % 256 == 0 and not np.all(np.isfinite(s)):
            raise RuntimeError(f"the simulation diverged before t = {inp.t[k + 1]:.6g} s")
    return S


def _samples(run: Run, S: np.ndarray, rec: np.ndarray, app_l: np.ndarray, app_r: np.ndarray) -> Samples:
    """The noise-free samples from the states; forces and accelerations as the mean of
    their one-sided limits (sampling convention of :mod:`algid.simulator`)."""
    inp, lay, plant = run.inputs, run.layout, run.plant
    n = inp.n
    X, V = S[:, :n], S[:, n : 2 * n]
    g_all = plant.effect_force(inp.t, X, V) if plant.nonlinear else 0.0
    if lay.n_w:
        app_l = app_r = S[:, lay.o_w : lay.o_z]
        rec_l = rec_r = S[:, lay.o_w : lay.o_z]
    else:
        rec_r = rec[:, 0]
        rec_l = np.empty((inp.T, n))
        rec_l[0] = rec_r[0]
        rec_l[1:] = peval(rec[:-1], inp.h)
    base = g_all - V * plant.c - X @ plant.K.T
    values = ((app_l + base) * plant.minv, (app_r + base) * plant.minv, rec_l, rec_r, app_l, app_r)
    lim = {name: np.array(v) for name, v in zip(LIMIT_NAMES, values)}
    A_true = 0.5 * (lim["a_minus"] + lim["a_plus"])
    A_clean = A_true.copy()
    if lay.n_lp:  # a low-pass reads its state z, a high-pass a - z
        Z, high = S[:, lay.o_lp : lay.o_w], lay.lp_high
        A_clean[:, lay.lp_idx[~high]] = Z[:, ~high]
        A_clean[:, lay.lp_idx[high]] -= Z[:, high]
    A_clean += run.bias
    return Samples(
        x=X.copy(),
        v=V.copy(),
        a_true=A_true,
        a_clean=A_clean,
        u_rec=0.5 * (rec_l + rec_r),
        u_applied=0.5 * (app_l + app_r),
        limits=lim,
    )
