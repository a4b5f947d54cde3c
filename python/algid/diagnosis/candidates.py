"""Candidate unmodelled effects, each fitted as an augmentation of the windowed equations.

The definitions are those of the simulator (the names are part of the interface). Spring
``j`` joins DOF ``j-1`` and DOF ``j`` with deformation ``d_j = x_j - x_{j-1}`` (walls at
``x_0 = x_{n+1} = 0``); a spring force ``f(d_j)`` enters the equation of DOF ``j`` with
``+`` and that of DOF ``j-1`` with ``-``, like the linear ``k_j d_j``.

| effect | location | what it adds / changes | parameters (first = main) |
|---|---|---|---|
| coulomb_friction | dof i | ``+ force * tanh(v_i / v_scale)`` in eq. i | force [N], v_scale [m/s] |
| stribeck_friction | dof i | ``+ (force + (static - force) exp(-(v_i/v_s)^2)) sgn(v_i)`` | force, static [N], v_s |
| amplitude_damping | spring j | ``f = c_amp * |d| d'`` (micro-slip: damping growing with amplitude) | c_amp [N s/m^2] |
| quadratic_damping | dof i | ``+ c_quadratic * v_i |v_i|`` in eq. i | c_quadratic [N s^2/m^2] |
| cubic_stiffness | spring j | ``f = k_cubic d^3`` | k_cubic [N/m^3] |
| clearance | spring j | ``f = k_contact * sign(d) max(|d| - gap, 0)`` | gap [m], k_contact [N/m] |
| input_delay | dof i | eq. i is driven by ``u_i(t - delay)`` | delay [s] |
| sensor_bias | dof i | true acceleration is ``a_i - bias`` | bias [m/s^2] |
| sensor_lowpass | dof i | measured ``a_i`` is the first-order low-pass of the true one | cutoff_hz [Hz] |
| sensor_highpass | dof i | measured ``a_i`` is the first-order high-pass (AC coupling) of the truth | cutoff_hz |
| parameter_drift | spring j | ``k_j(t) = k_j (1 + rel_change (t - t_0) / duration)`` | rel_change [-] |

How each enters the least-squares problem (everything else as in :mod:`.core`): an
effect force ``g`` (eq. 1 read as ``m a + c v + k x + g = u``) enters equation e as
``-g / m_e`` in the acceleration form, with ``m_e`` from the linear fit, and as ``g`` in
the force form (:func:`.equations.effect_column`), so that its coefficient is the physical
parameter either way:

* linear in the effect parameter, from the reconstructed states ``x``, ``v``: quadratic
  damping (``v|v|``), cubic spring (``d^3``), drift (``(t - t_0)/duration * d``,
  coefficient ``k_j rel_change``);
* amplitude damping, linear in ``c_amp``: ``|d| d'`` from the states;
* one nonlinear parameter on a grid, linear coefficients solved at every grid value:
  Coulomb friction (``v_scale``: a log grid below the RMS velocity, ``tanh(v / v_scale)``),
  Stribeck friction (``v_stribeck``: a log grid below the RMS velocity; two coefficients,
  the Coulomb level on ``sign(v)`` and the static excess on ``exp(-(v/v_s)^2) sign(v)``; it
  is reported only when the excess is beyond :data:`STRIBECK_Z` of its jackknife sigma,
  else it is Coulomb friction with extra freedom),
  clearance (``gap``: quantiles of ``|d_j|``), input delay (``delay``: log grid, the force
  shifted by cubic-spline interpolation), sensor low-pass (``cutoff``: log grid; equation
  i is filtered by the same low-pass — ``m a + c v + k (x_i - LP x_other) = LP u`` holds
  exactly for the measured ``a_i`` — and the true ``x_i = x_meas + v_meas / (2 pi fc)`` in
  the neighbouring equations, so no measured signal is differentiated), sensor high-pass
  (``cutoff``: log grid; the inverse filter ``1 + w_c / s`` recovers the truth from the
  measured signal and its integrals, ``a_i = a + w_c A1``, ``v_i = A1 + w_c A2``,
  ``x_i = A2 + w_c A3`` with ``A3`` the third integral, all from the first sample: the
  high-pass is taken settled at rest there, its state zero, as the simulator starts it);
* sensor bias: the true ``x_i`` is ``x_meas - bias t^2 / 2``, which leaves
  ``-bias t^2/2 * (sum of the springs of eq. i)`` and ``+bias t^2/2 * k_j`` in the
  neighbours (the rest is a per-window line, removed anyway); the stiffnesses are taken
  from the linear fit, then from a second pass with the bias.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter, lfilter_zi

from .equations import base_design, effect_column, linear_design, target, to_physical
from .gram import CVResult, EqSpec, cross_validate, jackknife_std, score_walk, walk_grid, window_stats
from .integrals import integrals
from .linear import LinearFit
from .windows import Prepared

EFFECTS = (
    "coulomb_friction",
    "stribeck_friction",
    "quadratic_damping",
    "amplitude_damping",
    "cubic_stiffness",
    "clearance",
    "input_delay",
    "sensor_bias",
    "sensor_lowpass",
    "sensor_highpass",
    "parameter_drift",
)

#: Main parameter of every effect (the first of its parameters).
MAIN_PARAM = {
    "coulomb_friction": "force",
    "stribeck_friction": "force",
    "amplitude_damping": "c_amp",
    "quadratic_damping": "c_quadratic",
    "cubic_stiffness": "k_cubic",
    "clearance": "gap",
    "input_delay": "delay",
    "sensor_bias": "bias",
    "sensor_lowpass": "cutoff_hz",
    "sensor_highpass": "cutoff_hz",
    "parameter_drift": "rel_change",
}

#: What a fitted effect must satisfy to be physical: friction and damping dissipate (a
#: negative friction force or quadratic damping would feed energy in), a clearance has a
#: positive gap and contact stiffness, a delay and a cut-off are positive. A candidate that
#: fits only with the wrong sign is not an explanation, whatever its gap.
PHYSICAL = {
    "coulomb_friction": lambda p: p["force"] > 0,
    "stribeck_friction": lambda p: p["force"] > 0 and p["static"] > p["force"],
    "amplitude_damping": lambda p: p["c_amp"] > 0,
    "quadratic_damping": lambda p: p["c_quadratic"] > 0,
    "clearance": lambda p: p["gap"] > 0 and p["k_contact"] > 0,
    "input_delay": lambda p: p["delay"] > 0,
    "sensor_lowpass": lambda p: p["cutoff_hz"] > 0,
    "sensor_highpass": lambda p: p["cutoff_hz"] > 0,
}


def physical(fit: CandidateFit) -> bool:
    """True when the fitted parameters have physical signs (:data:`PHYSICAL`); for a
    combination, every part's."""
    if "+" in fit.effect:
        return all(PHYSICAL.get(eff, lambda p: True)(fit.params[eff]) for eff in fit.effect.split("+"))
    rule = PHYSICAL.get(fit.effect)
    return True if rule is None else bool(rule(fit.params))


#: A Stribeck peak counts only beyond this many jackknife sigma of its excess over the
#: Coulomb level (the nested Coulomb model otherwise explains as much).
STRIBECK_Z = 4.0
#: Velocity scale of the Stribeck candidate's sign, a share of its Stribeck velocity, when
#: no Coulomb candidate was fitted at the same DOF first.
STRIBECK_SIGN = 0.05
#: Smallest Stribeck velocity searched, in shares of the velocity scale over which the
#: Coulomb fit's sign fades in (the velocity noise around rest): a peak narrower than that
#: fade-in is not told apart from it by the record.
STRIBECK_RESOLVED = 3.0
#: Longest input delay searched [samples]; the analysis skips at least this many samples.
MAX_DELAY_SAMPLES = 100


def lead_in(T: int, dt: float) -> int:
    """Samples the analysis skips at the start of a record of ``T``: 0.1 s, at least
    :data:`MAX_DELAY_SAMPLES` (the delay candidate looks that far back), at most a tenth."""
    return int(min(max(MAX_DELAY_SAMPLES, round(0.1 / dt)), T // 10))


#: Points of a candidate's grid (:func:`_fit_grid`), and of the quick grid (no refinement)
#: that :func:`algid.identify`'s fit check searches.
N_GRID = 24
QUICK_GRID = 8
#: Refinement factor of the second grid stage.
FINE = 4


@dataclass
class Context:
    """What the candidates are fitted against: windows, linear fit and states."""

    P: Prepared
    lin: LinearFit
    x: np.ndarray
    v: np.ndarray
    #: what one candidate's fit tells another (the Coulomb velocity scale of each DOF)
    shared: dict = field(default_factory=dict)
    #: points of every grid search, and whether the second stage refines it
    grid: int = N_GRID
    refine: bool = True

    @property
    def mass(self) -> np.ndarray:
        return self.lin.mass


@dataclass
class CandidateFit:
    """A fitted candidate: cross-validation result, parameters and their std."""

    effect: str
    location: dict | None
    eqs: list[int]
    cv: CVResult
    params: dict[str, float]
    params_std: dict[str, float]
    thetas: list[np.ndarray]  # acceleration-form parameters of the candidate's equations
    specs: list[EqSpec] = field(repr=False, default_factory=list)
    #: fits the candidate again, exactly as it was fitted (its equations are rebuilt from it
    #: after :meth:`release`)
    remake: Callable[[], CandidateFit] | None = field(repr=False, default=None)

    def equations(self) -> list[EqSpec]:
        """The candidate's equations (:class:`EqSpec`), rebuilt if they were released."""
        if not self.specs and self.remake is not None:
            self.specs = self.remake().specs
        return self.specs

    def release(self) -> None:
        """Drop the equations' columns (a few columns of the record's length each, for
        every one of dozens of candidates) when they can be rebuilt."""
        if self.remake is not None:
            self.specs = []


def coupled(P: Prepared, i: int) -> list[tuple[int, int]]:
    """Equations (other than i) whose spring columns involve x_i: (equation, spring)."""
    out = []
    for e, cols in enumerate(P.columns):
        for j, other in cols:
            if other == i and e != i:
                out.append((e, j))
    return out


def _cubic_gauss() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """8-point Gauss-Legendre nodes on [0, 1], their weights, and the (4, 8) values there of the
    Lagrange polynomials of the cubic through the samples at -1, 0, 1, 2 (:func:`lowpass`)."""
    gx, gw = np.polynomial.legendre.leggauss(8)
    s_ = 0.5 * (gx + 1.0)
    nodes = np.array([-1.0, 0.0, 1.0, 2.0])
    lagrange = np.array([np.prod([(s_ - o) / (nodes[m] - o) for o in np.delete(nodes, m)], axis=0) for m in range(4)])
    return s_, gw, lagrange


_CUBIC_GAUSS = _cubic_gauss()


def lowpass(x: np.ndarray, cutoff_hz: float, dt: float) -> np.ndarray:
    """First-order low-pass ``y' = 2 pi fc (x - y)`` of sampled columns (axis 0).

    Exact for an input that is the cubic through the four nearest samples on every
    interval (as smooth as the spline a simulator or a DAC reconstruction gives; a
    piecewise-linear input model is off by ~(w dt)^2 / 8, which matters for cutoffs near
    the Nyquist rate): ``y_{k+1} = alpha y_k + sum_m w_m x_{k-1+m}`` with the weights
    integrated by 8-point Gauss-Legendre. Started at ``y = x``; the start-up transient
    decays with the time constant ``1 / (2 pi fc)``.
    """
    wc = 2 * np.pi * cutoff_hz
    lam = wc * dt
    al = np.exp(-lam)
    s_, gw, lagrange = _CUBIC_GAUSS
    kern = 0.5 * gw * lam * np.exp(-lam * (1.0 - s_))
    w = lagrange @ kern
    x2 = np.asarray(x, dtype=float)
    x2 = x2 if x2.ndim == 2 else x2[:, None]
    # Two copies of the first sample in front and one extrapolated sample at the end (the
    # cubic through the last four); with xp[j] = x[j-2] the filter
    # z[j] = al z[j-1] + w3 xp[j] + w2 xp[j-1] + w1 xp[j-2] + w0 xp[j-3] gives y[n] = z[n+3].
    ext = (4 * x2[-1] - 6 * x2[-2] + 4 * x2[-3] - x2[-4])[None, :]
    xp = np.concatenate([x2[:1], x2[:1], x2, ext], axis=0)
    b, a = w[::-1], np.array([1.0, -al])
    zi = lfilter_zi(b, a)[:, None] * xp[0][None, :]  # settled on the first sample
    y = lfilter(b, a, xp, axis=0, zi=zi)[0][3:]
    return y if np.ndim(x) == 2 else y[:, 0]


def _fit_linear_effect(
    ctx: Context,
    effect: str,
    location: dict,
    eq_forces: list[tuple[int, np.ndarray]],
    names: list[str],
    transform=None,
    signals: tuple | None = None,
) -> CandidateFit:
    """Linear model plus one shared effect parameter: ``eq_forces`` gives, per equation,
    the effect force per unit parameter ``g`` (eq. 1 read as ``m a + c v + k x + g = u``,
    :func:`.equations.effect_column`); ``signals = (a, A1, A2)`` replaces the measured
    acceleration and its integrals (e.g. bias-corrected)."""
    P = ctx.P
    specs = []
    for e, g in eq_forces:
        col = effect_column(P, e, g, ctx.mass)
        if signals is None:
            specs.append(EqSpec(e=e, X=linear_design(P, e), y=target(P, e), E=col[:, None], key=("base", e)))
        else:
            a, A1, A2 = signals
            specs.append(EqSpec(e=e, X=base_design(P, e, A1, A2, a=a[:, e]), y=target(P, e, a=a[:, e]), E=col[:, None]))
    cv = cross_validate(P, window_stats(P, specs))
    thetas = [cv.theta[s] for s in cv.stats.slices]
    gam = cv.theta[cv.stats.shared]
    gam_f = cv.theta_folds[:, cv.stats.shared]
    if transform is not None:
        vals = transform(gam, [to_physical(P, s.e, th) for s, th in zip(specs, thetas)])
        vals_f = np.array(
            [
                transform(
                    gam_f[k], [to_physical(P, s.e, cv.theta_folds[k][sl]) for s, sl in zip(specs, cv.stats.slices)]
                )
                for k in range(gam_f.shape[0])
            ]
        )
    else:
        vals, vals_f = gam, gam_f
    std = jackknife_std(vals_f)
    return CandidateFit(
        effect=effect,
        location=location,
        eqs=[s.e for s in specs],
        cv=cv,
        params={nm: float(vals[k]) for k, nm in enumerate(names)},
        params_std={nm: float(std[k]) for k, nm in enumerate(names)},
        thetas=thetas,
        specs=specs,
    )


def fit_dof_force(ctx: Context, effect: str, i: int) -> CandidateFit:
    """Quadratic damping at DOF i (0-based)."""
    v = ctx.v[:, i]
    return _fit_linear_effect(ctx, effect, {"dof": i + 1}, [(i, v * np.abs(v))], [MAIN_PARAM[effect]])


def fit_coulomb(ctx: Context, i: int) -> CandidateFit:
    """Dry friction ``force tanh(v / v_scale)`` at DOF i (0-based), ``v_scale`` on a grid
    from ``1e-4`` to ``0.3`` times the RMS velocity (the first is a sign; a larger scale is
    friction that fades in around rest, as a drive's or a regularised model's does, and
    keeps the velocity noise of a resting axis from flipping a sign)."""
    P = ctx.P
    v = ctx.v[:, i]
    grid = np.log(np.sqrt(np.mean(v**2)) * np.geomspace(1e-4, 0.3, ctx.grid))

    def build(lg):
        col = effect_column(P, i, np.tanh(v / np.exp(lg)), ctx.mass)
        return [EqSpec(e=i, X=linear_design(P, i), y=target(P, i), E=col[:, None], key=("base", i))]

    fit = _fit_grid(ctx, "coulomb_friction", {"dof": i + 1}, build, grid, np.exp, ["v_scale"], ["force"])
    ctx.shared[("v_scale", i)] = fit.params["v_scale"]
    order = ("force", "v_scale")
    fit.params = {k: fit.params[k] for k in order}
    fit.params_std = {k: fit.params_std[k] for k in order}
    return fit


def fit_stribeck(ctx: Context, i: int) -> CandidateFit:
    """Stribeck friction at DOF i (0-based), see the module docstring."""
    P = ctx.P
    v = ctx.v[:, i]
    rms = np.sqrt(np.mean(v**2))
    v_sign = ctx.shared.get(("v_scale", i))  # the Coulomb fit's: the velocity noise around rest
    lowest = 1e-3 * rms if v_sign is None else max(1e-3 * rms, STRIBECK_RESOLVED * v_sign)
    grid = np.log(np.geomspace(min(lowest, rms), rms, ctx.grid))

    # the friction's sign fades in as the Coulomb candidate found, or well inside the zone
    found = None if v_sign is None else np.tanh(v / v_sign)
    v2 = v**2

    def build(lg):
        vs = np.exp(lg)
        sgn = found if found is not None else np.tanh(v / (STRIBECK_SIGN * vs))
        cols = np.stack(
            [effect_column(P, i, sgn, ctx.mass), effect_column(P, i, np.exp(-v2 / vs**2) * sgn, ctx.mass)], axis=1
        )
        return [EqSpec(e=i, X=linear_design(P, i), y=target(P, i), E=cols, key=("base", i))]

    fit = _fit_grid(ctx, "stribeck_friction", {"dof": i + 1}, build, grid, np.exp, ["v_stribeck"], ["force", "excess"])
    p, sd = fit.params, fit.params_std
    fit.params = {"force": p["force"], "static": p["force"] + p["excess"], "v_stribeck": p["v_stribeck"]}
    fit.params_std = {
        "force": sd["force"],
        "static": float(np.hypot(sd["force"], sd["excess"])),
        "v_stribeck": sd["v_stribeck"],
        "excess": sd["excess"],
    }
    if not abs(p["excess"]) > STRIBECK_Z * sd["excess"]:
        fit.params["static"] = float("nan")  # no peak beyond noise: not Stribeck (PHYSICAL fails)
    return fit


def fit_amplitude_damping(ctx: Context, j: int) -> CandidateFit:
    """Amplitude-dependent (micro-slip) damping in the joint of spring j (1-based)."""
    P = ctx.P
    d = P.deformation(ctx.x, j)
    dd = P.deformation(ctx.v, j)
    g = np.abs(d) * dd
    return _fit_linear_effect(ctx, "amplitude_damping", {"spring": j}, [(e, s * g) for e, s in P.sides(j)], ["c_amp"])


def spring_k(P: Prepared, thetas: list[np.ndarray], eqs: list[int], j: int) -> float:
    """Mean stiffness of spring j over the equations that estimate it (physical thetas)."""
    vals = []
    for th, e in zip(thetas, eqs):
        for (jj, _), k in zip(P.columns[e], th[2:]):
            if jj == j:
                vals.append(k)
    return float(np.mean(vals)) if vals else float("nan")


def fit_spring_linear(ctx: Context, effect: str, j: int) -> CandidateFit:
    """Cubic stiffness or parameter drift on spring j (1-based)."""
    P = ctx.P
    d = P.deformation(ctx.x, j)
    if effect == "cubic_stiffness":
        f = d**3
        transform = None
    else:  # parameter_drift: coefficient k_j * rel_change
        f = (P.t / P.duration) * d
        sides = [e for e, _ in P.sides(j)]

        def transform(gam, thetas):
            return np.atleast_1d(gam) / spring_k(P, thetas, sides, j)

    return _fit_linear_effect(
        ctx, effect, {"spring": j}, [(e, s * f) for e, s in P.sides(j)], [MAIN_PARAM[effect]], transform
    )


def _fit_grid(
    ctx: Context,
    effect: str,
    location: dict,
    build,
    grid: np.ndarray,
    to_param,
    names: list[str],
    shared_names: list[str],
) -> CandidateFit:
    """Grid search of one nonlinear parameter; ``build(g) -> specs``; ``to_param`` maps
    the search coordinate to the reported parameter.

    Two stages: the coarse ``grid``, then a grid :data:`FINE` times finer spanning the
    coarse neighbours of every fold's choice and of the all-window choice (so each fold
    refines inside its own bracket), on which the cross-validation is repeated.
    """
    P = ctx.P
    fitting: dict[float, object] = {}  # the fitting Grams of every grid value walked (the fine grid holds the coarse)

    def stats_of(g: float, scoring: bool):
        if scoring:
            return window_stats(P, build(g), True)
        if g not in fitting:
            fitting[g] = window_stats(P, build(g), False)
        return fitting[g]

    walk = walk_grid(P, stats_of, grid)
    lo, hi = max(min(walk.pick) - 1, 0), min(max(walk.pick) + 1, len(grid) - 1)
    if hi > lo and ctx.refine:
        fine = np.interp(np.arange(FINE * (hi - lo) + 1) / FINE, np.arange(hi - lo + 1), grid[lo : hi + 1])
        walk = walk_grid(P, stats_of, fine)
    cv = score_walk(P, stats_of, walk)
    g = cv.extra["g"]
    specs = build(g)  # refit at the refined value
    cv_ref = cross_validate(P, window_stats(P, specs))
    cv.theta = cv_ref.theta
    cv.stats = cv_ref.stats
    cv.fit_sse = cv_ref.fit_sse
    thetas = [cv.theta[s] for s in cv.stats.slices]
    params = {names[0]: float(to_param(g))}
    stds = {names[0]: float(jackknife_std(np.array([to_param(x) for x in cv.extra["g_folds"]])[:, None])[0])}
    if shared_names:
        gam = cv.theta[cv.stats.shared]
        gam_f = cv.theta_folds[:, cv.stats.shared]
        sd = jackknife_std(gam_f)
        for k, nm in enumerate(shared_names):
            params[nm] = float(gam[k])
            stds[nm] = float(sd[k])
    return CandidateFit(
        effect=effect,
        location=location,
        eqs=[s.e for s in specs],
        cv=cv,
        params=params,
        params_std=stds,
        thetas=thetas,
        specs=specs,
    )


def fit_clearance(ctx: Context, j: int) -> CandidateFit:
    """Symmetric clearance (dead zone of half-width ``gap``) on spring j."""
    P = ctx.P
    d = P.deformation(ctx.x, j)
    ad = np.abs(d)
    grid = np.quantile(ad, np.linspace(0.05, 0.95, ctx.grid))
    grid = np.unique(grid[grid > 0])
    sides = P.sides(j)
    base = {e: linear_design(P, e) for e, _ in sides}

    def build(g):
        f = np.sign(d) * np.maximum(ad - g, 0.0)
        return [
            EqSpec(e=e, X=base[e], y=target(P, e), E=effect_column(P, e, s * f, ctx.mass)[:, None], key=("base", e))
            for e, s in sides
        ]

    return _fit_grid(ctx, "clearance", {"spring": j}, build, grid, lambda g: g, ["gap"], ["k_contact"])


def fit_delay(ctx: Context, i: int) -> CandidateFit:
    """Input delay at DOF i: the equation is driven by the force recorded ``delay`` earlier."""
    P = ctx.P
    tf = P.dt * np.arange(P.u_full.shape[0])
    spline = CubicSpline(tf, P.u_full[:, i])
    t = P.t
    hi = min(MAX_DELAY_SAMPLES, P.skip) * P.dt
    grid = np.log(np.geomspace(0.02 * P.dt, hi, ctx.grid))

    def build(lg):
        u = spline(t - np.exp(lg))
        return [EqSpec(e=i, X=base_design(P, i, P.A1, P.A2, u=u), y=target(P, i, u=u), E=None)]

    return _fit_grid(ctx, "input_delay", {"dof": i + 1}, build, grid, np.exp, ["delay"], [])


def fit_bias(ctx: Context, i: int, iterations: int = 4) -> CandidateFit:
    """Accelerometer bias at DOF i, by Gauss-Newton on the bias.

    Every pass removes the current bias estimate from the acceleration and its integrals
    (``a - b``, ``A1 - b t``, ``A2 - b t^2 / 2``, t from the first sample) and fits the
    linear equations plus the bias column built with the stiffnesses of the previous pass
    (its coefficient is the correction of b). The reported fit is the last pass.
    """
    P = ctx.P
    t = P.t
    thetas = list(ctx.lin.theta)  # physical
    bias = 0.0
    fit = None
    for _ in range(iterations):
        fit = a = A1 = A2 = None  # the previous pass's columns and signals go before the next are built
        a, A1, A2 = P.a.copy(), P.A1.copy(), P.A2.copy()
        a[:, i] -= bias
        A1[:, i] -= bias * t
        A2[:, i] -= 0.5 * bias * t**2
        # the true x_i is A2_i - b t^2/2: a force -b (sum_j k_j) t^2/2 in eq. i and
        # +b k_j t^2/2 in a neighbour e joined by spring j (constants and lines are
        # per-window terms); per unit mass for an unforced equation.
        m_i = thetas[i][0]
        forces = [(i, -float(np.sum(thetas[i][2:])) * 0.5 * t**2 / (1.0 if P.forced[i] else m_i))]
        for e, j in coupled(P, i):
            kk = [k for (jj, _), k in zip(P.columns[e], thetas[e][2:]) if jj == j][0]
            forces.append((e, kk * 0.5 * t**2 / (1.0 if P.forced[e] else thetas[e][0])))
        fit = _fit_linear_effect(ctx, "sensor_bias", {"dof": i + 1}, forces, ["bias"], signals=(a, A1, A2))
        step = fit.params["bias"]
        for e, th in zip(fit.eqs, fit.thetas):
            thetas[e] = to_physical(P, e, th)
        if abs(step) <= 1e-6 * max(abs(bias), 1e-300):
            bias += step
            break
        bias += step
    fit.params["bias"] = float(bias)
    return fit


def fit_lowpass(ctx: Context, i: int) -> CandidateFit:
    """First-order accelerometer low-pass at DOF i."""
    P = ctx.P
    sl = P.sl
    nyq = 0.5 / P.dt
    # The filter must settle within the skipped lead-in: 3 time constants.
    lo = max(3.0 / (2 * np.pi * max(P.skip, 1) * P.dt), 1e-3 * nyq)
    grid = np.log(np.geomspace(lo, nyq, ctx.grid))
    others = coupled(P, i)
    cols_i = P.columns[i]

    def build(lg):
        fc = np.exp(lg)
        tc = 1.0 / (2 * np.pi * fc)
        specs = []
        need = [o for _, o in cols_i if o >= 0]
        filt = {o: lowpass(P.A2_full[:, o], fc, P.dt)[sl] for o in need}
        u_lp = lowpass(P.u_full[:, i], fc, P.dt)[sl] if P.forced[i] else None
        x = P.A2.copy()
        for o in need:  # eq. i sees its neighbours through the same low-pass
            x[:, o] = filt[o]
        specs.append(EqSpec(e=i, X=base_design(P, i, P.A1, x, u=u_lp), y=target(P, i, u=u_lp), E=None))
        x = P.A2.copy()
        x[:, i] = P.A2[:, i] + tc * P.A1[:, i]
        for e, _ in others:
            specs.append(EqSpec(e=e, X=base_design(P, e, P.A1, x), y=target(P, e), E=None))
        return specs

    return _fit_grid(ctx, "sensor_lowpass", {"dof": i + 1}, build, grid, np.exp, ["cutoff_hz"], [])


#: Cut-off range of the high-pass candidate: from this many cycles over the record (a slower
#: high-pass bends the record's motion less than the per-window lines absorb) to a tenth of
#: the Nyquist rate [Hz].
HIGHPASS_CYCLES = 0.3
HIGHPASS_TOP = 0.1


def fit_highpass(ctx: Context, i: int) -> CandidateFit:
    """First-order accelerometer high-pass (AC coupling) at DOF i: the truth recovered by the
    inverse filter (module docstring) in equation i and in the equations its position enters."""
    P = ctx.P
    sl = P.sl
    nyq = 0.5 / P.dt
    grid = np.log(np.geomspace(max(HIGHPASS_CYCLES / P.duration, 1e-4 * nyq), HIGHPASS_TOP * nyq, ctx.grid))
    A3 = integrals(P.A1_full[:, i : i + 1], P.dt)[1][sl, 0]  # int int int a_i from the first sample
    others = [e for e, _ in coupled(P, i)]

    def build(lg):
        wc = 2 * np.pi * np.exp(lg)
        a = P.a[:, i] + wc * P.A1[:, i]
        v, x = P.A1.copy(), P.A2.copy()
        v[:, i] = P.A1[:, i] + wc * P.A2[:, i]
        x[:, i] = P.A2[:, i] + wc * A3
        specs = [EqSpec(e=i, X=base_design(P, i, v, x, a=a), y=target(P, i, a=a), E=None)]
        for e in others:
            specs.append(EqSpec(e=e, X=base_design(P, e, v, x), y=target(P, e), E=None))
        return specs

    return _fit_grid(ctx, "sensor_highpass", {"dof": i + 1}, build, grid, np.exp, ["cutoff_hz"], [])


def all_candidates(P: Prepared) -> list[tuple[str, int]]:
    """Every (effect, location) pair to try: DOF effects at every DOF, spring effects on
    every spring that exists and can be told apart."""
    out = []
    for eff in EFFECTS:
        if eff in ("cubic_stiffness", "clearance", "parameter_drift", "amplitude_damping"):
            out += [(eff, j) for j in P.network.identifiable_springs()]
        elif eff == "input_delay":  # a force delay needs a force
            out += [(eff, i) for i in range(P.n) if P.forced[i]]
        else:
            out += [(eff, i) for i in range(P.n)]
    return out


def fit_candidate(ctx: Context, effect: str, loc: int) -> CandidateFit:
    """Fit one candidate; ``loc`` is a 0-based DOF or a 1-based spring."""
    fits = {
        "coulomb_friction": fit_coulomb,
        "stribeck_friction": fit_stribeck,
        "amplitude_damping": fit_amplitude_damping,
        "clearance": fit_clearance,
        "input_delay": fit_delay,
        "sensor_bias": fit_bias,
        "sensor_lowpass": fit_lowpass,
        "sensor_highpass": fit_highpass,
        "quadratic_damping": lambda c, i: fit_dof_force(c, effect, i),
        "cubic_stiffness": lambda c, j: fit_spring_linear(c, effect, j),
        "parameter_drift": lambda c, j: fit_spring_linear(c, effect, j),
    }
    if effect not in fits:
        raise ValueError(f"unknown effect {effect!r}")
    before = dict(ctx.shared)  # what the fit reads of the others (a remake must read the same)
    fit = fits[effect](ctx, loc)
    fit.remake = lambda: fits[effect](replace(ctx, shared=dict(before)), loc)
    return fit


#: Effects that only add a force column to the linear equations (their fits combine).
ADDITIVE = (
    "coulomb_friction",
    "stribeck_friction",
    "quadratic_damping",
    "amplitude_damping",
    "cubic_stiffness",
    "clearance",
)


def fit_combination(ctx: Context, fits: list[CandidateFit]) -> CandidateFit:
    """Two or more additive candidates fitted together: every equation any of them enters
    gets all their force columns (their grid parameters, a Coulomb velocity scale or a
    clearance gap, kept at their own fits' values); the shared coefficients are refitted
    jointly. ``effect`` joins the names with ``+``, ``location`` and ``params`` keep each
    part's (``params`` as ``{effect: {...}}``)."""
    P = ctx.P
    eqs = sorted({e for f in fits for e in f.eqs})
    widths = [f.equations()[0].E.shape[1] for f in fits]
    specs = []
    for e in eqs:
        cols = []
        for f, wdt in zip(fits, widths):
            spec = next((sp for sp in f.equations() if sp.e == e), None)
            cols.append(spec.E if spec is not None else np.zeros((P.y.shape[0], wdt)))
        specs.append(
            EqSpec(e=e, X=linear_design(P, e), y=target(P, e), E=np.concatenate(cols, axis=1), key=("base", e))
        )
    cv = cross_validate(P, window_stats(P, specs))
    gam, sd = cv.theta[cv.stats.shared], jackknife_std(cv.theta_folds[:, cv.stats.shared])
    params, stds, off = {}, {}, 0
    for f, wdt in zip(fits, widths):
        own = dict(f.params)
        own_sd = dict(f.params_std)
        coef_names = _coefficient_names(f)
        for k, nm in enumerate(coef_names):
            own[nm], own_sd[nm] = float(gam[off + k]), float(sd[off + k])
        if f.effect == "stribeck_friction":
            own["static"] = own["force"] + own.pop("excess")
        params[f.effect], stds[f.effect] = own, own_sd
        off += wdt
    return CandidateFit(
        effect="+".join(f.effect for f in fits),
        location={"parts": [f.location for f in fits]},
        eqs=eqs,
        cv=cv,
        params=params,
        params_std=stds,
        thetas=[cv.theta[sl] for sl in cv.stats.slices],
        specs=specs,
        remake=lambda: fit_combination(ctx, fits),
    )


def _coefficient_names(fit: CandidateFit) -> list[str]:
    """Names of a candidate's shared (linear) coefficients, in column order."""
    return {"coulomb_friction": ["force"], "stribeck_friction": ["force", "excess"], "clearance": ["k_contact"]}.get(
        fit.effect, [MAIN_PARAM[fit.effect]]
    )


def raw_residual(ctx: Context, fit: CandidateFit) -> np.ndarray:
    """Undetrended equation errors (N, n) of the linear model with the candidate's
    equations replaced by the candidate's, in each equation's target units (for state
    reconstruction and plots)."""
    P = ctx.P
    out = np.stack([target(P, e) - linear_design(P, e) @ th for e, th in enumerate(ctx.lin.theta_a)], axis=1)
    q = fit.cv.stats.shared
    gam = fit.cv.theta[q]
    for s, th in zip(fit.equations(), fit.thetas):
        r = s.y - s.X @ th
        if s.E is not None and s.E.shape[1]:
            r = r - s.E @ gam
        out[:, s.e] = r
    return out
