"""``algid identify`` on measured recordings (``../shared/data``; skipped when absent).

The Silverbox (an electronic Duffing oscillator recorded as input voltage and output
displacement only) must come out as a physical one-DOF chain close to the least-squares
fit of the diagnosis; the F-16 ground vibration test, which is no lumped chain, must never
give an impossible estimate marked valid.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"measured data not present at {DATA}")


def _identify_cli(path: Path, out: Path, *extra: str) -> dict:
    proc = subprocess.run(
        [sys.executable, "-m", "algid.cli", "identify", str(path), "--json", str(out), *extra],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(out.read_text())


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_silverbox_through_the_command_line(tmp_path):
    """The linear chain is close to the least-squares fit but biased by the cubic spring:
    ``model_misfit`` pointing at ``--effect cubic_stiffness:1``; with that effect, m, c, k and
    the cubic coefficient are valid, the latter the diagnosis's within 5 %."""
    from algid.diagnosis import diagnose
    from algid.recording import save_recording
    from algid.recording.datasets import silverbox_recording

    rec = silverbox_recording(DATA, "arrow")  # the first 40,000 samples (65.5 s)
    path = save_recording(tmp_path / "silverbox.npz", rec)
    doc = _identify_cli(path, tmp_path / "linear.json")
    assert doc["valid"] is False and doc["motion"] == "displacement"
    assert [p["status"] for p in doc["parameters"][:3]] == ["model_misfit"] * 3
    assert "--effect cubic_stiffness:1" in doc["parameters"][0]["reason"]
    est = np.array([doc["mass"][0], doc["damping"][0], doc["stiffness"][0]])
    sig = np.array([doc["sigma_mass"][0], doc["sigma_damping"][0], doc["sigma_stiffness"][0]])
    assert np.all(est > 0)
    ls = diagnose(rec, effects=()).lin.theta[0]  # the least-squares fit of the same record
    assert 5e-6 < ls[0] < 6e-6 and 1.0 < ls[2] < 1.1  # the PROVENANCE values (volt units)
    close = (np.abs(est / ls - 1) <= 0.05) | (np.abs(est - ls) <= 3 * sig)
    assert close.all(), (est, ls, sig)

    doc = _identify_cli(path, tmp_path / "cubic.json", "--effect", "cubic_stiffness")
    assert doc["valid"] is True and all(p["valid"] for p in doc["parameters"])
    (e,) = doc["effects"]
    assert e["effect"] == "cubic_stiffness" and e["valid"]
    assert e["params"]["k_cubic"] == pytest.approx(diagnose(rec).params["k_cubic"], rel=0.05)


@pytest.mark.parametrize("level", [1, 7])
def test_f16_estimates_are_plausible_or_flagged(level):
    import algid
    from algid.recording import Recording
    from algid.recording.datasets import f16_arrays, f16_chain_recording

    F, acc, fs = f16_arrays(DATA, level)
    shaker = Recording(t=np.arange(F.size) / fs, u=F[:, None], a=acc[:, :1])
    for rec, boundary in ((shaker, "fixed"), (f16_chain_recording(DATA, level), "free")):
        res = algid.identify(rec, boundary=boundary, replicates=4)
        for p, v in enumerate(res.verdicts):
            value, sigma = res.theta[p], res.sigma[p]
            if v.name.startswith("m") and v.valid:
                assert value > 3 * sigma, (v, value, sigma)
            if v.valid and np.isfinite(value):
                assert value >= -3 * sigma, (v, value, sigma)
            if not v.valid:
                assert v.reason
        # the aircraft is no lumped chain: at least the shaker DOF is not called a valid chain
        assert not res.valid
