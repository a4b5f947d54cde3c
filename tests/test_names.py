"""One vocabulary for both estimators (reset, valid, ready, sample/time_s, spring), the
0-based DOF / 1-based parameter-name convention, and the deprecated old names."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from algid.model.chain import TABLE1, Chain
from signals import multisine, simulate_chain

ESTIMATORS = (algid.ChainEstimator, algid.ContinuousEstimator)


@pytest.fixture(scope="module")
def table1_record():
    _, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.5)
    return a, u


@pytest.mark.parametrize("cls", ESTIMATORS)
def test_both_estimators_speak_the_same_names(cls, table1_record):
    a, u = table1_record
    est = cls(3, 1e-3)
    assert est.names == ["m1", "m2", "m3", "c1", "c2", "c3", "k1", "k2", "k3", "k4"]
    assert est.valid.shape == (3,) and est.valid.dtype == bool and not est.valid.any()
    assert est.ready is False
    out = est.run(a, u)
    np.testing.assert_array_equal(out["time_s"], out["sample"] * 1e-3)
    assert est.ready is bool(est.valid.all())
    est.reset()
    assert not est.valid.any() and est.ready is False


def test_chain_estimator_springs_by_their_1_based_names(table1_record):
    """Noise-free Table 1 record: spring(j) is k_j of the chain, theta(i) holds m_{i+1},
    c_{i+1}, k_{i+1}, k_{i+2}, and the packed names index the same values."""
    a, u = table1_record
    est = algid.ChainEstimator(3, 1e-3)
    est.run(a, u)
    assert est.ready
    for j in range(1, 5):
        assert est.spring(j) == pytest.approx(TABLE1.stiffness[j - 1], rel=1e-6)
        assert est.names[6 + j - 1] == f"k{j}"
    for i in range(3):
        m, c, k_left, k_right = est.theta(i)
        assert (m, c) == (pytest.approx(TABLE1.mass[i], rel=1e-6), pytest.approx(TABLE1.damping[i], rel=1e-6))
        assert k_left == pytest.approx(est.spring(i + 1), rel=1e-6)
        assert k_right == pytest.approx(est.spring(i + 2), rel=1e-6)
    for j in (0, 5, -1):
        with pytest.raises(IndexError, match="1-based"):
            est.spring(j)


def test_continuous_estimator_springs_and_validity_follow_the_boundary():
    """n = 1 with walls identifies only k1 + k2 (k2 NaN): the DOF is still valid; a free end
    reports k_{n+1} = 0 known. Values from a noise-free record agree with the chain."""
    one = Chain([2.0], [3.0], [800.0, 400.0])
    _, a, u, _ = simulate_chain(one, multisine(1, seed=1), 3.0)
    est = algid.ContinuousEstimator(1, 1e-3)
    est.run(a, u)
    assert est.valid.tolist() == [True] and est.ready
    assert est.spring(1) == pytest.approx(1200.0, rel=1e-3) and np.isnan(est.spring(2))

    free = Chain([2.0, 1.5], [3.0, 2.0], [800.0, 500.0, 0.0], boundary="free")
    _, a, u, _ = simulate_chain(free, multisine(2, seed=2), 3.0)
    est = algid.ContinuousEstimator(2, 1e-3, boundary="free")
    est.run(a, u)
    assert est.valid.tolist() == [True, True]
    assert [est.spring(j) for j in (1, 2)] == [pytest.approx(800.0, rel=1e-3), pytest.approx(500.0, rel=1e-3)]
    assert est.spring(3) == 0.0


def test_old_names_warn_and_mean_the_new_ones(table1_record):
    a, u = table1_record
    old, new = algid.ChainEstimator(3, 1e-3), algid.ChainEstimator(3, 1e-3)
    out = old.run(a, u)
    with pytest.warns(DeprecationWarning, match=r"run\(\)\['time_index'\] is deprecated, use run\(\)\['sample'\]"):
        time_index = out["time_index"]
    np.testing.assert_array_equal(time_index, np.arange(a.shape[0]) - old.delay_samples)
    assert "time_index" not in out  # the alias answers out[...] only
    with pytest.raises(KeyError):
        out["no_such_history"]

    new.run(a, u)
    with pytest.warns(DeprecationWarning, match=r"ChainEstimator.reseed\(\) is deprecated, use reset\(\)"):
        old.reseed()
    new.reset()
    fresh = algid.ChainEstimator(3, 1e-3).run(a[100:400], u[100:400])
    for est in (old, new):  # both restarted: the same as a fresh estimator on the same samples
        np.testing.assert_array_equal(est.run(a[100:400], u[100:400])["mass"], fresh["mass"])
    assert np.isfinite(fresh["mass"][-1]).all()


def test_effect_parameters_never_take_a_chain_parameters_name():
    # k3 is the third spring: the cubic coefficient is k_cubic, the contact stiffness k_contact
    import re

    from algid.diagnosis.units import PARAMETER_DIMENSIONS
    from algid.simulator.effects import _EFFECT_SPECS

    names = set(PARAMETER_DIMENSIONS) | {p for _, req, opt in _EFFECT_SPECS.values() for p in req + opt}
    clashes = {p for p in names if re.fullmatch(r"[mck]\d+", p) or p in ("mass", "damping", "stiffness")}
    assert not clashes


def test_renamed_effect_parameters_still_read_with_a_warning():
    import pytest

    from algid.simulator.effects import Effect

    with pytest.warns(DeprecationWarning, match="k_cubic"):
        e = Effect("cubic_stiffness", {"spring": 1}, {"k3": 2.0})
    assert dict(e.params) == {"k_cubic": 2.0}
