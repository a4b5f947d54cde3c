"""One simulation set up for a driver: the validated inputs, the sub-step schedule, the
plant, the state layout and linear system, the stepper, the input routing, and the
progress report."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .inputs import RunInputs
from .pieces import InputRouting
from .plant import Plant
from .schedule import Schedule, substep_schedule
from .sensors import accelerometer_bias
from .state_space import StateLayout, Stepper, linear_system, state_layout

__all__ = ["Progress", "Run", "build_run"]


class Progress:
    """Reports the fraction of the samples done about every 1 % to ``callback`` (if any)."""

    def __init__(self, callback: Callable[[float], None] | None, samples: int) -> None:
        self.callback = callback
        self.samples = samples
        self.every = max(1, samples // 100)

    def __call__(self, k: int) -> None:
        if self.callback is not None and k % self.every == 0:
            self.callback(k / self.samples)

    def done(self) -> None:
        if self.callback is not None:
            self.callback(1.0)


@dataclass
class Run:
    """Everything a driver needs: ``Bg`` and ``B_in`` say how a force on the masses and the
    commanded force enter the state (:func:`~.state_space.linear_system`), ``bias`` is the
    accelerometers' bias [m/s^2] (n,)."""

    inputs: RunInputs
    schedule: Schedule
    plant: Plant
    layout: StateLayout
    Bg: np.ndarray
    B_in: np.ndarray
    stepper: Stepper
    routing: InputRouting
    bias: np.ndarray
    report: Progress

    @property
    def rk(self) -> bool:
        """ETDRK4 steps (a nonlinear part exists), else exact linear steps."""
        return self.plant.nonlinear or self.inputs.controller_in_ode

    def initial_state(self) -> np.ndarray:
        """The state at ``t = 0``: ``x0``, ``v0``, every other state zero."""
        n = self.inputs.n
        s = np.zeros(self.layout.size)
        s[:n] = self.inputs.x0
        s[n : 2 * n] = self.inputs.v0
        return s


def build_run(inp: RunInputs, report: Progress) -> Run:
    """Set up a run; starts the controller of a closed loop (it tells its number of states)."""
    sched = substep_schedule(inp)
    plant = Plant(inp.chain, inp.effects, inp.duration_s, sched.v_eps)
    if inp.closed:
        inp.controller.start(chain_n=inp.n, dt=inp.h, boundary=inp.chain.boundary, samples=inp.T, mode=inp.mode)
    n_z = int(inp.controller.n_states) if inp.controller_in_ode else 0
    lay = state_layout(inp, n_z)
    Lm, Bg, B_in = linear_system(plant, lay, inp.actuator_lag_s)
    rk = plant.nonlinear or inp.controller_in_ode
    stepper = Stepper(Lm, B_in, None if inp.controller_in_ode else Bg, sched.lengths_s, inp.fs_hz, rk, plant)
    return Run(
        inputs=inp,
        schedule=sched,
        plant=plant,
        layout=lay,
        Bg=Bg,
        B_in=B_in,
        stepper=stepper,
        routing=InputRouting(sched.bounds, inp.delays, inp.fs_hz, inp.h),
        bias=accelerometer_bias(inp.effects, inp.n),
        report=report,
    )
