"""The C++ estimator through Python: agreement with the numpy reference, accuracy figures,
boundaries, per-sample vs batch, argument checking and bad samples."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import algid
from algid.estimator import reference
from algid.model.chain import TABLE1, Chain
from signals import multisine, relative_errors, simulate_chain


@pytest.fixture(scope="module")
def table1_record():
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.5)
    return t, a, u


def test_cpp_agrees_with_numpy_reference(table1_record):
    t, a, u = table1_record
    est = algid.ChainEstimator(3, 1e-3)
    out = est.run(a, u, full=True)
    ref = reference.estimate(a, u, 1e-3, points=8)
    d = est.delay_samples
    cpp = out["theta"][d:]
    npy = ref["theta_ratio"][: len(t) - d]
    assert np.array_equal(np.isnan(cpp), np.isnan(npy)), "same validity decisions"
    late = slice(40, None)  # after the first trusted samples (ill-conditioned, rounding-dominated)
    rel = np.abs(cpp[late] / npy[late] - 1)
    assert np.nanmax(rel) < 1e-9
    inst_rel = np.abs(out["theta_instant"][d:][late] / ref["theta_inst"][: len(t) - d][late] - 1)
    assert np.nanmedian(inst_rel) < 1e-9


def test_delta_power_identity_against_direct_quadrature():
    """The core integrates f once and gets I^r(Delta^p f) by integration by parts. On a
    polynomial of degree P-1 that is exact while the direct quadrature of Delta^p f is not
    (its integrand has degree P-1+p); on a smooth signal both converge to the same integrals,
    the difference shrinking at the rule's order P."""
    h, P = 0.1, 8  # a coarse step, so that the direct rule's truncation error is far above rounding
    t = h * np.arange(80)
    f = 0.3 + t - 2 * t**3 + 0.5 * t**7  # degree P - 1
    G = reference.moments(f, t, h, P)
    Gd = reference.moments_direct(f, t, h, P)
    # exact: I^r(t^d) = d!/(d+r)! t^(d+r), term by term, with Delta^p raising every degree by p
    coeffs = {0: 0.3, 1: 1.0, 3: -2.0, 7: 0.5}
    from math import factorial

    def exact(p, r):
        return sum(c * factorial(d + p) / factorial(d + p + r) * t ** (d + p + r) for d, c in coeffs.items())

    late = slice(20, None)
    worst = 0.0
    for p in range(3):
        for r in range(6):
            e = exact(p, r)[late]
            worst = max(worst, np.max(np.abs(G[p, r][late] - e) / np.abs(e)))
    assert worst < 1e-11
    direct_err = np.max(np.abs(Gd[2, 3][late] - exact(2, 3)[late]) / np.abs(exact(2, 3)[late]))
    assert direct_err > 1e3 * worst  # the direct rule is not exact for Delta^2 f at this degree

    # Smooth signal: I^3(Delta^2 g)(1) against the exact value; the identity converges at the
    # rule's order P and beats the direct quadrature at every step.
    from scipy.integrate import quad

    def g(s):
        return np.sin(7 * s) + 0.5 * np.cos(3 * s)

    exact_value = quad(lambda s: (1 - s) ** 2 / 2 * s**2 * g(s), 0, 1, epsabs=1e-15, epsrel=1e-14, limit=200)[0]
    errors = []
    for step in (1 / 16, 1 / 32, 1 / 64):
        tt = step * np.arange(int(round(1 / step)) + 1)
        ident = reference.moments(g(tt), tt, step, P)[2, 3, -1]
        direct = reference.moments_direct(g(tt), tt, step, P)[2, 3, -1]
        errors.append(abs(ident - exact_value))
        if step > 1 / 64:  # at 1/64 both reach rounding
            assert abs(ident - exact_value) < abs(direct - exact_value) / 10
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > P - 0.6) & (orders < P + 1.5)), orders


def test_table1_accuracy_figures(table1_record):
    """Issue 2: within 1 % by t0 + 0.05 s and 1e-6 by t0 + 0.5 s (noise-free multisine)."""
    t, a, u = table1_record
    est = algid.ChainEstimator(3, 1e-3)
    out = est.run(a, u)
    k50 = 50 + est.delay_samples  # the row describing the window [0, 0.05 s]
    err50 = relative_errors(TABLE1, out["mass"][k50], out["damping"][k50], out["stiffness"][k50])
    assert err50.size == 10 and err50.max() < 1e-2  # m1..3, c1..3, k1..4 (k2, k3 fused)
    # the last row describes [0, 0.5 s - delay]: feed the delay more samples for 0.5 s exactly
    t2, a2, u2, _ = simulate_chain(TABLE1, multisine(3), 0.5 + 0.006)
    out2 = algid.ChainEstimator(3, 1e-3).run(a2, u2)
    err_end = relative_errors(TABLE1, out2["mass"][-1], out2["damping"][-1], out2["stiffness"][-1])
    assert err_end.max() < 1e-6


@pytest.mark.parametrize("n,boundary", [(1, "fixed"), (1, "free"), (2, "fixed"), (5, "free")])
def test_random_chains_and_boundaries(n, boundary):
    chain = Chain.random(n, np.random.default_rng(n), boundary)
    _, a, u, _ = simulate_chain(chain, multisine(n, seed=n), 0.3)
    out = algid.ChainEstimator(n, 1e-3, boundary=boundary).run(a, u)
    err = relative_errors(chain, out["mass"][-1], out["damping"][-1], out["stiffness"][-1])
    assert err.max() < 1e-5
    if n == 1 and boundary == "fixed":
        assert np.isnan(out["stiffness"][-1, 1])  # only k1 + k2, reported in k1
    if boundary == "free":
        assert out["stiffness"][-1, -1] == 0.0


def test_interior_springs_estimated_twice(table1_record):
    _, a, u = table1_record
    est = algid.ChainEstimator(3, 1e-3)
    est.run(a, u)
    # spring 2 from DOF 1 (slot 3) and from DOF 2 (slot 2), fused = mean
    left, right = est.theta(0)[3], est.theta(1)[2]
    assert abs(left / 900 - 1) < 1e-6 and abs(right / 900 - 1) < 1e-6
    assert est.stiffness[1] == pytest.approx(0.5 * (left + right), rel=1e-14)


def test_update_matches_run(table1_record):
    _, a, u = table1_record
    batch = algid.ChainEstimator(3, 1e-3).run(a[:200], u[:200])
    est = algid.ChainEstimator(3, 1e-3)
    for k in range(200):
        est.update(a[k], u[k])
    np.testing.assert_array_equal(est.mass, batch["mass"][-1])
    np.testing.assert_array_equal(est.stiffness, batch["stiffness"][-1])
    np.testing.assert_array_equal(est.valid, batch["valid"][-1])


def test_bad_sample_reseeds(table1_record):
    _, a, u = table1_record
    est = algid.ChainEstimator(3, 1e-3)
    est.run(a[:100], u[:100])
    assert est.valid.all()
    bad = a[100].copy()
    bad[1] = np.inf
    assert est.update(bad, u[100]) == algid.Status.BAD_INPUT
    assert not est.valid.any() and np.isnan(est.mass).all()
    out = est.run(a[101:400], u[101:400])  # restarts at t0 = 0.101 s: no initial conditions needed
    err = relative_errors(TABLE1, out["mass"][-1], out["damping"][-1], out["stiffness"][-1])
    assert err.max() < 1e-5


@pytest.mark.parametrize("n,boundary", [(1, "fixed"), (1, "free"), (2, "free"), (4, "fixed")])
def test_noisy_eq7_agrees_with_numpy_reference(n, boundary):
    """With noise the instantaneous solutions scatter and eq. 7's weighting shows: every system
    size (3x3 for n = 1 and a free end, 4x4 otherwise) weighs them by |det A| as the reference
    does, to rounding."""
    chain = Chain.random(n, np.random.default_rng(n), boundary)
    _, a, u, _ = simulate_chain(chain, multisine(n, seed=n), 0.3)
    a = a + 1e-2 * np.random.default_rng(1).standard_normal(a.shape) * a.std(0)
    est = algid.ChainEstimator(n, 1e-3, boundary=boundary)
    out = est.run(a, u, full=True)
    ref = reference.estimate(a, u, 1e-3, boundary=boundary, points=8)
    d = est.delay_samples
    cpp, npy = out["theta"][d:][40:], ref["theta_ratio"][: len(a) - d][40:]
    assert np.array_equal(np.isnan(cpp), np.isnan(npy))
    assert np.nanmax(np.abs(cpp / npy - 1)) < 1e-8


@pytest.mark.parametrize("n,boundary", [(11, "fixed"), (30, "free")])
def test_any_n_agrees_with_numpy_reference(n, boundary):
    """Sizes that are not compiled as fixed-size instantiations run the run-time sized
    estimator: the same eq. 7 estimates as the numpy reference, exact on noise-free data."""
    assert n not in algid.SIZES
    chain = Chain.random(n, np.random.default_rng(n), boundary)
    _, a, u, _ = simulate_chain(chain, multisine(n, seed=n), 0.3)
    est = algid.ChainEstimator(n, 1e-3, boundary=boundary)
    out = est.run(a, u, full=True)
    ref = reference.estimate(a, u, 1e-3, boundary=boundary, points=8)
    d = est.delay_samples
    cpp, npy = out["theta"][d:], ref["theta_ratio"][: len(a) - d]
    assert np.array_equal(np.isnan(cpp), np.isnan(npy)), "same validity decisions"
    late = slice(40, None)
    assert np.nanmax(np.abs(cpp[late] / npy[late] - 1)) < 1e-8
    err = relative_errors(chain, out["mass"][-1], out["damping"][-1], out["stiffness"][-1])
    assert err.max() < 1e-5


@pytest.mark.parametrize("n", [1, 3, 10])
def test_fixed_and_runtime_sizes_agree(n):
    """The fixed-size and the run-time sized estimators of one build are one arithmetic: the same
    estimates to rounding (bit for bit where their lane widths agree)."""
    from algid.estimator import chain_core

    core = chain_core()
    _, a, u, _ = simulate_chain(Chain.random(n, np.random.default_rng(n)), multisine(n, seed=n), 0.2)
    cfg = algid.ChainConfig()
    fixed, dynamic = getattr(core, f"ChainEstimator{n}")(cfg, n), core.ChainEstimatorDynamic(cfg, n)
    out_f, out_d = fixed.run(a, u), dynamic.run(a, u)
    for key in ("mass", "damping", "stiffness"):
        if fixed.lanes == dynamic.lanes and n > 1:
            np.testing.assert_array_equal(out_f[key], out_d[key])
        else:
            np.testing.assert_allclose(out_f[key], out_d[key], rtol=1e-9, atol=0)
    np.testing.assert_array_equal(out_f["valid"], out_d["valid"])


@pytest.mark.parametrize("n", [200, 1000])
def test_large_chains_run(n):
    """Large chains identify every parameter of a noise-free record."""
    chain = Chain.random(n, np.random.default_rng(n))
    _, a, u, _ = simulate_chain(chain, multisine(n, seed=n), 0.1)
    out = algid.ChainEstimator(n, 1e-3).run(a, u)
    err = relative_errors(chain, out["mass"][-1], out["damping"][-1], out["stiffness"][-1])
    assert out["valid"][-1].all() and err.max() < 1e-4


def test_configuration_is_the_cpp_struct():
    """Defaults live in C++: a fresh ChainConfig carries them, options set its fields, and
    unknown options, bad sizes and bad values are refused with the reason."""
    cfg = algid.ChainConfig()
    assert (cfg.dt, cfg.boundary, cfg.min_samples, cfg.min_hadamard) == (1e-3, "fixed", 16, 1e-9)
    est = algid.ChainEstimator(4, 2e-3, boundary="free", min_samples=20)
    assert (est.config.dt, est.config.boundary, est.config.min_samples) == (2e-3, "free", 20)
    with pytest.raises(TypeError, match="unknown option"):
        algid.ChainEstimator(3, 1e-3, min_sample=3)
    with pytest.raises(ValueError, match=">= 1"):
        algid.ChainEstimator(0, 1e-3)
    with pytest.raises(ValueError, match="min_hadamard"):
        algid.ChainEstimator(3, 1e-3, min_hadamard=2.0)
    assert cfg.validate(3) == "ok" and "DOF" in cfg.validate(0)


def test_argument_errors():
    with pytest.raises(ValueError, match="boundary"):
        algid.ChainEstimator(3, 1e-3, boundary="clamped")
    with pytest.raises(ValueError, match="dt"):
        algid.ChainEstimator(3, 0.0)
    est = algid.ChainEstimator(3, 1e-3)
    with pytest.raises(ValueError, match=r"\(T, 3\)"):
        est.run(np.zeros((10, 2)), np.zeros((10, 2)))
    with pytest.raises(ValueError, match="3 entries"):
        est.update(np.zeros(2), np.zeros(3))
    for index in (3, -1, 100_000):
        with pytest.raises(IndexError, match="dof"):
            est.theta(index)
        with pytest.raises(IndexError, match="dof"):
            est._impl.theta_instant(index)


def test_run_releases_the_gil():
    """Another Python thread keeps running while run() loops in C++."""
    T = 400_000
    rng = np.random.default_rng(0)
    a, u = rng.standard_normal((T, 10)), rng.standard_normal((T, 10))
    est = algid.ChainEstimator(10, 1e-3)
    ticks = []
    worker = threading.Thread(target=est.run, args=(a, u))
    start = time.perf_counter()
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    # with the GIL held the main thread would tick about once
    assert elapsed < 0.05 or len(ticks) > 5


def _isa_builds() -> list[str]:
    """Instruction-set builds of the chain estimators this machine has and can run, narrowest first."""
    import importlib

    from algid import _core

    builds = ["x86-64"]
    for level in ("v3", "v4"):
        # The CPU check first: importing a build this CPU cannot run dies of SIGILL.
        if not _core.cpu_supports(f"x86-64-{level}"):
            continue
        try:
            importlib.import_module(f"algid._core_{level}")
        except ImportError:
            continue
        builds.append(f"x86-64-{level}")
    return builds


@pytest.mark.parametrize("isa", _isa_builds())
@pytest.mark.parametrize("n,boundary", [(1, "fixed"), (2, "free"), (3, "fixed"), (10, "fixed")])
def test_run_is_update_bit_for_bit_in_every_build(isa, n, boundary):
    """Within one build, run() leaves every estimate, instantaneous solution and Hadamard ratio
    exactly where update() does, sample by sample, across a bad sample."""
    from algid.estimator import chain_core

    core = chain_core(isa)
    chain = Chain.random(n, np.random.default_rng(n), boundary=boundary)
    t, a, u, _ = simulate_chain(chain, multisine(n), 0.403)
    a[211, 0] = np.nan  # reseeds inside what would be a block
    make = getattr(core, f"ChainEstimator{n}")
    cfg = algid.ChainConfig()
    cfg.boundary = boundary
    batch = make(cfg, n).run(a, u, True)
    one = make(cfg, n)
    theta = np.empty_like(batch["theta"])
    inst = np.empty_like(batch["theta_instant"])
    had = np.empty_like(batch["hadamard"])
    status = np.empty_like(batch["status"])
    for k in range(len(t)):
        status[k] = one.update(a[k], u[k])
        theta[k] = [one.theta(i) for i in range(n)]
        inst[k] = [one.theta_instant(i) for i in range(n)]
        had[k] = [one.hadamard(i) for i in range(n)]
    np.testing.assert_array_equal(status, batch["status"])
    np.testing.assert_array_equal(theta, batch["theta"])  # NaN == NaN for this function
    np.testing.assert_array_equal(inst, batch["theta_instant"])
    np.testing.assert_array_equal(had, batch["hadamard"])
    assert np.isfinite(batch["mass"][-1]).all()


def test_isa_builds_agree_and_selection():
    """The builds agree to rounding (FMA in the wider builds' chain products), the default is
    the widest build this CPU runs, and asking for an unknown level is an error."""
    from algid.estimator import chain_core

    builds = _isa_builds()
    assert algid.ISA == builds[-1]
    with pytest.raises(ValueError, match="x86-64"):
        chain_core("armv8")
    if len(builds) < 2:
        pytest.skip("no wider build or CPU here")
    _, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.3)
    outs = [chain_core(isa).ChainEstimator3(algid.ChainConfig(), 3).run(a, u) for isa in builds]
    late = slice(60, None)
    for out in outs[1:]:
        for key in ("mass", "damping", "stiffness"):
            rel = np.abs(out[key][late] / outs[0][key][late] - 1)
            assert np.nanmax(rel) < 1e-9, key


def _one_force_record(dof: int, duration_s: float = 0.5):
    """Table 1 under the multisine on DOF ``dof`` alone (the other forces exactly 0)."""
    force = multisine(3)
    t, a, u, _ = simulate_chain(TABLE1, lambda t: np.where(np.arange(3) == dof, force(t), 0.0), duration_s)
    assert np.all(u[:, np.arange(3) != dof] == 0.0)
    return t, a, u


@pytest.mark.parametrize("dof", [0, 1], ids=["dof1", "dof2"])
def test_one_force_scales_the_whole_chain(dof):
    """Issue 35, item 3: one force, every parameter. An unforced DOF's eq. 7 gives the ratios to
    its mass, the shared springs carry the forced DOF's scale (noise-free: as exact as a force
    on every DOF, test_table1_accuracy_figures)."""
    t, a, u = _one_force_record(dof, 0.5 + 0.006)
    est = algid.ChainEstimator(3, 1e-3)
    out = est.run(a, u)
    assert est.forced.tolist() == [i == dof for i in range(3)] and est.ready
    err = relative_errors(TABLE1, out["mass"][-1], out["damping"][-1], out["stiffness"][-1])
    assert err.max() < 1e-6, err
    # the spring that carried the scale is one number on both sides (not averaged with itself)
    for i in range(dof, 2):  # springs k_{i+2} right of the forced DOF
        assert est.theta(i)[3] == pytest.approx(est.theta(i + 1)[2], rel=1e-14)
    # an unforced DOF's instantaneous solution is the ratios to its mass
    other = 2 if dof != 2 else 0
    inst = est.theta_instant(other)
    m, c, k = TABLE1.mass[other], TABLE1.damping[other], TABLE1.stiffness
    np.testing.assert_allclose(inst[1:] * m, [c, k[other], k[other + 1]], rtol=1e-5)
    assert inst[0] == pytest.approx(1.0, rel=1e-15)  # det * (1 / det)


def test_no_force_has_no_scale():
    t, a, u = _one_force_record(0, 0.2)
    est = algid.ChainEstimator(3, 1e-3)
    out = est.run(a, np.zeros_like(u))
    assert not est.forced.any() and not est.valid.any()
    assert np.isnan(out["mass"][-1]).all() and np.isnan(out["stiffness"][-1]).all()


def test_one_force_window_of_identify():
    """algid.identify's single window returns every parameter of a clean short record with one
    force (``raw``: the verdicts' scale rule is applied by the engine)."""
    t, a, u = _one_force_record(1, 1.0)
    res = algid.identify(algid.Recording(t=t, u=u, a=a), estimator="window", replicates=2)
    assert res.plan.estimator == "window"
    truth = TABLE1.identifiable()
    assert np.max(np.abs(res.raw / truth - 1)) < 1e-6


def test_one_force_algebraic_windows_of_the_continuous_estimator():
    """The algebraic windows of ContinuousEstimator are ChainEstimators: one force scales every
    window result, so the running estimate has every parameter."""
    t, a, u = _one_force_record(0, 4.0)
    est = algid.ContinuousEstimator(3, 1e-3, method="algebraic")
    out = est.run(a, u)
    last = np.concatenate([out["mass"][-1], out["damping"][-1], out["stiffness"][-1]])
    err = np.abs(last / TABLE1.identifiable() - 1)
    assert np.isfinite(last).all() and err.max() < 1e-3, err
