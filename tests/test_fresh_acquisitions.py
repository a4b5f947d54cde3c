"""``algid diagnose`` on acquisitions as converters and loggers write them (issue 35, item 4):
a decimating converter's filter that starts from rest, a quasi-static device whose mass the
force-form fit cannot determine, a Stribeck peak on an axis read through encoder counts, a
multiplexer's skew on a device and beside an effect. The
slow cases are records of the fresh-acquisition bench (``bench/realistic_blind.py --fresh``)
that an earlier diagnosis got wrong, drawn by the bench's own generator with their labels."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from algid.diagnosis import MAIN_PARAM, diagnose
from algid.diagnosis.engine import FIT_FLOOR_RATIO, _prepare, coloured_floor, relative_floors
from algid.diagnosis.model import force_response
from algid.diagnosis.windows import prepare
from algid.model.chain import Chain
from algid.recording import Recording
from algid.simulator import simulate
from signals import multisine

BENCH = Path(__file__).resolve().parents[1] / "bench" / "realistic_blind.py"


def test_coherence_is_read_on_the_analysed_samples():
    """A converter's filter starting from rest puts a spike in the record's first samples, inside
    the lead-in the windows skip: it must not lower the coherence of forces and motion."""
    res = simulate(Chain([1.0], [2.0], [400.0, 0.0]), multisine(1), 10.0, 1000.0, noise_db=50.0, seed=0)
    a = res.a.copy()
    a[:5] += 1e4 * a.std()  # the start-up: the motion rising from rest to its offset in 5 samples
    coherence = force_response(prepare(a, res.u, res.dt, 1000, "free", skip=100), 50.0)
    assert coherence["related"] and coherence["coherence"][1] > 0.9


def test_coloured_accelerometer_noise_is_carried_through_the_integrals():
    """1/f accelerometer noise as strong as the white (a free 4-DOF chain, 50 dB): the equations'
    integrals lift it far above its own 1/f in the band. Carried through the analysis, the floor
    is the linear chain's withheld gap, so a linear record is ``none``; read on the equations as
    white plus 1/f, the floor is several times lower and the record was ``unknown``."""
    chain = Chain([1.13, 1.16, 1.13, 2.9], [6.5, 2.6, 2.9, 7.9], [1500.0, 1376.0, 1116.0, 1385.0, 0.0])
    res = simulate(chain, multisine(4), 10.0, 1000.0, seed=0)
    rng = np.random.default_rng(1)
    T = res.a.shape[0]
    f = np.fft.rfftfreq(T)
    tilt = np.where(f > 0, 1.0 / np.sqrt(np.maximum(f, 1.0 / T)), 0.0)[:, None]
    pink = np.fft.irfft(np.fft.rfft(rng.standard_normal((T, 4)), axis=0) * tilt, T, axis=0)
    white = 10 ** (-50 / 20) * res.a.std(axis=0)  # [m/s^2]
    st = _prepare(
        Recording(t=res.t, u=res.u, a=res.a + white * (rng.standard_normal((T, 4)) + pink / pink.std(axis=0))),
        "free",
        None,
    )
    gap = np.sqrt(st.lin.cv.test_sse.sum() / st.denom)
    carried = relative_floors(st.P, st.floor_band, st.denom, st.lin.resid, st.shapes)[1]
    flat = relative_floors(st.P, st.floor_band, st.denom, st.lin.resid)[1]
    assert 0.7 < carried / gap < 1.4 and flat < 0.3 * gap
    assert st.model.verdict == "chain" and gap <= FIT_FLOOR_RATIO * carried  # the verdict's ``none``
    assert np.all(coloured_floor(st.P, st.lin.resid) <= coloured_floor(st.P, st.lin.resid, st.shapes))


def _bench(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH.parent))  # the bench imports its sibling blind_diagnosis
    spec = importlib.util.spec_from_file_location("realistic_blind", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
@pytest.mark.parametrize(
    "seed, rel, why",
    [
        (50250, 0.01, "CIC decimation started from rest: its start-up spike read as no force response"),
        (50002, 0.01, "device, random-walk force drift: force-form mass undetermined, solved for acceleration"),
        (50067, 0.01, "device, 1/f noise: force-form mass undetermined, solved for acceleration"),
        # the Coulomb level of a Stribeck fit through encoder counts is biased (35 % here)
        (50107, 0.4, "axis in 2 um encoder counts: Stribeck peak fitted below the velocity noise"),
        (50185, None, "device, force half a sample before the motion: its negligible negative mass is no effect"),
        (50148, 0.01, "clearance and a 4-channel skew: the skew found only with the clearance in the fit"),
    ],
)
def test_fresh_acquisitions_the_diagnosis_once_missed(seed, rel, why, monkeypatch):
    rec, label = _bench(monkeypatch).draw(seed, fresh=True)
    d = diagnose(rec, boundary=label["boundary"])
    assert d.effect == label["effect"], why
    if rel is not None:
        main = MAIN_PARAM[label["effect"]]
        assert d.params[main] == pytest.approx(label["params"][main], rel=rel), why
