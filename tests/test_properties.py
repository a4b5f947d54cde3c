"""Invariances, checked by hypothesis on records of Table 1's chain under a multisine
(``signals.simulate_chain``): what must not change the estimates does not.

* column order: a file's columns in any order, in any case, with units in the header, with
  columns the reader ignores, or renamed and mapped by ``columns``, read to the same arrays
  and the same estimates, bit for bit;
* time offset: ``t + t0`` in the file gives the same estimates (bit for bit when the sampling
  interval computed from the offset times comes out the same; they may differ in the last
  bits, by the rounding of ``t0 + k dt``);
* units: forces and accelerations scaled alike leave every parameter unchanged; forces alone
  scaled by s scale every parameter by s (bit for bit for powers of two);
* a bad sample then a reseed: ``ChainEstimator`` reseeds by itself on a non-finite or
  overflowing sample, and any estimator reset after garbage continues exactly as a clean
  estimator started there; ``ContinuousEstimator`` is back within 1 % of the truth after a
  burst of garbage followed by clean samples.

Deterministic (derandomized, no example database), a few seconds each; a longer randomized
search: ``ALGID_PROPERTY_EXAMPLES=2000 pytest tests/test_properties.py``.
"""

from __future__ import annotations

import os
from functools import cache

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import algid
from algid.model.chain import TABLE1
from algid.recording import load_recording
from signals import multisine, simulate_chain

#: Examples per property: 10 in the fast tier; .ci/run searches longer (ALGID_PROPERTY_EXAMPLES=50),
#: and ALGID_PROPERTY_RANDOM=1 draws them at random instead of from a fixed seed.
EXAMPLES = int(os.environ.get("ALGID_PROPERTY_EXAMPLES", "10"))
PROPERTY = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize="ALGID_PROPERTY_RANDOM" not in os.environ,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
DT = 1e-3
BAD = int(algid.Status.BAD_INPUT)
N = TABLE1.n


@cache
def record(duration_s: float):
    """Times, accelerations and forces (T, 3) of Table 1's chain [s, m/s^2, N]."""
    t, a, u, _ = simulate_chain(TABLE1, multisine(N, seed=4), duration_s, 1.0 / DT)
    for arr in (t, a, u):
        arr.setflags(write=False)
    return t, a, u


def chain_estimates(a, u, dt=DT, reset_at=None) -> dict[str, np.ndarray]:
    """``ChainEstimator.run`` histories and final parameters; ``reset()`` before sample ``reset_at``."""
    est = algid.ChainEstimator(N, dt)
    if reset_at is not None:
        est.run(a[:reset_at], u[:reset_at])
        est.reset()
        a, u = a[reset_at:], u[reset_at:]
    out = {
        k: np.asarray(v) for k, v in est.run(a, u).items() if k in ("status", "mass", "damping", "stiffness", "valid")
    }
    out["final"] = np.concatenate([est.mass, est.damping, est.stiffness])
    return out


def continuous_estimates(a, u, reset_at=None) -> dict[str, np.ndarray]:
    est = algid.ContinuousEstimator(N, DT)
    if reset_at is not None:
        est.run(a[:reset_at], u[:reset_at], stride=50)
        est.reset()
        a, u = a[reset_at:], u[reset_at:]
    out = est.run(a, u, stride=50)
    return {k: np.asarray(out[k]) for k in ("status", "estimate", "sigma", "windows", "event_sample")}


def assert_same(x: dict, y: dict) -> None:
    assert x.keys() == y.keys()
    for key in x:
        np.testing.assert_array_equal(x[key], y[key], err_msg=key)


# ---- column order --------------------------------------------------------------------------
UNITS = {"t": "s", "u": "N", "a": "m/s^2"}
IGNORED = ("Unnamed: 0", "temperature [C]", "status", "x_ref2", "sample")


@st.composite
def layouts(draw):
    """Header names in file order (signal names spelled in any case, with or without a unit;
    or renamed and mapped) and the ``columns`` mapping the reader needs."""
    signals = ["t"] + [f"{k}{i}" for k in "ua" for i in range(1, N + 1)]
    extra = draw(st.lists(st.sampled_from(IGNORED), unique=True, max_size=3))
    order = draw(st.permutations(signals + extra))
    mapped = draw(st.sets(st.sampled_from(["t", "u", "a"]), max_size=3))
    names, columns = [], {}
    for col in order:
        if col in IGNORED:
            names.append(col)
            continue
        if col[0] in mapped:
            name = f"chan{order.index(col)}_{col[0]}"
            columns.setdefault(col[0], []).append((col, name))
        else:
            name = col.upper() if draw(st.booleans()) else col
            name = f"{name} [{UNITS[col[0]]}]" if draw(st.booleans()) else name
        names.append(name)
    # the mapping lists DOF 1..n in order, whatever the file order
    mapping = {k: [name for _, name in sorted(v)] for k, v in columns.items()}
    if "t" in mapping:
        mapping["t"] = mapping["t"][0]
    return order, names, mapping


def write(path, order, names, cols) -> None:
    table = np.column_stack([cols[c] for c in order])
    if path.suffix == ".npz":
        np.savez(path, **dict(zip(names, table.T)))
    else:
        np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def columns_of(t, a, u) -> dict[str, np.ndarray]:
    cols = {"t": t, **{f"u{i + 1}": u[:, i] for i in range(N)}, **{f"a{i + 1}": a[:, i] for i in range(N)}}
    rng = np.random.default_rng(0)
    return cols | {name: rng.standard_normal(t.size) for name in IGNORED}


@PROPERTY
@given(layout=layouts(), suffix=st.sampled_from([".csv", ".npz"]))
def test_column_order_changes_nothing(tmp_path, layout, suffix):
    t, a, u = record(1.0)
    order, names, mapping = layout
    path = tmp_path / f"r{suffix}"
    write(path, order, names, columns_of(t, a, u))
    rec = load_recording(path, columns=mapping or None)
    np.testing.assert_array_equal(rec.t, t)
    np.testing.assert_array_equal(rec.u, u)
    np.testing.assert_array_equal(rec.a, a)
    assert_same(chain_estimates(rec.a, rec.u, rec.dt), chain_estimates(a, u))


# ---- time offset ---------------------------------------------------------------------------
@PROPERTY
@given(
    dt=st.sampled_from([1e-3, 1 / 1024, 2.5e-4, 1e-2, 1 / 3000]),
    samples=st.floats(-1e9, 1e9),
    fraction=st.floats(0, 1),
)
def test_time_offset_changes_nothing(tmp_path, dt, samples, fraction):
    """t0 up to a billion samples from zero (a Unix time stamp at 1 Hz..3 kHz)."""
    _, a, u = record(1.0)
    t0 = (round(samples) + fraction) * dt
    cols = columns_of(DT * np.arange(a.shape[0]), a, u)
    order = ["t"] + [f"{k}{i}" for k in "ua" for i in range(1, N + 1)]
    reads = []
    for offset in (0.0, t0):
        path = tmp_path / "r.csv"
        write(path, order, order, cols | {"t": offset + dt * np.arange(a.shape[0])})
        reads.append(load_recording(path))
    # dt = (t[-1] - t[0]) / (T - 1) from times rounded at the offset's ulp
    drift = abs(reads[1].dt / reads[0].dt - 1)
    assert drift <= 4 * np.finfo(float).eps * (abs(t0) / (dt * a.shape[0]) + 1)
    ref, shifted = (chain_estimates(r.a, r.u, r.dt) for r in reads)
    if drift == 0:
        assert_same(ref, shifted)
    np.testing.assert_allclose(shifted["final"], ref["final"], rtol=1e-10 + 3 * drift)


# ---- units ---------------------------------------------------------------------------------
@PROPERTY
@given(power=st.integers(-60, 60), both=st.booleans())
def test_scaling_by_powers_of_two_is_exact(power, both):
    t, a, u = record(8.0)
    s = 2.0**power
    ref = chain_estimates(a, u)
    scaled = chain_estimates(a * s if both else a, u * s)
    factor = 1.0 if both else s
    np.testing.assert_array_equal(scaled["final"], ref["final"] * factor)
    np.testing.assert_array_equal(scaled["valid"], ref["valid"])
    cref = continuous_estimates(a, u)
    cscaled = continuous_estimates(a * s if both else a, u * s)
    np.testing.assert_array_equal(cscaled["estimate"], cref["estimate"] * factor)
    np.testing.assert_array_equal(cscaled["event_sample"], cref["event_sample"])


@PROPERTY
@given(s=st.floats(1e-6, 1e6), both=st.booleans())
def test_scaling_units_scales_the_parameters(s, both):
    """Any factor (N to kN, m/s^2 to g, volts): equal to rounding."""
    t, a, u = record(8.0)
    factor = 1.0 if both else s
    ref, scaled = chain_estimates(a, u)["final"], chain_estimates(a * s if both else a, u * s)["final"]
    np.testing.assert_allclose(scaled, ref * factor, rtol=1e-9)
    cref = continuous_estimates(a, u)["estimate"][-1]
    cscaled = continuous_estimates(a * s if both else a, u * s)["estimate"][-1]
    np.testing.assert_allclose(cscaled, cref * factor, rtol=1e-8)


# ---- a bad sample, then a reseed ----------------------------------------------------------
NON_FINITE = st.sampled_from([np.nan, np.inf, -np.inf])
#: Finite accelerations whose window systems overflow: the chain estimator's own reseed.
OVERFLOWING = st.builds(lambda e, sign: sign * 10.0**e, st.floats(100, 308), st.sampled_from([1.0, -1.0]))
GARBAGE = st.one_of(NON_FINITE, st.floats(allow_nan=True, allow_infinity=True), OVERFLOWING)


@PROPERTY
@given(k=st.integers(10, 1500), channel=st.integers(0, 2 * N - 1), value=st.one_of(NON_FINITE, OVERFLOWING))
def test_chain_estimator_reseeds_on_a_bad_sample(k, channel, value):
    t, a, u = record(2.0)
    if channel >= N and np.isfinite(value):
        channel -= N  # a finite force never overflows the systems: see test_reset_after_garbage
    bad_a, bad_u = a.copy(), u.copy()
    (bad_a if channel < N else bad_u)[k, channel % N] = value
    out = chain_estimates(bad_a, bad_u)
    reseeds = np.flatnonzero(out["status"] == BAD)
    assert reseeds.size == 1 and k <= reseeds[0] <= k + 8
    j = reseeds[0] + 1
    clean = chain_estimates(a[j:], u[j:])
    assert_same(
        {key: v[j:] for key, v in out.items() if key != "final"}, {k_: clean[k_] for k_ in clean if k_ != "final"}
    )
    np.testing.assert_array_equal(out["final"], clean["final"])


@PROPERTY
@given(
    k=st.integers(10, 1500),
    burst=st.lists(st.tuples(st.integers(0, 2 * N - 1), GARBAGE), min_size=1, max_size=40),
    wait=st.integers(0, 200),
)
def test_reset_after_garbage_is_a_clean_start(k, burst, wait):
    """Any garbage (finite or not, a force or an acceleration), then ``reset()``: the chain
    estimator and the continuous estimator continue exactly as new ones would."""
    t, a, u = record(8.0)
    bad_a, bad_u = a.copy(), u.copy()
    for i, (channel, value) in enumerate(burst):
        (bad_a if channel < N else bad_u)[k + i, channel % N] = value
    j = k + len(burst) + wait
    bad_a[j:], bad_u[j:] = a[j:], u[j:]
    assert_same(chain_estimates(bad_a, bad_u, reset_at=j), chain_estimates(a[j:], u[j:]))
    assert_same(continuous_estimates(bad_a, bad_u, reset_at=j), continuous_estimates(a[j:], u[j:]))


@PROPERTY
@given(
    burst=st.lists(st.tuples(st.integers(0, 2 * N - 1), GARBAGE), min_size=1, max_size=200),
    rejected=st.booleans(),
)
def test_continuous_estimator_recovers_from_a_burst(burst, rejected):
    """Garbage at 1 s, then 7 s of clean samples: no state left NaN or frozen (finite running
    estimates, windows still harvested); after values the estimator rejects (not finite, or
    beyond ``outlier_ratio`` times the RMS) the estimates are back within 1 % of the truth.
    (A finite outlier it accepts biases them for good: docs/reliability.md.)"""
    t, a, u = record(8.0)
    bad_a, bad_u = a.copy(), u.copy()
    for i, (channel, value) in enumerate(burst):
        value = np.copysign(1e150, value) if rejected and np.isfinite(value) else value
        (bad_a if channel < N else bad_u)[1000 + i, channel % N] = value
    est = algid.ContinuousEstimator(N, DT)
    out = est.run(bad_a, bad_u, stride=50)
    assert np.isfinite(est.estimate).all() and est.ready
    assert (out["status"][-1000:] != BAD).all()
    assert out["window_sample"][-1] > a.shape[0] - 1000  # still harvesting windows
    if rejected:
        assert np.abs(est.estimate / TABLE1.identifiable() - 1).max() < 0.01
