"""The diagnosis on measured data (``../shared/data``; skipped when absent).

Oracles are independent of the diagnosis: the Silverbox's cubic spring is known by
construction and its size from an ordinary least-squares fit of u = m y'' + c y' + k y +
k3 y^3 on central differences (PROVENANCE.md: k3 ~ 3.5, k ~ 1.09-1.12, volt units); the
F-16 torsion mode's resonance peak moves from 7.324 Hz (level 1) to 7.227 Hz (level 7) and
flattens ~3x (PROVENANCE.md, period-averaged FRF).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"measured data not present at {DATA}")


def _ls_cubic_oracle(rec) -> float:
    """k3 of u = m y'' + c y' + k y + k3 y^3 + offset by plain least squares on central
    differences of the displacement (the PROVENANCE check), independent of algid."""
    y, u, dt = rec.x[:, 0], rec.u[:, 0], rec.dt
    yd = (y[2:] - y[:-2]) / (2 * dt)
    ydd = (y[2:] - 2 * y[1:-1] + y[:-2]) / dt**2
    yc = y[1:-1]
    X = np.stack([ydd, yd, yc, yc**3, np.ones_like(yc)], axis=1)
    return float(np.linalg.lstsq(X, u[1:-1], rcond=None)[0][3])


def test_silverbox_is_a_hardening_cubic_spring():
    from algid.diagnosis import diagnose
    from algid.recording.datasets import silverbox_recording

    rec = silverbox_recording(DATA, "arrow")
    d = diagnose(rec)
    assert (d.effect, d.location) == ("cubic_stiffness", {"spring": 1})
    oracle = _ls_cubic_oracle(rec)
    assert 3.0 < oracle < 4.0  # the PROVENANCE value, 3.5
    assert d.params["k_cubic"] == pytest.approx(oracle, rel=0.1)
    assert d.params["k_cubic"] > 0  # hardening
    k = d.lin.stiffness()[0]
    assert 1.0 < k < 1.15  # PROVENANCE: 1.09-1.12
    assert d.gap_after < 0.6 * d.gap_before
    # Where: the error follows the deformation, not the velocity, and peaks near the
    # resonance (~70 Hz).
    amp = d.where["amplitude"]
    assert amp["springs"][0]["explained"] > 5 * amp["masses"][0]["explained"]
    assert 50.0 < d.where["frequency"]["peak_hz"] < 90.0


def test_f16_torsion_mode_softens_and_damps_with_level():
    from algid.diagnosis import diagnose
    from algid.recording.datasets import f16_modal_recording

    fits = {}
    for level in (1, 7):
        d = diagnose(f16_modal_recording(DATA, level))
        m, c, k = d.lin.theta[0]
        fits[level] = (np.sqrt(k / m) / (2 * np.pi), c / (2 * np.sqrt(k * m)))
    f1, z1 = fits[1]
    f7, z7 = fits[7]
    assert f1 == pytest.approx(7.324, abs=0.05)  # the level-1 FRF peak
    assert f7 < f1 - 0.05  # softening, as the FRF peak (7.227 Hz)
    assert z7 > 2.5 * z1  # ~3x flatter resonance


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_f16_lumped_chain_is_not_explained_by_one_effect():
    from algid.diagnosis import diagnose
    from algid.recording.datasets import f16_chain_recording

    d = diagnose(f16_chain_recording(DATA, 7), boundary="free")
    assert d.effect == "unknown"
    assert d.gap_before > 0.2  # a three-mass chain is far from a full aircraft
    # ... and says why: the drive point shows the aircraft's modes, more than three
    model = d.extra["model"]
    assert model.verdict == "more_modes_than_dof"
    peaks = model.evidence["resonances"][1]["peaks_hz"]
    assert len(peaks) > 3 and any(abs(f - 7.3) < 0.2 for f in peaks)  # the wing-torsion mode among them
    # The worst equations are those of the joint (wing side, payload side), not the shaker's.
    gaps = [p["gap"] for p in d.where["per_dof"]]
    assert min(gaps[1], gaps[2]) > gaps[0]
