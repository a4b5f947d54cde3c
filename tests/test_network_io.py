"""A spring network through the files and commands around identify (issue 39): an identify
result or a diagnosis's model read back as a :class:`NetworkModel`, ``algid demo --topology``
(the network open loop, identified against its truth) and ``algid batch --topology``."""

from __future__ import annotations

import json

import numpy as np
import pytest

import algid
from algid import Chain, Network, NetworkModel
from algid.cli import main
from algid.control.network_demo import demo_force, probe_lines, read_network
from algid.control.trajectories import BezierReference
from algid.model.modal import modal_analysis
from algid.recording import save_recording
from algid.simulator import simulate
from algid.simulator.scenarios import network_model, network_recording

HALF_CAR = {"n": 4, "springs": [[1, 2], [3, 1], [4, 2], [0, 3], [0, 4]]}


@pytest.fixture(scope="module")
def half_car():
    """A noise-free 1 s half-car record, its truth, and its identification."""
    scenario = network_recording("half_car", duration_s=1.0)
    net = scenario.chain.network
    return scenario, algid.identify(scenario.recording, topology=net)


def test_a_half_car_identify_json_reads_back_as_its_network_model(half_car, tmp_path):
    scenario, result = half_car
    path = tmp_path / "id.json"
    path.write_text(json.dumps(result.to_json()))
    back = NetworkModel.from_json(path)
    assert back.network == scenario.chain.network
    np.testing.assert_array_equal(back.packed(), result.theta)  # the file's numbers, exactly
    np.testing.assert_allclose(back.packed(), scenario.chain.packed(), rtol=1e-6)
    np.testing.assert_allclose(
        [m.frequency_hz for m in modal_analysis(path).modes], [m.frequency_hz for m in result.modes()[0].modes]
    )
    with pytest.raises(ValueError, match="not a chain: read it with algid.NetworkModel.from_json"):
        Chain.from_json(path)


def test_a_network_diagnosis_model_reads_back(half_car):
    from algid.diagnosis import diagnose
    from algid.diagnosis.corrected import linear_model

    scenario, _ = half_car
    model = linear_model(diagnose(scenario.recording, boundary=scenario.chain.network))
    back = NetworkModel.from_json(json.loads(json.dumps(model)))
    np.testing.assert_allclose(back.packed(), scenario.chain.packed(), rtol=1e-6)


def test_network_documents_and_their_one_line_errors(tmp_path):
    doc = {
        **HALF_CAR,
        "mass": [2.0, 2.5, 1.0, 1.0],
        "damping": [1.0, 2.0, 3.0, 4.0],
        "stiffness": [5e3, 2e3, 2e3, 9e3, 8e3],
    }
    model = NetworkModel.from_json(doc)
    assert NetworkModel.from_json(model.to_json(tmp_path / "m.json")).packed().tolist() == model.packed().tolist()
    # springs in parallel: the second's null is 0, the sum in the first leaves K as it is
    par = {"n": 2, "springs": [[0, 1], [1, 2], [1, 2]], "mass": [1.0, 2.0], "damping": [1.0, 1.0]}
    two = NetworkModel.from_json({**par, "stiffness": [100.0, 50.0, None]})
    np.testing.assert_array_equal(two.matrices()[2], [[150.0, -50.0], [-50.0, 50.0]])
    with pytest.raises(ValueError, match="no estimate of m2, k1: a network model needs every parameter"):
        NetworkModel.from_json({**par, "mass": [1.0, None], "stiffness": [None, 50.0, None]})
    with pytest.raises(ValueError, match="inadmissible estimates k2 = -3"):
        NetworkModel.from_json({**par, "stiffness": [100.0, -3.0, None]})
    (tmp_path / "net.json").write_text(json.dumps(HALF_CAR))
    with pytest.raises(ValueError, match="a topology without values .read it with algid.Network.from_json"):
        NetworkModel.from_json(tmp_path / "net.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(ValueError, match="not JSON"):
        NetworkModel.from_json(tmp_path / "bad.json")


@pytest.mark.parametrize("boundary", ["fixed", "free"])
def test_a_chain_document_is_its_network_and_back(boundary):
    chain = Chain.random(3, np.random.default_rng(1), boundary)
    doc = {"n": 3, "boundary": boundary, "mass": list(chain.mass), "damping": list(chain.damping)}
    doc["stiffness"] = list(chain.stiffness)
    net = NetworkModel.from_json(doc)
    assert net.network == Network.chain(3, boundary)
    for a, b in zip(net.matrices(), chain.matrices()):
        np.testing.assert_array_equal(a, b)
    again = Chain.from_json(net.to_json())  # a network whose springs are a chain's is that chain
    assert again.boundary == boundary and again.stiffness.tolist() == chain.stiffness.tolist()
    one = NetworkModel.from_json(
        {"n": 1, "boundary": "fixed", "mass": [2.0], "damping": [1.0], "stiffness": [9.0, None]}
    )
    assert one.matrices()[2].tolist() == [[9.0]]


def test_the_demo_force_moves_the_network_along_the_references():
    """Without the probe, the force is the inverse dynamics: the network follows the
    references to the integrator's accuracy (oracle: the Bezier polynomials)."""
    model, source = read_network(HALF_CAR)
    assert source.startswith("no values") and model.stiffness.tolist() == [1000.0, 900.0, 900.0, 700.0, 1000.0]
    sim = simulate(model, demo_force(model, 1.0, 0.0), 1.0, 1000.0)
    ref = BezierReference.paper(4, t_out=(0.0, 0.4), t_back=(0.5, 0.9))
    x_ref = np.array([ref.evaluate(t)[0] for t in sim.t])
    assert np.max(np.abs(sim.x - x_ref)) < 1e-6 * 0.005


@pytest.mark.parametrize("name", ["frame", "half_car", "lattice"])
def test_the_demo_probe_spans_every_mode_of_the_network(name):
    """The probe's lines reach below the lowest natural frequency and above the highest (the
    chain demo's lines stop at 15.7 Hz, below the lattice's upper modes), two lines per DOF."""
    model = network_model(name)
    f_hz, lines = model.natural_frequencies_hz(), probe_lines(model)
    assert lines.size == max(6, 2 * model.n) and np.all(np.diff(lines) > 0)
    assert lines[0] < f_hz.min() and lines[-1] > f_hz.max()


def test_demo_topology_identifies_the_network_against_its_truth(tmp_path, capsys):
    (tmp_path / "car.json").write_text(json.dumps(HALF_CAR))
    out = tmp_path / "demo"
    assert (
        main(["demo", "--topology", str(tmp_path / "car.json"), "--duration", "1", "--no-plots", "--out", str(out)])
        == 0
    )
    text = capsys.readouterr().out
    assert "open loop: the closed loop of eqs. 8-10 is the chain's" in text
    s = json.loads((out / "summary.json").read_text())
    assert [p["name"] for p in s["parameters"]] == Network(4, HALF_CAR["springs"]).parameter_names()
    assert all(p["status"] == "ok" and abs(p["rel_err"]) < 1e-6 for p in s["parameters"])
    assert s["parameters"][0]["true"] == 2.0  # Table 1's m1
    assert main(["demo", "--topology", str(tmp_path / "car.json"), "--mode", "sampled", "--n", "4"]) == 2
    assert (
        capsys.readouterr().err.strip()
        == "algid demo: error: --mode, --n: the chain's closed loop, not with --topology"
    )


def test_a_batch_row_of_a_network_is_its_identification(half_car, tmp_path, capsys):
    pytest.importorskip("psutil")
    from algid.fleet.task import Options, run_one

    scenario, result = half_car
    (tmp_path / "m01").mkdir()
    path = save_recording(tmp_path / "m01" / "rec.npz", scenario.recording)
    topology = json.dumps(scenario.chain.network.to_json())
    row = run_one(str(path), Options(topology=topology))
    assert row["status"] == "ok" and row["boundary"] is None and json.loads(row["springs"]) == HALF_CAR["springs"]
    np.testing.assert_allclose([row[f"k{s}"] for s in range(1, 6)], result.theta[8:], rtol=1e-9)
    np.testing.assert_allclose(row["f1_hz"], scenario.chain.natural_frequencies_hz()[0], rtol=1e-6)
    assert b"topology" not in Options().fingerprint()  # a chain's key as before networks
    with pytest.raises(ValueError, match="no boundary or estimator"):
        Options(topology=topology, boundary="free")
    assert (
        main(["batch", str(path), "--out", str(tmp_path / "o"), "--topology", "x.json", "--estimator", "window"]) == 2
    )
    assert "--estimator: the chain's, not with --topology" in capsys.readouterr().err


@pytest.mark.slow
def test_algid_batch_topology_on_a_local_cluster(half_car, tmp_path):
    pytest.importorskip("distributed")
    pytest.importorskip("pyarrow")
    scenario, result = half_car
    (tmp_path / "rigs" / "m01").mkdir(parents=True)
    save_recording(tmp_path / "rigs" / "m01" / "rec.npz", scenario.recording)
    (tmp_path / "car.json").write_text(json.dumps(HALF_CAR))
    table = algid.batch(tmp_path / "rigs", tmp_path / "out", workers=1, diagnose=True, topology=tmp_path / "car.json")
    assert table.attrs["counts"] == {"ok": 1, "failed": 0, "skipped": 0}
    np.testing.assert_allclose(table.loc[0, "m1"], result.theta[0], rtol=1e-9)
    assert table.loc[0, "effect"] == "none"
