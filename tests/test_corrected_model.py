"""The chain refitted with the diagnosed effect (``corrected_model``): closer to the truth than
the linear fit, calibrated by its jackknife sigmas, readable by ``Chain.from_json``."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from algid.diagnosis import diagnose
from algid.diagnosis.corrected import corrected_model
from algid.diagnosis.report import to_json
from algid.model.chain import TABLE1, Chain
from algid.recording import save_recording
from fleet_recordings import EFFECTS, recording

COULOMB = EFFECTS[2]  # 1.5 N of dry friction at DOF 1


@pytest.fixture(scope="module")
def coulomb():
    rec = recording(TABLE1, 20.0, 2, COULOMB)
    return rec, diagnose(rec)


def test_the_chain_with_friction_is_the_true_chain(coulomb):
    _, d = coulomb
    assert d.effect == "coulomb_friction" and d.location == {"dof": 1}
    cm = corrected_model(d)
    theta = np.array(cm["mass"] + cm["damping"] + cm["stiffness"], dtype=float)
    sigma = np.array(cm["sigma_mass"] + cm["sigma_damping"] + cm["sigma_stiffness"], dtype=float)
    truth = TABLE1.identifiable()
    err = np.abs(theta / truth - 1)
    assert err[:3].max() < 0.005 and err[6:].max() < 0.005 and err[3:6].max() < 0.03
    assert np.max(np.abs(theta - truth) / sigma) < 4
    # the linear fit takes the friction for viscous damping: c1 more than doubled
    assert d.lin.damping()[0] > 2 * TABLE1.damping[0]
    assert cm["effects"][0]["params"]["force"] == pytest.approx(COULOMB["params"]["force"], rel=0.03)
    assert cm["refitted_dofs"] == [1]


def test_json_and_model_file_read_back_as_a_chain(coulomb, tmp_path):
    rec, d = coulomb
    doc = to_json(d)
    chain = Chain.from_json(doc["corrected_model"])
    np.testing.assert_allclose(
        chain.identifiable(),
        np.array(
            doc["corrected_model"]["mass"] + doc["corrected_model"]["damping"] + doc["corrected_model"]["stiffness"]
        ),
    )
    path = tmp_path / "axis.csv"
    save_recording(path, rec)
    out = tmp_path / "model.json"
    cmd = [sys.executable, "-m", "algid.cli", "diagnose", str(path), "--model", str(out), "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    written = json.loads(out.read_text())
    assert Chain.from_json(out).n == 3 and written["effects"][0]["effect"] == "coulomb_friction"
    np.testing.assert_allclose(written["damping"], doc["corrected_model"]["damping"], rtol=1e-9)


def test_no_effect_no_corrected_model():
    d = diagnose(recording(TABLE1, 20.0, 0, None))
    assert d.effect == "none" and corrected_model(d) is None and to_json(d)["corrected_model"] is None
