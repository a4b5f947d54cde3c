"""Eqs. 8-10 controller: gains, references, closed-loop error dynamics and tracking."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from algid.control.controller import DEFAULT_POLES, BezierReference, TrackingController, bezier, pole_placement_gains
from algid.model.chain import TABLE1
from algid.simulator import simulate


class Oracle:
    """Estimator stand-in returning fixed parameters (the truth unless told otherwise)."""

    def __init__(self, m, c, k, valid=True):
        self.mass, self.damping, self.stiffness = (np.array(v, dtype=float) for v in (m, c, k))
        self.valid = np.full(len(self.mass), valid)
        self.delay_samples = 0
        self.calls = 0

    def update(self, accel, force):
        self.calls += 1
        return 0


def truth(chain=TABLE1):
    return lambda n, dt, boundary: Oracle(chain.mass, chain.damping, chain.stiffness)


def test_pole_placement():
    b0, b1, b2 = pole_placement_gains(DEFAULT_POLES)
    assert (b0, b1, b2) == pytest.approx((8000.0, 1200.0, 60.0))
    poles = (-3.0 + 4.0j, -3.0 - 4.0j, -10.0)
    b0, b1, b2 = pole_placement_gains(poles)
    roots = np.roots([1.0, b2, b1, b0])
    assert np.allclose(np.sort_complex(roots), np.sort_complex(np.array(poles)))
    for bad in ((-1.0, -2.0), (1.0, -2.0, -3.0), (-1 + 1j, -1 + 1j, -2.0)):
        with pytest.raises(ValueError):
            pole_placement_gains(bad)


def test_bezier_rest_to_rest():
    p, dp, ddp = bezier(np.array([0.0, 1.0]))
    assert np.allclose(p, [0.0, 1.0]) and np.allclose(dp, 0.0) and np.allclose(ddp, 0.0)
    # derivatives 1 to 4 vanish at both ends
    poly = np.polynomial.Polynomial([0] * 5 + [252, -1050, 1800, -1575, 700, -126])
    for d in (1, 2, 3, 4):
        assert poly.deriv(d)(0.0) == 0.0 and abs(poly.deriv(d)(1.0)) < 1e-9
    ref = BezierReference.paper(3)
    assert np.allclose(ref.targets, [0.005, 0.005, -0.005])
    assert np.allclose(BezierReference.paper(5).targets, [0.005, 0.005, -0.005, 0.005, 0.005])
    t = np.linspace(0, 5, 5001)
    x, xd, xdd = ref.evaluate(t)
    assert np.allclose(x[0], 0) and np.allclose(x[-1], 0) and np.allclose(x[2250], ref.targets)
    h = t[1] - t[0]
    assert np.allclose(np.gradient(x, h, axis=0)[1:-1], xd[1:-1], atol=1e-8)
    assert np.allclose(np.gradient(xd, h, axis=0)[1:-1], xdd[1:-1], atol=1e-7)
    for tk in (0.3, 1.7, 2.2, 3.1, 4.9):
        assert all(np.allclose(a, b[int(round(tk / h))]) for a, b in zip(ref.evaluate(tk), (x, xd, xdd)))


def test_error_dynamics_after_the_switch_are_the_placed_poles():
    """With exact parameters from the switch on, eqs. 8-10 leave
    e''' + beta2 e'' + beta1 e' + beta0 e = 0: compare with its closed-form solution."""
    ctrl = TrackingController(switch_time_s=0.3, estimator_factory=truth())
    res = simulate(TABLE1, None, 1.5, 1000.0, controller=ctrl)
    b0, b1, b2 = ctrl.beta0, ctrl.beta1, ctrl.beta2
    k = ctrl.k_switch
    xr, xdr, xddr = (res.controller_log[key] for key in ("x_ref", "xd_ref", "xdd_ref"))
    e, de = res.x[k] - xr[k], res.v[k] - xdr[k]
    dde = res.limits["a_plus"][k] - xddr[k]
    ie = -(dde + b2 * de + b1 * e) / b0  # int e from eq. 9 at the switch
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-b0, -b1, -b2]])
    tt = res.t[k:] - res.t[k]
    expect = np.array([[(expm(A * s) @ np.array([ie[i], e[i], de[i]]))[1] for i in range(3)] for s in tt[::25]])
    got = (res.x - xr)[k:][::25]
    assert np.max(np.abs(e)) > 1e-5  # the nominal phase left a real error to remove
    assert np.max(np.abs(got - expect)) < 1e-6 * np.max(np.abs(expect))


@pytest.mark.parametrize("mode", ["continuous", "sampled"])
def test_tracking_with_exact_estimates(mode):
    res = simulate(TABLE1, None, 3.0, 1000.0, controller=TrackingController(estimator_factory=truth()), mode=mode)
    err = np.abs(res.x - res.x_ref)
    stroke = 0.005
    tol = 1e-6 if mode == "continuous" else 2e-3  # the hold costs half a sample of phase
    assert np.max(err[res.t >= 1.0]) < tol * stroke
    used = res.controller_log["used"]
    assert np.all(used["mass"][:100] == 1.0) and np.all(used["stiffness"][:100] == 0.0)
    assert np.allclose(used["mass"][100:], TABLE1.mass)


def test_eq10_forms_agree_for_constant_estimates():
    runs = [
        simulate(TABLE1, None, 1.0, 1000.0, controller=TrackingController(eq10=form, estimator_factory=truth()))
        for form in ("integrated", "product")
    ]
    assert np.max(np.abs(runs[0].x - runs[1].x)) < 1e-12
    # and the reconstructed velocity is the true one once the true parameters are in use
    vel = runs[0].controller_log["velocity_estimate"]
    assert np.max(np.abs(vel[100:] - runs[0].v[100:])) < 1e-8 * np.max(np.abs(runs[0].v))


def test_inadmissible_or_unsettled_estimates_are_not_used():
    def bad(n, dt, b):
        return Oracle(TABLE1.mass, TABLE1.damping, [1000.0, -900.0, 900.0, 700.0])

    res = simulate(TABLE1, None, 0.3, 1000.0, controller=TrackingController(estimator_factory=bad))
    assert np.all(res.controller_log["used"]["stiffness"] == 0.0)
    assert res.controller_log["first_accepted_s"] is None
    lenient = simulate(TABLE1, None, 0.3, 1000.0, controller=TrackingController(estimator_factory=bad, accept="valid"))
    assert lenient.controller_log["used"]["stiffness"][-1, 1] == -900.0

    class Jumpy(Oracle):
        def update(self, accel, force):
            self.calls += 1
            self.mass = TABLE1.mass * (1.5 if self.calls < 150 else 1.0)
            return 0

    ctrl = TrackingController(estimator_factory=lambda n, dt, b: Jumpy(TABLE1.mass, TABLE1.damping, TABLE1.stiffness))
    res = simulate(TABLE1, None, 0.3, 1000.0, controller=ctrl)
    # steady at 1.5 m until sample 149: accepted at sample 19; the jump is taken 20 samples later
    assert res.controller_log["first_accepted_s"] == pytest.approx(0.019)
    m_used = res.controller_log["used"]["mass"][:, 0]
    assert np.all(m_used[100:169] == 3.0) and np.all(m_used[170:] == 2.0)


def test_closed_loop_with_the_on_line_estimator():
    pytest.importorskip("algid._core")
    res = simulate(TABLE1, None, 5.0, 1000.0, controller=TrackingController())
    est = res.estimates
    theta = np.concatenate([est["mass"], est["damping"], est["stiffness"]], axis=1)
    rel = np.abs(theta / TABLE1.identifiable() - 1)
    assert np.max(rel[99]) < 0.01  # all estimates within 1 % before 0.1 s
    err = np.abs(res.x - res.x_ref)
    assert np.max(err[100:]) < 0.10 * 0.005
    assert np.max(err[1000:]) < 0.02 * 0.005
