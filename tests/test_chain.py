"""The chain topology of eq. 1 (algid.model.chain) against the energy form ``K = D^T diag(k) D``."""

from __future__ import annotations

import numpy as np
import pytest

from algid.model.chain import (
    Chain,
    deformation_matrix,
    parameter_names,
    spring_columns,
    spring_deformation,
    spring_sides,
    springs,
    stiffness_matrix,
)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_stiffness_matrix_is_the_energy_form(n):
    k = np.random.default_rng(n).uniform(100.0, 1000.0, n + 1)
    D = deformation_matrix(n)  # d = D x: spring deformations from positions
    np.testing.assert_allclose(stiffness_matrix(k), D.T @ np.diag(k) @ D, rtol=1e-15)
    np.testing.assert_array_equal(Chain(np.ones(n), np.ones(n), k).matrices()[2], stiffness_matrix(k))


@pytest.mark.parametrize("boundary", ["fixed", "free"])
@pytest.mark.parametrize("n", [2, 3, 5])
def test_spring_columns_sides_and_deformations_agree_with_the_stiffness_matrix(n, boundary):
    rng = np.random.default_rng(n)
    k = rng.uniform(100.0, 1000.0, n + 1)
    if boundary == "free":
        k[-1] = 0.0
    K = np.zeros((n, n))
    for e, cols in enumerate(spring_columns(n, boundary)):  # column of spring j: x_e - x_other
        for j, other in cols:
            K[e, e] += k[j - 1]
            if other >= 0:
                K[e, other] -= k[j - 1]
    np.testing.assert_allclose(K, stiffness_matrix(k), rtol=1e-15)
    for j in springs(n, boundary):
        in_eqs = sorted(e for e, cols in enumerate(spring_columns(n, boundary)) if j in [jj for jj, _ in cols])
        assert sorted(e for e, _ in spring_sides(n, j)) == in_eqs
    x = rng.standard_normal((7, n))
    d = x @ deformation_matrix(n).T
    for j in springs(n, boundary):
        np.testing.assert_array_equal(spring_deformation(x, j, n), d[:, j - 1])


def test_parameter_names_follow_the_packed_order():
    assert parameter_names(2) == ["m1", "m2", "c1", "c2", "k1", "k2", "k3"]
    assert spring_columns(1, "fixed") == [[(1, -1)]] and springs(1, "fixed") == [1]
