"""The closed-loop driver: the controller acts sample by sample, on measured positions
held over the interval (sampled mode) or inside the ODE (continuous mode), and its
estimator is fed the measured accelerations and recorded forces of every sample."""

from __future__ import annotations

from typing import Any

import numpy as np

from .protocol import ContinuousController
from .result import LIMIT_NAMES, Samples
from .run import Run
from .sensors import encoder

__all__ = ["ClosedLoop"]


class ControlledDynamics:
    """``N(t, s)`` of a continuous-mode loop: the controller's force (and the effects)
    driving the plant, and the derivative of the controller states, with the parameters
    :attr:`params` of the current interval. :attr:`force` is the force of the latest call [N]."""

    def __init__(self, controller: ContinuousController, run: Run) -> None:
        self.controller = controller
        self.run = run
        self.params: Any = None
        self.force: np.ndarray | None = None

    def __call__(self, t: float, st: np.ndarray) -> np.ndarray:
        n, o_z, plant = self.run.inputs.n, self.run.layout.o_z, self.run.plant
        x = st[:n]
        u, dz = self.controller.continuous(t, x, st[o_z:], self.params)
        self.force = u
        out = self.run.B_in @ u
        if plant.nonlinear:
            out = out + self.run.Bg @ plant.effect_force(t, x, st[n : 2 * n])
        out[o_z:] = dz
        return out


class ClosedLoop:
    """Runs a closed loop sample by sample.

    Per sample ``k`` the controller gets the parameters for ``[t_k, t_{k+1})``, the force
    at ``t_k+`` is formed (held command or the law in the ODE), the sensors are read (one-
    sided limits averaged; ``noise_scale`` RMS times the unit noise ``unit``) and fed to the
    controller, then the interval is integrated. :attr:`left_rec` and :attr:`left_app`
    are the recorded and applied forces at ``t_k-`` (from the interval before).
    """

    def __init__(self, run: Run, noise_scale: dict[str, np.ndarray], unit: dict[str, np.ndarray]) -> None:
        inp = run.inputs
        self.run = run
        self.controller = inp.controller
        self.noise_scale = noise_scale
        self.unit = unit
        self.dynamics = ControlledDynamics(self.controller, run)
        self.out = Samples.empty(inp.T, inp.n)
        self.history = np.zeros((inp.T, inp.n))  # held commands so far (sampled mode)
        self.s = run.initial_state()
        self.left_rec: np.ndarray | None = None
        self.left_app: np.ndarray | None = None

    def drive(self) -> Samples:
        """Run every sample; the noise-free samples and the readings the controller saw."""
        inp, o_z = self.run.inputs, self.run.layout.o_z
        for k in range(inp.T):
            params = self.controller.params_for_sample(k, self.s[o_z:] if inp.controller_in_ode else None)
            self.dynamics.params = params
            pending = self._sample(k)
            self.run.report(k)
            if k == inp.T - 1:
                break
            if inp.mode == "sampled":
                self._held_interval(k, *pending)
            else:
                self._ode_interval(k, params, pending)
            if self.run.layout.n_w:
                self.left_app = self.left_rec = self.s[self.run.layout.o_w : o_z].copy()
            if not np.all(np.isfinite(self.s)):
                raise RuntimeError(f"the simulation diverged before t = {inp.t[k + 1]:.6g} s")
        return self.out

    def _command(self, k: int, x_read: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any]:
        """Commanded and applied force [N] at ``t_k+``, and what integrating interval ``k``
        needs: the held command and its per-sub-interval values, or ``N(t_k, s)``."""
        inp = self.run.inputs
        tk = inp.t[k]
        if inp.mode == "sampled":
            u_k = np.asarray(self.controller.sampled_force(k, tk, x_read.copy()), dtype=float).reshape(inp.n)
            self.history[k] = u_k
            app_q = self.run.routing.held(self.history, k)
            return u_k, app_q[0], (u_k, app_q)
        n0 = self.dynamics(tk, self.s)
        return self.dynamics.force, self.dynamics.force, n0

    def _sample(self, k: int) -> Any:
        """Form the force at ``t_k+``, read the sensors at ``t_k`` and feed the controller."""
        inp, lay, plant, s = self.run.inputs, self.run.layout, self.run.plant, self.s
        n, tk = inp.n, inp.t[k]
        x, v = s[:n], s[n : 2 * n]
        base = -plant.c * v - plant.K @ x
        if plant.nonlinear:
            base = base + plant.effect_force(tk, x, v)
        x_read = self._position_reading(k, x)
        cmd_r, app_r, pending = self._command(k, x_read)
        if lay.n_w:
            rec_r = app_r = s[lay.o_w : lay.o_z].copy()
        else:
            rec_r = cmd_r
        a_r = (app_r + base) * plant.minv
        if k == 0:
            if lay.n_lp:  # low-pass accelerometers settled on a(0+), high-pass ones on rest
                s[lay.o_lp : lay.o_w] = np.where(lay.lp_high, 0.0, a_r[lay.lp_idx])
            self.left_rec, self.left_app = rec_r, app_r
        a_l = (self.left_app + base) * plant.minv
        self._record(k, x, v, (a_l, a_r, self.left_rec, rec_r, self.left_app, app_r))
        a_read, u_read = self._accel_force_readings(k)
        out = self.out
        out.a_meas[k], out.u_meas[k], out.x_meas[k] = a_read, u_read, x_read
        in_ode = inp.controller_in_ode
        self.controller.observe(
            k, tk, a_read, u_read, x.copy() if in_ode else x_read, s[lay.o_z :].copy() if in_ode else None
        )
        return pending

    def _position_reading(self, k: int, x: np.ndarray) -> np.ndarray:
        """Position sensors at ``t_k`` [m]: noise, then the encoder."""
        if "position" in self.noise_scale:
            x_read = x + self.noise_scale["position"] * self.unit["position"][k]
        else:
            x_read = x.copy()
        return encoder(x_read, self.run.inputs.encoder_resolution_m)

    def _record(self, k: int, x: np.ndarray, v: np.ndarray, limits: tuple[np.ndarray, ...]) -> None:
        """Keep sample ``k``: state and the one-sided limits ``(a-, a+, u-, u+, u_applied-,
        u_applied+)`` and their means."""
        out = self.out
        for name, value in zip(LIMIT_NAMES, limits):
            out.limits[name][k] = value
        a_l, a_r, rec_l, rec_r, app_l, app_r = limits
        out.x[k], out.v[k] = x, v
        out.a_true[k] = 0.5 * (a_l + a_r)
        out.u_rec[k] = 0.5 * (rec_l + rec_r)
        out.u_applied[k] = 0.5 * (app_l + app_r)

    def _accel_force_readings(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Accelerometers (low-pass, bias, noise) [m/s^2] and force sensors (noise) [N] at ``t_k``."""
        lay, out, s = self.run.layout, self.out, self.s
        am = out.a_true[k].copy()
        if lay.n_lp:  # a low-pass reads its state z, a high-pass a - z
            z, high = s[lay.o_lp : lay.o_w], lay.lp_high
            am[lay.lp_idx[~high]] = z[~high]
            am[lay.lp_idx[high]] -= z[high]
        am += self.run.bias
        out.a_clean[k] = am
        if "accel" in self.noise_scale:
            am = am + self.noise_scale["accel"] * self.unit["accel"][k]
        if "force" in self.noise_scale:
            um = out.u_rec[k] + self.noise_scale["force"] * self.unit["force"][k]
        else:
            um = out.u_rec[k].copy()
        return am, um

    def _held_interval(self, k: int, u_k: np.ndarray, app_q: np.ndarray) -> None:
        """Integrate interval ``k`` under the held forces ``app_q`` (J, n) [N]."""
        run, n = self.run, self.run.inputs.n
        P, lens = run.stepper.P, run.schedule.lengths_s
        s, tq = self.s, run.inputs.t[k]
        for q in range(run.schedule.J):
            wf = P[q].G[0] @ app_q[q]
            if run.rk:
                wh = P[q].Gh[0] @ app_q[q]
                coef = np.zeros((4, n))
                coef[0] = app_q[q]
                s = run.stepper.step(q, s, tq, coef, wf, wh, wf - P[q].E2 @ wh, run.plant.state_force)
            else:
                s = P[q].E @ s + wf
            tq += lens[q]
        self.s = s
        self.left_app = app_q[run.schedule.J - 1]
        self.left_rec = u_k

    def _ode_interval(self, k: int, params: Any, n0: np.ndarray) -> None:
        """Integrate interval ``k`` with the law inside the ODE (``n0 = N(t_k, s)``)."""
        run = self.run
        inp, o_z = run.inputs, run.layout.o_z
        zero_w = np.zeros(run.layout.size)
        s, tq = self.s, inp.t[k]
        for q in range(run.schedule.J):
            s = run.stepper.step(q, s, tq, None, zero_w, zero_w, zero_w, self.dynamics, n0 if q == 0 else None)
            tq += run.schedule.lengths_s[q]
        self.s = s
        u_l, _ = self.controller.continuous(inp.t[k + 1], s[: inp.n], s[o_z:], params)
        self.left_app = self.left_rec = u_l
