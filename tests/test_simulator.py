"""Plant simulator against independent oracles (eigen-analysis, energy, scipy, exact ZOH)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.signal import cont2discrete

from algid.estimator import reference
from algid.model.chain import TABLE1, Chain
from algid.simulator import EFFECT_NAMES, Effect, SensorNoise, simulate


def multisine(n: int, freqs=(1.3, 2.9, 4.7, 7.1), amp: float = 2.0, seed: int = 0):
    rng = np.random.default_rng(seed)
    ph = rng.uniform(0, 2 * np.pi, (n, len(freqs)))
    f = np.asarray(freqs)

    def force(t):
        return amp * np.sum(np.sin(2 * np.pi * f[None, :] * t + ph), axis=1)

    return force


def rhs_reference(chain: Chain, force, effects=(), v_eps=None, duration=1.0):
    """Eq. 1 with effects, written independently of the simulator (plain loops)."""
    n = chain.n
    m, c, k = chain.mass, chain.damping, chain.stiffness
    lp = {e.location["dof"] - 1: 2 * np.pi * e.params["cutoff_hz"] for e in effects if e.name == "sensor_lowpass"}
    lp_dofs = sorted(lp)

    def accel(t, x, v):
        xe = np.concatenate([[0.0], x, [0.0]])
        f = np.array(force(t), dtype=float)
        for i in range(n):
            f[i] -= c[i] * v[i] + k[i] * (xe[i + 1] - xe[i]) + k[i + 1] * (xe[i + 1] - xe[i + 2])
        for e in effects:
            if e.name == "coulomb_friction":
                i = e.location["dof"] - 1
                f[i] -= e.params["force"] * np.tanh(v[i] / v_eps[i + 1])
            elif e.name == "stribeck_friction":
                i = e.location["dof"] - 1
                p = e.params
                level = p["force"] + (p["static"] - p["force"]) * np.exp(-((v[i] / p["v_stribeck"]) ** 2))
                f[i] -= level * np.tanh(v[i] / v_eps[i + 1])
            elif e.name == "quadratic_damping":
                i = e.location["dof"] - 1
                f[i] -= e.params["c_quadratic"] * v[i] * abs(v[i])
            elif e.name in ("cubic_stiffness", "clearance", "parameter_drift", "amplitude_damping"):
                j = e.location["spring"]  # joins DOF j-1 (xe[j-1]) and DOF j (xe[j])
                d = xe[j] - xe[j - 1]
                ve = np.concatenate([[0.0], v, [0.0]])
                if e.name == "amplitude_damping":
                    s = e.params["c_amp"] * abs(d) * (ve[j] - ve[j - 1])
                elif e.name == "cubic_stiffness":
                    s = e.params["k_cubic"] * d**3
                elif e.name == "clearance":
                    s = e.params["k_contact"] * max(abs(d) - e.params["gap"], 0.0) * np.sign(d)
                else:
                    s = k[j - 1] * e.params["rel_change"] * t / duration * d
                if j <= n:
                    f[j - 1] -= s
                if j >= 2:
                    f[j - 2] += s
        return f / m

    def rhs(t, y):
        x, v, z = y[:n], y[n : 2 * n], y[2 * n :]
        a = accel(t, x, v)
        dz = [lp[i] * (a[i] - z[q]) for q, i in enumerate(lp_dofs)]
        return np.concatenate([v, a, dz])

    return rhs, accel, lp_dofs


def test_free_vibration_is_the_modes_of_M_inv_K():
    chain = Chain(TABLE1.mass, np.zeros(3), TABLE1.stiffness)
    M, _, K = chain.matrices()
    lam, phi = np.linalg.eig(np.linalg.solve(M, K))
    res = None
    for j in range(3):
        w = np.sqrt(lam[j].real)
        shape = phi[:, j].real * 1e-3 / np.max(np.abs(phi[:, j]))
        res = simulate(chain, None, 1.0, 1000.0, x0=shape)
        expect = shape[None, :] * np.cos(w * res.t)[:, None]
        assert np.max(np.abs(res.x - expect)) < 1e-12
        assert np.max(np.abs(res.a_true + w**2 * expect)) < 1e-12 * w**2
    assert np.allclose(np.sort(np.sqrt(lam.real)) / (2 * np.pi), chain.natural_frequencies_hz())


def test_free_right_end_modes():
    chain = Chain([1.0, 2.0], [0.0, 0.0], [400.0, 300.0, 0.0], boundary="free")
    M, _, K = chain.matrices()
    lam, phi = np.linalg.eig(np.linalg.solve(M, K))
    w = np.sqrt(lam[0].real)
    shape = phi[:, 0].real * 1e-3
    res = simulate(chain, None, 0.5, 2000.0, x0=shape)
    assert np.max(np.abs(res.x - shape * np.cos(w * res.t)[:, None])) < 1e-12


def test_energy_balance_without_damping():
    chain = Chain(TABLE1.mass, np.zeros(3), TABLE1.stiffness)
    f = multisine(3)
    res = simulate(chain, f, 2.0, 1000.0)
    M, _, K = chain.matrices()
    energy = 0.5 * np.einsum("ti,ij,tj->t", res.v, M, res.v) + 0.5 * np.einsum("ti,ij,tj->t", res.x, K, res.x)
    power = np.einsum("ti,ti->t", res.u, res.v)
    # Simpson's rule on pairs of intervals: work done by the forces
    h = res.dt
    work = np.concatenate([[0.0], np.cumsum(h / 3 * (power[:-2:2] + 4 * power[1:-1:2] + power[2::2]))])
    e_even = energy[::2][: work.size]
    assert np.max(np.abs(e_even - e_even[0] - work)) < 1e-8 * np.max(energy)


@pytest.mark.parametrize("mode", ["continuous", "sampled"])
def test_linear_chain_matches_solve_ivp(mode):
    f = multisine(3, freqs=(1.3, 4.1, 9.7, 17.3))
    res = simulate(TABLE1, f, 1.5 if mode == "continuous" else 0.4, 1000.0, mode=mode)
    h = res.dt
    held = (lambda t: f(h * np.floor(t / h + 1e-9))) if mode == "sampled" else f
    rhs, accel, _ = rhs_reference(TABLE1, held)
    if mode == "sampled":  # integrate interval by interval across the jumps
        y = np.zeros(6)
        X = [y[:3]]
        for k in range(len(res.t) - 1):
            uk = f(res.t[k])
            sol = solve_ivp(
                lambda t, y, uk=uk: rhs_reference(TABLE1, lambda _t: uk)[0](t, y),
                (res.t[k], res.t[k + 1]),
                y,
                rtol=1e-12,
                atol=1e-16,
                method="DOP853",
            )
            y = sol.y[:, -1]
            X.append(y[:3])
        X = np.array(X)
    else:
        sol = solve_ivp(rhs, (0, res.t[-1]), np.zeros(6), t_eval=res.t, rtol=1e-12, atol=1e-16, method="DOP853")
        X = sol.y[:3].T
        A = np.array([accel(t, y[:3], y[3:6]) for t, y in zip(sol.t, sol.y.T)])
        assert np.max(np.abs(A - res.a_true)) < 1e-8 * np.max(np.abs(A))
    assert np.max(np.abs(X - res.x)) < 1e-8 * np.max(np.abs(X))


def _effects_error(effects, substeps=None, duration=1.0):
    f = multisine(3, amp=4.0, seed=2)
    res = simulate(TABLE1, f, duration, 1000.0, effects=effects, substeps=substeps)
    rhs, accel, lp_dofs = rhs_reference(TABLE1, f, effects, res.stats["v_eps"], duration)
    y0 = np.zeros(6 + len(lp_dofs))
    y0[6:] = accel(0.0, np.zeros(3), np.zeros(3))[lp_dofs]  # the sensor starts settled
    sol = solve_ivp(rhs, (0, res.t[-1]), y0, t_eval=res.t, rtol=1e-11, atol=1e-15, method="DOP853")
    X = sol.y[:3].T
    A = np.array([accel(t, y[:3], y[3:6]) for t, y in zip(sol.t, sol.y.T)])
    ex = np.max(np.abs(X - res.x)) / np.max(np.abs(X))
    ea = np.max(np.abs(A - res.a_true)) / np.max(np.abs(A))
    return res, sol, A, ex, ea


def test_smooth_effects_match_solve_ivp():
    effects = [
        Effect("cubic_stiffness", {"spring": 2}, {"k_cubic": 3e7}),
        Effect("quadratic_damping", {"dof": 3}, {"c_quadratic": 200.0}),
        Effect("parameter_drift", {"spring": 1}, {"rel_change": -0.3}),
        Effect("sensor_lowpass", {"dof": 2}, {"cutoff_hz": 15.0}),
    ]
    res, sol, A, ex, ea = _effects_error(effects)
    assert ex < 1e-7 and ea < 1e-6
    # the low-pass accelerometer of DOF 2 reads the filter state, the others the truth
    assert np.max(np.abs(sol.y[6] - res.a[:, 1])) < 1e-6 * np.max(np.abs(A[:, 1]))
    assert np.array_equal(res.a[:, [0, 2]], res.a_true[:, [0, 2]])


def test_highpass_accelerometer_is_the_truth_less_its_integrated_reading():
    """``a_meas = a - z``, ``z' = w_c a_meas``, ``z(0) = 0``: the truth is the reading plus
    ``w_c`` times its integral (Simpson's cumulative rule, independent of the simulator)."""
    from scipy.integrate import cumulative_simpson

    fc = 0.8
    eff = [Effect("sensor_highpass", {"dof": 2}, {"cutoff_hz": fc})]
    res = simulate(TABLE1, multisine(3, seed=4), 4.0, 1000.0, effects=eff)
    ref = simulate(TABLE1, multisine(3, seed=4), 4.0, 1000.0)
    a_m = res.a[:, 1]
    back = a_m + 2 * np.pi * fc * cumulative_simpson(a_m, dx=1e-3, initial=0.0)
    assert np.max(np.abs(back - res.a_true[:, 1])) < 1e-6 * np.max(np.abs(res.a_true[:, 1]))
    assert np.max(np.abs(a_m - res.a_true[:, 1])) > 0.05 * np.max(np.abs(res.a_true[:, 1]))  # it does filter
    assert np.array_equal(res.a[:, [0, 2]], res.a_true[:, [0, 2]])
    assert np.array_equal(res.x, ref.x) and np.array_equal(res.x_meas, ref.x_meas)  # only the accelerometer
    with pytest.raises(ValueError, match="same accelerometer"):
        simulate(TABLE1, None, 0.1, effects=eff + [Effect("sensor_lowpass", {"dof": 2}, {"cutoff_hz": 50.0})])


@pytest.mark.slow  # 7 s: the fast tier stays within 6 minutes
def test_steep_effects_match_solve_ivp_and_converge_with_substeps():
    """Dry friction and a clearance contact switch within a step: fourth order is lost at
    the switches, the error is still small and shrinks with sub-steps."""
    clearance = [Effect("clearance", {"spring": 4}, {"gap": 5e-4, "k_contact": 3000.0})]
    friction = [Effect("coulomb_friction", {"dof": 1}, {"force": 0.3, "v_eps": 2e-4})]
    stribeck = [
        Effect("stribeck_friction", {"dof": 2}, {"force": 0.2, "static": 0.5, "v_stribeck": 2e-3, "v_eps": 2e-4})
    ]
    joint = [Effect("amplitude_damping", {"spring": 3}, {"c_amp": 2e4})]  # |d| kinks at d = 0
    for effects, tol in ((clearance, 1e-6), (friction, 5e-5), (stribeck, 5e-5), (joint, 5e-5)):
        _, _, _, ex1, ea1 = _effects_error(effects)
        _, _, _, ex4, _ = _effects_error(effects, substeps=4)
        assert ex1 < tol and ea1 < 10 * tol
        assert ex4 < 0.5 * ex1


def test_zero_order_hold_matches_exact_discretisation():
    chain = Chain([2.0], [3.0], [500.0, 300.0])
    m, c, k = 2.0, 3.0, 800.0
    rng = np.random.default_rng(3)
    T = 400
    U = rng.standard_normal((T, 1))
    res = simulate(chain, U, T / 1000.0, 1000.0, mode="sampled")
    A = np.array([[0.0, 1.0], [-k / m, -c / m]])
    B = np.array([[0.0], [1.0 / m]])
    Ad, Bd, *_ = cont2discrete((A, B, np.eye(2), np.zeros((2, 1))), 1e-3, method="zoh")
    y = np.zeros(2)
    out = []
    for kk in range(T):
        out.append(y)
        y = Ad @ y + Bd[:, 0] * U[kk, 0]
    out = np.array(out)
    scale = np.max(np.abs(out), axis=0)
    assert np.max(np.abs(out[:, 0] - res.x[:, 0])) < 1e-12 * scale[0]
    assert np.max(np.abs(out[:, 1] - res.v[:, 0])) < 1e-12 * scale[1]


def test_samples_at_jumps_are_the_mean_of_the_one_sided_limits():
    rng = np.random.default_rng(4)
    U = rng.standard_normal((300, 3))
    res = simulate(TABLE1, U, 0.3, 1000.0, mode="sampled")
    L = res.limits
    assert np.array_equal(L["u_plus"], U)
    assert np.array_equal(L["u_minus"][1:], U[:-1])
    assert np.allclose(res.u, 0.5 * (L["u_minus"] + L["u_plus"]), rtol=0, atol=1e-15)
    assert np.allclose(res.a_true, 0.5 * (L["a_minus"] + L["a_plus"]), rtol=0, atol=1e-15)
    # the acceleration jumps by exactly the force jump over the mass
    jump = (L["a_plus"] - L["a_minus"]) * TABLE1.mass
    assert np.allclose(jump[1:], U[1:] - U[:-1], rtol=0, atol=1e-12)


def test_sample_convention_decides_the_estimator_bias(monkeypatch):
    """Held multisine at 1 kHz on Table 1: the mean-of-limits pairing identifies the chain,
    pairing the held force with either one-sided acceleration biases it (issue 3)."""
    # the numpy reference rebuilds its quadrature weights on every call: cache them
    monkeypatch.setattr(reference, "quadrature_weights", functools.lru_cache()(reference.quadrature_weights))
    fs, T = 1000.0, 500
    t = np.arange(T) / fs
    rng = np.random.default_rng(1)
    U = np.stack(
        [sum(np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in (1.3, 2.9, 4.7, 7.1)) for _ in range(3)],
        axis=1,
    )
    res = simulate(TABLE1, U, T / fs, fs, mode="sampled")
    L = res.limits
    theta = np.array(
        [[TABLE1.mass[i], TABLE1.damping[i], TABLE1.stiffness[i], TABLE1.stiffness[i + 1]] for i in range(3)]
    )

    def err(a, u):
        est = reference.estimate(a, u, 1 / fs)["theta_ratio"][-1]
        return np.max(np.abs(est / theta - 1))

    e_mean = err(res.a_true, res.u)
    e_pre = err(L["a_minus"], L["u_minus"])
    e_post = err(L["a_plus"], L["u_plus"])
    assert e_mean < 1e-3
    assert e_pre > 0.05 and e_post > 0.05
    assert min(e_pre, e_post) > 100 * e_mean


def test_continuous_array_force_is_recorded_as_given():
    rng = np.random.default_rng(5)
    U = np.cumsum(rng.standard_normal((500, 3)), axis=0) * 0.1
    res = simulate(TABLE1, U, 0.5, 1000.0)
    assert np.allclose(res.u, U, rtol=0, atol=1e-12)
    assert np.allclose(res.u_applied, U, rtol=0, atol=1e-12)
    lin = simulate(TABLE1, U, 0.5, 1000.0, force_interp="linear")
    assert np.allclose(lin.u, U, rtol=0, atol=1e-12)


def test_sensor_bias_and_input_delay():
    f = multisine(3)
    U = np.array([f(t) for t in np.arange(600) / 1000.0])
    base = simulate(TABLE1, U, 0.6, 1000.0, mode="sampled")
    res = simulate(
        TABLE1,
        U,
        0.6,
        1000.0,
        mode="sampled",
        effects=[
            Effect("sensor_bias", {"dof": 2}, {"bias": 0.25}),
            Effect("input_delay", {"dof": 1}, {"delay": 0.005}),
        ],
    )
    assert np.allclose(res.a[:, 1] - res.a_true[:, 1], 0.25, rtol=0, atol=1e-14)
    assert np.array_equal(res.u, base.u)  # the sensor reads the command
    # a delay of 5 samples shifts the held staircase by exactly 5 samples
    assert np.allclose(res.u_applied[6:, 0], base.u[1:-5, 0], rtol=0, atol=1e-14)
    assert np.all(res.u_applied[:5, 0] == 0.0)
    assert res.u_applied[5, 0] == 0.5 * U[0, 0]  # mean of the limits of the jump from rest
    assert np.allclose(res.u_applied[:, 1:], base.u[:, 1:], rtol=0, atol=1e-14)
    # continuous mode, delay off the sample grid: same as the undelayed plant under f(t - d)
    d = 0.0123
    res = simulate(TABLE1, f, 0.5, 1000.0, effects=[Effect("input_delay", {"dof": 3}, {"delay": d})])

    def shifted(t):
        out = f(t)
        out[2] = f(t - d)[2] if t >= d else 0.0
        return out

    rhs, _, _ = rhs_reference(TABLE1, shifted)
    kw = dict(rtol=1e-12, atol=1e-16, method="DOP853")
    before, after = res.t[res.t <= d], res.t[res.t > d]
    X1 = solve_ivp(rhs, (0, d), np.zeros(6), t_eval=before, **kw).y[:3].T
    y_d = solve_ivp(rhs, (0, d), np.zeros(6), **kw).y[:, -1]
    X2 = solve_ivp(rhs, (d, res.t[-1]), y_d, t_eval=after, **kw).y[:3].T
    X = np.concatenate([X1, X2])
    assert np.max(np.abs(X - res.x)) < 1e-7 * np.max(np.abs(X))


def test_sensor_noise_level_reproducibility_and_independence():
    f = multisine(3)
    kw = dict(noise_db=30.0, seed=7)
    a = simulate(TABLE1, f, 2.0, 1000.0, noise_on=("accel",), **kw)
    b = simulate(TABLE1, f, 2.0, 1000.0, noise_on=("accel", "force", "position"), **kw)
    clean = simulate(TABLE1, f, 2.0, 1000.0)
    assert np.array_equal(a.a, b.a)  # switching force noise on leaves the accel noise alone
    assert np.array_equal(a.u, clean.u) and np.array_equal(a.x_meas, clean.x)
    for name, noisy, ref in (("accel", b.a, clean.a_true), ("force", b.u, clean.u), ("position", b.x_meas, clean.x)):
        ratio = np.sqrt(np.mean((noisy - ref) ** 2, axis=0)) / np.sqrt(np.mean(ref**2, axis=0))
        assert np.allclose(20 * np.log10(ratio), -30.0, atol=1e-9)
        assert np.allclose(b.snr_db[name], 30.0, atol=1e-9)
    c = simulate(TABLE1, f, 2.0, 1000.0, noise=SensorNoise(30.0, ("accel",), seed=8))
    assert not np.array_equal(c.a, a.a)


def test_to_arrays_is_the_recording_format():
    res = simulate(TABLE1, multisine(3), 0.2, 1000.0, noise_db=40, seed=1, noise_on=("position",))
    rec = res.to_arrays()
    assert sorted(rec) == sorted(["t"] + [f"{s}{i}" for s in "uax" for i in (1, 2, 3)])
    assert np.array_equal(rec["x2"], res.x_meas[:, 1]) and np.array_equal(rec["a3"], res.a[:, 2])
    assert np.array_equal(rec["t"], np.arange(200) / 1000.0)


@pytest.mark.parametrize(
    "bad",
    [
        ("spring_softening", {"spring": 1}, {"k_cubic": 1.0}),
        ("cubic_stiffness", {"dof": 1}, {"k_cubic": 1.0}),
        ("cubic_stiffness", {"spring": 1}, {"k": 1.0}),
        ("coulomb_friction", {"dof": 1}, {"force": -1.0}),
        ("sensor_lowpass", {"dof": 1}, {"cutoff_hz": 0.0}),
        ("parameter_drift", {"spring": 1}, {"rel_change": -1.5}),
        ("clearance", {"spring": 1}, {"gap": 1e-3}),
        ("input_delay", {"dof": 1.5}, {"delay": 0.01}),
    ],
)
def test_bad_effects_are_rejected(bad):
    with pytest.raises(ValueError):
        Effect(*bad)


def test_effect_locations_are_checked_against_the_chain():
    free = Chain([1.0, 1.0], [1.0, 1.0], [100.0, 100.0, 0.0], boundary="free")
    for chain, eff in (
        (TABLE1, Effect("coulomb_friction", {"dof": 4}, {"force": 1.0})),
        (TABLE1, Effect("cubic_stiffness", {"spring": 5}, {"k_cubic": 1.0})),
        (free, Effect("cubic_stiffness", {"spring": 3}, {"k_cubic": 1.0})),
    ):
        with pytest.raises(ValueError):
            simulate(chain, None, 0.01, effects=[eff])
    assert set(EFFECT_NAMES) == {
        "coulomb_friction",
        "quadratic_damping",
        "cubic_stiffness",
        "clearance",
        "input_delay",
        "sensor_bias",
        "sensor_lowpass",
        "sensor_highpass",
        "parameter_drift",
        "force_offset",
        "stribeck_friction",
        "amplitude_damping",
    }
    with pytest.raises(ValueError, match="static"):
        Effect("stribeck_friction", {"dof": 1}, {"force": 2.0, "static": 1.0, "v_stribeck": 1e-3})
    with pytest.raises(ValueError):
        simulate(TABLE1, np.zeros((5, 3)), 0.01)  # too short
    with pytest.raises(ValueError):
        simulate(TABLE1, lambda t: np.zeros(2), 0.01)  # wrong width


def test_force_offset_acts_like_an_unrecorded_constant_force():
    rng = np.random.default_rng(11)
    u = rng.standard_normal((500, 3))
    off = np.array([0.0, 2.5, 0.0])
    with_eff = simulate(
        TABLE1, u, 0.5, effects=[{"name": "force_offset", "location": {"dof": 2}, "params": {"offset": 2.5}}]
    )
    shifted = simulate(TABLE1, u + off, 0.5)
    np.testing.assert_allclose(with_eff.x, shifted.x, rtol=0, atol=1e-9 * np.abs(shifted.x).max())
    np.testing.assert_allclose(with_eff.u, u, rtol=0, atol=1e-12)  # the force sensor does not see it


def test_encoder_readings_are_whole_counts_in_open_and_closed_loop():
    from algid.control.positioning import BangBangReference, PositioningController

    q = 1e-5
    res = simulate(TABLE1, np.random.default_rng(12).standard_normal((300, 3)), 0.3, encoder_resolution_m=q)
    counts = res.x_meas / q
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-9)
    assert np.max(np.abs(res.x_meas - res.x)) <= q / 2 + 1e-15
    ref = BangBangReference([[0.01], [-0.01]], a_max=2.0, dwell_s=0.2)
    ctl = PositioningController(ref, f_max=50.0, kp=2e4, kd=400.0, ki=1e5, m0=1.0)
    loop = simulate(Chain([1.0], [5.0], [0.0, 0.0]), None, 0.8, controller=ctl, mode="sampled", encoder_resolution_m=q)
    np.testing.assert_allclose(loop.x_meas / q, np.round(loop.x_meas / q), atol=1e-9)
    assert np.max(np.abs(loop.x[-1] - (-0.01))) < 2e-4  # the move is done and held
    with pytest.raises(ValueError, match="encoder_resolution_m"):
        simulate(TABLE1, None, 0.01, encoder_resolution_m=-1.0)


def test_bang_bang_reference_profile():
    from algid.control.positioning import BangBangReference

    ref = BangBangReference([[0.04], [0.0]], a_max=4.0, dwell_s=0.5, start_s=0.2)
    dur = 2 * np.sqrt(0.04 / 4.0)  # 0.2 s per move
    t = np.linspace(0, ref.end_s, 2001)
    x, v, a = ref.evaluate(t)
    assert np.max(np.abs(a)) == pytest.approx(4.0)
    # the profile integrates: v = int a, x = int v (trapezoid, fine grid)
    dt = t[1] - t[0]
    np.testing.assert_allclose(np.cumsum((a[1:] + a[:-1]) / 2 * dt), v[1:, 0] - v[0, 0], atol=2e-2)
    np.testing.assert_allclose(np.cumsum((v[1:] + v[:-1]) / 2 * dt), x[1:, 0] - x[0, 0], atol=1e-4)
    assert x[np.searchsorted(t, 0.2 + dur + 0.1), 0] == pytest.approx(0.04)
    assert x[-1, 0] == pytest.approx(0.0, abs=1e-12)
    assert ref.evaluate(0.3)[0].shape == (1,)


def test_a_controller_needs_only_the_protocol_methods():
    """A sampled loop runs a controller that has the methods of ``algid.simulator.Controller``
    and nothing else (no ``reference``); a noisy loop's noise level comes from its
    ``reference_motion``: noise RMS = SNR ratio x RMS of the nominal position."""

    class HoldAt:
        __slots__ = ("n", "target", "forces")

        def __init__(self, target_m):
            self.target = target_m

        def start(self, chain_n, dt, boundary="fixed", samples=0, mode="continuous"):
            self.n, self.forces = chain_n, []

        def params_for_sample(self, k, z=None):
            return None

        def sampled_force(self, k, t, x_meas):
            u = 2000.0 * (self.target - x_meas)
            self.forces.append(u)
            return u

        def observe(self, k, t, accel, force, x_meas, z=None):
            pass

        def reference_motion(self, t):
            still = np.zeros((np.size(t), self.n))
            return still + self.target, still, still

        def log(self):
            return {"force_command": np.array(self.forces)}

    ctl = HoldAt(np.array([1e-3, -2e-3, 1e-3]))
    res = simulate(
        TABLE1, None, 0.5, 1000.0, controller=ctl, mode="sampled", noise_db=40.0, noise_on=("position",), seed=3
    )
    ratio = 10 ** (-40.0 / 20)
    np.testing.assert_allclose(res.noise_rms["position"], ratio * np.abs(ctl.target), rtol=1e-12)
    np.testing.assert_array_equal(res.controller_log["force_command"], res.limits["u_plus"])  # held from t_k+
    assert res.x_ref is None and res.estimates is None
