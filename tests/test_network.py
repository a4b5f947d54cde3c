"""Spring networks (issue 39): the topology and its JSON, the chain as a network, the
identifiability reasons, the simulator and the modes of a network model, the numpy reference
identifier of networks against noise-free records and against the chain's oracle, and the
Cramer-Rao bound of a network."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from algid.estimator import network_reference as nr
from algid.estimator import reference
from algid.identification import crlb as C
from algid.model import chain as chain_topology
from algid.model.chain import TABLE1, Chain
from algid.model.network import Network, NetworkModel
from algid.simulator import simulate
from algid.simulator.scenarios import NETWORKS, network_model
from signals import multisine, simulate_chain

# --- topology ---------------------------------------------------------------------------------


def test_chain_network_is_eq1():
    """Spring j joins DOF j-1 and j; K is eq. 1's tridiagonal matrix, written out here."""
    k = np.array([1000.0, 900.0, 800.0, 700.0])
    net = Network.chain(3)
    assert net.springs == ((0, 1), (1, 2), (2, 3), (3, 0))
    K = np.array([[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2] + k[3]]])
    assert np.array_equal(net.stiffness_matrix(k), K)
    assert Network.chain(3, "free").springs == ((0, 1), (1, 2), (2, 3))
    assert Network.chain(1).springs == ((0, 1), (1, 0))
    assert net.parameter_names() == chain_topology.parameter_names(3)


def test_chain_topology_functions_follow_the_network():
    """model/chain.py's functions are the network's (one implementation), with eq. 1's values."""
    assert chain_topology.spring_columns(3, "fixed") == [[(1, -1), (2, 1)], [(2, 0), (3, 2)], [(3, 1), (4, -1)]]
    assert chain_topology.spring_columns(3, "free")[-1] == [(3, 1)]
    assert chain_topology.spring_columns(1, "fixed") == [[(1, -1)]]  # k1 + k2 in parallel: one column
    assert chain_topology.springs(1, "fixed") == [1] and chain_topology.springs(3, "free") == [1, 2, 3]
    assert chain_topology.spring_sides(3, 2) == [(1, 1.0), (0, -1.0)]
    assert chain_topology.spring_sides(3, 4) == [(2, -1.0)]
    x = np.arange(6.0).reshape(2, 3) ** 2
    assert np.array_equal(chain_topology.spring_deformation(x, 2, 3), x[:, 1] - x[:, 0])
    assert np.array_equal(chain_topology.spring_deformation(x, 4, 3), -x[:, 2])


def test_incident_springs_give_the_stiffness_force():
    """K x equals, DOF by DOF, the sum over incident springs of k_s (x_i - x_other)."""
    model = network_model("lattice")
    net, k = model.network, model.stiffness
    x = np.random.default_rng(1).standard_normal(net.n)
    xg = np.concatenate([[0.0], x])  # index 0: ground
    force = [sum(k[s - 1] * (xg[i] - xg[o]) for s, _, o in net.incident(i)) for i in range(1, net.n + 1)]
    K = net.stiffness_matrix(k)
    np.testing.assert_allclose(K @ x, force, rtol=1e-13)
    assert np.array_equal(K, K.T)
    assert net.degree(5) == 8 and len(net.columns(5)) == 8
    # deformation and signs: sign k_s d_s is spring s's term in DOF i's equation
    X = x[None, :]
    for i in range(1, net.n + 1):
        for s, sign, o in net.incident(i):
            assert sign * net.deformation(X, s)[0] == pytest.approx(xg[i] - xg[o])


def test_json_round_trip_and_one_line_errors(tmp_path):
    net = Network(3, [(0, 1), (1, 2), (1, 2)])  # a parallel pair is allowed, DOF 3 has no spring
    path = tmp_path / "net.json"
    assert net.to_json(path) == {"n": 3, "springs": [[0, 1], [1, 2], [1, 2]]}
    assert Network.from_json(path) == net and Network.from_json(net.to_json()) == net
    cases = [
        ({"n": 2, "springs": [[0, 3]]}, r"k1 = \(0, 3\) joins DOF 3, outside 0..2"),
        ({"n": 2, "springs": [[0, 1], [2, 2]]}, r"k2 = \(2, 2\) joins DOF 2 to itself"),
        ({"n": 2}, "needs keys n and springs"),
        ({"n": 2, "springs": [[1]]}, "every spring is a pair"),
        ({"n": 0, "springs": []}, "n >= 1"),
    ]
    for doc, msg in cases:
        with pytest.raises(ValueError, match=msg) as err:
            Network.from_json(doc)
        assert "\n" not in str(err.value)
    (tmp_path / "bad.json").write_text("{", encoding="utf-8")
    with pytest.raises(ValueError, match="not JSON"):
        Network.from_json(tmp_path / "bad.json")


# --- identifiability --------------------------------------------------------------------------


def test_identifiability_reasons():
    assert network_model("lattice").network.identifiability() == {}
    assert network_model("lattice").network.identifiability(forced=[1]) == {}  # connected: the scale spreads
    par = Network(2, [(0, 1), (1, 2), (2, 1)]).identifiability()
    assert set(par) == {"k2", "k3"} and "only their sum" in par["k2"]
    blind = Network(3, [(0, 1), (1, 2), (2, 3)]).identifiability(measured=[1, 2])
    assert set(blind) == {"m3", "c3", "k3"} and "DOF 3, which is not measured" in blind["k3"]
    # DOF 3 and 4 joined to each other and to ground only: no force reaches them
    apart = Network(4, [(0, 1), (1, 2), (0, 3), (3, 4)]).identifiability(forced=[1])
    assert set(apart) == {"m3", "c3", "m4", "c4", "k3", "k4"} and "no scale" in apart["m4"]
    assert Network(2, [(0, 1)]).identifiability(forced=[1]) == {"m2": _no_scale(2), "c2": _no_scale(2)}


def _no_scale(i: int) -> str:
    return f"no force on DOF {i} nor a path of springs to a forced DOF: no scale"


# --- model, simulator, modes ------------------------------------------------------------------


def test_chain_as_network_model_has_the_chain_matrices_and_modes():
    model = NetworkModel(Network.chain(3), TABLE1.mass, TABLE1.damping, TABLE1.stiffness)
    for a, b in zip(model.matrices(), TABLE1.matrices()):
        assert np.array_equal(a, b)
    np.testing.assert_allclose(model.natural_frequencies_hz(), TABLE1.natural_frequencies_hz(), rtol=1e-12)
    sigma = 0.01 * TABLE1.identifiable()
    a, b = model.modes(sigma=sigma), TABLE1.modes(sigma=sigma)
    np.testing.assert_allclose(
        [m.sigma_frequency_hz for m in a.modes], [m.sigma_frequency_hz for m in b.modes], rtol=1e-9
    )
    with pytest.raises(ValueError, match="the network has 4 springs"):
        NetworkModel(Network.chain(3), TABLE1.mass, TABLE1.damping, [1.0, 2.0])


@pytest.mark.parametrize("name", sorted(NETWORKS))
def test_example_networks_are_in_table1_range(name):
    model = network_model(name)
    assert np.all((model.mass >= 1.0) & (model.mass <= 3.0))
    assert np.all((model.stiffness >= 1e3) & (model.stiffness <= 1e4))
    assert np.all((model.damping >= 1.0) & (model.damping <= 5.0))
    assert 0 < model.natural_frequencies_hz()[0] and model.natural_frequencies_hz()[-1] < 100.0


def test_simulator_runs_a_network_like_the_exact_integration():
    model = network_model("half_car")
    _, a_ref, _, x_ref = simulate_chain(model, multisine(model.n), 0.2)
    sim = simulate(model, multisine(model.n), 0.2)
    assert np.max(np.abs(sim.a - a_ref[:-1])) < 1e-6 * np.max(np.abs(a_ref))
    assert np.max(np.abs(sim.x - x_ref[:-1])) < 1e-6 * np.max(np.abs(x_ref))
    effect = {"name": "cubic_stiffness", "location": {"spring": 9}, "params": {"k_cubic": 1e6}}
    with pytest.raises(ValueError, match="spring 9 outside 1..5"):
        simulate(model, multisine(model.n), 0.05, effects=[effect])


# --- the reference identifier -----------------------------------------------------------------


@pytest.fixture(scope="module")
def records():
    """0.15 s noise-free records of the example networks (exact integration)."""
    out = {}
    for name in NETWORKS:
        model = network_model(name)
        _, a, u, _ = simulate_chain(model, multisine(model.n), 0.15)
        out[name] = (model, a, u)
    return out


@pytest.mark.parametrize("name", sorted(NETWORKS))
def test_reference_identifies_the_networks_noise_free(records, name):
    """Within 1e-6 by t = 0.1 s for every DOF of up to 7 unknowns; the lattice's centre (8
    springs, 10 unknowns, the worst conditioned) within 1e-6 by 0.15 s."""
    model, a, u = records[name]
    names, truth = model.network.parameter_names(), model.packed()
    out = nr.estimate(model.network, a, u, 1e-3)
    for k, top in ((100, 7), (150, 10)):
        for d in out["dof"]:
            if len(d["names"]) <= top:
                exact = truth[[names.index(p) for p in d["names"]]]
                assert np.max(np.abs(d["theta_ratio"][k] / exact - 1)) < 1e-6, (name, d["names"], k)
    assert np.max(np.abs(out["packed"][-1] / truth - 1)) < 1e-6


def test_reference_least_squares_rows_agree_with_the_square_system(records):
    model, a, u = records["frame"]
    # every sample trusted in both: the least-squares Hadamard measure is not the square one
    square = nr.estimate(model.network, a[:101], u[:101], 1e-3, min_hadamard=0.0)
    ls = nr.estimate(model.network, a[:101], u[:101], 1e-3, extra_rows=2, min_hadamard=0.0)
    np.testing.assert_allclose(ls["packed"][-1], square["packed"][-1], rtol=2e-6)


@pytest.mark.parametrize(
    "chain", [TABLE1, Chain.random(4, np.random.default_rng(1), "free"), Chain([2.0], [3.0], [800.0, 500.0])]
)
def test_chain_as_network_gives_the_chain_oracle(chain):
    _, a, u, _ = simulate_chain(chain, multisine(chain.n), 0.2)
    ref = reference.estimate(a, u, 1e-3, boundary=chain.boundary)
    out = nr.estimate(chain.network, a, u, 1e-3)
    for i, d in enumerate(out["dof"]):
        M = len(d["names"])
        assert np.array_equal(np.isnan(d["theta_ratio"]), np.isnan(ref["theta_ratio"][:, i, :M]))
        np.testing.assert_allclose(d["theta_inst"][1:], ref["theta_inst"][1:, i, :M], rtol=1e-12)
        np.testing.assert_allclose(d["theta_ratio"], ref["theta_ratio"][:, i, :M], rtol=1e-12)


# --- Cramer-Rao bound -------------------------------------------------------------------------


def test_crlb_of_the_chain_as_network_is_the_chain_bound_under_a_held_force():
    model = NetworkModel(Network.chain(3), TABLE1.mass, TABLE1.damping, TABLE1.stiffness)
    n, T = 3, 300
    w = np.random.default_rng(4).standard_normal((T, n))
    drive = C.Drive(np.zeros((0, 0)), np.zeros((0, n)), np.zeros((n, 0)), np.eye(n), np.zeros(0), w)
    theta, y0 = C.params_of(TABLE1), np.zeros(2 * n)
    Jc, idx_c = C.driven_sensitivities(TABLE1, theta, y0, drive, 1e-3)
    Jn, idx_n = C.driven_sensitivities(model, theta, y0, drive, 1e-3)
    assert np.array_equal(idx_c, idx_n)
    np.testing.assert_allclose(Jn, Jc, rtol=0, atol=1e-12 * np.abs(Jc).max())
    sigma = np.full(n, 0.01)
    bc, bn = C.bound(Jc, idx_c, theta, sigma, 1e-3, [0.3]), C.bound(Jn, idx_n, theta, sigma, 1e-3, [0.3])
    np.testing.assert_allclose(bn[0.3], bc[0.3], rtol=1e-9)
    with pytest.raises(ValueError, match="only their sum"):
        C.identified_mask(NetworkModel(Network(1, [(0, 1), (1, 0)]), [1.0], [1.0], [1e3, 1e3]))


@pytest.mark.slow
def test_crlb_of_the_chain_as_network_is_the_chain_bound():
    """The benchmark's record and bound (crlb.simulate's filter gain alone takes ~10 s)."""
    model = NetworkModel(Network.chain(3), TABLE1.mass, TABLE1.damping, TABLE1.stiffness)
    rec_c = C.simulate(TABLE1, 0.3, seed=2, burn_in_s=0.2)
    rec_n = C.simulate(model, 0.3, seed=2, burn_in_s=0.2)
    np.testing.assert_allclose(rec_n.a, rec_c.a, rtol=0, atol=1e-12 * np.abs(rec_c.a).max())
    bc, bn = C.crlb(rec_c, 40.0, [0.3]), C.crlb(rec_n, 40.0, [0.3])
    np.testing.assert_allclose(bn[0.3], bc[0.3], rtol=1e-6)


@pytest.mark.slow
def test_network_crlb_sensitivities_match_finite_differences():
    """The half-car's sensitivities against central differences of re-simulated records."""
    model = network_model("half_car")
    rec = C.simulate(model, 0.3, seed=3, burn_in_s=0.3)
    J, idx = C.sensitivities(rec)
    theta = C.params_of(model)
    n, net = model.n, model.network
    Af, Bf, Cf = C.force_filter(n, rec.band_hz)
    nf = Af.shape[0]

    def accel(p):
        Phi, Gam = C._plant(p, n, Af, Bf, Cf, rec.dt, net)
        A, B = C.chain_blocks(p[:n], p[n : 2 * n], p[2 * n :], net)
        z, out = rec.z0.copy(), np.empty_like(rec.a)
        for k in range(rec.t.size):
            out[k] = A[n:] @ z[nf:] + B[n:] @ (Cf @ z[:nf])
            z = Phi @ z + Gam @ rec.w[k]
        return out

    assert np.allclose(accel(theta), rec.a, rtol=0, atol=1e-9 * np.abs(rec.a).max())
    for j in (0, n + 1, 2 * n + 2):
        e = np.zeros_like(theta)
        e[j] = 1e-5 * theta[j]
        fd = (accel(theta + e) - accel(theta - e)) / (2 * e[j])
        col = int(np.nonzero(idx == j)[0][0])
        assert np.max(np.abs(J[:, :, col] - fd)) < 1e-6 * np.max(np.abs(fd))


def test_top_level_names():
    assert algid.Network is Network and algid.NetworkModel is NetworkModel
