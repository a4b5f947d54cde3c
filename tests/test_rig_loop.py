"""The paper's loop on a rig: held command behind an actuator lag (sampled mode), eq. 10 on
the measured force, and the estimator fed the smooth-equivalent samples (issue 19)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import quad

import algid
from algid.control.control_law import pole_placement_gains
from algid.control.controller import BezierReference, TrackingController
from algid.control.demo import _continuous_factory, _relative_errors, run_scenario, substitution_disturbance
from algid.control.estimate_gate import EstimateGate
from algid.control.held_input import HeldLaggedInput, LagEstimator, RigInput
from algid.control.trajectories import Multisine
from algid.model.chain import TABLE1
from algid.simulator import simulate

H = 1e-3


@pytest.mark.parametrize("tau", [0.5e-3, 2e-3, 5e-3])
def test_interval_mean_is_exact_for_the_lagged_hold(tau):
    """(H2) against the quadrature of (H1) itself."""
    u, w0 = np.array([1.3, -0.4]), np.array([0.2, 0.7])
    exact = [quad(lambda s, i=i: u[i] + (w0[i] - u[i]) * np.exp(-s / tau), 0.0, H)[0] / H for i in range(2)]
    assert HeldLaggedInput(2, H, tau).interval_mean(u, w0) == pytest.approx(exact, rel=1e-12)


def _held_mass(tau: float, m: float = 2.5, T: int = 400) -> tuple:
    """A free mass [kg] behind a held, lagged multisine command: commands, accelerations,
    forces at the samples (the simulator's convention) and the exact positions [m]."""
    t = np.arange(T) * H
    u = 3.0 * np.sin(2 * np.pi * 7.0 * t + 0.3) + 2.0 * np.sin(2 * np.pi * 23.0 * t)
    model = HeldLaggedInput(1, H, tau)
    w, x, v = np.zeros(T), np.zeros(T), 0.0
    w[0] = u[0]
    decay = np.exp(-H / tau) if tau > 0 else 0.0
    for k in range(T - 1):  # (H1) exactly: the force, its mean and first moment per interval
        x[k + 1] = x[k] + v * H + (u[k] * H * H / 2 + (w[k] - u[k]) * model.e) / m
        v += H * float(model.interval_mean(u[k], w[k])) / m
        w[k + 1] = u[k] + (w[k] - u[k]) * decay
    w_sampled = w.copy()
    if tau == 0:  # a jump at every sample: the mean of the one-sided limits
        w_sampled[1:] = 0.5 * (u[:-1] + u[1:])
    return u, w_sampled / m, w_sampled, x


def _positions_error(a: np.ndarray, x: np.ndarray) -> float:
    """RMS of the twice-integrated samples (cubic spline) against the positions, up to the
    initial conditions (a straight line)."""
    from scipy.interpolate import CubicSpline

    t = np.arange(len(a)) * H
    d = x - CubicSpline(t, a).antiderivative(2)(t)
    inner = slice(10, len(a) - 10)  # away from the spline's end conditions
    line = np.polyfit(t[inner], d[inner], 1)
    return float(np.sqrt(np.mean((d[inner] - np.polyval(line, t[inner])) ** 2)))


@pytest.mark.parametrize("tau", [0.0, 2e-3])
def test_smooth_samples_integrate_to_the_measured_positions(tau):
    """(H3, H4, H6): the smooth accelerations of a held, lagged force on a free mass
    integrate twice to its exact positions; two samples late, the first two unchanged."""
    m = 2.5
    u, a, w, x = _held_mass(tau, m)
    model = HeldLaggedInput(1, H, tau)
    out = [model.smooth(u[k : k + 1], a[k : k + 1], w[k : k + 1], np.array([m])) for k in range(len(u))]
    assert out[0] is None and out[1] is None
    assert out[2][0] == pytest.approx(a[:1]) and out[2][1] == pytest.approx(w[:1])
    a_s = np.array([o[0][0] for o in out[2:]])
    raw, smooth = _positions_error(a[:-2], x[:-2]), _positions_error(a_s, x[:-2])
    # raw samples: 8.6e-8 m (no lag), 7.9e-7 m (2 ms); smooth: 5.7e-10 and 6.3e-10 m
    assert smooth < 0.01 * raw


class _Counting:
    """An estimator that counts the samples it gets."""

    def __init__(self) -> None:
        self.samples = 0

    def update(self, accel, force) -> int:
        self.samples += 1
        return 0


@pytest.mark.parametrize("accepted", [True, False])
def test_rig_input_reseeds_at_the_switch_only_with_every_mass_accepted(accepted):
    made = []
    rig = RigInput(2, H, "estimate", 10, lambda: made.append(_Counting()) or made[-1])
    first = est = _Counting()
    for k in range(12):
        mass = np.array([2.0, 3.0 if accepted else np.nan]) if k >= 5 else np.full(2, np.nan)  # [kg]
        est, _ = rig.update(k, np.ones(2), np.zeros(2), np.ones(2), mass, est)
    # two samples late: 0..7 again at k = 9 into the new one, then 8 and 9 at k = 10 and 11
    assert (est is not first, est.samples, len(made)) == ((True, 10, 1) if accepted else (False, 10, 0))


def _open_loop_errors(tau: float) -> tuple[float, float]:
    """Largest relative error of the single window after 1 s of a held multisine behind the
    lag: raw samples, and the smooth-equivalent ones with the true masses."""
    fr = np.array([[1.3, 3.1, 7.0], [1.7, 4.3, 9.1], [2.3, 5.3, 11.0]])

    def f(t):
        return np.sum(np.sin(2 * np.pi * fr * t), axis=1)

    res = simulate(TABLE1, f, 1.0, 1000.0, mode="sampled", actuator_lag_s=tau)
    model = HeldLaggedInput(3, H, tau)
    smooth = [model.smooth(f(tk), res.a[k], res.u[k], TABLE1.mass) for k, tk in enumerate(res.t)][2:]
    errors = []
    for a, u in ((res.a, res.u), (np.array([s[0] for s in smooth]), np.array([s[1] for s in smooth]))):
        out = algid.ChainEstimator(3, H).run(a, u)
        theta = np.concatenate([out["mass"], out["damping"], out["stiffness"]], axis=1)
        errors.append(float(np.max(np.abs(theta[-1] / TABLE1.identifiable() - 1))))
    return errors[0], errors[1]


@pytest.mark.parametrize("tau", [2e-3, 5e-3])
def test_smooth_samples_remove_the_lag_bias_of_the_estimator(tau):
    raw, smooth = _open_loop_errors(tau)
    assert raw > 0.01  # the ripple between samples biases the raw estimates (3.3 %, 1.4 %)
    assert smooth < 1e-5  # 1.4e-6 and 5.6e-7 (the two-interval box of (H3) alone: 4e-4)


class _Truth:
    def __init__(self, n, dt, boundary):
        self.mass, self.damping, self.stiffness = TABLE1.mass.copy(), TABLE1.damping.copy(), TABLE1.stiffness.copy()
        self.valid = np.ones(n, bool)
        self.delay_samples = 0

    def update(self, accel, force):
        return 0


class _CommandedEq10(TrackingController):
    """Eq. 10 on the commanded force (the continuous-time form of the paper)."""

    def start(self, *args, **kwargs):
        super().start(*args, **kwargs)
        self.law.force_source = "commanded"


def test_eq10_on_the_measured_force_tracks_behind_a_lag():
    """True parameters in the law, 5 ms lag: eq. 10 on the measured force tracks; the
    velocity error tau w / m of the commanded force's integral costs several times more."""
    ref = BezierReference.paper(3, t_out=(0.0, 0.8), t_back=(1.0, 1.8))
    peaks = []
    for cls in (TrackingController, _CommandedEq10):
        ctrl = cls(reference=ref, estimator_factory=_Truth)
        res = simulate(TABLE1, None, 2.0, 1000.0, controller=ctrl, mode="sampled", actuator_lag_s=5e-3)
        peaks.append(np.max(np.abs(res.x - res.x_ref)[res.t >= 0.5]) / 0.005)
    assert peaks[0] < 0.01  # 0.65 % of the stroke
    assert peaks[1] > 3 * peaks[0]


class _SpringOff(_Truth):
    """The true parameters but ``k_1`` 1 % high."""

    def __init__(self, n, dt, boundary):
        super().__init__(n, dt, boundary)
        self.stiffness[0] *= 1.01


@pytest.mark.parametrize("lag_s", [0.0, 5e-3])
def test_position_feedback_removes_the_velocity_drift_of_a_spring_error(lag_s):
    """k_1 1 % off in the law: eq. 10's velocity drifts at dk x1 / m1 while DOF 1 holds at
    x1 = 5 mm, and the loop settles at e1 = (beta_2 - c1/m1) dk x1 / (m1 beta_0) (3.6 % of the
    stroke, the closed form); (10c) pulls int xd onto the measured positions and removes it."""
    ref = BezierReference.paper(3, t_out=(0.0, 0.8), t_back=(1.0, 1.8))
    peak, hold = {}, {}
    for pole in (None, 40.0):
        ctrl = TrackingController(reference=ref, estimator_factory=_SpringOff, velocity_pole=pole, actuator_lag_s=lag_s)
        res = simulate(TABLE1, None, 2.0, 1000.0, controller=ctrl, mode="sampled", actuator_lag_s=lag_s)
        err = np.abs(res.x - res.x_ref)
        peak[pole] = np.max(err[res.t >= 0.5]) / 0.005
        hold[pole] = err[(res.t >= 0.95) & (res.t < 1.0), 0].mean()
    m1, c1, dk = TABLE1.mass[0], TABLE1.damping[0], 0.01 * TABLE1.stiffness[0]
    beta0, beta1, beta2 = pole_placement_gains()
    assert hold[None] == pytest.approx((beta2 - c1 / m1) * dk * 0.005 / (m1 * beta0), rel=0.1)
    assert peak[None] > 0.03
    assert peak[40.0] < 0.01  # 0.24 % (no lag), 0.64 % (5 ms)
    assert hold[40.0] < 0.1 * hold[None]


def test_position_feedback_is_for_sampled_mode_only():
    ctrl = TrackingController(estimator_factory=_Truth, velocity_pole=40.0)
    with pytest.raises(ValueError, match="sampled mode only"):
        simulate(TABLE1, None, 0.2, 1000.0, controller=ctrl)


def _rig(lag_s: float, noise_db: float | None, **kw) -> tuple:
    return run_scenario(3, "sampled", noise_db, 0, 2.0, drift=False, actuator_lag_s=lag_s, **kw)


def _worst_after(res, t_s: float) -> float:
    return float(np.max(_relative_errors(res)[res.t >= t_s]))


@pytest.mark.parametrize("lag_s", [2e-3, 5e-3])
def test_noise_free_rig_loop_estimates_and_tracks(lag_s):
    res, s = _rig(lag_s, None)
    assert s["estimator"] == "continuous" and s["excitation_n"] > 0  # the demo's rig defaults
    assert s["all_stay_within_1pct_s"] <= 0.1  # 0.075-0.099 s (the raw samples: never)
    assert s["estimates_substituted_s"] == pytest.approx(0.1)  # the growing window's, at the switch
    # 0.25 %, 0.05 %: the smooth samples (H3, H6), and those from before the masses were
    # accepted smoothed again at the switch; either alone leaves 0.7-2.1 % (5 s loop)
    assert _worst_after(res, 0.1) < 0.005
    assert _worst_after(res, 0.5) < 1e-4  # 3e-5
    assert s["tracking"]["peak_after_1s_pct_stroke"] < 2.0  # about 1 %, the probe's motion


@pytest.mark.parametrize("lag_s", [2e-3, 5e-3])
def test_noisy_rig_loop_estimates_and_tracks(lag_s):
    """40 dB on the accelerations: with (10c) the loop tracks within 2 % of the stroke after
    1 s (0.9-1.1 %; without it the 5 s runs reach up to 2.2 %), the estimates within a
    few percent (0.24-1.1 % after 1 s: the dampings' information limit, not the loop). The
    growing window never steadies within 1 % under this noise, so the law waits for the
    running estimate, and the substitution disturbs the estimates by well under 1 % (0.1-0.2 %
    above the same loop's, same noise, that never takes them)."""
    res, s = _rig(lag_s, 40.0, disturbance_reference=True)
    assert s["estimates_substituted_s"] >= s["continuous_running_from_s"]
    # 0.02-0.49 % in the 5 s benchmark loops (bench/demo_report.py --rig-only); this 2 s loop
    # (a faster Bezier move) measures 1.5 % at 2 ms lag: above the 1 %, not hidden
    assert s["substitution"]["estimate_disturbance_vs_reference"] < 0.02
    assert s["tracking"]["peak_after_1s_pct_stroke"] < 2.0
    assert _worst_after(res, 1.0) < 0.04


def test_substitution_disturbance_against_a_reference_run():
    """Against itself the disturbance is 0; an estimate bumped by 2 % within 0.1 s of the
    substitution reads as a 2 % disturbance; after the window it does not count."""
    res, _ = _rig(2e-3, None)
    assert substitution_disturbance(res, res) == 0.0
    log = res.controller_log
    k_sub = max(log["k_switch"], int(round(log["first_accepted_s"] * 1000)) + 1)  # the first interval using them
    for k, expected in ((k_sub + 50, 0.02), (k_sub + 150, 0.0)):
        bumped = {key: np.array(v, copy=True) for key, v in res.estimates.items()}
        m_err = abs(res.estimates["mass"][k, 0] / TABLE1.mass[0] - 1)
        bumped["mass"][k, 0] = TABLE1.mass[0] * (1 + m_err + 0.02)  # its error 2 % larger
        run = dataclasses.replace(res, estimates=bumped)
        assert substitution_disturbance(run, res) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("tau", [0.0, 2e-3, 5e-3])
def test_lag_estimator_recovers_the_actuator_time_constant(tau):
    """(H5) on a held random command behind the simulator's first-order actuator: the lag
    from the commands and the measured forces alone."""
    rng = np.random.default_rng(3)
    cmd = rng.standard_normal((400, 3))
    held = lambda t: cmd[min(int(round(t * 1000)), 399)]  # noqa: E731
    res = simulate(TABLE1, held, 0.4, 1000.0, mode="sampled", actuator_lag_s=tau)
    est = LagEstimator(H)
    for k in range(len(res.t)):
        est.update(cmd[k], res.u[k])
    assert est.tau == pytest.approx(tau, abs=1e-6)


def test_a_wrong_lag_spoils_the_rig_loop_and_the_estimated_one_does_not():
    """Table 1, 5 ms lag, 2 s: told 4 ms (20 % off) the smooth samples are wrong enough to
    bias the estimates by several percent; estimating the lag on line matches knowing it."""
    ref = BezierReference.paper(3, t_out=(0.0, 0.8), t_back=(1.0, 1.8))
    errs = {}
    for told in (4e-3, 5e-3, "estimate"):
        ctrl = TrackingController(
            reference=ref,
            estimator_factory=_continuous_factory,
            accept="sigma",
            excitation=Multisine(3, 0.05),
            actuator_lag_s=told,
        )
        res = simulate(TABLE1, None, 2.0, 1000.0, controller=ctrl, mode="sampled", actuator_lag_s=5e-3)
        E = res.estimates
        th = np.concatenate([E["mass"], E["damping"], E["stiffness"]], axis=1)[res.t >= 1.0]
        errs[told] = float(np.max(np.abs(th / TABLE1.identifiable() - 1)))
    assert errs[4e-3] > 0.02
    assert errs[5e-3] < 0.005
    assert errs["estimate"] == pytest.approx(errs[5e-3], abs=1e-4)


def _offer(gate, k, theta, rel, sigma, rank=1):
    n = gate.n
    gate.offer(k, theta[:n], theta[n : 2 * n], theta[2 * n :], np.ones(n, bool), (rel, sigma, rank))


def test_the_better_rule_never_takes_worse_or_inconsistent_estimates():
    """Rule ``better``: a DOF's accepted estimates change only for ones with a smaller
    uncertainty that agree with them within 3 sigma, or that stay better but inconsistent
    for ``confirm_s``; a statistical source outranks a steadiness proxy."""
    n, dt = 2, 1e-3
    gate = EstimateGate(n, "fixed", dt, "better", 0.02, 0.02, False, 1.0, consistency_z=3.0, confirm_s=0.005)
    theta = np.array([2.0, 3.0, 5.0, 4.0, 1000.0, 900.0, 700.0])
    rel = np.full(7, 0.02)
    _offer(gate, 0, theta, rel, rel * theta, rank=0)
    assert gate.accepted.all() and gate.good_m == pytest.approx([2.0, 3.0])
    worse = theta * 1.001
    _offer(gate, 1, worse, rel * 2, rel * 2 * theta, rank=0)  # larger uncertainty: kept out
    assert gate.good_m == pytest.approx([2.0, 3.0])
    better = theta * 1.01
    _offer(gate, 2, better, rel / 2, rel / 2 * theta, rank=0)  # smaller and consistent: taken
    assert gate.good_m == pytest.approx([2.02, 3.03])
    running = theta * 1.2
    _offer(gate, 3, running, rel, rel * theta, rank=1)  # the running estimate outranks the proxy
    assert gate.good_m == pytest.approx([2.4, 3.6])
    jump = theta.copy()  # better but 20 % away from the accepted (10 sigma): waits confirm_s
    for k in range(4, 8):
        _offer(gate, k, jump, rel / 4, rel / 4 * theta)
        assert gate.good_m == pytest.approx([2.4, 3.6])
    _offer(gate, 8, jump, rel / 4, rel / 4 * theta)
    assert gate.good_m == pytest.approx([2.0, 3.0])
