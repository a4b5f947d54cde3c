"""Threads: run() releases the GIL, so one estimator object must refuse a second concurrent
call (RuntimeError) instead of interleaving two records, and distinct estimators in parallel
threads must give exactly what they give one after the other."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import algid

KINDS = [(algid.ChainEstimator, "mass"), (algid.ContinuousEstimator, "estimate")]


def _record(T: int, n: int = 3, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.standard_normal((T, n)), rng.standard_normal((T, n))


@pytest.mark.parametrize("cls,key", KINDS)
def test_a_second_call_on_a_running_estimator_is_refused(cls, key):
    a, u = _record(1_500_000)
    est = cls(3, 1e-3)
    result = {}
    worker = threading.Thread(target=lambda: result.setdefault("out", est.run(a, u)))
    worker.start()
    refused, early = [], []  # calls refused; calls that went through before the run began
    calls = [lambda e: e.update(a[0], u[0]), lambda e: e.run(a[:10], u[:10]), lambda e: getattr(e, key)]
    deadline = time.monotonic() + 5.0
    while worker.is_alive() and time.monotonic() < deadline and len(refused) < 3:
        for call in calls:
            try:
                call(est)
                if not refused:
                    early.append(call)
            except RuntimeError as err:
                assert "in use by another thread" in str(err)
                refused.append(err)
        time.sleep(0.005)
    worker.join()
    assert refused, "the record ended before a concurrent call could be made: lengthen it"
    # The running call was not disturbed: the same as a fresh estimator given the calls that
    # went through before the run started, then the record.
    fresh = cls(3, 1e-3)
    for call in early:
        call(fresh)
    np.testing.assert_array_equal(result["out"][key], fresh.run(a, u)[key])
    est.run(a[:10], u[:10])  # and the object is usable again afterwards


@pytest.mark.parametrize("cls,key", KINDS)
def test_distinct_estimators_in_parallel_equal_sequential_runs(cls, key):
    records = [_record(60_000, seed=s) for s in range(4)]
    sequential = [cls(3, 1e-3).run(a, u)[key] for a, u in records]
    parallel: list = [None] * 4

    def work(i: int) -> None:
        a, u = records[i]
        parallel[i] = cls(3, 1e-3).run(a, u)[key]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got, want in zip(parallel, sequential):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    "options,needle",
    [
        ({"method": "algebraic", "prefilter_hz": 1e-300}, "prefilter_hz"),
        ({"method": "algebraic", "prefilter_hz": 1e-12}, "prefilter_hz"),
        ({"window_s": 1e6}, "window_s"),
    ],
)
def test_continuous_options_outside_their_physical_range(options, needle):
    with pytest.raises(ValueError, match=needle):
        algid.ContinuousEstimator(3, 1e-3, **options)


@pytest.mark.parametrize("dt", [1e-300, 1e300, 0.0, -1e-3])
def test_sample_period_outside_its_physical_range(dt):
    for cls in (algid.ChainEstimator, algid.ContinuousEstimator):
        with pytest.raises(ValueError, match="dt must be in"):
            cls(3, dt)


@pytest.mark.parametrize("scale", [1e-75, 1e80])
def test_valid_is_never_true_for_an_estimate_that_is_not_a_number(scale):
    a, u = _record(3000)
    out = algid.ChainEstimator(3, 1e-3).run(a * scale, u * scale)
    finite = np.isfinite(out["mass"]) & np.isfinite(out["damping"])
    assert not (out["valid"] & ~finite).any()
