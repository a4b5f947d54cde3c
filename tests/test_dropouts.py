"""Sensor dropouts that are finite numbers (cpp/include/algid/detail/dropout.hpp): an
accelerometer stuck at one value or clipped at its range is detected, its samples are
discarded like NaNs (status DROPOUT) and reported, and never read as a parameter change;
without the detector the same records raise change events (the negative control)."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from test_continuous import CHAIN, DT, tone_record

DROPOUT = int(algid.Status.DROPOUT)


@pytest.fixture(scope="module")
def record():
    return tone_record(CHAIN, 30.0, seed=11, snr_db=40.0)


def _stuck(a, dof, start, stop):
    a = a.copy()
    a[start:stop, dof] = a[start - 1, dof]  # frozen at its last reading
    return a


def _clipped(a, dof, share=0.7):
    """An accelerometer whose range is ``share`` of the largest acceleration: every peak beyond
    it reads as the range (826 of 30 000 samples at 0.7)."""
    a = a.copy()
    limit = share * np.abs(a[:, dof]).max()
    a[:, dof] = np.clip(a[:, dof], -limit, limit)
    return a


def _run(a, u, **options):
    est = algid.ContinuousEstimator(3, DT, **options)
    return est, est.run(a, u, stride=100)


def test_stuck_channel_is_a_dropout_not_a_change(record):
    a, u, truth = record
    bad = _stuck(a, 1, 12000, 14000)  # a2 frozen for 2 s
    est, out = _run(bad, u)
    assert out["events"] == []
    assert est.dropouts["runs"] == 1 and est.dropouts["last"] == "stuck" and est.dropouts["channel"] == 2
    stuck = est.options["stuck_samples"]
    flagged = np.nonzero(out["status"] == DROPOUT)[0]
    # from the run's completion (it starts with the last true reading, sample 11999) to its end
    assert flagged[0] == 11999 + stuck - 1 and flagged[-1] == 13999
    assert np.abs(out["estimate"][-1] / truth[0] - 1)[[0, 1, 2, 6, 7, 8, 9]].max() < 0.005


def test_clipped_channel_is_a_dropout_not_a_change(record):
    a, u, truth = record
    bad = _clipped(a, 0)
    est, out = _run(bad, u)
    assert out["events"] == []
    assert est.dropouts["last"] == "clipped" and est.dropouts["channel"] == 1 and est.dropouts["runs"] > 10
    inside = np.abs(bad[:, 0]) < np.abs(bad[:, 0]).max()
    assert np.all(out["status"][inside] != DROPOUT)  # only samples at the range are dropped
    assert np.abs(out["estimate"][-1] / truth[0] - 1)[[0, 1, 2, 6, 7, 8, 9]].max() < 0.002


def test_without_the_detector_the_same_records_mislead(record):
    a, u, truth = record
    est, out = _run(_stuck(a, 1, 12000, 14000), u, stuck_samples=0, clip_samples=0)
    assert est.dropouts["samples"] == 0
    assert out["events"], "a frozen accelerometer reads as a parameter change"
    est, out = _run(_clipped(a, 0), u, stuck_samples=0, clip_samples=0)
    err = np.abs(out["estimate"][-1] / truth[0] - 1)[[0, 1, 2, 6, 7, 8, 9]].max()
    assert out["events"] or err > 0.01, "a clipped accelerometer biases the estimates"


def test_quiet_channels_and_clean_records_are_not_dropouts(record):
    a, u, _ = record
    est, out = _run(a, u)
    assert est.dropouts == {"samples": 0, "runs": 0, "last": None, "channel": None}
    # a channel that never moved (a DOF at rest, a zero signal) is not stuck
    a0 = a.copy()
    a0[:, 2] = 0.0
    est, out = _run(a0, u, detect=False)
    assert est.dropouts["samples"] == 0


def test_dropout_options_are_checked():
    for bad in ({"stuck_samples": 1}, {"stuck_samples": -1}, {"clip_samples": 1}, {"clip_samples": -1}):
        with pytest.raises(ValueError, match="stuck_samples"):
            algid.ContinuousEstimator(3, DT, **bad)
