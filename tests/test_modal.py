"""Modal results, state space and FRFs of a chain (``algid.model.modal``, ``algid.model.frf``) against
closed forms, an independent eigen-solver, python-control, scipy and Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest

from algid import TABLE1, Chain
from algid.model.frf import h1_estimate, state_matrices
from algid.model.modal import modal_analysis

SIGMA_REL = 0.01  # relative standard deviation of every parameter in the propagation tests


def _packed(chain: Chain) -> np.ndarray:
    return np.concatenate([chain.mass, chain.damping, chain.stiffness])


@pytest.mark.parametrize("m,c,k", [(2.0, 3.0, 800.0), (0.5, 0.01, 2.0e4), (7.0, 40.0, 100.0)])
def test_one_dof_is_the_closed_form(m, c, k):
    ma = Chain([m], [c], [k, 0.0]).modes()
    (mode,) = ma.modes
    wn, zeta = np.sqrt(k / m), c / (2 * np.sqrt(k * m))
    assert mode.kind == "underdamped"
    assert mode.frequency_hz == pytest.approx(wn / (2 * np.pi), rel=1e-12)
    assert mode.damping_ratio == pytest.approx(zeta, rel=1e-10)
    assert mode.damped_frequency_hz == pytest.approx(wn * np.sqrt(1 - zeta**2) / (2 * np.pi), rel=1e-12)
    assert mode.shape == pytest.approx([1.0])


def test_overdamped_and_rigid_one_dof():
    m, c, k = 1.0, 30.0, 100.0  # zeta = 1.5
    (over,) = Chain([m], [c], [k, 0.0]).modes().modes
    assert over.kind == "overdamped" and len(over.eigenvalues) == 2
    assert over.frequency_hz == pytest.approx(np.sqrt(k / m) / (2 * np.pi), rel=1e-10)
    assert over.damping_ratio == pytest.approx(c / (2 * np.sqrt(k * m)), rel=1e-10)
    (critical,) = Chain([m], [20.0], [k, 0.0]).modes(sigma=[0.1, 0.1, 1.0, 0.0]).modes
    assert critical.damping_ratio == pytest.approx(1.0, abs=1e-7) and np.isnan(critical.sigma_damping_ratio)
    (rigid,) = Chain([m], [c], [0.0, 0.0]).modes().modes
    assert rigid.kind == "rigid" and rigid.frequency_hz == 0.0 and np.isnan(rigid.damping_ratio)
    assert sorted(lam.real for lam in rigid.eigenvalues) == pytest.approx([-c / m, 0.0], abs=1e-12)


def test_free_chain_without_walls_has_a_rigid_body_mode():
    chain = Chain([1.0, 2.0], [0.0, 0.0], [0.0, 10.0, 0.0], "free")
    rigid, swing = chain.modes().modes
    assert rigid.kind == "rigid" and np.abs(rigid.shape) == pytest.approx([1.0, 1.0])
    # two masses on one spring: w^2 = k (1/m1 + 1/m2), opposite motion, amplitudes 1 : m1/m2
    assert swing.frequency_hz == pytest.approx(np.sqrt(10.0 * 1.5) / (2 * np.pi), rel=1e-12)
    assert swing.shape.real == pytest.approx([1.0, -0.5])


def test_two_dof_against_python_control_damp_and_numpy_eig():
    control = pytest.importorskip("control")
    chain = Chain([1.5, 0.7], [2.0, 9.0], [600.0, 300.0, 900.0])  # non-proportional damping
    ma = chain.modes()
    assert not ma.proportional
    wn, zeta, poles = control.damp(chain.to_control(), doprint=False)
    order = np.argsort(wn)[::2]  # each pair of complex poles once
    assert ma.frequencies_hz == pytest.approx(wn[order] / (2 * np.pi), rel=1e-10)
    assert ma.damping_ratios == pytest.approx(zeta[order], rel=1e-9)
    # the complex shape is the eigenvector of the quadratic problem (K + lambda C + lambda^2 M) q = 0
    M, C, K = chain.matrices()
    for mode in ma.modes:
        (lam,) = mode.eigenvalues
        assert np.linalg.norm((K + lam * C + lam**2 * M) @ mode.shape) < 1e-9 * np.linalg.norm(K)


def test_proportional_shapes_are_mass_orthonormal_and_match_the_complex_ones():
    chain = Chain([2.0, 2.0, 2.0], [4.0, 4.0, 4.0], [1000.0, 500.0, 500.0, 1000.0])  # C = 2 M: proportional
    ma = chain.modes()
    assert ma.proportional
    M, _, K = chain.matrices()
    Phi = np.column_stack([m.real_shape for m in ma.modes])
    np.testing.assert_allclose(Phi.T @ M @ Phi, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(Phi.T @ K @ Phi, np.diag((2 * np.pi * ma.frequencies_hz) ** 2), atol=1e-8)
    for m in ma.modes:
        assert np.abs(m.shape.imag).max() < 1e-12
        scaled = m.real_shape / m.real_shape[np.argmax(np.abs(m.real_shape))]
        np.testing.assert_allclose(m.shape.real, scaled, atol=1e-12)
    assert ma.frequencies_hz == pytest.approx(chain.natural_frequencies_hz(), rel=1e-12)
    assert ma.damping_ratios == pytest.approx(1.0 / (2 * np.pi * ma.frequencies_hz), rel=1e-10)  # zeta = a / 2 w


@pytest.mark.filterwarnings("ignore:Badly conditioned filter coefficients")
def test_frf_against_the_closed_form_and_scipy_freqresp():
    from scipy.signal import freqresp

    m, c, k = 2.0, 3.0, 800.0
    f = np.linspace(0.1, 20.0, 50)
    w = 2 * np.pi * f
    one = Chain([m], [c], [k, 0.0])
    receptance = 1.0 / (k - m * w**2 + 1j * c * w)
    for output, factor in (("displacement", 1.0), ("velocity", 1j * w), ("acceleration", -(w**2))):
        np.testing.assert_allclose(one.frf(f, output)[:, 0, 0], factor * receptance, rtol=1e-12)
    for output in ("displacement", "velocity", "acceleration"):
        A, B, C, D = state_matrices(TABLE1, output)
        H = TABLE1.frf(f, output)
        for e in range(3):
            for j in range(3):  # scipy's freqresp takes one input and one output at a time
                _, h = freqresp((A, B[:, [j]], C[[e]], D[[e]][:, [j]]), w)
                np.testing.assert_allclose(H[:, e, j], h, rtol=1e-6)  # via poles and zeros
    assert TABLE1.state_space("velocity").C.shape == (3, 6)
    with pytest.raises(ValueError, match="output must be one of"):
        TABLE1.frf(f, "jerk")


def test_h1_of_a_long_simulated_recording_matches_the_model():
    from algid.simulator import simulate

    fs, duration = 100.0, 600.0
    rng = np.random.default_rng(1)
    force = rng.standard_normal((int(duration * fs) + 1, 3))
    res = simulate(TABLE1, force, duration, fs)
    worst = []
    for nperseg in (1024, 4096):
        est = h1_estimate(res.u, res.a, 1 / fs, nperseg=nperseg)
        band = (est.f_hz > 0.5) & (est.f_hz < 20.0)
        H, model = est.H[band], TABLE1.frf(est.f_hz[band])
        assert np.median(np.abs(H - model) / np.abs(model)) < 0.005
        worst.append(np.max(np.abs(H - model) / np.abs(model).max(axis=0)))  # against each entry's peak
        assert est.coherence[band].min() > 0.9
    # the error left is the leakage bias at the resonances: it shrinks with longer segments
    assert worst[1] < 0.07 and worst[1] < 0.6 * worst[0]
    # one force only: the other columns are NaN and the coherence of a noisy output drops
    noisy = res.a + 0.3 * res.a.std(axis=0) * rng.standard_normal(res.a.shape)
    u1 = res.u.copy()
    u1[:, 1:] = 0.0
    one = h1_estimate(u1, noisy, 1 / fs, nperseg=4096)
    assert np.isnan(one.H[:, :, 1:]).all() and np.isfinite(one.H[1:, :, 0]).all()  # no FRF at 0 Hz
    assert np.median(one.coherence[band]) < 0.9


def _quantities(chain: Chain) -> np.ndarray:
    ma = chain.modes()
    return np.concatenate([ma.frequencies_hz, ma.damping_ratios] + [np.abs(m.shape) for m in ma.modes])


@pytest.mark.parametrize(
    "chain",
    [
        TABLE1,
        Chain([1.5, 0.7], [2.0, 9.0], [600.0, 300.0, 900.0]),  # non-proportional
        Chain([1.0, 2.0], [50.0, 70.0], [10.0, 10.0, 10.0]),  # both modes overdamped
        Chain([2.0, 1.0, 0.5], [1.0, 2.0, 0.5], [500.0, 300.0, 200.0, 0.0], "free"),
    ],
)
def test_perturbation_jacobian_agrees_with_central_differences(chain):
    from algid.model.modal import jacobian

    theta = _packed(chain)
    n, J = chain.n, jacobian(chain)
    for p in range(theta.size - (chain.boundary == "free")):  # a free end's k_{n+1} = 0 cannot move down
        h = 1e-5 * theta[p]
        up, down = theta.copy(), theta.copy()
        up[p] += h
        down[p] -= h
        fd = [_quantities(Chain(t[:n], t[n : 2 * n], t[2 * n :], chain.boundary)) for t in (up, down)]
        np.testing.assert_allclose(J[:, p], (fd[0] - fd[1]) / (2 * h), rtol=1e-5, atol=1e-8 * np.abs(J).max())


def test_uncertainty_propagation_agrees_with_monte_carlo():
    chain = TABLE1
    sigma = SIGMA_REL * _packed(chain)
    ma = modal_analysis(chain, sigma=sigma)
    rng = np.random.default_rng(7)
    draws = _packed(chain) + sigma * rng.standard_normal((2000, sigma.size))
    f, z, s = [], [], []
    for theta in draws:
        mc = Chain(theta[:3], theta[3:6], theta[6:]).modes()
        f.append(mc.frequencies_hz)
        z.append(mc.damping_ratios)
        s.append([np.abs(m.shape) for m in mc.modes])
    # 2000 draws: the sample standard deviation is within about 3 % of the truth (1.6 % sd)
    np.testing.assert_allclose(np.std(f, axis=0), [m.sigma_frequency_hz for m in ma.modes], rtol=0.06)
    np.testing.assert_allclose(np.std(z, axis=0), [m.sigma_damping_ratio for m in ma.modes], rtol=0.06)
    shape_sd = np.array([m.sigma_shape for m in ma.modes])
    moving = shape_sd > 1e-6  # the normalising entry is 1 in every draw
    np.testing.assert_allclose(np.std(s, axis=0)[moving], shape_sd[moving], rtol=0.08)
    # a full covariance gives the same with its diagonal, and more with correlated m and k
    same = modal_analysis(chain, covariance=np.diag(sigma**2))
    assert same.modes[0].sigma_frequency_hz == pytest.approx(ma.modes[0].sigma_frequency_hz, rel=1e-12)
    cov = np.diag(sigma**2)
    cov[0, 6] = cov[6, 0] = -0.9 * sigma[0] * sigma[6]  # m1 up, k1 down: frequencies move more
    assert modal_analysis(chain, covariance=cov).modes[0].sigma_frequency_hz > ma.modes[0].sigma_frequency_hz


def test_from_json_round_trip_and_errors(tmp_path):
    import json

    doc = {
        "n": 3,
        "boundary": "fixed",
        "mass": list(TABLE1.mass),
        "damping": list(TABLE1.damping),
        "stiffness": list(TABLE1.stiffness),
        "sigma_mass": [0.01] * 3,
        "sigma_damping": [0.1] * 3,
        "sigma_stiffness": [5.0] * 4,
    }
    path = tmp_path / "est.json"
    path.write_text(json.dumps(doc))
    back = Chain.from_json(path)
    for a, b in zip(back.matrices(), TABLE1.matrices()):
        np.testing.assert_array_equal(a, b)
    assert modal_analysis(path).modes[0].sigma_frequency_hz > 0
    # n = 1 with walls: k1 holds k1 + k2, k2 is null
    one = Chain.from_json({"n": 1, "boundary": "fixed", "mass": [2.0], "damping": [3.0], "stiffness": [1200.0, None]})
    assert one.matrices()[2][0, 0] == 1200.0
    with pytest.raises(ValueError, match="no estimate of c2, k3"):
        Chain.from_json({**doc, "damping": [5.5, None, 4.5], "stiffness": [1000.0, 900.0, None, 700.0]})
    with pytest.raises(ValueError, match="inadmissible estimates k2 = -3"):
        Chain.from_json({**doc, "stiffness": [1000.0, -3.0, 900.0, 700.0]})
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(ValueError, match="not JSON"):
        Chain.from_json(bad)


def test_to_control_without_python_control_is_one_line(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_control(name, *args, **kw):
        if name == "control":
            raise ImportError("No module named 'control'")
        return real(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", no_control)
    with pytest.raises(ImportError, match="needs python-control: pip install control"):
        TABLE1.to_control()


def test_recording_h1_is_labelled_in_the_recordings_units(tmp_path):
    from types import SimpleNamespace

    from algid.model.frf import recording_h1
    from algid.plotting.frf import frf_figure, save_frf

    rng = np.random.default_rng(3)
    u = rng.standard_normal((4096, 1))
    x = np.convolve(u[:, 0], [0.5, 0.3, 0.2])[:4096, None]  # any linear response
    si = SimpleNamespace(u=u, a=None, v=None, x=x, dt=1e-3)
    assert recording_h1(si).unit == "m/N"
    volts = SimpleNamespace(**vars(si), units={"force": "V", "displacement": "V"})
    est = recording_h1(volts)
    assert est.unit == "V/V" and est.output == "displacement"
    # the same FIR filter in the frequency domain: H = 0.5 + 0.3 z^-1 + 0.2 z^-2
    z = np.exp(-2j * np.pi * est.f_hz * 1e-3)
    np.testing.assert_allclose(est.H[1:, 0, 0], (0.5 + 0.3 * z + 0.2 * z**2)[1:], atol=0.02)  # no FRF at 0 Hz
    assert save_frf(est, tmp_path).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert frf_figure(est).axes[0].get_ylabel() == "|H| [V/V]"
