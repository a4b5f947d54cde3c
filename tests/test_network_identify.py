"""``algid.identify(rec, topology=net)`` and ``--topology``: a spring network identified by the
diagnosis's windowed equation-error fit, jointly over its equations, then by output error
(:mod:`algid.identification.network`); the chain as a network gives the chain's fit bit for
bit."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import algid
from algid.cli import main
from algid.diagnosis.corrected import linear_model
from algid.diagnosis.integrals import integrals
from algid.diagnosis.linear import fit_linear
from algid.diagnosis.windows import prepare
from algid.identification.network import FLOOR_RATIO, judge_network
from algid.model.chain import TABLE1
from algid.model.network import Network, NetworkModel
from algid.recording import Recording, save_recording
from algid.simulator import simulate
from algid.simulator.exact import multisine
from algid.simulator.scenarios import network_model, network_recording


@pytest.fixture(scope="module")
def half_car():
    """The half-car at 40 dB, 4 s, and its identification."""
    sc = network_recording("half_car", duration_s=4.0, noise_db=40.0, seed=3)
    return sc, algid.identify(sc.recording, topology=network_model("half_car").network)


def test_network_record_identified_within_its_sigmas(half_car):
    _, r = half_car
    truth = network_model("half_car").packed()
    z = (r.theta - truth) / r.sigma
    assert r.valid and r.plan.estimator == "integral_equations"
    assert np.all(np.isfinite(z)) and np.max(np.abs(z)) < 5.0, z
    mk = np.r_[0:4, 8:13]  # masses and springs: within 1 %
    assert np.max(np.abs(r.theta[mk] / truth[mk] - 1)) < 0.01
    assert len(r.modes()[0].modes) == 4  # the modal table of the NetworkModel


def test_noise_on_the_forces_keeps_the_joint_fit(half_car):
    """The fixture's forces carry 40 dB of noise: the output error's residual is above the
    accelerometers' floor, so the joint equation-error fit is the answer."""
    _, r = half_car
    oe = r.model_fit["output_error"]
    assert not oe["kept"] and oe["residual_over_floor"] > FLOOR_RATIO
    assert "output error" not in r.plan.reason


def test_output_error_refines_a_record_with_exact_forces():
    """Noise on the accelerations alone (the Cramer-Rao bound's model): the output error's
    residual is the sensor noise, it is kept, its sigmas are calibrated and its errors are a
    fraction of the joint fit's."""
    model = network_model("half_car")
    truth = model.packed()
    sim = simulate(model, multisine(4, 3), 4.0, 1000.0, noise_db=40.0, noise_on=("accel",), seed=3)
    r = algid.identify(Recording(t=sim.t, u=sim.u, a=sim.a), topology=model.network)
    assert r.model_fit["output_error"]["kept"] and "refined by output error" in r.plan.reason
    assert r.valid and np.max(np.abs((r.theta - truth) / r.sigma)) < 5.0
    cm = linear_model(r.diagnosis)
    joint = np.array(cm["mass"] + cm["damping"] + cm["stiffness"], dtype=float)
    rms = lambda theta: float(np.sqrt(np.mean((theta / truth - 1) ** 2)))  # noqa: E731
    assert rms(r.theta) < 0.5 * rms(joint), (rms(r.theta), rms(joint))


def test_json_names_the_springs_in_the_networks_order(half_car):
    _, r = half_car
    doc = r.to_json()
    net = network_model("half_car").network
    assert doc["springs"] == [list(p) for p in net.springs] and "boundary" not in doc
    assert len(doc["stiffness"]) == net.size == len(doc["sigma_stiffness"])
    assert [p["name"] for p in doc["parameters"]] == net.parameter_names()


def test_chain_as_a_network_is_the_chains_fit_bit_for_bit():
    sim = simulate(TABLE1, multisine(3, 5), 2.0, 1000.0, noise_db=40.0, seed=5)
    a, u, dt = sim.a, sim.u, float(sim.t[1] - sim.t[0])
    A = integrals(a, dt)
    for boundary in ("fixed", "free"):
        chain = fit_linear(prepare(a, u, dt, 100, boundary, A=A))
        net = fit_linear(prepare(a, u, dt, 100, Network.chain(3, boundary), A=A))
        assert chain.names == net.names
        for x, y in zip(chain.theta, net.theta):
            np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(chain.stiffness()[: 3 + (boundary == "fixed")], net.stiffness())


def test_parallel_springs_get_their_reason_not_a_number():
    net = Network(2, [(0, 1), (1, 0), (1, 2)])
    theta = np.array([1.0, 2.0, 1.0, 1.0, 3000.0, math.nan, 1000.0])
    sigma = np.full(7, 0.01)
    by = {v.name: v for v in judge_network(theta, sigma, net, [1, 2], "")}
    assert by["k1"].status == by["k2"].status == "not_separable"
    assert "k1 + k2 in parallel between ground and DOF 1" in by["k2"].reason
    assert "reported as k1" in by["k1"].reason
    assert by["k3"].status == "ok" and by["m2"].status == "ok"
    one_force = {v.name: v for v in judge_network(theta, sigma, net, [1], "")}
    assert one_force["m2"].status == "ok"  # scaled through k3 from DOF 1


def _one_force(model: NetworkModel, dof: int, duration_s: float, noise_db):
    """``model`` driven by the tests' multisine at DOF ``dof`` (1-based) alone, identified."""
    full = multisine(model.n, 3)

    def force(t):
        f = full(t)
        return np.where(np.arange(model.n) == dof - 1, f, 0.0)

    sim = simulate(model, force, duration_s, 1000.0, noise_db=noise_db, noise_on=("accel", "force"), seed=3)
    assert np.count_nonzero(np.any(sim.u != 0.0, axis=0)) == 1
    return algid.identify(Recording(t=sim.t, u=sim.u, a=sim.a), topology=model.network)


@pytest.mark.parametrize(
    "name, dof",
    [
        pytest.param("half_car", 1, marks=pytest.mark.slow),
        pytest.param("frame", 1, marks=pytest.mark.slow),
        pytest.param("frame", 5, marks=pytest.mark.slow),
    ],
)
def test_one_force_scales_the_whole_network(name, dof):
    """Issue 39: one force, every parameter. The joint fit carries the force's scale along the
    springs to every unforced DOF: noise-free within 1e-6, at 40 dB every parameter valid and
    within its sigmas."""
    model = network_model(name)
    truth = model.packed()
    exact = _one_force(model, dof, 4.0, None)
    assert np.max(np.abs(exact.theta / truth - 1)) < 1e-6
    noisy = _one_force(model, dof, 4.0, 40.0)
    assert noisy.valid, [(v.name, v.status, v.reason) for v in noisy.verdicts if v.status != "ok"]
    assert np.max(np.abs((noisy.theta - truth) / noisy.sigma)) < 5.0


def test_a_part_without_force_nor_path_to_one_gets_its_reason():
    """DOF 3 hangs on its own spring to ground: no force reaches it, so it has no scale."""
    model = NetworkModel(Network(3, [(0, 1), (1, 2), (0, 3)]), [1.0, 2.0, 1.5], [2.0, 3.0, 2.5], [2e3, 1e3, 1.5e3])
    r = _one_force(model, 1, 2.0, None)
    by = {v.name: v for v in r.verdicts}
    assert all(by[p].status == "ok" for p in ("m1", "m2", "c1", "c2", "k1", "k2"))
    for p in ("m3", "c3", "k3"):
        assert by[p].status == "not_identifiable" and "no force on DOF 3" in by[p].reason
    np.testing.assert_allclose(r.theta[[0, 1, 3, 4, 6, 7]], model.packed()[[0, 1, 3, 4, 6, 7]], rtol=1e-6)
    assert np.all(np.isnan(r.theta[[2, 5, 8]]))


@pytest.mark.slow
def test_topology_json_round_trip_on_the_command_line(tmp_path):
    model = NetworkModel(
        Network(3, [(0, 1), (1, 2), (2, 3), (1, 3)]), [1.0, 2.0, 1.5], [2.0, 3.0, 2.5], [2e3, 1e3, 1.5e3, 8e2]
    )
    sim = simulate(model, multisine(3, 7), 4.0, 1000.0, noise_db=40.0, noise_on=("accel", "force"), seed=7)
    rec = save_recording(tmp_path / "rec.npz", Recording(t=sim.t, u=sim.u, a=sim.a))
    model.network.to_json(tmp_path / "net.json")
    assert Network.from_json(tmp_path / "net.json") == model.network
    code = main(
        [
            "identify",
            str(rec),
            "--topology",
            str(tmp_path / "net.json"),
            "--json",
            str(tmp_path / "out.json"),
            "--quiet",
        ]
    )
    doc = json.loads((tmp_path / "out.json").read_text())
    assert code == 0 and doc["springs"] == [[0, 1], [1, 2], [2, 3], [1, 3]]
    assert np.allclose(doc["stiffness"], model.stiffness, rtol=0.05)
    assert main(["diagnose", str(rec), "--topology", str(tmp_path / "net.json"), "--quiet"]) == 0


@pytest.mark.slow
def test_a_chain_record_without_topology_is_identified_as_today():
    """The chain record's result does not pass through the network path: no springs key, the
    chain's boundary and estimator."""
    sim = simulate(TABLE1, multisine(3, 2), 10.0, 1000.0, noise_db=40.0, noise_on=("accel", "force"), seed=2)
    doc = algid.identify(Recording(t=sim.t, u=sim.u, a=sim.a)).to_json()
    assert doc["boundary"] == "fixed" and "springs" not in doc and len(doc["stiffness"]) == 4


@pytest.mark.slow
def test_output_error_at_the_noise_overrules_the_windowed_misfit():
    """The frame under the demo's slow references and probe at 40 dB: the windowed fit check
    leaves a gap above its floor, the output error predicts every acceleration to its noise, and
    the verdicts follow the output error (every estimate valid, within 5 sigma of the truth)."""
    from algid.control.network_demo import run_network

    model = network_model("frame")
    _, res, _ = run_network(model, noise_db=40.0)
    assert res.model_fit["output_error"]["kept"]
    truth = np.concatenate([model.mass, model.damping, model.stiffness])
    z = (res.theta - truth) / res.sigma
    assert all(v.status == "ok" for v in res.verdicts)
    assert np.max(np.abs(z)) < 5.0
